"""The CUDA backend inside a VTK pipeline: what stays on the GPU
(Documentation/user-guide/backends.md).

- 100 progressive renders upload each channel once (GetNumberOfDataUploads).
- Camera moves, transfer-function edits and ParaView-style per-frame shallow
  copies of the input (a new vtkImageData sharing the arrays) upload nothing;
  a change of the values uploads again.
- Two mappers on one GPU, in two render windows, keep their own copies: each
  uploads once, rendering them in turn uploads nothing more, and with the
  same seed they give the same image.
- ReleaseGraphicsResources gives the device memory back: the mapper reports
  0 bytes, and nvidia-smi's figure for this process falls by at least 90 % of
  the bytes the mapper reported (when nvidia-smi is there).

Needs a CUDA device: without one the test is skipped (exit status 125).
"""
import os
import shutil
import subprocess
import sys

import numpy as np

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))

import vtkmodules.vtkRenderingOpenGL2  # noqa: F401 (OpenGL render window)
from vtkmodules.vtkCommonCore import vtkFloatArray
from vtkmodules.vtkCommonDataModel import vtkImageData, vtkPiecewiseFunction
from vtkmodules.vtkRenderingCore import (vtkColorTransferFunction, vtkRenderer, vtkRenderWindow, vtkVolume,
                                         vtkVolumeProperty)
from vtkmodules.util.numpy_support import numpy_to_vtk, vtk_to_numpy

from mcvol import vtkMultiChannelVolumeMapper
from mcvolTesting import Checker, ErrorCatcher, capture_rgba

SKIP = 125
probe = vtkMultiChannelVolumeMapper()
probe.SetBackendToCUDA()
if probe.GetActiveBackendName() != "cuda":
    print("SKIP: no usable CUDA device:", probe.GetBackendReport())
    sys.exit(SKIP)

t = Checker()
channels = 3
n = 160  # 3 x 160^3 float32 = 47 MiB: large beside the CUDA context's noise
z, y, x = np.mgrid[0:n, 0:n, 0:n].astype(np.float32) / n
fields = [np.exp(-((x - cx) ** 2 + (y - 0.5) ** 2 + (z - 0.5) ** 2) / 0.04) for cx in (0.3, 0.5, 0.7)]
data = np.ascontiguousarray(np.stack(fields, axis=-1).reshape(-1, channels))
array = numpy_to_vtk(data, deep=1)
array.SetName("fields")
image = vtkImageData()
image.SetDimensions(n, n, n)
image.GetPointData().SetScalars(array)
data_bytes = data.nbytes


def make_property():
    prop = vtkVolumeProperty()
    prop.IndependentComponentsOn()
    for c, rgb in enumerate([(1.0, 0.3, 0.1), (0.2, 1.0, 0.3), (0.2, 0.4, 1.0)]):
        ctf = vtkColorTransferFunction()
        ctf.AddRGBPoint(0, *rgb)
        ctf.AddRGBPoint(1, *rgb)
        otf = vtkPiecewiseFunction()
        otf.AddPoint(0, 0.0)
        otf.AddPoint(1, 0.6)
        prop.SetColor(c, ctf)
        prop.SetScalarOpacity(c, otf)
    return prop


def make_view(mapper):
    volume = vtkVolume()
    volume.SetMapper(mapper)
    volume.SetProperty(make_property())
    renderer = vtkRenderer()
    renderer.AddVolume(volume)
    window = vtkRenderWindow()
    window.SetOffScreenRendering(1)
    window.SetMultiSamples(0)
    window.SetSize(96, 96)
    window.AddRenderer(renderer)
    renderer.ResetCamera()
    return window, renderer, volume


