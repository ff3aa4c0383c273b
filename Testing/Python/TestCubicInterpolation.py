"""Cubic B-spline interpolation through the VTK mappers
(Documentation/user-guide/channels-and-blending.md):
SetInterpolationType / SetInterpolationTypeToCubic / ...ToProperty.

- Default -1 follows the vtkVolumeProperty; PrintSelf names the setting.
- The ray marcher (deterministic) draws a different image with cubic than
  with linear; the mapper's cubic equals a property that says cubic (VTK
  9.2's SetInterpolationTypeToCubic); the mapper's nearest overrides a linear
  property; ToProperty returns to the property's linear image exactly.
- The opacity compositing model with cubic: a clear error, nothing drawn;
  the extinction model renders again.
- The Monte Carlo mapper renders cubic, and its mean alpha agrees with the
  cubic march within 0.02 (64 samples per pixel; the difference of the
  image means, not of pixels).
"""
import os
import sys

import numpy as np

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))

import vtkmodules.vtkRenderingOpenGL2  # noqa: F401 (OpenGL render window)
from vtkmodules.vtkCommonCore import vtkFloatArray
from vtkmodules.vtkCommonDataModel import vtkImageData, vtkPiecewiseFunction
from vtkmodules.vtkRenderingCore import (vtkColorTransferFunction, vtkRenderer, vtkRenderWindow, vtkVolume,
                                         vtkVolumeProperty)
from vtkmodules.util.numpy_support import numpy_to_vtk, vtk_to_numpy

from mcvol import vtkMultiChannelRayMarchMapper, vtkMultiChannelVolumeMapper
from mcvolTesting import Checker, ErrorCatcher, capture_rgba, use_test_backend

t = Checker()

# Two channels, a blob and a one-voxel-thick sheet (where cubic and linear
# differ most), 16^3 float32.
n = 16
z, y, x = np.mgrid[0:n, 0:n, 0:n].astype(np.float32)
blob = np.exp(-((x - 6) ** 2 + (y - 8) ** 2 + (z - 7) ** 2) / 18.0)
sheet = (np.abs(x - 9) < 0.5).astype(np.float32)
data = np.stack([blob, sheet], axis=-1).reshape(-1, 2)
image = vtkImageData()
image.SetDimensions(n, n, n)
array = numpy_to_vtk(np.ascontiguousarray(data), deep=1)
array.SetName("channels")
image.GetPointData().SetScalars(array)

prop = vtkVolumeProperty()
prop.IndependentComponentsOn()
prop.SetInterpolationTypeToLinear()
for c, rgb in enumerate([(1.0, 0.4, 0.1), (0.2, 0.5, 1.0)]):
    ctf = vtkColorTransferFunction()
    ctf.AddRGBPoint(0, *rgb)
    ctf.AddRGBPoint(1, *rgb)
    otf = vtkPiecewiseFunction()
    otf.AddPoint(0, 0.0)
    otf.AddPoint(0.1, 0.0)
    otf.AddPoint(1, 0.6)
    prop.SetColor(c, ctf)
    prop.SetScalarOpacity(c, otf)


def setup(mapper):
    mapper.SetInputData(image)
    volume = vtkVolume()
    volume.SetMapper(mapper)
    volume.SetProperty(prop)
    renderer = vtkRenderer()
    renderer.SetBackground(0, 0, 0)
    renderer.AddVolume(volume)
    window = vtkRenderWindow()
    window.SetOffScreenRendering(1)
    window.SetMultiSamples(0)
    window.SetSize(40, 40)
    window.AddRenderer(renderer)
    renderer.ResetCamera()
    renderer.GetActiveCamera().Azimuth(30)
    renderer.GetActiveCamera().Elevation(20)
    return window


march = vtkMultiChannelRayMarchMapper()
march_errors = ErrorCatcher(march)
march.SetBackendToCPU()
march.SetStepSize(0.125)
march_window = setup(march)


def render(mapper, window, errors):
    """Renders; returns the accumulated float image (P x 4), or None when
    nothing was drawn."""
    errors.clear()
    if capture_rgba(window)[..., :3].max() == 0:
        return None
    a = vtkFloatArray()
    mapper.GetAccumulatedImage(a)
    return vtk_to_numpy(a).reshape(-1, 4).astype(np.float64)


