"""The checks of the OME-TIFF GUI walk (GUIOpenOMETIFF.sh), typed into the
GUI's Python shell by its playback (`import GUIOpenOMETIFF as walk`, then
`walk.opened()`, ...): they read what the clicks did, finish the refinement
the GUI did while idle (render until Converged, as the quick start's
script does), and write a line per check to $MCVOL_WALK_OUT/checks.txt and
a file STEP.ready that tells the walk to take its screenshot.

- opened(): the file was read by the plugin's reader (mcvol Channel Files),
  as one uint16 array with the OME channels as named components and the
  OME physical sizes as spacing; the representation is Multi-Channel Volume
  (Monte Carlo) with the components as channels; the GUI refined while idle;
  the refinement converges with the corner annotation on.
- edit_applied(): right after the editor's edits: the samples so far.
- edited(): Edit Channel 1 points the editor at the second channel
  ("membrane"), its colours and opacity are the edited ones, and the edit
  started the image over, which refined again to convergence.
"""
import os

from paraview import servermanager as sm
from paraview import simple

OUT = os.environ["MCVOL_WALK_OUT"]
NAMES = ["DAPI", "membrane", "puncta"]
SPACING = (0.2, 0.2, 0.8)
state = {}


def _check(ok, what):
    with open(os.path.join(OUT, "checks.txt"), "a") as f:
        f.write("%s %s\n" % ("ok  " if ok else "FAIL", what))


def _scene():
    source = simple.FindSource("cells.ome.tif")
    view = simple.GetActiveView()
    return source, view, simple.GetDisplayProperties(source, view)


def _refine(view, rep, limit=600):
    """Renders until the representation says Converged (at most `limit`
    renders), as the GUI does (simple.Render would reset the camera on its
    first call, which starts the image over)."""
    n = 0
    while not rep.Converged and n < limit:
        view.StillRender()
        n += 1
    return n


def _ready(step):
    with open(os.path.join(OUT, step + ".ready"), "w") as f:
        f.write(step + "\n")


def opened():
    source, view, rep = _scene()
    _check(source is not None and source.GetXMLName() == "mcvolChannelFiles",
           "File > Open used the reader mcvol Channel Files (%s)" % (source.GetXMLName() if source else None))
    image = sm.Fetch(source)
    array = image.GetPointData().GetArray("cells")
    names = [array.GetComponentName(k) for k in range(array.GetNumberOfComponents())] if array else []
    _check(array is not None and array.GetDataTypeAsString() == "unsigned short" and names == NAMES,
           "one uint16 array 'cells' with the OME channels %s as components (%s)" % (NAMES, names))
    spacing = image.GetSpacing()
    _check(image.GetDimensions() == (128, 128, 40) and all(abs(a - b) < 1e-9 for a, b in zip(spacing, SPACING)),
           "128 x 128 x 40 voxels of 0.2 x 0.2 x 0.8 um (%s, %s)" % (image.GetDimensions(), spacing))
    _check(rep.Representation == "Multi-Channel Volume (Monte Carlo)"
           and rep.ChannelSource == "Components of One Array" and rep.ChannelComponentsArray == "cells",
           "shown as Multi-Channel Volume (Monte Carlo), channels from the components of 'cells' (%s, %s, %s)"
           % (rep.Representation, rep.ChannelSource, rep.ChannelComponentsArray))
    idle = rep.TotalSamples
    _check(idle > rep.SamplesPerRender, "the GUI refined while idle (%d samples)" % idle)
    renders = _refine(view, rep)
    state["samples"] = rep.TotalSamples
    state["rgb"] = list(simple.GetColorTransferFunction("cells:1").RGBPoints)
    state["opacity"] = list(simple.GetOpacityTransferFunction("cells:1").Points)
    _check(rep.Converged == 1 and rep.ProgressAnnotation == 1 and "converged" in rep.ProgressText,
           "converged with the corner annotation on: %d samples, %.1f dB, %d renders after the idle ones (%r)"
           % (rep.TotalSamples, rep.EstimatedPSNR, renders, rep.ProgressText))
    _ready("open")


def edit_applied():
    _, _, rep = _scene()
    state["edit_samples"] = rep.TotalSamples


def edited():
    source, view, rep = _scene()
    lut = simple.GetColorTransferFunction("cells:1")
    pwf = simple.GetOpacityTransferFunction("cells:1")
    channel = sm.Fetch(source).GetPointData().GetArray("cells").GetComponentName(rep.ActiveChannel)
    _check(rep.ActiveChannel == 1 and channel == "membrane" and list(rep.ColorArrayName) == ["POINTS", "cells"]
           and rep.LookupTable == lut and lut.VectorMode == "Component" and lut.VectorComponent == 1,
           "Edit Channel %d: the editor is on the second channel %r (colouring by %s, function 'cells:1', component %d)"
           % (rep.ActiveChannel, channel, list(rep.ColorArrayName), lut.VectorComponent))
    rgb = list(lut.RGBPoints)
    _check(rgb != state["rgb"] and abs(rgb[0] - state["rgb"][0]) < 1e-6 and abs(rgb[-4] - state["rgb"][-4]) < 1e-6,
           "the preset changed the channel's colours and kept its range %.0f..%.0f" % (rgb[0], rgb[-4]))
    points = list(pwf.Points)
    _check(abs(points[-3] - 0.5) < 1e-9 and points != state["opacity"],
           "the opacity table set the top opacity to %.2f (was %.2f)" % (points[-3], state["opacity"][-3]))
    _check(state["edit_samples"] < state["samples"],
           "the edit started the image over (%d samples after the edit, %d before)"
           % (state["edit_samples"], state["samples"]))
    idle = rep.TotalSamples
    renders = _refine(view, rep)
    _check(idle > state["edit_samples"] and rep.Converged == 1 and "converged" in rep.ProgressText,
           "it refined again: %d samples while idle, converged at %d samples, %.1f dB, %d more renders"
           % (idle, rep.TotalSamples, rep.EstimatedPSNR, renders))
    _ready("edit")
