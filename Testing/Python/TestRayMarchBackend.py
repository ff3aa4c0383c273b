"""vtkMultiChannelRayMarchMapper's Backend setting
(Documentation/user-guide/backends.md): the reference marches on the backend
chosen, with the Monte Carlo mapper's API and words
(SetBackendToAuto/CPU/CUDA, GetBackendAsString, GetActiveBackendName,
GetBackendReport, PrintSelf).

- CPU: renders, reports "cpu", and the image is the same whatever Backend
  the previous render used (switching backends re-marches).
- Auto: picks CUDA when a usable device exists, else the CPU, saying why.
- CUDA without a device (CI): a clear error naming the cause, nothing drawn,
  no crash, and the mapper renders again once set back to the CPU.
- CUDA with a device: the image equals the CPU's within 1e-4 per component
  (the same per-ray code, software interpolation: float rounding only).
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

from mcvol import vtkMultiChannelRayMarchMapper
from mcvolTesting import Checker, ErrorCatcher, capture_rgba

t = Checker()

# Two channels of smooth blobs (16^3, float32).
n = 16
z, y, x = np.mgrid[0:n, 0:n, 0:n].astype(np.float32)
blob_a = np.exp(-((x - 6) ** 2 + (y - 8) ** 2 + (z - 7) ** 2) / 18.0)
blob_b = np.exp(-((x - 10) ** 2 + (y - 7) ** 2 + (z - 9) ** 2) / 12.0)
data = np.stack([blob_a, blob_b], axis=-1).reshape(-1, 2)
image = vtkImageData()
image.SetDimensions(n, n, n)
array = numpy_to_vtk(np.ascontiguousarray(data), deep=1)
array.SetName("blobs")
image.GetPointData().SetScalars(array)

mapper = vtkMultiChannelRayMarchMapper()
errors = ErrorCatcher(mapper)
mapper.SetInputData(image)
mapper.SetStepSize(0.25)
prop = vtkVolumeProperty()
prop.IndependentComponentsOn()
for c, rgb in enumerate([(1.0, 0.4, 0.1), (0.2, 0.5, 1.0)]):
    ctf = vtkColorTransferFunction()
    ctf.AddRGBPoint(0, *rgb)
    ctf.AddRGBPoint(1, *rgb)
    otf = vtkPiecewiseFunction()
    otf.AddPoint(0, 0.0)
    otf.AddPoint(0.2, 0.0)
    otf.AddPoint(1, 0.5)
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
window.SetSize(48, 48)
window.AddRenderer(renderer)
renderer.ResetCamera()


def render():
    """Renders; returns the accumulated float image (P x 4), or None when
    nothing was drawn."""
    errors.clear()
    if capture_rgba(window)[..., :3].max() == 0:
        return None
    a = vtkFloatArray()
    mapper.GetAccumulatedImage(a)
    return vtk_to_numpy(a).reshape(-1, 4).astype(np.float64)


# The inherited setting, with the Monte Carlo mapper's enum and strings.
t.check(mapper.GetBackend() == mapper.BACKEND_AUTO, "default Backend is Auto: %d" % mapper.GetBackend())
t.check(mapper.GetBackendAsString() == "Auto", "Auto as string: %s" % mapper.GetBackendAsString())

# CPU.
mapper.SetBackendToCPU()
t.check(mapper.GetBackendAsString() == "CPU", "CPU as string")
cpu = render()
t.check(cpu is not None and not errors.errors, "CPU march renders: %s" % errors.errors)
t.check(cpu is not None and cpu[:, 3].max() > 0.2, "the blobs are visible")
t.check(mapper.GetActiveBackendName() == "cpu", "CPU in use: %s" % mapper.GetActiveBackendName())
t.check(mapper.GetBackendReport() == "CPU backend (requested)", "CPU report: %s" % mapper.GetBackendReport())
t.check(mapper.GetLastTraceSeconds() > 0.0, "the march was timed")
printed = str(mapper)
t.check("Backend: CPU" in printed and "ActiveBackend: cpu" in printed, "PrintSelf names the backend")
t.check("StepSize: 0.25" in printed, "PrintSelf has the march's settings")

# Auto: the Monte Carlo mapper's rule.
mapper.SetBackendToAuto()
auto_name = mapper.GetActiveBackendName()
auto_report = mapper.GetBackendReport()
print("Auto backend here:", auto_name, "-", auto_report)
t.check(auto_name in ("cpu", "cuda"), "auto picks a backend: %s" % auto_name)
t.check(("CUDA" in auto_report) if auto_name == "cuda" else auto_report.startswith(("CPU backend (auto: ", "CPU backend (auto, MCVOL_BACKEND=cpu)")),
        "auto report names the choice and the reason: %s" % auto_report)
auto = render()
t.check(auto is not None and not errors.errors, "Auto renders: %s" % errors.errors)
t.check(mapper.GetActiveBackendName() == auto_name, "Auto used what it said: %s" % mapper.GetActiveBackendName())

# CUDA.
mapper.SetBackendToCUDA()
name = mapper.GetActiveBackendName()
report = mapper.GetBackendReport()
print("CUDA backend here:", name, "-", report)
cuda = render()
if auto_name == "cpu":
    t.check(name == "none", "no CUDA device: the CUDA backend is unavailable (%s)" % name)
    t.check(report.startswith("unavailable: the CUDA backend was requested but "),
            "the report names the cause: %s" % report)
    t.check(cuda is None, "no CUDA device: nothing drawn")
    text = " ".join(errors.errors)
    t.check("Backend CUDA is not available" in text and "CUDA backend was requested but" in text,
            "the error names the backend and the cause: %r" % text)
    after = mapper.GetBackendReport()
    t.check(after.startswith("unavailable: ") and "CUDA backend was requested but" in after,
            "after the render the report still names the cause: %s" % after)
    t.check(mapper.GetActiveBackendName() == "none", "nothing in use: %s" % mapper.GetActiveBackendName())
else:
    t.check(cuda is not None and not errors.errors, "CUDA march renders: %s" % errors.errors)
    t.check(name == "cuda" and mapper.GetActiveBackendName() == "cuda", "CUDA in use")
    diff = np.abs(cuda - cpu).max()
    print("max |CPU - CUDA| = %.3g" % diff)
    t.check(diff <= 1e-4, "CUDA march equals the CPU march within 1e-4: %.3g" % diff)

# Back to the CPU: the image is marched again and is the same.
mapper.SetBackendToCPU()
again = render()
t.check(again is not None and not errors.errors, "CPU again renders: %s" % errors.errors)
t.check(again is not None and cpu is not None and np.array_equal(again, cpu), "CPU again: the same image")
t.check(mapper.GetActiveBackendName() == "cpu", "CPU in use again")

t.finish()
