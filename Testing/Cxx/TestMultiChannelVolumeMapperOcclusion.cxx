// SPDX-License-Identifier: BSD-3-Clause
// An opaque sphere inside the volume: rays stop at the depth of the geometry
// drawn before the volume. The volume fills only the half of the box behind
// the sphere's centre (seen from the camera), so wherever the sphere is
// visible it must look exactly as it does without the volume, while the
// volume shows beside it. A visible actor without geometry, listed before
// the sphere, changes nothing.
#include "vtkMultiChannelVolumeMapper.h"

#include "vtkActor.h"
#include "vtkCamera.h"
#include "vtkColorTransferFunction.h"
#include "vtkImageData.h"
#include "vtkNew.h"
#include "vtkPiecewiseFunction.h"
#include "vtkPointData.h"
#include "vtkPolyData.h"
#include "vtkPolyDataMapper.h"
#include "vtkProperty.h"
#include "vtkRenderWindow.h"
#include "vtkRenderer.h"
#include "vtkSphereSource.h"
#include "vtkUnsignedShortArray.h"
#include "vtkVolume.h"
#include "vtkVolumeProperty.h"
#include "vtkWindowToImageFilter.h"

#include "mcvolTestUtilities.h"

#include <cstdlib>
#include <iostream>

int TestMultiChannelVolumeMapperOcclusion(int argc, char* argv[])
{
  constexpr int N = 32;
  vtkNew<vtkImageData> image;
  image->SetDimensions(N, N, N);
  image->SetOrigin(0, 0, 0);
  image->SetSpacing(1, 1, 1);
  // Two uint16 channels; both are non-zero only for z < 12 (the camera looks
  // down -z, so that is the back part of the box).
  vtkNew<vtkUnsignedShortArray> scalars;
  scalars->SetNumberOfComponents(2);
  scalars->SetNumberOfTuples(static_cast<vtkIdType>(N) * N * N);
  for (int z = 0; z < N; ++z)
  {
    for (int y = 0; y < N; ++y)
    {
      for (int x = 0; x < N; ++x)
      {
        const vtkIdType p = (static_cast<vtkIdType>(z) * N + y) * N + x;
        const bool back = z < 12;
        scalars->SetTypedComponent(p, 0, back && x < N / 2 ? 1000 : 0);
        scalars->SetTypedComponent(p, 1, back && x >= N / 2 ? 1000 : 0);
      }
    }
  }
  image->GetPointData()->SetScalars(scalars);

  vtkNew<vtkMultiChannelVolumeMapper> mapper;
  mapper->SetInputData(image);
  mapper->SetBackendToCPU();
  mapper->SetSamplesPerPixel(8);
  // The baseline was made with the independent sampler (see
  // TestMultiChannelVolumeMapper.cxx).
  mapper->SetSampleSequenceToIndependent();
  mapper->SetEstimatorToCollision(); // and the collision estimator

  vtkNew<vtkVolumeProperty> property;
  property->IndependentComponentsOn();
  const double colours[2][3] = { { 0.1, 0.3, 1.0 }, { 0.1, 1.0, 0.3 } };
  vtkNew<vtkColorTransferFunction> colour[2];
  vtkNew<vtkPiecewiseFunction> opacity[2];
  for (int c = 0; c < 2; ++c)
  {
    colour[c]->AddRGBPoint(0, colours[c][0], colours[c][1], colours[c][2]);
    colour[c]->AddRGBPoint(1000, colours[c][0], colours[c][1], colours[c][2]);
    opacity[c]->AddPoint(0, 0.0);
    opacity[c]->AddPoint(1000, 0.3);
    property->SetColor(c, colour[c]);
    property->SetScalarOpacity(c, opacity[c]);
  }
  vtkNew<vtkVolume> volume;
  volume->SetMapper(mapper);
  volume->SetProperty(property);

  // Opaque red sphere at the centre of the box, in front of the filled part.
  vtkNew<vtkSphereSource> sphere;
  sphere->SetCenter(15.5, 15.5, 15.5);
  sphere->SetRadius(6);
  sphere->SetThetaResolution(48);
  sphere->SetPhiResolution(48);
  vtkNew<vtkPolyDataMapper> sphereMapper;
  sphereMapper->SetInputConnection(sphere->GetOutputPort());
  vtkNew<vtkActor> actor;
  actor->SetMapper(sphereMapper);
  actor->GetProperty()->SetColor(1, 0, 0);

  // A visible actor with no geometry first, as ParaView keeps in its views:
  // it occludes nothing (the mapper skips the depth read-back for it), and
  // must not hide the sphere behind it in the list of props.
  vtkNew<vtkPolyData> nothing;
  vtkNew<vtkPolyDataMapper> nothingMapper;
  nothingMapper->SetInputData(nothing);
  vtkNew<vtkActor> emptyActor;
  emptyActor->SetMapper(nothingMapper);

  vtkNew<vtkRenderer> renderer;
  renderer->SetBackground(0, 0, 0);
  renderer->AddActor(emptyActor);
  renderer->AddActor(actor);
  renderer->AddVolume(volume);
  vtkNew<vtkRenderWindow> window;
  window->SetMultiSamples(0);
  window->SetOffScreenRendering(1);
  window->SetSize(200, 200);
  window->AddRenderer(renderer);
  renderer->ResetCamera();
  vtkCamera* camera = renderer->GetActiveCamera();
  camera->SetFocalPoint(15.5, 15.5, 15.5);
  camera->SetPosition(15.5, 15.5, 90);
  camera->SetViewUp(0, 1, 0);
  renderer->ResetCameraClippingRange();

  int failures = 0;
  // Without the volume: the sphere alone.
  volume->VisibilityOff();
  vtkNew<vtkWindowToImageFilter> sphereOnly;
  mcvolTest::capture(window, sphereOnly);
  volume->VisibilityOn();
  for (int i = 0; i < 3; ++i)
  {
    window->Render();
  }
  vtkNew<vtkWindowToImageFilter> both;
  mcvolTest::capture(window, both);

  // The sphere's projected radius is about 200 * 6 / (2 * 74.5 * tan(15 deg))
  // = 30 pixels; look well inside and well outside it.
  const int cx = 100, cy = 100;
  for (int dy = -12; dy <= 12; dy += 6)
  {
    for (int dx = -12; dx <= 12; dx += 6)
    {
      const auto a = mcvolTest::pixel(sphereOnly->GetOutput(), cx + dx, cy + dy);
      const auto b = mcvolTest::pixel(both->GetOutput(), cx + dx, cy + dy);
      for (int k = 0; k < 3; ++k)
      {
        if (std::abs(a[k] - b[k]) > 2)
        {
          std::cerr << "Pixel (" << cx + dx << ", " << cy + dy << ") on the sphere: " << b[0] << " " << b[1] << " "
                    << b[2] << " with the volume, " << a[0] << " " << a[1] << " " << a[2]
                    << " without: the volume shows through the geometry.\n";
          ++failures;
          break;
        }
      }
      if (a[0] < 100 || a[1] > 10 || a[2] > 10)
      {
        std::cerr << "Pixel (" << cx + dx << ", " << cy + dy << ") is not the red sphere: " << a[0] << " " << a[1]
                  << " " << a[2] << "\n";
        ++failures;
      }
    }
  }
  // Beside the sphere, left (channel 0, blue) and right (channel 1, green).
  const auto left = mcvolTest::pixel(both->GetOutput(), cx - 45, cy);
  const auto right = mcvolTest::pixel(both->GetOutput(), cx + 45, cy);
  if (!(left[2] > 40 && left[2] > left[0] && left[2] > left[1]))
  {
    std::cerr << "Left of the sphere should be the blue channel: " << left[0] << " " << left[1] << " " << left[2]
              << "\n";
    ++failures;
  }
  if (!(right[1] > 40 && right[1] > right[0] && right[1] > right[2]))
  {
    std::cerr << "Right of the sphere should be the green channel: " << right[0] << " " << right[1] << " " << right[2]
              << "\n";
    ++failures;
  }
  if (failures)
  {
    return EXIT_FAILURE;
  }
  return mcvolTest::compareWithBaseline(argc, argv, both, 0.15);
}
