"""Progressive accumulation: GetTotalSamples grows on a plain re-render and
starts over (at SamplesPerPixel) when, and only when, something that changes
the image changes."""

import os
import sys

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))

import vtkmodules.vtkRenderingOpenGL2  # noqa: F401 (OpenGL render window)
from vtkmodules.vtkCommonCore import vtkFloatArray
from vtkmodules.vtkCommonDataModel import vtkImageData, vtkPiecewiseFunction
from vtkmodules.vtkFiltersSources import vtkSphereSource
from vtkmodules.vtkRenderingCore import (
    vtkActor,
    vtkColorTransferFunction,
    vtkPolyDataMapper,
    vtkRenderer,
    vtkRenderWindow,
    vtkVolume,
    vtkVolumeProperty,
)

from mcvol import vtkMultiChannelVolumeMapper
from mcvolTesting import Checker, use_test_backend

N = 24
image = vtkImageData()
image.SetDimensions(N, N, N)
scalars = vtkFloatArray()
scalars.SetNumberOfComponents(2)
scalars.SetNumberOfTuples(N * N * N)
for p in range(N * N * N):
    x, y, z = p % N, (p // N) % N, p // (N * N)
    scalars.SetTuple2(p, x / (N - 1.0), y / (N - 1.0))
image.GetPointData().SetScalars(scalars)

mapper = vtkMultiChannelVolumeMapper()
mapper.SetInputData(image)
use_test_backend(mapper)

prop = vtkVolumeProperty()
opacities = []
for c in range(2):
    ctf = vtkColorTransferFunction()
    ctf.AddRGBPoint(0, 1, 1 - c, c)
    ctf.AddRGBPoint(1, 1, 1 - c, c)
    otf = vtkPiecewiseFunction()
    otf.AddPoint(0, 0.0)
    otf.AddPoint(1, 0.1)
    prop.SetColor(c, ctf)
    prop.SetScalarOpacity(c, otf)
    opacities.append(otf)

volume = vtkVolume()
volume.SetMapper(mapper)
volume.SetProperty(prop)
renderer = vtkRenderer()
renderer.AddVolume(volume)
window = vtkRenderWindow()
window.SetOffScreenRendering(1)
window.SetMultiSamples(0)
window.SetSize(96, 96)
window.AddRenderer(renderer)
renderer.ResetCamera()
camera = renderer.GetActiveCamera()

t = Checker()


def render_and_expect(samples, why, tf_updates=None):
    window.Render()
    got = mapper.GetTotalSamples()
    t.check(got == samples, "%s: expected %d samples, got %d" % (why, samples, got))
    if tf_updates is not None:
        n = mapper.GetLastTransferFunctionUpdates()
        t.check(n == tf_updates,
                "%s: expected %d transfer-function table(s) rebuilt, got %d" % (why, tf_updates, n))


render_and_expect(1, "first render", tf_updates=2)
render_and_expect(2, "plain re-render", tf_updates=0)
render_and_expect(3, "plain re-render")

opacities[1].AddPoint(0.5, 0.3)
render_and_expect(1, "channel 1 opacity changed", tf_updates=1)
render_and_expect(2, "re-render after the opacity change", tf_updates=0)
# Touched without a value change (ParaView's lookup tables are, on every
# render while they colour something): the tables are the same, so the
# image keeps refining.
opacities[0].Modified()
prop.GetRGBTransferFunction(1).Modified()
render_and_expect(3, "transfer functions touched, values unchanged", tf_updates=0)

camera.Azimuth(10)
render_and_expect(1, "camera moved")
render_and_expect(2, "re-render after the camera move")

mapper.SetSamplesPerPixel(4)
render_and_expect(4, "SamplesPerPixel changed")
render_and_expect(8, "re-render with 4 samples per pixel")
mapper.SetSamplesPerPixel(4)  # same value: no Modified, no reset
render_and_expect(12, "SamplesPerPixel set to its own value")

volume.SetPosition(1, 0, 0)
render_and_expect(4, "volume moved")

scalars.Modified()
render_and_expect(4, "data modified", tf_updates=0)

window.SetSize(100, 90)
render_and_expect(4, "viewport resized")

mapper.ResetAccumulation()
render_and_expect(4, "ResetAccumulation")

prop.SetScalarOpacityUnitDistance(0, 2.0)
render_and_expect(4, "unit distance of channel 0 changed", tf_updates=1)

prop.ShadeOn()
render_and_expect(4, "volume property changed", tf_updates=0)
render_and_expect(8, "re-render after the property change")

mapper.SetChannelBlendModeToMax()
render_and_expect(4, "blend mode changed")

t.check(mapper.GetMinimumSamplesPerVoxel() == 0.0, "no minimum tentative rate by default")
prop.ShadeOff()  # the expected-value estimator serves unlit rays
render_and_expect(4, "unlit again")
mapper.SetMinimumSamplesPerVoxel(2.0)
render_and_expect(4, "minimum samples per voxel changed")
render_and_expect(8, "re-render with a minimum of 2 samples per voxel")

# Opaque geometry in front of part of the volume: the depth buffer changes.
sphere = vtkSphereSource()
sphere.SetCenter(N / 2.0 + 1, N / 2.0, N)
sphere.SetRadius(3)
sphere_mapper = vtkPolyDataMapper()
sphere_mapper.SetInputConnection(sphere.GetOutputPort())
actor = vtkActor()
actor.SetMapper(sphere_mapper)
renderer.AddActor(actor)
render_and_expect(4, "geometry added (depth buffer changed)")
render_and_expect(8, "re-render with the geometry")
actor.SetPosition(0, 2, 0)
render_and_expect(4, "geometry moved")
render_and_expect(8, "re-render after moving the geometry")
render_and_expect(12, "another re-render")

# Time-budgeted progression (SetInteractiveFrameTime): the first batch has
# SamplesPerPixel samples, later ones as many as the measured cost fits in
# the budget (this 96x96 view costs well under 10 ms per sample, so a 0.5 s
# budget gives more than 4); MaximumTotalSamples cuts the last one; the image
# after 48 samples equals the one traced in batches of 4, up to the running
# mean's float rounding.
import numpy as np  # noqa: E402
from vtkmodules.util.numpy_support import vtk_to_numpy  # noqa: E402


def accumulated():
    out = vtkFloatArray()
    mapper.GetAccumulatedImage(out)
    return vtk_to_numpy(out).copy()


renderer.RemoveActor(actor)
mapper.SetMaximumTotalSamples(48)
mapper.ResetAccumulation()
while not mapper.IsConverged():
    window.Render()
fixed = accumulated()
t.check(mapper.GetLastSamplesPerRender() == 4, "fixed batches of SamplesPerPixel (%d)" % mapper.GetLastSamplesPerRender())
mapper.SetInteractiveFrameTime(0.5)
batches = []
while True:  # (IsConverged() notices the change only at the next Render())
    window.Render()
    batches.append(mapper.GetLastSamplesPerRender())
    if mapper.IsConverged() or len(batches) > 48:
        break
t.check(sum(batches) == 48 and mapper.GetTotalSamples() == 48,
        "budgeted batches %s add up to MaximumTotalSamples" % batches)
t.check(max(batches) > 4, "a 0.5 s budget takes more than SamplesPerPixel samples per render (%s)" % batches)
d = float(np.abs(accumulated() - fixed).max())
t.check(d < 1e-5, "48 samples in budgeted batches give the image of 48 in batches of 4 (max |diff| %.2g)" % d)
mapper.SetInteractiveFrameTime(1e-9)
mapper.SetMaximumTotalSamples(0)
window.Render()
t.check(mapper.GetLastSamplesPerRender() == 1, "a budget below one sample's cost still takes 1 (%d)"
        % mapper.GetLastSamplesPerRender())
mapper.SetInteractiveFrameTime(0.0)

t.finish()
