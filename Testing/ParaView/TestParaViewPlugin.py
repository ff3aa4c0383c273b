"""pvpython: the plugin's representation renders channels chosen as arrays or
as components, with their transfer functions and blend modes, against
baseline images; no limit of 4 channels."""
import numpy as np
from paraview import simple

import mcvolParaViewTesting as T

checks = T.Checks()
T.load_plugin()

figure3 = simple.XMLImageDataReader(FileName=[T.DATA + "/figure3.vti"])
names = ["red", "green", "blue"]
split = T.split_channels(figure3, "channels", names)

view = T.make_view()
rep = T.show(split, view)
rep.ChannelArrays = names
checks.check(
    [lut.GetXMLName() for lut in rep.ChannelLookupTables] == ["PVLookupTable"] * 3
    and list(rep.ChannelLookupTables) == [simple.GetColorTransferFunction(n) for n in names],
    "each channel array gets ParaView's transfer function of that array",
)
T.set_channel_functions(names)
simple.Hide(figure3, view)

images = {}
# The baseline of Mix is Eq. 10 as published (the default colour, Average,
# is tested in TestParaViewProperties and the core tests).
rep.MixColorMode = "Equation 10"
for mode in ["Density", "Max", "Mix", "Composite"]:
    rep.ChannelBlendMode = mode
    total = T.render_converged(view, rep)
    checks.check(total == 32, "%s: refinement stops at Maximum Total Samples (%d)" % (mode, total))
    checks.check(T.info(rep, "ChannelStatus") == "", "%s: no channel problem reported" % mode)
    images[mode] = T.capture(view)
    T.compare_baseline(checks, images[mode], "ParaView_figure3_" + mode.lower())
    # Redrawing a finished image traces nothing and changes nothing.
    simple.Render(view)
    checks.check(T.info(rep, "TotalSamples") == 32, "%s: a finished image is not refined further" % mode)
    checks.check(np.array_equal(T.capture(view), images[mode]), "%s: redrawing gives the same image" % mode)

for a in range(4):
    for b in range(a + 1, 4):
        ma, mb = list(images)[a], list(images)[b]
        diff = np.abs(images[ma].astype(int) - images[mb].astype(int)).mean()
        checks.check(diff > 1.0, "blend modes %s and %s give different images (mean |diff| %.2f)" % (ma, mb, diff))

rep.MixColorMode = "Average"
# Mix weights: only the red channel left.
rep.ChannelBlendMode = "Mix"
rep.MixWeights = [1.0, 0.0, 0.0]
T.render_converged(view, rep)
red_only = T.capture(view).astype(float)
lit = red_only.sum(axis=2) > 30
checks.check(lit.any(), "mix weights 1 0 0 still draw the red channel")
checks.check(
    red_only[..., 0][lit].mean() > 3 * max(red_only[..., 1][lit].mean(), red_only[..., 2][lit].mean()),
    "mix weights 1 0 0 leave red only (mean R %.1f, G %.1f, B %.1f)"
    % tuple(red_only[..., c][lit].mean() for c in range(3)),
)
rep.MixWeights = []
rep.ChannelBlendMode = "Density"

# The same channels as the components of one array give the same image.
simple.Hide(split, view)
comp = T.show(figure3, view)
comp.ChannelSource = "Components of One Array"
comp.ChannelComponentsArray = "channels"
component_names = ["channels:0", "channels:1", "channels:2"]
checks.check(
    list(comp.ChannelLookupTables) == [simple.GetColorTransferFunction(n) for n in component_names],
    "components get the transfer functions named array:k",
)
T.set_channel_functions(component_names)
T.render_converged(view, comp)
image = T.capture(view)
diff = np.abs(image.astype(int) - images["Density"].astype(int))
checks.check(
    diff.max() <= 2, "components of one array render as the same arrays split apart (max |diff| %d)" % diff.max()
)

# More than 4 channels: the 12 components of the weather set, with the
# transfer functions the plugin creates (mcvol-render's colour of each
# channel, over its robust range).
simple.Hide(figure3, view)
weather = simple.XMLImageDataReader(FileName=[T.DATA + "/weather.vti"])
wrep = T.show(weather, view)
wrep.ChannelSource = "Components of One Array"
wrep.ChannelComponentsArray = "channels"
checks.check(len(wrep.ChannelLookupTables) == 12, "12 components give 12 channels (%d)" % len(wrep.ChannelLookupTables))
presets = {tuple(simple.GetColorTransferFunction("channels:%d" % k).RGBPoints[1:4]) for k in range(12)}
checks.check(len(presets) >= 5, "new channels get distinct colours (%d distinct first colours)" % len(presets))
simple.ResetCamera(view)
T.render_converged(view, wrep)
image = T.capture(view)
checks.check(T.info(wrep, "ChannelStatus") == "", "12 channels: no channel problem reported")
checks.check((image.sum(axis=2) > 30).mean() > 0.05, "12 channels: the volume is drawn")

