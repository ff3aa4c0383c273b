"""Bad input gives a clear error and draws nothing (no crash); hard but valid
input (NaN voxels, opacity 1, a single slice) renders; bounds of thin
volumes; parameter clamping."""

import math
import os
import sys

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))

import vtkmodules.vtkRenderingOpenGL2  # noqa: F401 (OpenGL render window)
from vtkmodules.vtkCommonCore import (
    vtkFloatArray,
    vtkIntArray,
    vtkUnsignedCharArray,
)
from vtkmodules.vtkCommonDataModel import vtkImageData, vtkPiecewiseFunction
from vtkmodules.vtkRenderingCore import (
    vtkColorTransferFunction,
    vtkRenderer,
    vtkRenderWindow,
    vtkVolume,
    vtkVolumeProperty,
)

from mcvol import vtkMultiChannelVolumeMapper
from mcvolTesting import Checker, ErrorCatcher, capture_rgba, use_test_backend

t = Checker()


def make_image(dims, components=1, array_type=vtkFloatArray, value=1.0, name="scalars"):
    image = vtkImageData()
    image.SetDimensions(*dims)
    n = dims[0] * dims[1] * dims[2]
    array = array_type()
    array.SetName(name)
    array.SetNumberOfComponents(components)
    array.SetNumberOfTuples(n)
    array.Fill(value)
    image.GetPointData().SetScalars(array)
    return image


mapper = vtkMultiChannelVolumeMapper()
use_test_backend(mapper)
errors = ErrorCatcher(mapper)
prop = vtkVolumeProperty()
for c in range(4):
    ctf = vtkColorTransferFunction()
    ctf.AddRGBPoint(0, 1, 1, 1)
    ctf.AddRGBPoint(1, 1, 1, 1)
    otf = vtkPiecewiseFunction()
    otf.AddPoint(0, 0.0)
    otf.AddPoint(1, 1.0)  # opacity 1: infinite extinction
    prop.SetColor(c, ctf)
    prop.SetScalarOpacity(c, otf)
volume = vtkVolume()
volume.SetMapper(mapper)
volume.SetProperty(prop)
renderer = vtkRenderer()
renderer.SetBackground(0, 0, 0)
renderer.AddVolume(volume)
window = vtkRenderWindow()
window.SetOffScreenRendering(1)
window.SetMultiSamples(0)
window.SetSize(64, 64)
window.AddRenderer(renderer)


def render(image, expect_error):
    """Renders `image`; checks that an error was (or was not) reported and that
    nothing (or something) was drawn. Returns the error messages."""
    errors.clear()
    mapper.SetInputData(image)
    renderer.ResetCamera()
    pixels = capture_rgba(window)
    drawn = pixels[..., :3].max() > 0
    if expect_error:
        t.check(len(errors.errors) > 0, "%s: an error was expected" % expect_error)
        t.check(not drawn, "%s: nothing should be drawn" % expect_error)
        t.check(mapper.GetNumberOfChannels() == 0,
                "%s: no channels should have rendered" % expect_error)
    else:
        t.check(not errors.errors, "unexpected errors: %s" % errors.errors)
    return list(errors.errors)


def expect_message(messages, *words):
    text = " ".join(messages)
    t.check(all(w in text for w in words),
            "error message should mention %s: %r" % (words, text))


# --- Bad input -------------------------------------------------------------
# No input: the renderer culls a volume without bounds, so call Render directly.
errors.clear()
mapper.RemoveAllInputConnections(0)
window.Render()
mapper.Render(renderer, volume)
t.check(errors.errors, "no input: an error was expected")
expect_message(errors.errors, "No input")

image = vtkImageData()
image.SetDimensions(8, 8, 8)
expect_message(render(image, "no scalars"), "no point scalars")

expect_message(render(make_image((8, 8, 8), array_type=vtkIntArray, value=1), "int type"),
               "type int", "unsigned char")

empty = vtkImageData()
empty.SetExtent(0, -1, 0, -1, 0, -1)
empty.GetPointData().SetScalars(vtkFloatArray())
expect_message(render(empty, "empty extent"), "empty extent")