def process_memory_mib():
    """This process's device memory in MiB from nvidia-smi, or None."""
    smi = shutil.which("nvidia-smi")
    if not smi:
        return None
    out = subprocess.run([smi, "--query-compute-apps=pid,used_memory", "--format=csv,noheader,nounits"],
                         capture_output=True, text=True).stdout
    for line in out.splitlines():
        parts = [p.strip() for p in line.split(",")]
        if len(parts) == 2 and parts[0] == str(os.getpid()):
            return float(parts[1])
    return None


mapper = vtkMultiChannelVolumeMapper()
errors = ErrorCatcher(mapper)
mapper.SetBackendToCUDA()
mapper.SetInputData(image)
window, renderer, volume = make_view(mapper)

# --- 100 progressive renders: one upload per channel ------------------------
for _ in range(100):
    window.Render()
t.check(not errors.errors, "no errors: %s" % errors.errors)
t.check(mapper.GetActiveBackendName() == "cuda", "rendered on CUDA: %s" % mapper.GetBackendReport())
t.check(mapper.GetTotalSamples() == 100, "100 samples accumulated: %d" % mapper.GetTotalSamples())
t.check(mapper.GetNumberOfDataUploads() == channels,
        "100 progressive renders upload each channel once: %d uploads" % mapper.GetNumberOfDataUploads())
device_bytes = mapper.GetDeviceMemory()
print("device memory: %.1f MiB for %.1f MiB of data" % (device_bytes / 2**20, data_bytes / 2**20))
t.check(device_bytes >= data_bytes, "the device holds the data: %d >= %d bytes" % (device_bytes, data_bytes))
t.check(mapper.GetLastTraceTime() > 0 and mapper.GetLastDrawTime() > 0,
        "stage times are measured: trace %g s, draw %g s" % (mapper.GetLastTraceTime(), mapper.GetLastDrawTime()))

# --- camera moves and transfer-function edits upload nothing -----------------
for _ in range(10):
    renderer.GetActiveCamera().Azimuth(3)
    window.Render()
volume.GetProperty().GetScalarOpacity(1).AddPoint(0.5, 0.3)
window.Render()
t.check(mapper.GetNumberOfDataUploads() == channels,
        "camera moves and a transfer-function edit upload nothing: %d" % mapper.GetNumberOfDataUploads())

# --- ParaView's per-frame shallow copies: a new image sharing the arrays -----
for _ in range(20):
    copy = vtkImageData()
    copy.ShallowCopy(image)
    mapper.SetInputData(copy)
    window.Render()
t.check(mapper.GetNumberOfDataUploads() == channels,
        "shallow copies of the same arrays upload nothing: %d" % mapper.GetNumberOfDataUploads())
# A new input object restarts the image (SetInputData modifies the mapper),
# but the device copy is reused: the restart costs a trace, not an upload.
t.check(mapper.GetTotalSamples() == 1, "a new input object restarts the image: %d samples" % mapper.GetTotalSamples())

# --- a change of the values uploads again ------------------------------------
vtk_to_numpy(array)[:, 0] *= 0.5  # in place, as a filter re-executing would
array.Modified()
window.Render()
t.check(mapper.GetNumberOfDataUploads() == 2 * channels,
        "changed values upload again: %d" % mapper.GetNumberOfDataUploads())
mapper.SetInputData(image)

# --- two mappers, two windows, one GPU ---------------------------------------
mapper_a = vtkMultiChannelVolumeMapper()
mapper_b = vtkMultiChannelVolumeMapper()
for m in (mapper_a, mapper_b):
    m.SetBackendToCUDA()
    m.SetInputData(image)
    m.SetSeed(7)
    m.SetMaximumTotalSamples(16)
errors_a, errors_b = ErrorCatcher(mapper_a), ErrorCatcher(mapper_b)
window_a, _, _ = make_view(mapper_a)
window_b, _, _ = make_view(mapper_b)
for _ in range(16):  # in turn, as two ParaView views would
    window_a.Render()
    window_b.Render()
