"""pvpython: the visibility optimization's properties reach the mapper.

A red occluder blob lies in front of a green target blob. Every property of
the "Visibility Optimization" group changes the image when it should and
leaves it identical, pixel for pixel, when it should not (optimization off,
or no channel important); unchanged importance does not restart the image;
importance on the target raises its share of the image, importance on the
occluder does not; channels from the components of one array get the same
importance as channels from separate arrays."""
import os

import numpy as np
from paraview import simple
from vtkmodules.vtkCommonDataModel import vtkImageData
from vtkmodules.util.numpy_support import numpy_to_vtk

import mcvolParaViewTesting as T

checks = T.Checks()
T.load_plugin()

# ---- Scene: occluder in front of the target, as seen from +z -----------------
N = 32
z, y, x = np.mgrid[0:N, 0:N, 0:N].astype(np.float32)  # x varies fastest, as VTK's point order


def blob(center, radius):
    r = np.sqrt((x - center[0]) ** 2 + (y - center[1]) ** 2 + (z - center[2]) ** 2)
    return np.clip((radius - r) / 3.0 + 0.5, 0.0, 1.0).astype(np.float32)


occluder = blob((15.5, 15.5, 22.0), 9.0)
target = blob((15.5, 15.5, 9.0), 6.0)
image = vtkImageData()
image.SetDimensions(N, N, N)
for name, values in [("occluder", occluder), ("target", target)]:
    array = numpy_to_vtk(values.ravel(), deep=True)
    array.SetName(name)
    image.GetPointData().AddArray(array)
both = numpy_to_vtk(np.stack([occluder.ravel(), target.ravel()], axis=1), deep=True)
both.SetName("both")
image.GetPointData().AddArray(both)
path = T.write_vti(image)
source = simple.XMLImageDataReader(FileName=[path])

names = ["occluder", "target"]
colors = [(1.0, 0.1, 0.1), (0.1, 1.0, 0.1)]
view = T.make_view((96, 96))
view.CameraPosition = [15.5, 15.5, 110.0]
view.CameraFocalPoint = [15.5, 15.5, 15.5]
view.CameraViewUp = [0.0, 1.0, 0.0]
rep = T.show(source, view)
rep.ChannelArrays = names
T.set_channel_functions(names, colors=colors, opacity=0.35)


def render():
    T.render_converged(view, rep)
    return T.capture(view)


def differs(a, b):
    return np.abs(a.astype(int) - b.astype(int)).mean()


def green_share(img):
    img = img.astype(float)
    return img[..., 1].sum() / max(img[..., 0].sum() + img[..., 1].sum(), 1.0)


off = render()
checks.check((off.sum(axis=2) > 30).mean() > 0.1, "the scene shows the volume")
share_off = green_share(off)
checks.check(share_off < 0.2, "without the optimization the occluder hides the target (green share %.3f)" % share_off)

reference = off


def expect(label, change, should_change):
    """Applies `change` and compares the converged image with `reference`
    (rendering is deterministic: same seed, same samples)."""
    change()
    d = differs(render(), reference)
    if should_change:
        checks.check(d > 0.0, "%s changes the image (mean |diff| %.4f)" % (label, d))
    else:
        checks.check(d == 0.0, "%s leaves the image unchanged (mean |diff| %.4f)" % (label, d))


def current(name):
    value = getattr(rep, name)
    if hasattr(value, "__len__") and not isinstance(value, str):
        return list(value)
    return value


def expect_property(name, value, should_change, label=None):
    """Sets a property, compares, sets it back and checks the image is back."""
    saved = current(name)
    expect(label or name, lambda: setattr(rep, name, value), should_change)
    setattr(rep, name, saved)
    checks.check(differs(render(), reference) == 0.0, "%s: restoring it restores the image" % (label or name))


# ---- Optimization off: nothing of it matters ---------------------------------
WEIGHTS = [("DeviationWeight", 3.0), ("OcclusionWeight", 10.0), ("ClutterWeight", 90.0),
           ("ImportanceEmphasis", 0.0), ("ImportanceSamples", 5),
           # Far below the automatic distance (two strata): samples stop merging
           # into segments. A larger one changes nothing in this scene, whose
           # rays cross one important region, sampled densely.
           ("ImportanceMergeDistance", 0.001)]