expect_message(render(make_image((4, 4, 4), components=33), "33 channels"), "33 channels")

# Channel 4 has no transfer function in the property (it holds only four).
expect_message(render(make_image((6, 6, 6), components=5), "5 channels, 4 functions"),
               "Channel 4", "SetChannelColor")
# ... and renders once the mapper provides them.
ctf4 = vtkColorTransferFunction()
ctf4.AddRGBPoint(0, 1, 0, 0)
otf4 = vtkPiecewiseFunction()
otf4.AddPoint(0, 0.5)
mapper.SetChannelColor(4, ctf4)
mapper.SetChannelScalarOpacity(4, otf4)
render(make_image((6, 6, 6), components=5), None)
t.check(mapper.GetNumberOfChannels() == 5, "5 channels should render with mapper functions")
mapper.RemoveAllChannelTransferFunctions()

# Named channel arrays: a missing one and a multi-component one are errors.
image = make_image((6, 6, 6), components=1)
mapper.AddChannelArray("nope")
expect_message(render(image, "missing channel array"), "nope")
mapper.RemoveAllChannelArrays()
three = vtkUnsignedCharArray()
three.SetName("three")
three.SetNumberOfComponents(3)
three.SetNumberOfTuples(6 * 6 * 6)
three.Fill(1)
image.GetPointData().AddArray(three)
mapper.AddChannelArray("three")
expect_message(render(image, "3-component channel array"), "three", "one")
mapper.RemoveAllChannelArrays()

# Named single-component arrays of different types as channels.
image = make_image((6, 6, 6), components=1, value=0.5)
for name, cls in [("a", vtkUnsignedCharArray), ("b", vtkFloatArray)]:
    a = cls()
    a.SetName(name)
    a.SetNumberOfTuples(6 * 6 * 6)
    a.Fill(1)
    image.GetPointData().AddArray(a)
    mapper.AddChannelArray(name)
t.check(mapper.GetNumberOfChannelArrays() == 2, "two channel arrays listed")
render(image, None)
t.check(mapper.GetNumberOfChannels() == 2, "two named arrays should give two channels")
mapper.RemoveAllChannelArrays()

# --- Hard but valid input --------------------------------------------------
image = make_image((8, 8, 8), components=2, value=1.0)
scalars = image.GetPointData().GetScalars()
for p in range(0, 8 * 8 * 8, 3):
    scalars.SetComponent(p, 0, math.nan)
scalars.SetComponent(1, 1, math.inf)
render(image, None)
t.check(mapper.GetNumberOfChannels() == 2, "NaN/Inf voxels with opacity 1 should render")

single_slice = make_image((10, 10, 1), value=1.0)
single_slice.SetSpacing(2, 2, 2)
pixels = capture_rgba(window)
render(single_slice, None)
t.check(capture_rgba(window)[..., :3].max() > 0, "a single slice should be visible")

# --- Bounds: one-voxel axes are one spacing thick --------------------------
mapper.SetInputData(single_slice)
b = mapper.GetBounds()
t.check(tuple(b) == (0, 18, 0, 18, -1, 1), "single-slice bounds: %s" % (tuple(b),))
one = make_image((1, 1, 1))
one.SetSpacing(0.5, 1, 2)
one.SetOrigin(10, 20, 30)
mapper.SetInputData(one)
b = mapper.GetBounds()
t.check(tuple(b) == (9.75, 10.25, 19.5, 20.5, 29, 31), "single-voxel bounds: %s" % (tuple(b),))