pixels_a = capture_rgba(window_a)
pixels_b = capture_rgba(window_b)
t.check(not errors_a.errors and not errors_b.errors, "two mappers: no errors")
t.check(mapper_a.GetTotalSamples() == 16 and mapper_b.GetTotalSamples() == 16, "both converge to 16 samples")
t.check(mapper_a.GetNumberOfDataUploads() == channels and mapper_b.GetNumberOfDataUploads() == channels,
        "each mapper uploads once, taking turns uploads nothing more: %d, %d"
        % (mapper_a.GetNumberOfDataUploads(), mapper_b.GetNumberOfDataUploads()))
t.check(pixels_a[..., :3].max() > 0, "the first view shows the volume")
t.check(np.array_equal(pixels_a, pixels_b), "same seed, same GPU: the same image (max difference %d)"
        % np.abs(pixels_a.astype(int) - pixels_b.astype(int)).max())
t.check(mapper.GetNumberOfDataUploads() == 2 * channels, "the first mapper's copy is untouched")

# --- the drawn image, from the device's 8-bit copy or the read-back floats ---
# The image is drawn from the device's RGBA8 display copy while it is pending
# there, and from the float image once it is read back (GetAccumulatedImage);
# a finished image redrawn after the read-back must look the same, and new
# samples after that go back to the 8-bit copy.
readback = vtkFloatArray()
mapper_a.GetAccumulatedImage(readback)
pixels_float = capture_rgba(window_a)
t.check(np.abs(pixels_float.astype(int) - pixels_a.astype(int)).max() <= 1,
        "drawn from the read-back floats: the same image as from the 8-bit copy (max difference %d)"
        % np.abs(pixels_float.astype(int) - pixels_a.astype(int)).max())
for w in (window_a, window_b):
    w.GetRenderers().GetFirstRenderer().GetActiveCamera().Azimuth(10)
pixels_a = capture_rgba(window_a)
pixels_b = capture_rgba(window_b)
t.check(mapper_a.GetTotalSamples() == 1 and pixels_a[..., :3].max() > 0,
        "a camera move restarts the image, drawn from the 8-bit copy again (%d sample)" % mapper_a.GetTotalSamples())
t.check(np.array_equal(pixels_a, pixels_b),
        "after a float draw, the 8-bit draw equals that of a mapper that never drew floats (max difference %d)"
        % np.abs(pixels_a.astype(int) - pixels_b.astype(int)).max())

# --- ReleaseGraphicsResources gives the memory back --------------------------
for m, w in ((mapper_a, window_a), (mapper_b, window_b)):
    m.ReleaseGraphicsResources(w)
window.Render()
device_bytes = mapper.GetDeviceMemory()
before = process_memory_mib()
mapper.ReleaseGraphicsResources(window)
after = process_memory_mib()
# The image was still on the device: the release reads it back first.
released = vtkFloatArray()
mapper.GetAccumulatedImage(released)
released = vtk_to_numpy(released)
t.check(released.size > 0 and np.isfinite(released).all() and released[3::4].max() > 0.1,
        "GetAccumulatedImage after the release returns the image (max alpha %.3f)"
        % (released[3::4].max() if released.size else 0))
t.check(mapper.GetDeviceMemory() == 0, "released: the mapper holds %g bytes" % mapper.GetDeviceMemory())
if before is not None and after is not None:
    freed = before - after
    print("nvidia-smi: %.0f MiB before the release, %.0f MiB after (%.0f MiB freed; the mapper held %.1f MiB)"
          % (before, after, freed, device_bytes / 2**20))
    t.check(freed >= 0.9 * device_bytes / 2**20 - 2,
            "the process's device memory falls by what the mapper held: %.0f MiB freed of %.1f MiB"
            % (freed, device_bytes / 2**20))
else:
    print("nvidia-smi not available: the process's device memory is not measured")
window.Render()
t.check(mapper.GetNumberOfDataUploads() == channels and mapper.GetDeviceMemory() > 0,
        "the next render uploads again: %d uploads" % mapper.GetNumberOfDataUploads())

t.finish()
