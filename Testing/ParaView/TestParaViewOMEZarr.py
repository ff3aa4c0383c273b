"""pvpython: microscopy from ParaView's File > Open, as a user drives it.

- An OME-Zarr folder (and its .zattrs) opens with the plugin's reader
  through ParaView's reader factory (what File > Open uses); Show picks the
  Multi-Channel Volume representation, the file's active channels (the
  inactive one left out) with its omero colours and windows (transparent
  below the window's start); the image shows the two channels in their
  colours over an untouched background. The time axis is ParaView's time,
  MemoryBudget and Level pick the level (and the output says which), a
  labels image is an error in the Output Messages.
- An OME-TIFF read by the Channel Files source (a Sources menu entry and an
  .ome.tif reader): its one 3-component array becomes "Components of One
  Array" by itself, and renders.
- A .vti with outliers shown as the Multi-Channel Volume: its channels get
  mcvol-render's default transfer functions, spread over the same robust
  range that mcvol-render computes (mcvol.scenefile.assemble.auto_range),
  transparent below 15 % of it.
"""
import os
import sys
import tempfile

import numpy as np
from paraview import servermanager as sm
from paraview import simple
from vtkmodules.vtkCommonCore import vtkOutputWindow, vtkStringOutputWindow

import mcvolParaViewTesting as T

sys.path.insert(0, os.path.join(T.SOURCE_DIR, "Testing", "Python"))
import omezarrWriter as W  # noqa: E402

checks = T.Checks()
T.load_plugin()
work = tempfile.mkdtemp(prefix="TestParaViewOMEZarr-")
rng = np.random.default_rng(11)

# -- an OME-Zarr with three channels, two active; two time steps; two levels ------------------------------
data = rng.poisson(100, (2, 3, 20, 24, 28)).astype(np.uint16)  # t c z y x, camera-like background
data[:, 0, 5:15, 6:18, 3:12] += 3000  # DAPI: a block on the left
data[:, 1, 5:15, 6:18, 16:25] += 2000  # GFP: a block on the right
data[1, 1, 5:15, 6:18, 16:25] += 20000  # GFP brighter at the second step
omero = {"channels": [W.omero_channel("DAPI", "0000FF", 200, 3000), W.omero_channel("GFP", "00FF00", 200, 2000),
                      W.omero_channel("off", "FF0000", 0, 10, active=False)]}
folder = W.write(os.path.join(work, "cells.ome.zarr"), [data, data[:, :, ::2, ::2, ::2].copy()], "tczyx",
                 [[2.0, 1, 2, 1, 1], [2.0, 1, 4, 2, 2]], omero=omero)

reader = simple.OpenDataFile(folder)
checks.check(reader is not None and reader.GetXMLName() == "mcvolOMEZarrReader",
             "File > Open of the .zarr folder uses the OME-Zarr reader (%s)" % (reader and reader.GetXMLName()))
again = simple.OpenDataFile(os.path.join(folder, ".zattrs"))
checks.check(again is not None and again.GetXMLName() == "mcvolOMEZarrReader", "and so does its .zattrs")
simple.Delete(again)
reader.UpdatePipeline(0.0)
checks.check(list(reader.TimestepValues) == [0.0, 2.0], "the time axis as time steps (%s)" % list(reader.TimestepValues))
checks.check(sorted(reader.PointData.keys()) == ["DAPI", "GFP", "off"], "one array per channel, named by label (%s)"
             % reader.PointData.keys())
info = reader.GetDataInformation()
checks.check(tuple(info.GetExtent()) == (0, 27, 0, 23, 0, 19) and np.allclose(info.GetBounds(), (0, 27, 0, 23, 0, 38)),
             "level 0's grid and spacing (%s, %s)" % (info.GetExtent(), info.GetBounds()))

view = T.make_view((160, 160))
view.CameraPosition = [13.5, 11.5, 140.0]
view.CameraFocalPoint = [13.5, 11.5, 19.0]
rep = simple.Show(reader, view)
checks.check(rep.Representation == T.REPRESENTATION, "shown as the Multi-Channel Volume (%s)" % rep.Representation)
simple.Render(view)
checks.check(list(rep.ChannelArrays) == ["DAPI", "GFP"], "the active channels (%s)" % list(rep.ChannelArrays))
dapi = simple.GetColorTransferFunction("DAPI")
checks.check(np.allclose(dapi.RGBPoints, [200, 0, 0, 0.35, 3000, 0, 0, 1]),
             "DAPI: its colour over its window (%s)" % list(dapi.RGBPoints))
