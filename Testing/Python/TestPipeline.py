"""The wrapped mapper in a plain VTK pipeline: two image sources combined into
a two-component image, rendered offscreen. Checks that the image is not
empty, that each channel's colour shows where its data is, and that alpha is
zero where there is no volume."""

import os
import sys

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))

import vtkmodules.vtkRenderingOpenGL2  # noqa: F401 (OpenGL render window)
from vtkmodules.vtkCommonDataModel import vtkPiecewiseFunction
from vtkmodules.vtkImagingCore import vtkImageAppendComponents
from vtkmodules.vtkImagingSources import vtkImageEllipsoidSource
from vtkmodules.vtkRenderingCore import (
    vtkColorTransferFunction,
    vtkRenderer,
    vtkRenderWindow,
    vtkVolume,
    vtkVolumeProperty,
)

from mcvol import vtkMultiChannelVolumeMapper
from mcvolTesting import Checker, capture_rgba, world_to_pixel, use_test_backend

extent = (0, 63, 0, 31, 0, 31)
centres = [(16.0, 16.0, 16.0), (48.0, 16.0, 16.0)]
sources = []
for centre in centres:
    source = vtkImageEllipsoidSource()
    source.SetWholeExtent(*extent)
    source.SetCenter(*centre)
    source.SetRadius(10, 10, 10)
    source.SetInValue(200)
    source.SetOutValue(0)
    source.SetOutputScalarTypeToUnsignedChar()
    sources.append(source)
append = vtkImageAppendComponents()
for source in sources:
    append.AddInputConnection(source.GetOutputPort())

mapper = vtkMultiChannelVolumeMapper()
mapper.SetInputConnection(append.GetOutputPort())
use_test_backend(mapper)
mapper.SetSamplesPerPixel(4)

prop = vtkVolumeProperty()
prop.IndependentComponentsOn()
colours = [(1.0, 0.0, 0.0), (0.0, 1.0, 0.0)]
for c, colour in enumerate(colours):
    ctf = vtkColorTransferFunction()
    ctf.AddRGBPoint(0, *colour)
    ctf.AddRGBPoint(200, *colour)
    otf = vtkPiecewiseFunction()
    otf.AddPoint(0, 0.0)
    otf.AddPoint(200, 0.5)
    prop.SetColor(c, ctf)
    prop.SetScalarOpacity(c, otf)

volume = vtkVolume()
volume.SetMapper(mapper)
volume.SetProperty(prop)

renderer = vtkRenderer()
renderer.SetBackground(0, 0, 0)
renderer.SetBackgroundAlpha(0.0)
renderer.AddVolume(volume)
window = vtkRenderWindow()
window.SetOffScreenRendering(1)
window.SetMultiSamples(0)
window.SetAlphaBitPlanes(1)
window.SetSize(256, 160)
window.AddRenderer(renderer)
renderer.ResetCamera()

for _ in range(3):
    window.Render()
pixels = capture_rgba(window)

t = Checker()
t.check(mapper.GetNumberOfChannels() == 2,
        "2 channels expected, got %d" % mapper.GetNumberOfChannels())
t.check(mapper.GetTotalSamples() == 16,
        "16 samples per pixel expected, got %d" % mapper.GetTotalSamples())
t.check(pixels[..., :3].max() > 100, "the image is empty")

# Channel 0 (red) and channel 1 (green) where their spheres project.
for c, centre in enumerate(centres):
    x, y = world_to_pixel(renderer, centre)
    r, g, b, a = [int(v) for v in pixels[y, x]]
    print("channel %d centre pixel (%d, %d): rgba %d %d %d %d" % (c, x, y, r, g, b, a))
    mine, other = (r, g) if c == 0 else (g, r)
    t.check(mine > 150 and other < 20 and b < 20,
            "channel %d's sphere should show its colour alone: %s" % (c, (r, g, b)))
    t.check(a > 150, "alpha over channel %d's sphere should be high: %d" % (c, a))

# No volume between the spheres' outlines and in the corners: background,
# alpha 0.
for x, y in [(2, 2), (253, 157), (2, 157)]:
    r, g, b, a = [int(v) for v in pixels[y, x]]
    t.check((r, g, b, a) == (0, 0, 0, 0),
            "pixel (%d, %d) outside the volume should be empty: %s" % (x, y, (r, g, b, a)))
xm, ym = world_to_pixel(renderer, (32.0, 16.0, 16.0))
r, g, b, a = [int(v) for v in pixels[ym, xm]]
t.check(a < 10, "between the spheres alpha should be ~0, got %d" % a)

t.finish()
