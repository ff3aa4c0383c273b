"""vtkMultiChannelDemoSource: every built-in dataset comes out with its size,
type and channel count, the interleaved "channels" scalars (component names =
channel names) equal the separate named arrays, suggested transfer functions
span each channel's data range, generation is deterministic, sizes and channel
counts can be changed, a piece asked for by its update extent (an MPI rank's
part) holds the whole volume's voxels there, a suggested transfer function
maps onto a given range, and an unknown name gives one error and an empty
output. No rendering."""

import os
import sys

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))

import numpy as np
from vtkmodules.util.numpy_support import vtk_to_numpy
from vtkmodules.vtkCommonCore import vtkDataArray
from vtkmodules.vtkCommonDataModel import vtkPiecewiseFunction
from vtkmodules.vtkRenderingCore import vtkColorTransferFunction

from mcvol import vtkMultiChannelDemoSource
from mcvolTesting import Checker, ErrorCatcher

EXPECTED = {
    "figure3": ((64, 64, 64), "float", ["red_cube", "green_cube", "blue_cube"]),
    "microscopy": ((128, 128, 40), "unsigned char", ["membranes", "nuclei", "puncta"]),
    "cosmology": (
        (64, 64, 64),
        "float",
        ["dark_matter_density", "baryon_density", "temperature", "velocity_magnitude"],
    ),
    "weather": ((100, 100, 20), "float", None),
}

t = Checker()
names = [vtkMultiChannelDemoSource.GetDatasetName(i) for i in range(vtkMultiChannelDemoSource.GetNumberOfDatasets())]
t.check(sorted(names) == sorted(EXPECTED), "dataset names %s" % names)

for name, (dims, vtype, channel_names) in EXPECTED.items():
    src = vtkMultiChannelDemoSource()
    src.SetDataset(name)
    src.Update()
    image = src.GetOutput()
    pd = image.GetPointData()
    scalars = pd.GetScalars()
    t.check(image.GetDimensions() == dims, "%s: dimensions %s" % (name, image.GetDimensions()))
    if not t.check(scalars is not None and scalars.GetName() == "channels", "%s: no 'channels' scalars" % name):
        continue
    n = scalars.GetNumberOfComponents()
    t.check(n == src.GetNumberOfOutputChannels(), "%s: %d components, %d channels" % (name, n, src.GetNumberOfOutputChannels()))
    t.check(scalars.GetDataTypeAsString() == vtype, "%s: type %s" % (name, scalars.GetDataTypeAsString()))
    if channel_names:
        t.check([src.GetChannelName(c) for c in range(n)] == channel_names, "%s: channel names" % name)
    t.check(pd.GetNumberOfArrays() == n + 1, "%s: %d point arrays" % (name, pd.GetNumberOfArrays()))
    inter = vtk_to_numpy(scalars)
    for c in range(n):
        cname = src.GetChannelName(c)
        t.check(scalars.GetComponentName(c) == cname, "%s: component %d named %s" % (name, c, scalars.GetComponentName(c)))
        sep = pd.GetArray(cname)
        if t.check(sep is not None and sep.GetNumberOfComponents() == 1, "%s: array %s" % (name, cname)):
            t.check(np.array_equal(vtk_to_numpy(sep), inter[:, c]), "%s: %s differs from component %d" % (name, cname, c))
            # The range the source stores in the array's range cache.
            t.check(sep.GetInformation().Has(vtkDataArray.PER_FINITE_COMPONENT()),
                    "%s: %s carries no cached range" % (name, cname))
            vals = vtk_to_numpy(sep).astype(np.float64)
            want = (vals.min(), vals.max())
            t.check(sep.GetRange(0) == want and sep.GetFiniteRange(0) == want,
                    "%s: %s range %s / finite %s, data %s" % (name, cname, sep.GetRange(0), sep.GetFiniteRange(0), want))
        rng = [0.0, 0.0]
        t.check(src.GetChannelRange(c, rng), "%s: no range for %d" % (name, c))
        data = inter[:, c].astype(np.float64)
        t.check(abs(rng[0] - data.min()) <= 1e-6 * max(1.0, abs(data.min())) and abs(rng[1] - data.max()) <= 1e-6 * max(1.0, abs(data.max())),
                "%s: range %s vs data [%g, %g]" % (name, rng, data.min(), data.max()))
        color, opacity = vtkColorTransferFunction(), vtkPiecewiseFunction()
        ok = src.GetSuggestedTransferFunction(c, color, opacity, None)
        unit = src.GetSuggestedUnitDistance(c)
        if t.check(ok and color.GetSize() >= 2 and opacity.GetSize() >= 2 and unit > 0, "%s: suggested TF %d" % (name, c)):
            lo, hi = opacity.GetRange()
            if rng[1] > rng[0]:
                t.check(abs(lo - rng[0]) <= 1e-6 * max(1.0, abs(rng[0])) and abs(hi - rng[1]) <= 1e-6 * max(1.0, abs(rng[1])),
                        "%s: opacity range [%g, %g] vs data %s" % (name, lo, hi, rng))

# Deterministic, resizable, more channels, interleaved only.
a, b = vtkMultiChannelDemoSource(), vtkMultiChannelDemoSource()
for s in (a, b):
    s.SetDataset("cosmology")
    s.SetDimensions(20, 12, 8)
    s.SetNumberOfChannels(6)
    s.SeparateArraysOff()
    s.Update()
