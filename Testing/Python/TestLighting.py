"""Lighting through vtkMultiChannelVolumeMapper
(Documentation/user-guide/lighting.md):
ShadeOff is pure emission-absorption whatever the lighting parameters say;
ShadeOn lights the volume with the renderer's lights (the primary collisions,
hence alpha, stay exactly the same for a seed, the colours change); ShadeOn
with no light and no ambient radiance is unlit; a light change restarts the
accumulation."""
import sys

import numpy as np

import vtkmodules.vtkRenderingOpenGL2  # noqa: F401
from vtkmodules.vtkCommonCore import vtkFloatArray
from vtkmodules.vtkCommonDataModel import vtkPiecewiseFunction
from vtkmodules.vtkRenderingCore import (vtkColorTransferFunction, vtkLight, vtkRenderer, vtkRenderWindow, vtkVolume,
                                         vtkVolumeProperty)
from vtkmodules.util.numpy_support import vtk_to_numpy

from mcvol import vtkMultiChannelDemoSource, vtkMultiChannelVolumeMapper
from mcvolTesting import Checker, use_test_backend

t = Checker()
src = vtkMultiChannelDemoSource()
src.SetDataset("cosmology")
src.SetDimensions(32, 32, 32)
src.Update()
prop = vtkVolumeProperty()
prop.IndependentComponentsOn()
for c in range(src.GetNumberOfOutputChannels()):
    ctf, otf, u = vtkColorTransferFunction(), vtkPiecewiseFunction(), [0.0]
    src.GetSuggestedTransferFunction(c, ctf, otf, u)
    prop.SetColor(c, ctf)
    prop.SetScalarOpacity(c, otf)
    prop.SetScalarOpacityUnitDistance(c, u[0])
mapper = vtkMultiChannelVolumeMapper()
mapper.SetInputConnection(src.GetOutputPort())
use_test_backend(mapper)
mapper.SetSamplesPerPixel(8)
mapper.SetSeed(3)
# Lit camera rays use the collision estimator whatever is set; the unlit
# images below use it too, so that alpha compares sample for sample.
mapper.SetEstimatorToCollision()
vol = vtkVolume()
vol.SetMapper(mapper)
vol.SetProperty(prop)
ren = vtkRenderer()
ren.AddVolume(vol)
win = vtkRenderWindow()
win.SetOffScreenRendering(1)
win.SetSize(48, 48)
win.AddRenderer(ren)
ren.ResetCamera()


def image():
    win.Render()
    a = vtkFloatArray()
    mapper.GetAccumulatedImage(a)
    return vtk_to_numpy(a).reshape(-1, 4).copy()


unlit = image()
for c in range(4):
    mapper.SetChannelAlbedo(c, 0.7)
    mapper.SetChannelAnisotropy(c, 0.3)
mapper.GradientShadingOn()
t.check(np.array_equal(image(), unlit), "ShadeOff: lighting parameters must not change the image")

prop.ShadeOn()
lit = image()
t.check(np.isfinite(lit).all(), "lit image finite")
t.check(np.array_equal(lit[:, 3], unlit[:, 3]), "lighting must not change which camera paths collide (alpha)")
t.check(np.abs(lit[:, :3] - unlit[:, :3]).max() > 1e-3, "ShadeOn with a headlight must change the colours")

ren.AutomaticLightCreationOff()
ren.RemoveAllLights()
mapper.SetAmbientRadiance(0, 0, 0)
t.check(np.array_equal(image(), unlit), "ShadeOn without lights or ambient radiance is unlit")

light = vtkLight()
light.SetPosition(1, 1, 1)
light.SetFocalPoint(0, 0, 0)
ren.AddLight(light)
image()
before = mapper.GetTotalSamples()
light.SetIntensity(0.5)
image()
t.check(mapper.GetTotalSamples() == 8 and before == 8, "a light change restarts the accumulation (%d, %d)"
        % (before, mapper.GetTotalSamples()))
win.Render()
t.check(mapper.GetTotalSamples() == 16, "nothing changed: the image refines")
sys.exit(t.finish())
