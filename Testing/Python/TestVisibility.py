"""Visibility optimization through the VTK API (Lerzer and Dachsbacher): a
green target slab behind a red occluder slab. With importance on the target
its share of the image rises; off, or with no importance, the image is the
unoptimized one bit for bit; a label channel of zero opacity can carry the
importance; the segment lists' memory is reported."""

import os
import sys

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))

import vtkmodules.vtkRenderingOpenGL2  # noqa: F401 (OpenGL render window)
from vtkmodules.vtkCommonCore import vtkFloatArray
from vtkmodules.vtkCommonDataModel import vtkImageData, vtkPiecewiseFunction
from vtkmodules.vtkRenderingCore import (
    vtkColorTransferFunction,
    vtkRenderer,
    vtkRenderWindow,
    vtkVolume,
)

from mcvol import vtkMultiChannelVolumeMapper
from mcvolTesting import Checker, ErrorCatcher

t = Checker()
NX, NY, NZ = 16, 16, 32


def make_image():
    image = vtkImageData()
    image.SetDimensions(NX, NY, NZ)
    arrays = {}
    for name in ("occluder", "target", "label"):
        a = vtkFloatArray()
        a.SetName(name)
        a.SetNumberOfTuples(NX * NY * NZ)
        arrays[name] = a
        image.GetPointData().AddArray(a)
    for k in range(NZ):
        front = k >= NZ // 2  # the camera looks down -z from above
        for j in range(NY):
            for i in range(NX):
                idx = (k * NY + j) * NX + i
                arrays["occluder"].SetValue(idx, 1.0 if front else 0.0)
                arrays["target"].SetValue(idx, 0.0 if front else 1.0)
                arrays["label"].SetValue(idx, 0.0 if front else 1.0)
    return image


def ramp(top):
    f = vtkPiecewiseFunction()
    f.AddPoint(0.0, 0.0)
    f.AddPoint(1.0, top)
    return f


def colour(r, g, b):
    c = vtkColorTransferFunction()
    c.AddRGBPoint(0.0, r, g, b)
    c.AddRGBPoint(1.0, r, g, b)
    return c


def step_importance():
    f = vtkPiecewiseFunction()
    f.AddPoint(0.0, 0.0)
    f.AddPoint(0.49, 0.0)
    f.AddPoint(0.51, 1.0)
    f.AddPoint(1.0, 1.0)
    return f


image = make_image()


def render(setup, spp=64):
    """Renders the scene after setup(mapper); returns (rgba list, mapper)."""
    mapper = vtkMultiChannelVolumeMapper()
    mapper.SetInputData(image)
    for name in ("occluder", "target", "label"):
        mapper.AddChannelArray(name)
    mapper.SetChannelColor(0, colour(1, 0, 0))
    mapper.SetChannelScalarOpacity(0, ramp(0.3))
    mapper.SetChannelColor(1, colour(0, 1, 0))
    mapper.SetChannelScalarOpacity(1, ramp(0.3))
    mapper.SetChannelColor(2, colour(0, 0, 1))
    mapper.SetChannelScalarOpacity(2, ramp(0.0))  # the label is invisible
    mapper.SetSamplesPerPixel(spp)
    mapper.SetSeed(4)
    # Optimized renders use the collision estimator whatever is set; the
    # unoptimized ones here too, so that p -> infinity compares like with like.
    mapper.SetEstimatorToCollision()
    setup(mapper)
    errors = ErrorCatcher(mapper)
    volume = vtkVolume()
    volume.SetMapper(mapper)
    ren = vtkRenderer()
    ren.AddVolume(volume)
    win = vtkRenderWindow()
    win.SetOffScreenRendering(1)
    win.SetSize(48, 48)
    win.AddRenderer(ren)
    cam = ren.GetActiveCamera()
    cam.SetFocalPoint(7.5, 7.5, 15.5)
    cam.SetPosition(7.5, 7.5, 80.0)
    cam.SetViewUp(0, 1, 0)
    cam.ParallelProjectionOn()
    cam.SetParallelScale(7.0)
    ren.ResetCameraClippingRange()
    for _ in range(4):
        win.Render()
    t.check(not errors.errors, "no errors: %s" % errors.errors)
    out = vtkFloatArray()
    mapper.GetAccumulatedImage(out)
    values = [out.GetValue(i) for i in range(out.GetNumberOfValues())]
    return values, mapper


def green_share(values):
    r = sum(values[0::4])
    g = sum(values[1::4])
    return g / (r + g)


plain, m0 = render(lambda m: None)
t.check(m0.GetImportanceMemory() == 0, "no segment lists without the optimization")


def off_with_importance(m):
    m.SetChannelImportance(1, step_importance())


off, _ = render(off_with_importance)
t.check(off == plain, "optimization off with an importance function: the same image")


def on_without_importance(m):
    m.VisibilityOptimizationOn()


on_none, _ = render(on_without_importance)
t.check(on_none == plain, "optimization on without importance: the same image")


def on_target(m):
    m.VisibilityOptimizationOn()
    m.SetChannelImportance(1, step_importance())


optimized, m1 = render(on_target)
share0, share1 = green_share(plain), green_share(optimized)
print("green share: unoptimized %.4f, optimized %.4f (%.2fx)" % (share0, share1, share1 / share0))
t.check(share1 > 3.0 * share0, "the target shows through: share %.4f -> %.4f" % (share0, share1))
t.check(m1.GetImportanceMemory() >= 48 * 48 * 16 * 16, "segment memory reported: %g" % m1.GetImportanceMemory())
t.check(m1.GetImportanceOverflows() == 0, "no list overflowed")
t.check("VisibilityOptimization: 1" in str(m1), "PrintSelf shows the setting")


def on_label(m):
    m.VisibilityOptimizationOn()
    m.SetChannelImportance(2, step_importance())  # the invisible label channel


labelled, _ = render(on_label)
share2 = green_share(labelled)
t.check(share2 > 3.0 * share0, "a zero-opacity label channel carries importance: %.4f -> %.4f" % (share0, share2))


def p_huge(m):
    on_target(m)
    m.SetDeviationWeight(1e9)


huge, _ = render(p_huge)
diff = max(abs(a - b) for a, b in zip(huge, plain))
t.check(diff < 2.0 / 256.0, "p -> infinity gives the unoptimized image (max diff %g)" % diff)

# The paper's defaults (Lerzer and Dachsbacher, Sec. 6), read before
# anything sets them.
m = vtkMultiChannelVolumeMapper()
t.check(m.GetDeviationWeight() == 1.0, "default p = 1 (got %g)" % m.GetDeviationWeight())
t.check(m.GetOcclusionWeight() == 70.0, "default q = 70 (got %g)" % m.GetOcclusionWeight())
t.check(m.GetClutterWeight() == 30.0, "default r = 30 (got %g)" % m.GetClutterWeight())
t.check(m.GetImportanceEmphasis() == 1.0, "default lambda = 1 (got %g)" % m.GetImportanceEmphasis())
t.check(m.GetLightRayImportanceSamples() == 200,
        "default 200 samples per light ray (got %d)" % m.GetLightRayImportanceSamples())
t.check(m.GetOptimizeLightRays(), "light rays optimized by default")

m = vtkMultiChannelVolumeMapper()
m.SetOcclusionWeight(-5)
t.check(m.GetOcclusionWeight() == 0.0, "weights are clamped")
t.check(not m.GetVisibilityOptimization(), "off by default")
t.check(m.GetDeviationWeight() == 1.0 and m.GetOcclusionWeight() == 0.0 and m.GetClutterWeight() == 30.0,
        "paper defaults p = 1, r = 30")

t.finish()