points = list(simple.GetOpacityTransferFunction("GFP").Points)
checks.check(points[0] == 200 and points[1] == 0 and points[-4] == 2000 and points[-3] > 0,
             "GFP: transparent at the window's start, opaque towards its end (%s)" % points)
rep.Backend = "CPU"
rep.Seed = 3
rep.ProgressAnnotation = 0  # the corner checks read the volume alone
rep.SamplesPerRender = 8
rep.InteractiveFrameTime = 0
rep.MaximumTotalSamples = 32
T.render_converged(view, rep)
image = T.capture(view).astype(int)
blue = (image[..., 2] > image[..., 0] + 60) & (image[..., 2] > image[..., 1] + 60)
green = (image[..., 1] > image[..., 0] + 60) & (image[..., 1] > image[..., 2] + 60)
cols = np.nonzero(blue.any(axis=0))[0], np.nonzero(green.any(axis=0))[0]
checks.check(blue.sum() > 200 and green.sum() > 200 and cols[0].mean() < cols[1].mean(),
             "DAPI blue on the left, GFP green on the right (%d blue, %d green pixels)" % (blue.sum(), green.sum()))
checks.check(np.abs(image[2:10, 2:10]).max() == 0, "the background noise is transparent (corner %s)"
             % image[2:10, 2:10].max())
before = reader.GetPointDataInformation().GetArray("GFP").GetRange()
view.ViewTime = 2.0
simple.Render(view)
after = reader.GetPointDataInformation().GetArray("GFP").GetRange()
checks.check(after[1] > before[1] + 10000, "time 2 reads the second step (GFP max %g -> %g)" % (before[1], after[1]))

# -- levels -----------------------------------------------------------------------------------------------
full_mib = 3 * 28 * 24 * 20 * 2 / 1048576.0
for label, settings, extent, level in (("a budget just under level 0", {"MemoryBudget": full_mib * 0.99}, 13, 1),
                                        ("Level '1'", {"Level": "1"}, 13, 1), ("Level 0", {"Level": "0"}, 27, 0)):
    small = simple.OpenDataFile(folder)
    for k, v in settings.items():
        setattr(small, k, v)
    small.UpdatePipeline(0.0)
    fetched = sm.Fetch(small)
    note = fetched.GetFieldData().GetAbstractArray("OME-Zarr level")
    text = note.GetValue(0) if note is not None else ""
    checks.check(small.GetDataInformation().GetExtent()[1] == extent and ("level %d" % level) in text,
                 "%s reads level %d and says so (%r)" % (label, level, text))
    simple.Delete(small)

# -- a labels image: an error line, an empty output --------------------------------------------------------
labels = W.write(os.path.join(work, "labels.ome.zarr"), [np.zeros((4, 5, 6), np.uint8)], "zyx", [[1, 1, 1]])
import zarr  # noqa: E402

zarr.open_group(labels, mode="r+").attrs["image-label"] = {"version": "0.4"}
messages = vtkStringOutputWindow()
previous = vtkOutputWindow.GetInstance()
vtkOutputWindow.SetInstance(messages)
bad = simple.OpenDataFile(labels)
bad.UpdatePipeline()
vtkOutputWindow.SetInstance(previous)
text = messages.GetOutput()
checks.check("labels image" in text and labels in text, "a labels image: one error naming it (%r)" % text.strip()[:200])
checks.check(bad.GetDataInformation().GetNumberOfPoints() == 0, "and an empty output")

# -- Channel Files: an OME-TIFF's channels as Components of One Array ----------------------------------------
definitions = sm.ProxyManager().GetProxyDefinitionManager()
hints = sm.ProxyManager().GetPrototypeProxy("sources", "mcvolChannelFiles").GetHints()
checks.check(hints is not None and hints.FindNestedElementByName("ShowInMenu") is not None,
             "Channel Files is in the Sources menu")
try:
    import tifffile
except ImportError:
    tifffile = None
