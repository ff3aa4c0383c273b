"""pvpython: editing a channel the ways a GUI user does (paraview.md, "Editing
a channel's transfer functions").

- Edit Channel (ActiveChannel) on a representation coloured by Solid Color
  connects the colour map editor: the representation colours by the
  channel's array (the editor's "Array Name"), with the channel's colour and
  opacity functions, whose range is the range the channel was first shown
  with (mcvol-render's robust range of its values).
- A visible scalar bar moves to the edited channel, titled with its name,
  and the previous channel's bar is hidden.
- ColorBy on a channel's array reaches the same functions as
  GetColorTransferFunction, and an edit of them changes that channel in the
  image.
- Channels from the components of one array: Edit Channel colours by that
  array with the function "array:k", which picks component k, so its range
  is that component's robust range.
- A float channel of more than 2^24 values gets the percentiles of a
  stratified sample (so that showing billions of voxels does not copy and
  select them all): within 0.01 percentile points of numpy's percentiles of
  every value (the sample's rank error is about 0.0008 points).
"""
import numpy as np
from paraview import servermanager as sm
from paraview import simple

from mcvol.scenefile.assemble import auto_range

import mcvolParaViewTesting as T

checks = T.Checks()
T.load_plugin()

# Channels from three arrays with different ranges (their own presets,
# fitted to each range when first shown).
wavelet = simple.Wavelet(WholeExtent=[0, 31, 0, 31, 0, 31])
calc = simple.Calculator(Input=wavelet, ResultArrayName="half", Function="RTData/2")
calc2 = simple.Calculator(Input=calc, ResultArrayName="offset", Function="RTData+100")
view = T.make_view((160, 160))
view.CameraPosition = [80.0, 60.0, 95.0]
view.CameraFocalPoint = [15.5, 15.5, 15.5]
rep = T.show(calc2, view)
rep.ColorArrayName = ["POINTS", ""]  # Solid Color, as after Show
names = ["RTData", "half", "offset"]
rep.ChannelArrays = names
simple.Render(view)

data = sm.Fetch(calc2)
ranges = {n: auto_range(data.GetPointData().GetArray(n), 0) for n in names}
for k, name in enumerate(names):
    rep.ActiveChannel = k
    lut = simple.GetColorTransferFunction(name)
    pwf = simple.GetOpacityTransferFunction(name)
    color_array = list(rep.ColorArrayName)
    lo, hi = lut.RGBPoints[0], lut.RGBPoints[-4]
    checks.check(color_array == ["POINTS", name], "Edit Channel %d colours by %r (%s)" % (k, name, color_array))
    checks.check(rep.LookupTable == lut and rep.ScalarOpacityFunction == pwf,
                 "Edit Channel %d: the editor's functions are %r's" % (k, name))
    checks.check(abs(lo - ranges[name][0]) < 1e-3 and abs(hi - ranges[name][1]) < 1e-3,
                 "Edit Channel %d: range %.3f..%.3f is the channel's robust range %.3f..%.3f" % (k, lo, hi, *ranges[name]))

# The scalar bar follows the edited channel.
rep.ActiveChannel = 0
rep.SetScalarBarVisibility(view, True)
bar0 = simple.GetScalarBar(simple.GetColorTransferFunction("RTData"), view)
checks.check(bar0.Visibility == 1, "the scalar bar of channel 0 is shown")
rep.ActiveChannel = 2
bar2 = simple.GetScalarBar(simple.GetColorTransferFunction("offset"), view)
checks.check(bar2.Visibility == 1 and bar0.Visibility == 0 and bar2.Title == "offset",
             "Edit Channel 2 moves the scalar bar to 'offset' (visible %d, title %r; channel 0's visible %d)"
             % (bar2.Visibility, bar2.Title, bar0.Visibility))

# ColorBy as a GUI user colours by a channel, then edits its colour: that
# channel's colour changes in the image, and only its functions change.
rep.ChannelBlendMode = "Density"
simple.ColorBy(rep, ("POINTS", "half"))
checks.check(rep.LookupTable == simple.GetColorTransferFunction("half"),
             "ColorBy 'half' shows the functions of channel 'half'")
