"""What a user saves is what was accumulated: a render in which nothing
changed adds samples and never restarts the image, whichever way VTK
renders it again. Driven as users save frames: vtkWindowToImageFilter with
its defaults (it renders the window again), vtkTesting's regression test
(vtkRegressionTestImage in C++), a window resized to the size it has, and the
Python example (Examples/Python/multichannel_volume.py). The saved image is
compared with the window's accumulated image (read without a new render)."""

import os
import sys
import tempfile

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, os.path.join(os.path.dirname(os.path.dirname(HERE)), "Examples", "Python"))

import numpy as np

import vtkmodules.vtkRenderingOpenGL2  # noqa: F401 (OpenGL render window)
from vtkmodules.util.numpy_support import vtk_to_numpy
from vtkmodules.vtkCommonDataModel import vtkPiecewiseFunction
from vtkmodules.vtkIOImage import vtkPNGWriter
from vtkmodules.vtkRenderingCore import vtkColorTransferFunction, vtkVolumeProperty, vtkWindowToImageFilter
from vtkmodules.vtkTestingRendering import vtkTesting

from mcvol import vtkMultiChannelDemoSource, vtkMultiChannelVolumeMapper
from mcvolTesting import Checker, capture_rgba, offscreen_view, use_test_backend

t = Checker()
SPP = 8


def scene():
    source = vtkMultiChannelDemoSource()
    source.SetDataset("figure3")
    mapper = vtkMultiChannelVolumeMapper()
    mapper.SetInputConnection(source.GetOutputPort())
    use_test_backend(mapper)
    mapper.SetSamplesPerPixel(SPP)
    mapper.SetSeed(3)
    prop = vtkVolumeProperty()
    for c in range(3):
        ctf = vtkColorTransferFunction()
        ctf.AddRGBPoint(0, 1, 1, 1)
        ctf.AddRGBPoint(1, 1 if c == 0 else 0.2, 1 if c == 1 else 0.2, 1 if c == 2 else 0.2)
        otf = vtkPiecewiseFunction()
        otf.AddPoint(0, 0.0)
        otf.AddPoint(1, 0.9)
        prop.SetColor(c, ctf)
        prop.SetScalarOpacity(c, otf)
    window = offscreen_view(mapper, prop, (96, 80))
    for _ in range(8):
        window.Render()
    return mapper, window


def grab(window, **options):
    g = vtkWindowToImageFilter()
    g.SetInput(window)
    g.SetInputBufferTypeToRGBA()
    for name, value in options.items():
        getattr(g, name)(value)
    g.Update()
    image = g.GetOutput()
    w, h, _ = image.GetDimensions()
    return vtk_to_numpy(image.GetPointData().GetScalars()).reshape(h, w, 4).astype(np.int32)


def window_image(window):
    return grab(window, SetShouldRerender=0, SetReadFrontBuffer=0)


# -- vtkWindowToImageFilter with its defaults: it renders the window again.
mapper, window = scene()
before = mapper.GetTotalSamples()
shown = window_image(window)
saved = grab(window)
after = mapper.GetTotalSamples()
t.check(before == 8 * SPP, "eight renders accumulate %d samples (%d)" % (8 * SPP, before))
t.check(after == before + SPP, "vtkWindowToImageFilter's render adds a batch: %d -> %d samples" % (before, after))
window.Render()
t.check(mapper.GetTotalSamples() == after + SPP,
        "the render after it adds another (%d -> %d)" % (after, mapper.GetTotalSamples()))
# 72 against 64 samples of the same image: within 2 8-bit levels (RMS) over
# the volume (0.6 measured); a restarted 8-sample image is 3.8 away.
inside = shown[..., :3].sum(axis=2) > 30
diff = np.sqrt(((saved[..., :3] - shown[..., :3])[inside] ** 2).mean())
print("saved against shown: RMS difference %.2f of 255 over %d pixels of the volume" % (diff, inside.sum()))
t.check(inside.mean() > 0.1, "the accumulated image shows the volume (%.2f of the pixels)" % inside.mean())
t.check(diff < 2.0, "the saved image is the accumulated one (RMS difference %.2f of 255)" % diff)

# -- vtkTesting (vtkRegressionTestImage) against a baseline of the window's
# image: it renders again, and passes.
work = tempfile.mkdtemp(prefix="mcvol-saved-")
baseline = os.path.join(work, "baseline.png")
w, h = window.GetSize()
from vtkmodules.util.numpy_support import numpy_to_vtk  # noqa: E402
from vtkmodules.vtkCommonDataModel import vtkImageData  # noqa: E402

current = window_image(window)
img = vtkImageData()
img.SetDimensions(w, h, 1)
img.GetPointData().SetScalars(numpy_to_vtk(current[..., :3].reshape(-1, 3).astype(np.uint8), deep=True))
writer = vtkPNGWriter()
writer.SetFileName(baseline)
writer.SetInputData(img)
writer.Write()
testing = vtkTesting()
for arg in ("-V", baseline, "-T", work):
    testing.AddArgument(arg)
testing.SetRenderWindow(window)
before = mapper.GetTotalSamples()
result = testing.RegressionTest(15)
t.check(result == vtkTesting.PASSED, "vtkTesting's regression test passes against the accumulated image")
t.check(mapper.GetTotalSamples() > before,
        "vtkTesting's render adds to the samples (%d -> %d)" % (before, mapper.GetTotalSamples()))

# -- A window resized to the size it has.
before = mapper.GetTotalSamples()
window.SetSize(*window.GetSize())
window.Render()
t.check(mapper.GetTotalSamples() == before + SPP,
        "a resize to the same size keeps the samples (%d -> %d)" % (before, mapper.GetTotalSamples()))
# ... and a real resize restarts.
window.SetSize(w + 2, h)
window.Render()
t.check(mapper.GetTotalSamples() == SPP, "a resize restarts the image (%d)" % mapper.GetTotalSamples())

# -- A camera moved by a visible amount still restarts; one moved by less
# than a thousandth of a pixel does not.
camera = window.GetRenderers().GetFirstRenderer().GetActiveCamera()
for _ in range(3):
    window.Render()
before = mapper.GetTotalSamples()
camera.SetViewAngle(camera.GetViewAngle() * (1 + 1e-8))
window.Render()
t.check(mapper.GetTotalSamples() == before + SPP,
        "a view angle changed by 1e-8 (no visible ray moves) keeps the image (%d -> %d)"
        % (before, mapper.GetTotalSamples()))
camera.Azimuth(0.05)
window.Render()
t.check(mapper.GetTotalSamples() == SPP,
        "an azimuth of 0.05 degrees restarts the image (%d)" % mapper.GetTotalSamples())

# -- The Python example writes its PNG the standard way (re-rendering).
import multichannel_volume  # noqa: E402

out = os.path.join(work, "example.png")
example_mapper = multichannel_volume.main(out, total_spp=32)
t.check(os.path.exists(out), "the example writes its image")
t.check(example_mapper.GetTotalSamples() >= 32,
        "the example's saved image has its 32 samples or more (%d)" % example_mapper.GetTotalSamples())

import shutil  # noqa: E402

shutil.rmtree(work, ignore_errors=True)
t.finish()
