// SPDX-License-Identifier: BSD-3-Clause
// Five channels on one image: channels 0-3 take their transfer functions from
// the vtkVolumeProperty, channel 4 (beyond VTK_MAX_VRCOMP) from the mapper.
// Regression image of the converged-enough mean (CPU backend, fixed seed).
#include "vtkMultiChannelVolumeMapper.h"

#include "vtkCamera.h"
#include "vtkColorTransferFunction.h"
#include "vtkFloatArray.h"
#include "vtkImageData.h"
#include "vtkNew.h"
#include "vtkPiecewiseFunction.h"
#include "vtkPointData.h"
#include "vtkRenderWindow.h"
#include "vtkRenderer.h"
#include "vtkVolume.h"
#include "vtkVolumeProperty.h"
#include "vtkWindowToImageFilter.h"

#include "mcvolTestUtilities.h"

#include <cmath>
#include <iostream>

int TestMultiChannelVolumeMapper(int argc, char* argv[])
{
  constexpr int N = 40;
  constexpr int C = 5;
  // Blob centres (voxels), one per channel, and colours.
  const double centres[C][3] = { { 12, 12, 20 }, { 28, 12, 20 }, { 12, 28, 20 }, { 28, 28, 20 }, { 20, 20, 20 } };
  const double colours[C][3] = { { 1, 0.2, 0.2 }, { 0.2, 1, 0.2 }, { 0.2, 0.2, 1 }, { 1, 1, 0.2 }, { 1, 0.2, 1 } };

  vtkNew<vtkImageData> image;
  image->SetDimensions(N, N, N);
  image->SetSpacing(0.5, 0.5, 0.5);
  image->SetOrigin(-10, -10, -10);
  vtkNew<vtkFloatArray> scalars;
  scalars->SetName("channels");
  scalars->SetNumberOfComponents(C);
  scalars->SetNumberOfTuples(static_cast<vtkIdType>(N) * N * N);
  for (int z = 0; z < N; ++z)
  {
    for (int y = 0; y < N; ++y)
    {
      for (int x = 0; x < N; ++x)
      {
        const vtkIdType p = (static_cast<vtkIdType>(z) * N + y) * N + x;
        for (int c = 0; c < C; ++c)
        {
          const double dx = x - centres[c][0], dy = y - centres[c][1], dz = z - centres[c][2];
          scalars->SetTypedComponent(p, c, static_cast<float>(std::exp(-(dx * dx + dy * dy + dz * dz) / 40.0)));
        }
      }
    }
  }
  image->GetPointData()->SetScalars(scalars);

  vtkNew<vtkMultiChannelVolumeMapper> mapper;
  mapper->SetInputData(image);
  mapper->SetBackendToCPU();
  mapper->SetSeed(7);
  // The baseline was made with the independent sampler; pinning it keeps this
  // an exact regression of that sampler's images (the Sobol' sampler, the
  // default, is tested statistically in Testing/Core/sequence_test.cxx).
  mapper->SetSampleSequenceToIndependent();
  mapper->SetEstimatorToCollision(); // and the collision estimator
  mapper->SetSamplesPerPixel(16);

  vtkNew<vtkVolumeProperty> property;
  property->IndependentComponentsOn();
  vtkNew<vtkColorTransferFunction> colour[C];
  vtkNew<vtkPiecewiseFunction> opacity[C];
  for (int c = 0; c < C; ++c)
  {
    colour[c]->AddRGBPoint(0.0, colours[c][0], colours[c][1], colours[c][2]);
    colour[c]->AddRGBPoint(1.0, colours[c][0], colours[c][1], colours[c][2]);
    opacity[c]->AddPoint(0.0, 0.0);
    opacity[c]->AddPoint(0.2, 0.0);
    opacity[c]->AddPoint(1.0, 0.6);
    if (c < 4)
    {
      property->SetColor(c, colour[c]);
      property->SetScalarOpacity(c, opacity[c]);
      property->SetScalarOpacityUnitDistance(c, 0.5);
    }
    else
    {
      mapper->SetChannelColor(c, colour[c]);
      mapper->SetChannelScalarOpacity(c, opacity[c]);
      mapper->SetChannelScalarOpacityUnitDistance(c, 0.5);
    }
  }

  vtkNew<vtkVolume> volume;
  volume->SetMapper(mapper);
  volume->SetProperty(property);

  vtkNew<vtkRenderer> renderer;
  renderer->SetBackground(0.1, 0.1, 0.1);
  renderer->AddVolume(volume);
  vtkNew<vtkRenderWindow> window;
  window->SetMultiSamples(0);
  window->SetOffScreenRendering(1);
  window->SetSize(256, 256);
  window->AddRenderer(renderer);
  renderer->ResetCamera();
  renderer->GetActiveCamera()->Azimuth(20);
  renderer->GetActiveCamera()->Elevation(15);
  renderer->ResetCameraClippingRange();

  for (int i = 0; i < 4; ++i)
  {
    window->Render();
  }
  if (mapper->GetNumberOfChannels() != C)
  {
    std::cerr << "Expected " << C << " channels, the mapper rendered " << mapper->GetNumberOfChannels() << ".\n";
    return EXIT_FAILURE;
  }
  if (mapper->GetTotalSamples() != 64)
  {
    std::cerr << "Expected 64 accumulated samples, got " << mapper->GetTotalSamples() << ".\n";
    return EXIT_FAILURE;
  }

  vtkNew<vtkWindowToImageFilter> grabber;
  mcvolTest::capture(window, grabber); // 80 samples per pixel
  if (mapper->GetTotalSamples() != 80)
  {
    std::cerr << "Expected 80 accumulated samples, got " << mapper->GetTotalSamples() << ".\n";
    return EXIT_FAILURE;
  }
  return mcvolTest::compareWithBaseline(argc, argv, grabber, 0.15);
}