# (Three renders each: the comparison needs no converged image.)
for _ in range(3):
    simple.Render(view)
before = T.capture(view).astype(float)
lut = simple.GetColorTransferFunction("half")
lo, hi = lut.RGBPoints[0], lut.RGBPoints[-4]
lut.RGBPoints = [lo, 0.0, 1.0, 0.0, hi, 0.0, 1.0, 0.0]  # pure green
simple.GetOpacityTransferFunction("half").Points = [lo, 0.5, 0.5, 0.0, hi, 0.5, 0.5, 0.0]
for _ in range(3):
    simple.Render(view)
after = T.capture(view).astype(float)
green_gain = after[..., 1].mean() - before[..., 1].mean()
checks.check(green_gain > 5.0, "editing channel 'half' to opaque green makes the image greener (+%.1f)" % green_gain)

# Components of one array.
vec = simple.Calculator(Input=wavelet, ResultArrayName="stains",
                        Function="RTData*iHat + (RTData/2)*jHat + (RTData+100)*kHat")
comp = T.show(vec, view)
simple.Hide(calc2, view)
comp.ColorArrayName = ["POINTS", ""]
comp.ChannelSource = "Components of One Array"
comp.ChannelComponentsArray = "stains"
simple.Render(view)
comp.ActiveChannel = 1
lut1 = simple.GetColorTransferFunction("stains:1")
crange = auto_range(sm.Fetch(vec).GetPointData().GetArray("stains"), 1)
checks.check(list(comp.ColorArrayName) == ["POINTS", "stains"] and comp.LookupTable == lut1,
             "Edit Channel 1 of a components array colours by 'stains' with 'stains:1' (%s)" % list(comp.ColorArrayName))
checks.check(lut1.VectorMode == "Component" and lut1.VectorComponent == 1,
             "the function 'stains:1' picks component 1 (%s %d)" % (lut1.VectorMode, lut1.VectorComponent))
checks.check(abs(lut1.RGBPoints[0] - crange[0]) < 1e-3 and abs(lut1.RGBPoints[-4] - crange[1]) < 1e-3,
             "its range %.2f..%.2f is component 1's robust range %.2f..%.2f" % (lut1.RGBPoints[0], lut1.RGBPoints[-4], *crange))

# More than 2^24 values: the sampled percentiles (lognormal values, seeded).
from vtkmodules.util.numpy_support import numpy_to_vtk  # noqa: E402
from vtkmodules.vtkCommonDataModel import vtkImageData  # noqa: E402

# Sorted, so that a sample of only part of the array would miss an end.
values = np.sort(np.random.default_rng(5).lognormal(0.0, 1.5, 256 * 256 * 257).astype(np.float32))
big = vtkImageData()
big.SetDimensions(256, 256, 257)
arr = numpy_to_vtk(values, deep=1)
arr.SetName("big")
big.GetPointData().AddArray(arr)
producer = simple.TrivialProducer()
producer.GetClientSideObject().SetOutput(big)
simple.Hide(vec, view)
brep = T.show(producer, view)
brep.ChannelArrays = ["big"]
simple.Render(view)
line = [l for l in T.info(brep, "ChannelDefaultRanges").splitlines() if l.startswith("big\t")]
lo, hi = (float(x) for x in line[0].split("\t")[2:]) if line else (np.nan, np.nan)
v = values.astype(np.float64)
checks.check(np.percentile(v, 0.09) <= lo <= np.percentile(v, 0.11),
             "2^24+ values: low end %.5g within numpy's 0.09..0.11 percentiles %.5g..%.5g"
             % (lo, np.percentile(v, 0.09), np.percentile(v, 0.11)))
checks.check(np.percentile(v, 99.89) <= hi <= np.percentile(v, 99.91),
             "2^24+ values: high end %.5g within numpy's 99.89..99.91 percentiles %.5g..%.5g"
             % (hi, np.percentile(v, 99.89), np.percentile(v, 99.91)))
checks.finish()
