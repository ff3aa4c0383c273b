"""The automatic estimator after an edit on the CUDA backend (mcvol::ChoiceAhead):
the render that makes the choice again starts its batch with the previous
choice's estimator while the pilots run, and keeps it where the same estimator
is chosen.

- The first choice of a mapper has nothing to render ahead (no line about it
  in the report).
- After a transfer-function edit the report says the batch was rendered
  during the pilots, and whether it was kept.
- The image does not depend on it: an edited mapper's image equals, bit for
  bit, that of a new mapper that made its first choice with the edited
  functions (same seed, same choice), after the first render and after two
  more.
- Interactive renders (SetInteractiveRendering(1)) render nothing ahead.

Needs a CUDA device: without one the test is skipped (exit status 125).
Microscopy phantom, fixed seed."""

import os
import sys

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))

import numpy as np

import vtkmodules.vtkRenderingOpenGL2  # noqa: F401 (OpenGL render window)
from vtkmodules.vtkCommonCore import vtkFloatArray
from vtkmodules.vtkCommonDataModel import vtkPiecewiseFunction
from vtkmodules.vtkRenderingCore import (vtkColorTransferFunction, vtkRenderer, vtkRenderWindow, vtkVolume,
                                         vtkVolumeProperty)
from vtkmodules.util.numpy_support import vtk_to_numpy

from mcvol import vtkMultiChannelDemoSource, vtkMultiChannelVolumeMapper
from mcvolTesting import Checker

SKIP = 125
probe = vtkMultiChannelVolumeMapper()
probe.SetBackendToCUDA()
if probe.GetActiveBackendName() != "cuda":
    print("SKIP: no usable CUDA device:", probe.GetBackendReport())
    sys.exit(SKIP)

check = Checker()
AHEAD = "rendered during the pilots"

src = vtkMultiChannelDemoSource()
src.SetDataset("microscopy")
src.SetDimensions(128, 112, 64)
src.Update()


def make_property(scale):
    """The suggested functions, channel 0's opacity times `scale`."""
    prop = vtkVolumeProperty()
    prop.SetInterpolationTypeToLinear()
    for c in range(src.GetNumberOfOutputChannels()):
        color, opacity = vtkColorTransferFunction(), vtkPiecewiseFunction()
        src.GetSuggestedTransferFunction(c, color, opacity, None)
        if c == 0:
            scale_opacity(opacity, scale)
        prop.SetColor(c, color)
        prop.SetScalarOpacity(c, opacity)
        prop.SetScalarOpacityUnitDistance(c, src.GetSuggestedUnitDistance(c))
    return prop


def scale_opacity(opacity, scale):
    node = [0.0] * 4
    points = []
    for i in range(opacity.GetSize()):
        opacity.GetNodeValue(i, node)
        points.append(list(node))
    opacity.RemoveAllPoints()
    for x, y, mid, sharp in points:
        opacity.AddPoint(x, min(1.0, y * scale), mid, sharp)


def make_view(prop):
    mapper = vtkMultiChannelVolumeMapper()
    mapper.SetInputConnection(src.GetOutputPort())
    mapper.SetBackendToCUDA()
    mapper.SetSeed(3)
    mapper.SetEstimatorToAutomatic()
    volume = vtkVolume()
    volume.SetMapper(mapper)
    volume.SetProperty(prop)
    renderer = vtkRenderer()
    renderer.AddVolume(volume)
    window = vtkRenderWindow()
    window.SetOffScreenRendering(1)
    window.SetMultiSamples(0)
    window.SetSize(256, 224)
    window.AddRenderer(renderer)
    renderer.ResetCamera()
    renderer.GetActiveCamera().Azimuth(30)
    renderer.GetActiveCamera().Elevation(20)
    return mapper, window, volume


def accumulated(mapper):
    a = vtkFloatArray()
    mapper.GetAccumulatedImage(a)
    return vtk_to_numpy(a).copy()


def ahead_line(mapper):
    lines = [line for line in mapper.GetEstimatorReport().splitlines() if AHEAD in line]
    return lines[0] if lines else ""


# A mapper's first choice: nothing to render ahead.
edited, edited_window, edited_volume = make_view(make_property(1.0))
edited_window.Render()
check.check(edited.GetNumberOfEstimatorChoices() == 1, "one choice after the first render")
check.check(ahead_line(edited) == "", f"no batch ahead at the first choice: {ahead_line(edited)!r}")
first_choice = edited.GetChosenEstimatorAsString()

# The edit: channel 0's opacity scaled by 0.9 (the choice is made again).
edited_volume.SetProperty(make_property(0.9))
edited_window.Render()
line = ahead_line(edited)
print("after the edit:", edited.GetChosenEstimatorAsString(), "(first:", first_choice + ")")
print(edited.GetEstimatorReport())
check.check(edited.GetNumberOfEstimatorChoices() == 2, "the edit made the choice again")
check.check(line != "", "the batch was rendered during the pilots after the edit")
kept = line.endswith(": kept")
check.check(kept == (edited.GetChosenEstimatorAsString() == first_choice),
            f"kept exactly where the choice is the previous one: {line!r}")
after_one = accumulated(edited)
edited_window.Render()
edited_window.Render()
after_three = accumulated(edited)

# A new mapper with the edited functions from the start: its first choice
# (no hint, nothing ahead), the same seed, so the same choice and image.
fresh, fresh_window, _ = make_view(make_property(0.9))
fresh_window.Render()
check.check(ahead_line(fresh) == "", "a new mapper renders nothing ahead")
check.check(fresh.GetChosenEstimatorAsString() == edited.GetChosenEstimatorAsString(),
            f"the same choice with and without the previous one: {fresh.GetChosenEstimatorAsString()} "
            f"and {edited.GetChosenEstimatorAsString()}")
fresh_one = accumulated(fresh)
fresh_window.Render()
fresh_window.Render()
fresh_three = accumulated(fresh)
check.check(after_one.shape == fresh_one.shape and after_one.size > 0, "images of the same size")
check.check(float(after_one.sum()) > 1.0, "something is visible")
check.check(np.array_equal(after_one, fresh_one),
            f"the first render's image equals a new mapper's (largest difference "
            f"{float(np.max(np.abs(after_one - fresh_one))) if after_one.shape == fresh_one.shape else -1:.3g})")
check.check(np.array_equal(after_three, fresh_three), "and after two more renders")

# Interactive renders keep expected value and render nothing ahead.
edited.SetInteractiveRendering(1)
edited_volume.SetProperty(make_property(0.8))
edited_window.Render()
check.check(edited.GetLastRenderInteractive(), "the render was interactive")
check.check(ahead_line(edited) == "", f"nothing ahead in an interactive render: {ahead_line(edited)!r}")

sys.exit(check.finish())