# --- Parameters ------------------------------------------------------------
mapper.SetSamplesPerPixel(0)
t.check(mapper.GetSamplesPerPixel() == 1, "SamplesPerPixel clamps to 1")
mapper.SetSamplesPerPixel(100000)
t.check(mapper.GetSamplesPerPixel() == 4096, "SamplesPerPixel clamps to 4096")
mapper.SetMacrocellSize(0)
t.check(mapper.GetMacrocellSize() == 1, "MacrocellSize clamps to 1")
mapper.SetMacrocellSize(1000)
t.check(mapper.GetMacrocellSize() == 256, "MacrocellSize clamps to 256")
mtime = mapper.GetMTime()
mapper.SetMacrocellSize(256)
t.check(mapper.GetMTime() == mtime, "setting a parameter to its value must not Modify")
mapper.SetMixWeight(3, 2.5)
t.check(mapper.GetMixWeight(3) == 2.5, "mix weight round trip")
errors.clear()
mapper.SetMixWeight(40, 1.0)
mapper.SetMixWeight(0, -1.0)
t.check(len(errors.errors) == 2, "bad mix weights are errors: %s" % errors.errors)
test_backend = "cuda" if os.environ.get("MCVOL_TEST_BACKEND", "").lower() == "cuda" else "cpu"
t.check(mapper.GetActiveBackendName() == test_backend, "%s backend: %s" % (test_backend, mapper.GetActiveBackendName()))
report = mapper.GetBackendReport()
t.check(report.startswith(test_backend.upper() + " backend"), "%s report: %s" % (test_backend, report))
# Auto and CUDA: with a usable device Auto takes CUDA; without one (CI) Auto
# falls back to the CPU saying why, and CUDA is an error naming the cause.
mapper.SetBackendToAuto()
auto_name = mapper.GetActiveBackendName()
auto_report = mapper.GetBackendReport()
print("Auto backend here:", auto_name, "-", auto_report)
t.check(auto_name in ("cpu", "cuda"), "auto picks a backend: %s" % auto_name)
t.check(("CUDA" in auto_report) if auto_name == "cuda" else auto_report.startswith(("CPU backend (auto: ", "CPU backend (auto, MCVOL_BACKEND=cpu)")),
        "auto report names the choice and the reason: %s" % auto_report)
errors.clear()
mapper.SetBackendToCUDA()
name = mapper.GetActiveBackendName()
print("CUDA backend here:", name, "-", mapper.GetBackendReport())
if auto_name == "cpu":
    t.check(name == "none", "no CUDA device: the CUDA backend is unavailable (%s)" % name)
    t.check(mapper.GetBackendReport().startswith("unavailable: the CUDA backend was requested but "),
            "the report names the cause: %s" % mapper.GetBackendReport())
    expect_message(render(make_image((6, 6, 6), components=1), "CUDA without a device"), "CUDA")
else:
    t.check(name == "cuda", "CUDA backend: %s" % name)
# MCVOL_BACKEND decides what Auto means (the GPU machine's test runs force
# CUDA with it, so a missing device fails instead of falling back quietly);
# an explicit choice ignores it.
saved_env = os.environ.get("MCVOL_BACKEND")
mapper.SetBackendToAuto()
os.environ["MCVOL_BACKEND"] = "cpu"
t.check(mapper.GetActiveBackendName() == "cpu", "MCVOL_BACKEND=cpu: Auto takes the CPU")
t.check("MCVOL_BACKEND=cpu" in mapper.GetBackendReport(), "the report names the variable: %s" % mapper.GetBackendReport())
os.environ["MCVOL_BACKEND"] = "cuda"
t.check(mapper.GetActiveBackendName() == ("none" if auto_name == "cpu" else "cuda"),
        "MCVOL_BACKEND=cuda: Auto demands CUDA (%s)" % mapper.GetActiveBackendName())
t.check("MCVOL_BACKEND=cuda" in mapper.GetBackendReport(), "the report names the variable: %s" % mapper.GetBackendReport())
if auto_name == "cpu":
    expect_message(render(make_image((6, 6, 6), components=1), "MCVOL_BACKEND=cuda without a device"), "CUDA",
                   "MCVOL_BACKEND")
mapper.SetBackendToCPU()
t.check(mapper.GetActiveBackendName() == "cpu", "an explicit CPU choice ignores MCVOL_BACKEND")
if saved_env is None:
    del os.environ["MCVOL_BACKEND"]
else:
    os.environ["MCVOL_BACKEND"] = saved_env

t.finish()
