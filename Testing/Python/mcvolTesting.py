"""Helpers shared by the Python tests of the VTK adapter."""

import os
import sys

from vtkmodules.vtkCommonCore import VTK_STRING
from vtkmodules.vtkRenderingCore import vtkRenderer, vtkRenderWindow, vtkVolume, vtkWindowToImageFilter
from vtkmodules.util.misc import calldata_type
from vtkmodules.util.numpy_support import vtk_to_numpy



def use_test_backend(mapper):
    """Sets the backend a test renders with: the CPU (the baselines' backend)
    by default, CUDA when MCVOL_TEST_BACKEND=cuda (the GPU machine's runs,
    Benchmarks/gpu/vtk.sh), as the core tests do."""
    if os.environ.get("MCVOL_TEST_BACKEND", "").lower() == "cuda":
        mapper.SetBackendToCUDA()
    else:
        mapper.SetBackendToCPU()

def suggested_property(src):
    """A vtkVolumeProperty with independent components, linear
    interpolation and, per channel, the colour, opacity and unit distance
    that `src` (an updated vtkMultiChannelDemoSource) suggests."""
    from vtkmodules.vtkCommonDataModel import vtkPiecewiseFunction
    from vtkmodules.vtkRenderingCore import vtkColorTransferFunction, vtkVolumeProperty

    prop = vtkVolumeProperty()
    prop.IndependentComponentsOn()
    prop.SetInterpolationTypeToLinear()
    for c in range(src.GetNumberOfOutputChannels()):
        ctf, otf, u = vtkColorTransferFunction(), vtkPiecewiseFunction(), [0.0]
        src.GetSuggestedTransferFunction(c, ctf, otf, u)
        prop.SetColor(c, ctf)
        prop.SetScalarOpacity(c, otf)
        prop.SetScalarOpacityUnitDistance(c, u[0])
    return prop


def offscreen_view(mapper, prop, size=(64, 64)):
    """`mapper` with `prop` as the one volume of a renderer in an off-screen
    window of `size` (no multisampling), the camera reset to the volume: the
    set-up the tests share. Returns the window."""
    volume = vtkVolume()
    volume.SetMapper(mapper)
    volume.SetProperty(prop)
    renderer = vtkRenderer()
    renderer.AddVolume(volume)
    window = vtkRenderWindow()
    window.SetOffScreenRendering(1)
    window.SetMultiSamples(0)
    window.SetSize(*size)
    window.AddRenderer(renderer)
    renderer.ResetCamera()
    return window


def capture_rgba(window):
    """Renders once more and returns the window as an (H, W, 4) uint8 array,
    row 0 at the bottom (OpenGL order)."""
    window.Render()
    grabber = vtkWindowToImageFilter()
    grabber.SetInput(window)
    grabber.ShouldRerenderOff()
    grabber.ReadFrontBufferOff()
    grabber.SetInputBufferTypeToRGBA()
    grabber.Update()
    image = grabber.GetOutput()
    w, h, _ = image.GetDimensions()
    return vtk_to_numpy(image.GetPointData().GetScalars()).reshape(h, w, 4).copy()


def read_png_rgb(path):
    """A PNG as an (H, W, 3) float64 array (row 0 at the bottom)."""
    import numpy as np
    from vtkmodules.vtkIOImage import vtkPNGReader

    reader = vtkPNGReader()
    reader.SetFileName(path)
    reader.Update()
    img = reader.GetOutput()
    w, h, _ = img.GetDimensions()
    return vtk_to_numpy(img.GetPointData().GetScalars()).reshape(h, w, -1)[:, :, :3].astype(np.float64)


def write_png_rgb(path, arr):
    """Writes an (H, W, 3) array of 0..255 values as a PNG (row 0 at the bottom)."""
    import numpy as np
    from vtkmodules.vtkCommonDataModel import vtkImageData
    from vtkmodules.vtkIOImage import vtkPNGWriter
    from vtkmodules.util.numpy_support import numpy_to_vtk

    h, w = arr.shape[0], arr.shape[1]
    img = vtkImageData()
    img.SetDimensions(w, h, 1)
    img.GetPointData().SetScalars(numpy_to_vtk(arr.reshape(-1, 3).astype(np.uint8), deep=True))
    writer = vtkPNGWriter()
    writer.SetFileName(path)
    writer.SetInputData(img)
    writer.Write()


def world_to_pixel(renderer, point):
    """Display (x, y) pixel of a world point."""
    renderer.SetWorldPoint(point[0], point[1], point[2], 1.0)
    renderer.WorldToDisplay()
    x, y, _ = renderer.GetDisplayPoint()
    return int(round(x)), int(round(y))


class Checker:
    """Collects failed checks so one run reports all of them."""

    def __init__(self):
        self.failures = []

    def check(self, condition, message):
        if not condition:
            self.failures.append(message)
            print("FAIL:", message)
        return condition

    def finish(self):
        if self.failures:
            print("%d check(s) failed" % len(self.failures))
            sys.exit(1)
        print("all checks passed")
        sys.exit(0)


class ErrorCatcher:
    """Observes ErrorEvent/WarningEvent on a VTK object and keeps the messages
    (so expected errors neither abort nor clutter the test output)."""

    def __init__(self, obj):
        self.errors = []
        self.warnings = []

        # The decorator makes VTK pass the message as call data.
        @calldata_type(VTK_STRING)
        def on_error(caller, event, message):
            self.errors.append(str(message))

        @calldata_type(VTK_STRING)
        def on_warning(caller, event, message):
            self.warnings.append(str(message))

        obj.AddObserver("ErrorEvent", on_error)
        obj.AddObserver("WarningEvent", on_warning)

    def clear(self):
        self.errors = []
        self.warnings = []