rep.ChannelImportanceLevels = [0.0, 1.0]
rep.ChannelImportanceThresholds = [0.0, 0.5]
for name, value in WEIGHTS + [("OptimizeLightRays", 0), ("LightRayImportanceSamples", 20),
                              ("ChannelImportanceThresholds", [0.0, 0.9]), ("ChannelImportanceLevels", [1.0, 1.0])]:
    expect_property(name, value, False, "%s with the optimization off" % name)

# ---- On, but no channel important: the unoptimized image ---------------------
rep.VisibilityOptimization = 1
for label, levels, thresholds in [
    ("levels 0", [0.0, 0.0], [0.5, 0.5]),
    ("no levels (missing entries are 0)", [], [0.5, 0.5]),
    ("no thresholds (missing entries are none)", [1.0, 1.0], []),
    ("NaN thresholds", [1.0, 1.0], [float("nan"), float("nan")]),
    ("levels below 1/8 (snapped to 0)", [0.1, 0.1], [0.5, 0.5]),
]:
    expect("optimization on with " + label,
           lambda: (setattr(rep, "ChannelImportanceLevels", levels),
                    setattr(rep, "ChannelImportanceThresholds", thresholds)), False)

# ---- On, target important ----------------------------------------------------
expect("importance on the target (level 1 where target >= 0.5)",
       lambda: (setattr(rep, "ChannelImportanceLevels", [0.0, 1.0]),
                setattr(rep, "ChannelImportanceThresholds", [0.0, 0.5])), True)
on = render()
share_on = green_share(on)
checks.check(share_on > share_off + 0.1,
             "importance on the target raises its share of the image (green share %.3f -> %.3f)" % (share_off, share_on))
checks.check(T.info(rep, "ImportanceMemory") > 0, "the segment lists are allocated (%g bytes)"
             % T.info(rep, "ImportanceMemory"))
reference = on

# Unchanged importance keeps refining instead of starting over.
total = T.info(rep, "TotalSamples")
for label, change in [
    ("another render", lambda: None),
    ("a new threshold of a channel without importance", lambda: setattr(rep, "ChannelImportanceThresholds", [0.3, 0.5])),
    ("a level that snaps to the same value", lambda: setattr(rep, "ChannelImportanceLevels", [0.1, 0.95])),
    ("the same lists sent again", lambda: (setattr(rep, "ChannelImportanceLevels", []),
                                           setattr(rep, "ChannelImportanceLevels", [0.0, 1.0]))),
]:
    change()
    simple.Render(view)
    checks.check(T.info(rep, "Converged") == 1 and T.info(rep, "TotalSamples") == total,
                 "%s does not restart the image (%d samples)" % (label, T.info(rep, "TotalSamples")))
rep.ChannelImportanceThresholds = [0.0, 0.5]
checks.check(differs(render(), reference) == 0.0, "the image is still the optimized one")
rep.ChannelImportanceThresholds = [0.0, 0.8]
simple.Render(view)
checks.check(T.info(rep, "TotalSamples") == 8, "a new threshold of the important channel restarts the image")
rep.ChannelImportanceThresholds = [0.0, 0.5]

for name, value in WEIGHTS + [("ChannelImportanceThresholds", [0.0, 0.9]), ("ChannelImportanceLevels", [0.0, 0.5])]:
    expect_property(name, value, True, "%s with the optimization on" % name)
# Light rays exist only with Shade on.
for name, value in [("OptimizeLightRays", 0), ("LightRayImportanceSamples", 20)]:
    expect_property(name, value, False, "%s with Shade off" % name)
rep.Shade = 1
reference = render()
expect_property("LightRayImportanceSamples", 20, True, "LightRayImportanceSamples with Shade on")
expect_property("OptimizeLightRays", 0, True, "OptimizeLightRays with Shade on")
rep.OptimizeLightRays = 0
reference = render()
expect_property("LightRayImportanceSamples", 20, False, "LightRayImportanceSamples with OptimizeLightRays off")
rep.OptimizeLightRays = 1
rep.Shade = 0
reference = on

