"""VTK settings the mappers do not use (cropping, clipping planes,
vtkVolumeMapper::SetBlendMode, gradient opacity, 2D transfer functions) are
named in a warning when a render finds them set, once per change, never
silently: GetIgnoredSettings() lists them, and the image is the one rendered
without them. A gradient opacity that changes nothing (constant 1, or
disabled) is not reported."""

import os
import sys

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))

import numpy as np
import vtkmodules.vtkRenderingOpenGL2  # noqa: F401 (OpenGL render window)
from vtkmodules.util.numpy_support import numpy_to_vtk
from vtkmodules.vtkCommonDataModel import vtkImageData, vtkPiecewiseFunction, vtkPlane
from vtkmodules.vtkRenderingCore import vtkColorTransferFunction, vtkVolumeProperty

from mcvol import vtkMultiChannelRayMarchMapper, vtkMultiChannelVolumeMapper
from mcvolTesting import Checker, ErrorCatcher, capture_rgba, offscreen_view, use_test_backend

t = Checker()

n = 16
z, y, x = np.mgrid[0:n, 0:n, 0:n].astype(np.float32) / (n - 1)
channels = [np.sin(3 * x) * np.cos(2 * y), x * y + 0.2 * z, np.exp(-((x - 0.5) ** 2 + (z - 0.5) ** 2) * 8)]
image = vtkImageData()
image.SetDimensions(n, n, n)
array = numpy_to_vtk(np.stack([c.reshape(-1) for c in channels], axis=1).astype(np.float32), deep=True)
array.SetName("channels")
image.GetPointData().SetScalars(array)

prop = vtkVolumeProperty()
for c, rgb in enumerate([(1, 0.2, 0.1), (0.1, 1, 0.2), (0.2, 0.3, 1)]):
    ctf = vtkColorTransferFunction()
    ctf.AddRGBPoint(0, *rgb)
    ctf.AddRGBPoint(1, *rgb)
    otf = vtkPiecewiseFunction()
    otf.AddPoint(0, 0.0)
    otf.AddPoint(1, 0.4)
    prop.SetColor(c, ctf)
    prop.SetScalarOpacity(c, otf)


def scene(mapper):
    use_test_backend(mapper)
    mapper.SetInputData(image)
    return offscreen_view(mapper, prop, (48, 48))


mapper = vtkMultiChannelVolumeMapper()
window = scene(mapper)
caught = ErrorCatcher(mapper)


def first_render():
    """The first render of a restarted image (the same samples every time)."""
    mapper.Modified()
    caught.clear()
    return capture_rgba(window)


reference = first_render()
t.check(not caught.warnings and not caught.errors, "plain scene: no warning (%r)" % caught.warnings)
t.check(mapper.GetIgnoredSettings() == "", "plain scene: nothing ignored")
t.check(reference[..., :3].max() > 0, "the scene draws something")


def expect_ignored(what, words):
    """A render with the setting on: one warning naming it, the settings list
    naming it, the reference image; a second render warns no more."""
    img = first_render()
    text = " ".join(caught.warnings)
    t.check(len(caught.warnings) == 1 and all(w in text for w in words),
            "%s: one warning naming %s, got %r" % (what, words, caught.warnings))
    t.check(all(w in mapper.GetIgnoredSettings() for w in words),
            "%s: GetIgnoredSettings names it: %r" % (what, mapper.GetIgnoredSettings()))
    t.check(np.array_equal(img, reference), "%s: the image is the one without it" % what)
    caught.clear()
    capture_rgba(window)
    t.check(not caught.warnings, "%s: warned once, not at every frame (%r)" % (what, caught.warnings))


def expect_clean(what):
    img = first_render()
    t.check(not caught.warnings, "%s: no warning (%r)" % (what, caught.warnings))
    t.check(mapper.GetIgnoredSettings() == "", "%s: nothing ignored (%r)" % (what, mapper.GetIgnoredSettings()))
    t.check(np.array_equal(img, reference), "%s: the reference image" % what)


mapper.CroppingOn()
expect_ignored("cropping", ["cropping"])
mapper.CroppingOff()
expect_clean("cropping off")

plane = vtkPlane()
plane.SetOrigin(0.5 * (n - 1), 0, 0)
plane.SetNormal(1, 0, 0)
mapper.AddClippingPlane(plane)
expect_ignored("a clipping plane", ["clipping planes"])
mapper.RemoveAllClippingPlanes()
expect_clean("no clipping planes")

mapper.SetBlendModeToMaximumIntensity()
expect_ignored("vtkVolumeMapper::SetBlendMode", ["SetBlendMode", "SetChannelBlendMode"])
mapper.SetBlendModeToComposite()
expect_clean("composite blend mode")

gradient = vtkPiecewiseFunction()
gradient.AddPoint(0, 0.0)
gradient.AddPoint(2, 1.0)
prop.SetGradientOpacity(1, gradient)
expect_ignored("a gradient opacity", ["gradient opacity of component 1"])
prop.DisableGradientOpacityOn(1)
expect_clean("the gradient opacity disabled")
prop.DisableGradientOpacityOff(1)
constant = vtkPiecewiseFunction()
constant.AddPoint(0, 1.0)
constant.AddPoint(255, 1.0)
prop.SetGradientOpacity(1, constant)
expect_clean("a constant gradient opacity")
prop.GetGradientOpacity(2)  # creates VTK's default (constant 1)
expect_clean("VTK's default gradient opacity")

prop.SetTransferFunctionModeTo2D()
expect_ignored("2D transfer functions", ["2D transfer functions"])
prop.SetTransferFunctionModeTo1D()
expect_clean("1D transfer functions")

# Two at once: both named in one warning.
mapper.CroppingOn()
mapper.AddClippingPlane(plane)
expect_ignored("cropping and a clipping plane", ["cropping", "clipping planes"])
mapper.CroppingOff()
mapper.RemoveAllClippingPlanes()
expect_clean("both off")

# Cached shadows where they do not apply, under post-render composite
# blending (lit: its shadow rays are tracked): named, the image unchanged.
# On the CPU: the CUDA backend refuses lit composite blending altogether.
mapper.SetBackendToCPU()
prop.ShadeOn()
mapper.SetChannelBlendMode(mapper.MC_COMPOSITE_BLEND)
reference = first_render()
mapper.SetShadowMode(mapper.CACHED_SHADOWS)
expect_ignored("cached shadows under composite blending", ["cached shadows", "composite"])
mapper.SetShadowMode(mapper.RATIO_TRACKING_SHADOWS)
expect_clean("ratio-tracking shadows under composite blending")
mapper.SetChannelBlendMode(mapper.MC_DENSITY_BLEND)
prop.ShadeOff()
use_test_backend(mapper)

# The ray-marching reference takes the same stages: the same warning.
march = vtkMultiChannelRayMarchMapper()
march_window = scene(march)
march_caught = ErrorCatcher(march)
march.CroppingOn()
capture_rgba(march_window)
t.check(any("cropping" in w for w in march_caught.warnings),
        "ray march: cropping warned (%r)" % march_caught.warnings)
t.check("cropping" in march.GetIgnoredSettings(), "ray march: GetIgnoredSettings names cropping")
t.check(not march_caught.errors, "ray march: no errors (%r)" % march_caught.errors)

t.finish()