# Data whose channels are separate arrays and which has no active scalars
# (as a file of separate arrays often is): ParaView's volume prop only draws
# a mapper whose scalars it finds, so the representation points the mapper
# at the first channel. Before that fix this drew nothing in the GUI.
import os
from vtkmodules.vtkCommonDataModel import vtkImageData
from vtkmodules.vtkIOXML import vtkXMLImageDataReader
from vtkmodules.vtkCommonCore import vtkFloatArray

reader = vtkXMLImageDataReader()
reader.SetFileName(T.DATA + "/figure3.vti")
reader.Update()
src = reader.GetOutput()
plain = vtkImageData()
plain.SetDimensions(src.GetDimensions())
both = src.GetPointData().GetArray("channels")
for k, name in enumerate(names):
    arr = vtkFloatArray()
    arr.SetName(name)
    arr.SetNumberOfTuples(both.GetNumberOfTuples())
    arr.CopyComponent(0, both, k)
    plain.GetPointData().AddArray(arr)
checks.check(plain.GetPointData().GetScalars() is None, "the test data has no active scalars")
path = T.write_vti(plain)
simple.Hide(weather, view)
separate = simple.XMLImageDataReader(FileName=[path])
srep = T.show(separate, view)
srep.ChannelArrays = names
view.CameraPosition = [150.0, 110.0, 190.0]
view.CameraFocalPoint = [31.5, 31.5, 31.5]
view.CameraViewUp = [0.0, 1.0, 0.0]
T.render_converged(view, srep)
image = T.capture(view)
os.remove(path)
# The same channels through the Extract Component pipeline, same camera.
simple.Hide(separate, view)
simple.Show(split, view)
T.render_converged(view, rep)
reference = T.capture(view)
diff = np.abs(image.astype(int) - reference.astype(int))
checks.check(T.info(srep, "TotalSamples") == 32 and diff.max() <= 2,
             "separate arrays without active scalars render (max |diff| to the split arrays %d)" % diff.max())

# The data stays on the device across ParaView's frames (the representation
# shallow-copies its input every update): camera moves, refinement and a
# transfer-function edit upload nothing. On the CPU backend nothing is ever
# uploaded (the data are read in place).
mapper = T.local_mapper(rep)
uploads = mapper.GetNumberOfDataUploads()
on_gpu = mapper.GetActiveBackendName() == "cuda"
checks.check(uploads >= 3 if on_gpu else uploads == 0,
             "%s: %d channel uploads so far" % (mapper.GetActiveBackendName(), uploads))
for _ in range(30):
    view.CameraPosition = [p + 0.5 for p in view.CameraPosition]
    simple.Render(view)
simple.GetOpacityTransferFunction("green").Points = [0.0, 0.0, 0.5, 0.0, 1.0, 0.8, 0.5, 0.0]
simple.Render(view)
checks.check(mapper.GetNumberOfDataUploads() == uploads,
             "30 ParaView frames and a transfer-function edit upload nothing more (%d, then %d)"
             % (uploads, mapper.GetNumberOfDataUploads()))
print("ParaView frames on %s: %d uploads, %.1f MiB on the device" % (
    mapper.GetActiveBackendName(), mapper.GetNumberOfDataUploads(), mapper.GetDeviceMemory() / 2**20))


# Bad input: a clear status, nothing drawn, no crash.
def status_after_render(r):
    simple.Render(view)
    return T.info(r, "ChannelStatus"), T.info(r, "TotalSamples")


simple.Hide(split, view)
bad = T.show(split, view)
bad.ChannelArrays = []
st, total = status_after_render(bad)
checks.check(st == "no channels selected" and total == 0, "no channels: '%s', %d samples" % (st, total))
bad.ChannelSource = "Components of One Array"
bad.ChannelComponentsArray = "no_such_array"
st, total = status_after_render(bad)
checks.check("no point array named 'no_such_array'" in st and total == 0, "a missing array: '%s'" % st)
simple.Hide(split, view)

import numpy
from vtkmodules.util.numpy_support import numpy_to_vtk

many = vtkImageData()
many.SetDimensions(6, 6, 6)
values = numpy_to_vtk(numpy.random.default_rng(1).random((216, 33)).astype(numpy.float32), deep=True)
values.SetName("many")
many.GetPointData().AddArray(values)
path = T.write_vti(many)
many_reader = simple.XMLImageDataReader(FileName=[path])
mrep = T.show(many_reader, view)
mrep.ChannelSource = "Components of One Array"
mrep.ChannelComponentsArray = "many"
st, total = status_after_render(mrep)
os.remove(path)
checks.check("33 channels; at most 32" in st and total == 0, "33 channels: '%s'" % st)

checks.finish()
