#!/usr/bin/python3
"""A multi-channel volume in a VTK Python pipeline with mcvol.

Renders the built-in 12-channel weather dataset (channels 4 to 11 take their
transfer functions from the mapper, since vtkVolumeProperty holds four),
refines the progressive image to 64 samples per pixel and writes a PNG.

    PYTHONPATH=build/lib/python3.11/site-packages xvfb-run -a \\
        /usr/bin/python3 Examples/Python/multichannel_volume.py out.png
"""
import sys

import vtkmodules.vtkRenderingOpenGL2  # noqa: F401  (the OpenGL render window)
from vtkmodules.vtkCommonDataModel import vtkPiecewiseFunction
from vtkmodules.vtkIOImage import vtkPNGWriter
from vtkmodules.vtkRenderingCore import (vtkColorTransferFunction, vtkRenderer, vtkRenderWindow, vtkVolume,
                                         vtkVolumeProperty, vtkWindowToImageFilter)

from mcvol import vtkMultiChannelDemoSource, vtkMultiChannelVolumeMapper


def main(out="multichannel_volume.png", total_spp=64):
    source = vtkMultiChannelDemoSource()
    source.SetDataset("weather")            # 12 float32 channels
    source.Update()
    channels = source.GetNumberOfOutputChannels()

    mapper = vtkMultiChannelVolumeMapper()
    mapper.SetInputConnection(source.GetOutputPort())
    mapper.SetChannelBlendModeToDensity()   # Eq. 6/7 of Sahistan et al.
    mapper.SetSamplesPerPixel(8)            # added by every Render()
    mapper.SetSeed(1)

    prop = vtkVolumeProperty()
    prop.IndependentComponentsOn()
    for c in range(channels):
        color, opacity, unit = vtkColorTransferFunction(), vtkPiecewiseFunction(), [0.0]
        source.GetSuggestedTransferFunction(c, color, opacity, unit)
        if c < 4:                           # VTK's way, as with any volume mapper
            prop.SetColor(c, color)
            prop.SetScalarOpacity(c, opacity)
            prop.SetScalarOpacityUnitDistance(c, unit[0])
        else:                               # beyond VTK_MAX_VRCOMP: on the mapper
            mapper.SetChannelColor(c, color)
            mapper.SetChannelScalarOpacity(c, opacity)
            mapper.SetChannelScalarOpacityUnitDistance(c, unit[0])

    volume = vtkVolume()
    volume.SetMapper(mapper)
    volume.SetProperty(prop)
    renderer = vtkRenderer()
    renderer.SetBackground(0.05, 0.05, 0.08)
    renderer.AddVolume(volume)
    window = vtkRenderWindow()
    window.SetOffScreenRendering(1)
    window.SetSize(400, 400)
    window.AddRenderer(renderer)
    renderer.ResetCamera()
    renderer.GetActiveCamera().Elevation(35)
    renderer.ResetCameraClippingRange()

    # Nothing changes between these renders, so the samples add up.
    while mapper.GetTotalSamples() < total_spp:
        window.Render()
    print("%d channels, %d samples per pixel, backend %s"
          % (mapper.GetNumberOfChannels(), mapper.GetTotalSamples(), mapper.GetActiveBackendName()))

    grab = vtkWindowToImageFilter()
    grab.SetInput(window)
    grab.ReadFrontBufferOff()
    writer = vtkPNGWriter()
    writer.SetFileName(out)
    writer.SetInputConnection(grab.GetOutputPort())
    writer.Write()
    return mapper


if __name__ == "__main__":
    main(*sys.argv[1:2])
