// SPDX-License-Identifier: BSD-3-Clause
// A 5-channel volume with vtkMultiChannelVolumeMapper from C++: channels 0-3
// take their transfer functions from the vtkVolumeProperty, channel 4 from
// the mapper. Usage: MultiChannelVolume [out.png]
#include "vtkMultiChannelVolumeMapper.h"

#include "vtkColorTransferFunction.h"
#include "vtkFloatArray.h"
#include "vtkImageData.h"
#include "vtkNew.h"
#include "vtkPNGWriter.h"
#include "vtkPiecewiseFunction.h"
#include "vtkPointData.h"
#include "vtkRenderWindow.h"
#include "vtkRenderer.h"
#include "vtkVolume.h"
#include "vtkVolumeProperty.h"
#include "vtkWindowToImageFilter.h"

#include <cmath>
#include <iostream>

int main(int argc, char* argv[])
{
  constexpr int N = 48;
  constexpr int C = 5;
  // One Gaussian blob per channel: 5 components = 5 channels.
  const double centres[C][3] = { { 14, 14, 24 }, { 34, 14, 24 }, { 14, 34, 24 }, { 34, 34, 24 }, { 24, 24, 24 } };
  const double colours[C][3] = { { 1, 0.3, 0.2 }, { 0.3, 1, 0.3 }, { 0.3, 0.4, 1 }, { 1, 0.9, 0.2 }, { 0.9, 0.3, 1 } };
  vtkNew<vtkImageData> image;
  image->SetDimensions(N, N, N);
  vtkNew<vtkFloatArray> scalars;
  scalars->SetNumberOfComponents(C);
  scalars->SetNumberOfTuples(static_cast<vtkIdType>(N) * N * N);
  for (int z = 0; z < N; ++z)
    for (int y = 0; y < N; ++y)
      for (int x = 0; x < N; ++x)
        for (int c = 0; c < C; ++c)
        {
          const double dx = x - centres[c][0], dy = y - centres[c][1], dz = z - centres[c][2];
          scalars->SetTypedComponent((static_cast<vtkIdType>(z) * N + y) * N + x, c,
            static_cast<float>(std::exp(-(dx * dx + dy * dy + dz * dz) / 60.0)));
        }
  image->GetPointData()->SetScalars(scalars);

  vtkNew<vtkMultiChannelVolumeMapper> mapper;
  mapper->SetInputData(image);
  mapper->SetSamplesPerPixel(16);
  vtkNew<vtkVolumeProperty> property;
  property->IndependentComponentsOn();
  vtkNew<vtkColorTransferFunction> color[C];
  vtkNew<vtkPiecewiseFunction> opacity[C];
  for (int c = 0; c < C; ++c)
  {
    color[c]->AddRGBPoint(0.0, colours[c][0], colours[c][1], colours[c][2]);
    color[c]->AddRGBPoint(1.0, colours[c][0], colours[c][1], colours[c][2]);
    opacity[c]->AddPoint(0.0, 0.0);
    opacity[c]->AddPoint(0.2, 0.0);
    opacity[c]->AddPoint(1.0, 0.5);
    if (c < 4)
    {
      property->SetColor(c, color[c]);
      property->SetScalarOpacity(c, opacity[c]);
      property->SetScalarOpacityUnitDistance(c, 2.0);
    }
    else
    {
      mapper->SetChannelColor(c, color[c]);
      mapper->SetChannelScalarOpacity(c, opacity[c]);
      mapper->SetChannelScalarOpacityUnitDistance(c, 2.0);
    }
  }
  vtkNew<vtkVolume> volume;
  volume->SetMapper(mapper);
  volume->SetProperty(property);
  vtkNew<vtkRenderer> renderer;
  renderer->AddVolume(volume);
  vtkNew<vtkRenderWindow> window;
  window->SetOffScreenRendering(1);
  window->SetSize(300, 300);
  window->AddRenderer(renderer);
  renderer->ResetCamera();
  while (mapper->GetTotalSamples() < 128)
  {
    window->Render();
  }
  std::cout << mapper->GetNumberOfChannels() << " channels, " << mapper->GetTotalSamples() << " spp\n";
  vtkNew<vtkWindowToImageFilter> grab;
  grab->SetInput(window);
  grab->ReadFrontBufferOff();
  vtkNew<vtkPNGWriter> writer;
  writer->SetFileName(argc > 1 ? argv[1] : "MultiChannelVolume.png");
  writer->SetInputConnection(grab->GetOutputPort());
  writer->Write();
  return mapper->GetNumberOfChannels() == C ? 0 : 1;
}