if tifffile is not None:
    stack = rng.poisson(80, (12, 3, 16, 20)).astype(np.uint16)  # Z C Y X
    for c in range(3):
        stack[3:9, c, 4:12, 2 + 6 * c:6 + 6 * c] += 4000
    tif = os.path.join(work, "stains.ome.tif")
    # OME colours (signed 32-bit RGBA): a blue, b malformed (its default colour, a warning), c magenta.
    tifffile.imwrite(tif, stack, ome=True, metadata={"axes": "ZCYX", "Channel": {
        "Name": ["a", "b", "c"], "Color": [65535, "x", -16711681]}})
    files = simple.mcvolChannelFiles(FileNames=[tif])
    files.UpdatePipeline()
    view2 = T.make_view((120, 120))
    view2.CameraPosition = [9.5, 7.5, 90.0]
    view2.CameraFocalPoint = [9.5, 7.5, 5.5]
    rep2 = simple.Show(files, view2)
    rep2.Representation = T.REPRESENTATION
    simple.Render(view2)
    checks.check(rep2.ChannelSource == "Components of One Array" and rep2.ChannelComponentsArray == "stains",
                 "one 3-component array: Components of One Array (%s, %r)" % (rep2.ChannelSource,
                                                                            rep2.ChannelComponentsArray))
    from mcvol.scenefile.assemble import DEFAULT_COLORS

    tops = [list(lut.RGBPoints)[-3:] for lut in rep2.ChannelLookupTables]
    checks.check(len(tops) == 3 and np.allclose(tops[0], [0, 0, 1]) and np.allclose(tops[1], DEFAULT_COLORS[1])
                 and np.allclose(tops[2], [1, 0, 1]), "the components in the file's colours (%s)" % tops)
    rep2.Backend = "CPU"
    rep2.MaximumTotalSamples = 8
    rep2.InteractiveFrameTime = 0
    T.render_converged(view2, rep2)
    checks.check(T.info(rep2, "ChannelStatus") == "", "its channels bind (%r)" % T.info(rep2, "ChannelStatus"))
    checks.check((T.capture(view2).sum(axis=2) > 60).sum() > 100, "and render")
    rep2.ChannelSource = "Point Arrays"
    rep2.ChannelArrays = ["stains"]
    simple.Render(view2)
    status = T.info(rep2, "ChannelStatus")
    checks.check("Components of One Array" in status and "3 components" in status,
                 "the 3-component array as one channel: the message names the fix (%r)" % status)

# -- mcvol-render's default transfer functions on a .vti ---------------------------------------------------
from vtkmodules.util.numpy_support import numpy_to_vtk  # noqa: E402
from vtkmodules.vtkCommonDataModel import vtkImageData  # noqa: E402
from vtkmodules.vtkIOXML import vtkXMLImageDataWriter  # noqa: E402

from mcvol.scenefile.assemble import auto_range  # noqa: E402

grid = vtkImageData()
grid.SetDimensions(24, 20, 16)
values = {"u16": rng.integers(0, 2000, 24 * 20 * 16).astype(np.uint16),
          "f32": rng.normal(10.0, 3.0, 24 * 20 * 16).astype(np.float32)}
values["u16"][:5] = 65535  # a few hot pixels
values["f32"][:5] = 1e6
for name, v in values.items():
    array = numpy_to_vtk(v, deep=True)
    array.SetName(name)
    grid.GetPointData().AddArray(array)
vti = os.path.join(work, "outliers.vti")
writer = vtkXMLImageDataWriter()
writer.SetInputData(grid)
writer.SetFileName(vti)
writer.Write()
plain = simple.OpenDataFile(vti)
view3 = T.make_view((64, 64))
rep3 = simple.Show(plain, view3)
rep3.Representation = T.REPRESENTATION
simple.Render(view3)
checks.check(sorted(rep3.ChannelArrays) == ["f32", "u16"], "every single-component array (%s)" % list(rep3.ChannelArrays))
for name in ("u16", "f32"):
    want = auto_range(grid.GetPointData().GetArray(name), 0)
    rgb = list(simple.GetColorTransferFunction(name).RGBPoints)
    pwf = list(simple.GetOpacityTransferFunction(name).Points)
    got = [rgb[0], rgb[-4]]
    checks.check(np.allclose(got, want, rtol=1e-12, atol=0), "%s: the robust range of mcvol-render %s (got %s)"
                 % (name, want, got))
    cut = want[0] + 0.15 * (want[1] - want[0])
    checks.check(len(pwf) == 12 and pwf[1] == 0 and np.isclose(pwf[4], cut) and pwf[5] == 0 and pwf[9] > 0,
                 "%s: transparent below 15 %% of it (%s)" % (name, pwf))
checks.finish()
