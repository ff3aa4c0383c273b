// SPDX-License-Identifier: BSD-3-Clause
// Helpers shared by the C++ rendering tests of the VTK adapter.
#ifndef mcvolTestUtilities_h
#define mcvolTestUtilities_h

#include "vtkImageData.h"
#include "vtkNew.h"
#include "vtkPNGWriter.h"
#include "vtkPointData.h"
#include "vtkRenderWindow.h"
#include "vtkTesting.h"
#include "vtkUnsignedCharArray.h"
#include "vtkWindowToImageFilter.h"
#include "vtksys/SystemTools.hxx"

#include <array>
#include <cstring>
#include <iostream>
#include <string>

namespace mcvolTest
{
/// Value following `flag` on the command line, or "" when absent.
inline std::string argValue(int argc, char* argv[], const char* flag)
{
  for (int i = 0; i + 1 < argc; ++i)
  {
    if (std::strcmp(argv[i], flag) == 0)
    {
      return argv[i + 1];
    }
  }
  return std::string();
}

inline bool hasArg(int argc, char* argv[], const char* flag)
{
  for (int i = 0; i < argc; ++i)
  {
    if (std::strcmp(argv[i], flag) == 0)
    {
      return true;
    }
  }
  return false;
}

/**
 * Renders once more (as vtkTesting does, with buffer swapping off so the back
 * buffer can be read) and returns the window's RGB image. Progressive
 * rendering adds samples on every render, so tests count this one.
 */
inline void capture(vtkRenderWindow* window, vtkWindowToImageFilter* grabber)
{
  const int swap = window->GetSwapBuffers();
  window->SwapBuffersOff();
  window->Render();
  grabber->SetInput(window);
  grabber->ShouldRerenderOff();
  grabber->ReadFrontBufferOff();
  grabber->SetInputBufferTypeToRGB();
  grabber->Modified();
  grabber->Update();
  window->SetSwapBuffers(swap);
}

/// RGB of pixel (x, y) (origin bottom-left) of a captured image.
inline std::array<int, 3> pixel(vtkImageData* image, int x, int y)
{
  auto* rgb = vtkUnsignedCharArray::SafeDownCast(image->GetPointData()->GetScalars());
  const int* dims = image->GetDimensions();
  const vtkIdType p = static_cast<vtkIdType>(y) * dims[0] + x;
  const int n = rgb->GetNumberOfComponents();
  return { rgb->GetValue(p * n), rgb->GetValue(p * n + 1), rgb->GetValue(p * n + 2) };
}

/**
 * Compares a captured image with the baseline named by `-V <file>` (writing
 * differences under `-T <dir>`), through vtkTesting and its threshold. A
 * missing baseline fails, unless `--generate-baseline` was given: then the
 * image is written there (never over an existing file) for a person to review.
 * Returns a process exit code.
 */
inline int compareWithBaseline(int argc, char* argv[], vtkWindowToImageFilter* grabber, double threshold)
{
  const std::string baseline = argValue(argc, argv, "-V");
  if (baseline.empty())
  {
    std::cerr << "No baseline given (-V <file>).\n";
    return EXIT_FAILURE;
  }
  if (!vtksys::SystemTools::FileExists(baseline))
  {
    if (!hasArg(argc, argv, "--generate-baseline"))
    {
      std::cerr << "Baseline " << baseline
                << " is missing. Configure with -DMCVOL_GENERATE_BASELINES=ON and run the test "
                   "once to create it, then review and commit it.\n";
      return EXIT_FAILURE;
    }
    vtksys::SystemTools::MakeDirectory(vtksys::SystemTools::GetFilenamePath(baseline));
    vtkNew<vtkPNGWriter> writer;
    writer->SetFileName(baseline.c_str());
    writer->SetInputConnection(grabber->GetOutputPort());
    writer->Write();
    std::cout << "Generated missing baseline " << baseline << " (review it before committing).\n";
    return EXIT_SUCCESS;
  }
  vtkNew<vtkTesting> testing;
  for (int i = 0; i < argc; ++i)
  {
    testing->AddArgument(argv[i]);
  }
  const int result = testing->RegressionTest(grabber, threshold);
  std::cout << "Image difference: " << testing->GetImageDifference() << " (threshold " << threshold << ")\n";
  return result == vtkTesting::PASSED ? EXIT_SUCCESS : EXIT_FAILURE;
}
} // namespace mcvolTest

#endif