t.check(march.GetInterpolationType() == -1, "default InterpolationType is -1: %d" % march.GetInterpolationType())
t.check("InterpolationType: Property" in str(march), "PrintSelf says Property")
linear = render(march, march_window, march_errors)
t.check(linear is not None and not march_errors.errors, "linear renders: %s" % march_errors.errors)

march.SetInterpolationTypeToCubic()
t.check(march.GetInterpolationType() == 2, "cubic is VTK_CUBIC_INTERPOLATION (2)")
t.check("InterpolationType: Cubic" in str(march), "PrintSelf says Cubic")
cubic = render(march, march_window, march_errors)
t.check(cubic is not None and not march_errors.errors, "cubic renders: %s" % march_errors.errors)
if linear is not None and cubic is not None:
    d = np.abs(cubic - linear).max()
    print("max |cubic - linear| = %.3g, mean alpha linear %.4f cubic %.4f" % (d, linear[:, 3].mean(),
                                                                             cubic[:, 3].mean()))
    t.check(d > 0.01, "cubic and linear images differ: %.3g" % d)
    t.check(np.all(np.isfinite(cubic)), "cubic image finite")

# The property's cubic (VTK 9.2 keeps it) gives the same image.
if hasattr(prop, "SetInterpolationTypeToCubic"):
    march.SetInterpolationTypeToProperty()
    prop.SetInterpolationTypeToCubic()
    if prop.GetInterpolationType() == 2:
        via_property = render(march, march_window, march_errors)
        t.check(via_property is not None and cubic is not None and np.array_equal(via_property, cubic),
                "a cubic property draws the mapper's cubic image")
    else:
        print("this VTK clamps the property's interpolation type to linear")
    prop.SetInterpolationTypeToLinear()

# The mapper's nearest overrides a linear property; ToProperty is linear again.
march.SetInterpolationTypeToNearest()
nearest = render(march, march_window, march_errors)
prop.SetInterpolationTypeToNearest()
march.SetInterpolationTypeToProperty()
nearest_property = render(march, march_window, march_errors)
t.check(nearest is not None and nearest_property is not None and np.array_equal(nearest, nearest_property),
        "the mapper's nearest equals the property's nearest")
prop.SetInterpolationTypeToLinear()
again = render(march, march_window, march_errors)
t.check(again is not None and linear is not None and np.array_equal(again, linear),
        "ToProperty with a linear property draws the linear image again")

# The opacity model has no cubic variant.
march.SetInterpolationTypeToCubic()
march.SetCompositingModelToOpacity()
refused = render(march, march_window, march_errors)
text = " ".join(march_errors.errors)
t.check(refused is None, "opacity model with cubic: nothing drawn")
t.check("cubic" in text and "opacity" in text, "the error names cubic and the opacity model: %r" % text)
march.SetCompositingModelToExtinction()
back = render(march, march_window, march_errors)
t.check(back is not None and cubic is not None and np.array_equal(back, cubic), "extinction model renders again")

# Monte Carlo with cubic interpolation.
mc = vtkMultiChannelVolumeMapper()
use_test_backend(mc)
mc_errors = ErrorCatcher(mc)
mc.SetPixelJitter(False)  # pixel centres, as the march
mc.SetSamplesPerPixel(16)
mc.SetInterpolationTypeToCubic()
mc_window = setup(mc)
img = None
for _ in range(4):
    img = render(mc, mc_window, mc_errors)
t.check(img is not None and not mc_errors.errors, "Monte Carlo cubic renders: %s" % mc_errors.errors)
if img is not None and cubic is not None:
    print("Monte Carlo cubic: %d spp, mean alpha %.4f (march %.4f)" % (mc.GetTotalSamples(), img[:, 3].mean(),
                                                                      cubic[:, 3].mean()))
    t.check(np.all(np.isfinite(img)), "Monte Carlo cubic image finite")
    t.check(abs(img[:, 3].mean() - cubic[:, 3].mean()) < 0.02, "Monte Carlo cubic mean alpha near the cubic march")

t.finish()