# Importance on the occluder instead: the target gains nothing.
rep.ChannelImportanceLevels = [1.0, 0.0]
rep.ChannelImportanceThresholds = [0.5, 0.0]
share_occluder = green_share(render())
checks.check(share_occluder <= share_off + 0.01,
             "importance on the occluder does not raise the target's share (green share %.3f)" % share_occluder)

occluder_important = render()

# ---- Importance functions, edited like opacity functions ----------------------
# "Channel 2 Importance" as the same step (0 below 0.5, 1 from 0.5 up) that the
# lists make: the same table, so the same image, bit for bit.
below = float(np.nextafter(0.5, -np.inf))
step = [below, 0.0, 0.5, 0.0, 0.5, 1.0, 0.5, 0.0]
function2 = rep.ChannelImportanceFunction2
checks.check(max(list(function2.Points)[1::4]) == 0.0, "an importance function starts at 0 everywhere")
rep.ChannelImportanceLevels = []
rep.ChannelImportanceThresholds = []
function2.Points = step
d = differs(render(), on)
checks.check(d == 0.0, "a step importance function gives the image of the same step from the lists "
             "(mean |diff| %.4f)" % d)
# The function wins over the lists; a function that snaps to 0 leaves them be.
rep.ChannelImportanceLevels = [0.0, 0.5]
rep.ChannelImportanceThresholds = [0.0, 0.9]
d = differs(render(), on)
checks.check(d == 0.0, "channel 2's function wins over its list entries (mean |diff| %.4f)" % d)
rep.ChannelImportanceLevels = [1.0, 0.0]
rep.ChannelImportanceThresholds = [0.5, 0.0]
function2.Points = [0.0, 0.1, 0.5, 0.0, 1.0, 0.1, 0.5, 0.0]
d = differs(render(), occluder_important)
checks.check(d == 0.0, "a function below 1/8 everywhere (snapped to 0) leaves the lists in charge "
             "(mean |diff| %.4f)" % d)
rep.ChannelImportanceLevels = []
rep.ChannelImportanceThresholds = []
function2.Points = step
render()
total = T.info(rep, "TotalSamples")
simple.Render(view)
checks.check(T.info(rep, "TotalSamples") > total or T.info(rep, "Converged") == 1,
             "an unchanged function keeps refining")
function2.Points = [0.7999, 0.0, 0.5, 0.0, 0.8, 1.0, 0.5, 0.0]
simple.Render(view)
checks.check(T.info(rep, "TotalSamples") == 8, "editing the function restarts the image (%d samples)"
             % T.info(rep, "TotalSamples"))
d = differs(render(), on)
checks.check(d > 0.0, "a higher threshold in the function changes the image (mean |diff| %.4f)" % d)
# Channel 1's function: importance on the occluder, as from the lists.
function2.Points = [0.0, 0.0, 0.5, 0.0, 1.0, 0.0, 0.5, 0.0]
rep.ChannelImportanceFunction1.Points = step
d = differs(render(), occluder_important)
checks.check(d == 0.0, "channel 1's function reaches channel 1 (mean |diff| %.4f)" % d)
rep.ChannelImportanceFunction1.Points = [0.0, 0.0, 0.5, 0.0, 1.0, 0.0, 0.5, 0.0]

# Channels from the components of one array: component k is channel k.
rep.ChannelImportanceLevels = [0.0, 1.0]
rep.ChannelImportanceThresholds = [0.0, 0.5]
simple.Hide(source, view)
# Another reader: Show() of the same source would return the same representation.
comp = T.show(simple.XMLImageDataReader(FileName=[path]), view)
comp.ChannelSource = "Components of One Array"
comp.ChannelComponentsArray = "both"
T.set_channel_functions(["both:0", "both:1"], colors=colors, opacity=0.35)
comp.VisibilityOptimization = 1
comp.ChannelImportanceLevels = [0.0, 1.0]
comp.ChannelImportanceThresholds = [0.0, 0.5]
T.render_converged(view, comp)
d = np.abs(T.capture(view).astype(int) - on.astype(int))
checks.check(d.max() <= 2, "components of one array get the same importance as separate arrays (max |diff| %d)"
             % d.max())

os.remove(path)
checks.finish()