ia = a.GetOutput()
t.check(ia.GetDimensions() == (20, 12, 8), "resized: %s" % (ia.GetDimensions(),))
t.check(ia.GetPointData().GetNumberOfArrays() == 1, "SeparateArraysOff: %d arrays" % ia.GetPointData().GetNumberOfArrays())
t.check(ia.GetPointData().GetScalars().GetNumberOfComponents() == 6, "6 channels")
t.check(np.array_equal(vtk_to_numpy(ia.GetPointData().GetScalars()), vtk_to_numpy(b.GetOutput().GetPointData().GetScalars())),
        "two generations differ")

# Separate arrays only.
s = vtkMultiChannelDemoSource()
s.SetDataset("figure3")
s.SetDimensions(8, 8, 8)
s.InterleavedOff()
s.Update()
pd = s.GetOutput().GetPointData()
t.check(pd.GetScalars() is None and pd.GetNumberOfArrays() == 3, "InterleavedOff: scalars %s, %d arrays" % (pd.GetScalars(), pd.GetNumberOfArrays()))

# Pieces: the update extent alone is generated, with the whole volume's
# values there, on every dataset (odd sizes, pieces touching no face).
for name, dims, ext in (
    ("cosmology", (20, 12, 9), (3, 17, 0, 11, 4, 8)),
    ("microscopy", (33, 30, 10), (0, 32, 7, 21, 2, 2)),
    ("weather", (24, 20, 7), (10, 23, 0, 19, 0, 3)),
    ("figure3", (16, 16, 16), (5, 5, 6, 6, 7, 7)),
):
    whole = vtkMultiChannelDemoSource()
    whole.SetDataset(name)
    whole.SetDimensions(*dims)
    whole.Update()
    piece = vtkMultiChannelDemoSource()
    piece.SetDataset(name)
    piece.SetDimensions(*dims)
    piece.UpdateExtent(ext)
    out = piece.GetOutput()
    t.check(out.GetExtent() == ext, "%s: piece extent %s, asked %s" % (name, out.GetExtent(), ext))
    full = vtk_to_numpy(whole.GetOutput().GetPointData().GetScalars())
    full = full.reshape(dims[2], dims[1], dims[0], -1)[ext[4]:ext[5] + 1, ext[2]:ext[3] + 1, ext[0]:ext[1] + 1]
    got = vtk_to_numpy(out.GetPointData().GetScalars())
    t.check(got.size == full.size and np.array_equal(got.reshape(full.shape), full),
            "%s: the piece differs from the whole volume's voxels there" % name)
    first = piece.GetChannelName(0)
    t.check(piece.GetSuggestedUnitDistance(0) == whole.GetSuggestedUnitDistance(0)
            and piece.GetOutput().GetExtent() == ext,
            "%s: a query after the piece changed it or the unit distance" % name)
    t.check(np.array_equal(vtk_to_numpy(out.GetPointData().GetArray(first)), full[..., 0].ravel()),
            "%s: separate array %s of the piece" % (name, first))

# A suggested transfer function over a given range (a piece's ranks use the
# whole volume's) spans that range; a reversed or NaN range is an error.
s = vtkMultiChannelDemoSource()
s.SetDataset("cosmology")
s.SetDimensions(8, 8, 8)
color, opacity = vtkColorTransferFunction(), vtkPiecewiseFunction()
t.check(s.GetSuggestedTransferFunction(0, [-2.0, 6.0], color, opacity, None), "TF over a given range refused")
t.check(opacity.GetRange() == (-2.0, 6.0) and color.GetRange() == (-2.0, 6.0),
        "TF over [-2, 6] spans %s / %s" % (opacity.GetRange(), color.GetRange()))
for bad in ([6.0, -2.0], [float("nan"), 1.0]):
    catcher = ErrorCatcher(s)
    t.check(not s.GetSuggestedTransferFunction(0, bad, color, opacity, None) and len(catcher.errors) == 1,
            "range %s accepted" % bad)

# Errors: unknown name, bad size, bad channel.
for setup, what in (
    (lambda s: s.SetDataset("galaxy"), "unknown dataset"),
    (lambda s: s.SetDimensions(0, 4, 4), "bad dimensions"),
):
    s = vtkMultiChannelDemoSource()
    catcher = ErrorCatcher(s)
    setup(s)
    s.Update()
    t.check(len(catcher.errors) == 1, "%s: %d errors %s" % (what, len(catcher.errors), catcher.errors))
    t.check(s.GetOutput().GetNumberOfPoints() == 0, "%s: output not empty" % what)
    t.check(s.GetNumberOfOutputChannels() == 0, "%s: channels reported" % what)
    # Fixing the parameter recovers.
    s.SetDataset("figure3")
    s.SetDimensions(4, 4, 4)
    s.Update()
    t.check(s.GetOutput().GetNumberOfPoints() == 64, "%s: no recovery" % what)
s = vtkMultiChannelDemoSource()
catcher = ErrorCatcher(s)
s.SetDataset("figure3")
s.SetDimensions(4, 4, 4)
t.check(not s.GetSuggestedTransferFunction(3, None, None, None) and len(catcher.errors) == 1, "channel 3 of figure3 accepted")

t.finish()
