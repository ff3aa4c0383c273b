"""Bad input to the mappers gets a true, clear message or documented
behaviour (Documentation/user-guide/numerical-limits.md):

- NaN in every double setter of vtkMultiChannelVolumeMapper and
  vtkMultiChannelRayMarchMapper: an error naming the setter, the value kept;
- a volume too small for VTK's camera (spacing 1e-25) or too far from the
  origin for double precision (origin 1e30): an error saying so, instead of
  a blank image or "the camera's projection is singular";
- a transfer function without points: a warning naming the channel;
- a channel array of strings: a message saying it holds no numbers;
- +Inf, -Inf and NaN voxels: nearest interpolation reads +-Inf as the ends
  of the transfer function, linear interpolation makes every sample that
  reads one transparent, as NaN.
"""

import math
import os
import re
import sys

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))

import numpy as np

import vtkmodules.vtkRenderingOpenGL2  # noqa: F401 (OpenGL render window)
from vtkmodules.util.numpy_support import numpy_to_vtk
from vtkmodules.vtkCommonCore import vtkStringArray
from vtkmodules.vtkCommonDataModel import vtkImageData, vtkPiecewiseFunction
from vtkmodules.vtkRenderingCore import vtkColorTransferFunction, vtkVolumeProperty

from mcvol import vtkMultiChannelRayMarchMapper, vtkMultiChannelVolumeMapper
from mcvolTesting import Checker, ErrorCatcher, capture_rgba, offscreen_view, use_test_backend

t = Checker()
NAN = float("nan")

# ---- NaN in every double setter ---------------------------------------------------
SETTERS = {
    vtkMultiChannelVolumeMapper: [
        "InteractiveUpdateRate", "MinimumSamplesPerVoxel", "MarchSamplesPerVoxel", "InteractiveFrameTime",
        "TargetError", "Shininess", "DeviationWeight", "OcclusionWeight", "ClutterWeight", "ImportanceEmphasis",
        "ImportanceMergeDistance", "MemoryBudget", "LightIntensityScale",
        "LightingStandInMemoryLimit", "ShadowCacheSpacing"],
    vtkMultiChannelRayMarchMapper: ["StepSize", "TerminationTransmittance"],
}


def double_setters(cls, base):
    """The Set...(double) methods `cls` declares beyond `base`, from the
    C++ signatures in the wrapped methods' documentation."""
    pattern = re.compile(r"C\+\+: (?:virtual )?void (Set\w+)\((?:double|float) \w*\)")
    inherited = set(dir(base))
    found = set()
    for name in dir(cls):
        if name.startswith("Set") and name not in inherited:
            found.update(m.group(1)[3:] for m in pattern.finditer(getattr(cls, name).__doc__ or ""))
    return found


# The lists hold every double setter the classes declare.
for cls, base in ((vtkMultiChannelVolumeMapper, vtkMultiChannelVolumeMapper.__bases__[0]),
                  (vtkMultiChannelRayMarchMapper, vtkMultiChannelVolumeMapper)):
    declared = double_setters(cls, base)
    t.check(declared == set(SETTERS[cls]), "%s: double setters not checked for NaN: %s; listed but not found: %s"
            % (cls.__name__, sorted(declared - set(SETTERS[cls])), sorted(set(SETTERS[cls]) - declared)))
for cls, names in SETTERS.items():
    # Every public Set...(double) of the class is listed (checked above; the
    # channel and vector setters are checked below).
    for name in names:
        mapper = cls()
        errors = ErrorCatcher(mapper)
        before = getattr(mapper, "Get" + name)()
        getattr(mapper, "Set" + name)(NAN)
        after = getattr(mapper, "Get" + name)()
        t.check(after == before, "%s.Set%s(NaN) keeps %g (got %g)" % (cls.__name__, name, before, after))
        t.check(len(errors.errors) == 1 and "Set" + name in errors.errors[0] and "NaN" in errors.errors[0],
                "%s.Set%s(NaN) is an error naming the setter: %s" % (cls.__name__, name, errors.errors))
for cls in SETTERS:
    mapper = cls()
    errors = ErrorCatcher(mapper)
    for call, getter in (
        (lambda m: m.SetMixWeight(0, NAN), lambda m: m.GetMixWeight(0)),
        (lambda m: m.SetChannelAlbedo(0, NAN), lambda m: m.GetChannelAlbedo(0)),
        (lambda m: m.SetChannelAnisotropy(0, NAN), lambda m: m.GetChannelAnisotropy(0)),
        (lambda m: m.SetChannelScalarOpacityUnitDistance(0, NAN), lambda m: m.GetChannelScalarOpacityUnitDistance(0)),
        (lambda m: m.SetAmbientRadiance(NAN, 0.2, 0.2), lambda m: m.GetAmbientRadiance()[0]),
        (lambda m: m.SetAmbientRadiance(0.2, math.inf, 0.2), lambda m: m.GetAmbientRadiance()[1]),
        (lambda m: m.SetAmbientRadiance(0.2, 0.2, -1.0), lambda m: m.GetAmbientRadiance()[2]),
    ):
        before, count = getter(mapper), len(errors.errors)
        call(mapper)
        t.check(getter(mapper) == before and len(errors.errors) == count + 1,
                "%s: a NaN, Inf or negative channel/lighting value is an error and is ignored (%s)"
                % (cls.__name__, errors.errors[count:]))
# Values in range still go through, out of range ones are clamped.
mapper = vtkMultiChannelVolumeMapper()
mapper.SetTargetError(0.01)
mapper.SetInteractiveFrameTime(1e9)
t.check(mapper.GetTargetError() == 0.01 and mapper.GetInteractiveFrameTime() == 3600.0,
        "valid values are set and large ones clamped (%g, %g)" % (mapper.GetTargetError(),
                                                                  mapper.GetInteractiveFrameTime()))


# ---- Scenes -----------------------------------------------------------------------------
def render(values, spacing=1.0, origin=0.0, interpolation=1, opacity_points=((0, 0.0), (1, 0.9)),
           color_points=((0, 1, 1, 1), (1, 1, 0, 0)), string_channel=False):
    n = round(len(values) ** (1 / 3))
    image = vtkImageData()
    image.SetDimensions(n, n, n)
    image.SetSpacing(spacing, spacing, spacing)
    image.SetOrigin(origin, origin, origin)
    scalars = numpy_to_vtk(np.asarray(values, np.float32), deep=True)
    scalars.SetName("density")
    image.GetPointData().SetScalars(scalars)
    mapper = vtkMultiChannelVolumeMapper()
    mapper.SetInputData(image)
    use_test_backend(mapper)
    if string_channel:
        names = vtkStringArray()
        names.SetName("labels")
        names.SetNumberOfValues(n ** 3)
        image.GetPointData().AddArray(names)
        mapper.AddChannelArray("labels")
    prop = vtkVolumeProperty()
    ctf = vtkColorTransferFunction()
    for p in color_points:
        ctf.AddRGBPoint(*p)
    otf = vtkPiecewiseFunction()
    for p in opacity_points:
        otf.AddPoint(*p)
    prop.SetColor(ctf)
    prop.SetScalarOpacity(otf)
    prop.SetScalarOpacityUnitDistance(spacing)
    prop.SetInterpolationType(interpolation)
    errors = ErrorCatcher(mapper)
    window = offscreen_view(mapper, prop, (32, 32))
    rgba = capture_rgba(window)
    return rgba, errors, mapper


N = 12
ones = np.ones(N ** 3, np.float32)

# Spacing: 1e-20 renders, 1e-25 is refused with the reason; 1e30 renders.
for spacing in (1e-20, 1e30):
    rgba, errors, mapper = render(ones, spacing=spacing)
    t.check(rgba[..., 3].max() == 255 and not errors.errors,
            "spacing %g renders the volume (alpha %d, %s)" % (spacing, rgba[..., 3].max(), errors.errors))
rgba, errors, mapper = render(ones, spacing=1e-25)
t.check(any("world units across" in e and "nothing would be drawn" in e for e in errors.errors),
        "spacing 1e-25 is refused with the reason: %s" % errors.errors)
t.check(rgba[..., 3].max() == 0, "spacing 1e-25: nothing is drawn")
# Origin: 1e12 renders; 1e30 is refused as too far, not as a singular camera.
rgba, errors, mapper = render(ones, origin=1e12)
t.check(rgba[..., 3].max() == 255 and not errors.errors, "origin 1e12 renders the volume (%s)" % errors.errors)
for origin in (1e14, 1e30):
    rgba, errors, mapper = render(ones, origin=origin)
    t.check(any("too far from the world origin" in e for e in errors.errors)
            and not any("singular" in e for e in errors.errors),
            "origin %g is refused as too far from the origin: %s" % (origin, errors.errors))

# Empty transfer functions: a warning naming the channel.
rgba, errors, mapper = render(ones, opacity_points=())
t.check(any("Channel 0's scalar opacity function has no points" in w for w in errors.warnings),
        "an opacity function without points is a warning: %s" % errors.warnings)
t.check(rgba[..., 3].max() == 0, "an opacity function without points leaves the channel transparent")
rgba, errors, mapper = render(ones, color_points=())
t.check(any("Channel 0's colour function has no points" in w for w in errors.warnings),
        "a colour function without points is a warning: %s" % errors.warnings)
rgba, errors, mapper = render(ones)
t.check(not errors.warnings, "functions with points give no warning (%s)" % errors.warnings)

# A channel array of strings.
rgba, errors, mapper = render(ones, string_channel=True)
t.check(any('"labels" is a point array of vtkStringArray, which holds no numbers' in e for e in errors.errors),
        "a string channel array is named as such: %s" % errors.errors)

# +-Inf and NaN voxels: a 6^3 box of them inside transparent zeros, against a
# box of 1 (the table's top, opacity 0.9).
def box(fill):
    v = np.zeros((N, N, N), np.float32)
    v[3:9, 3:9, 3:9] = fill
    return v.ravel()


NEAREST, LINEAR = 0, 1
top = {}
for interpolation in (NEAREST, LINEAR):
    top[interpolation], _, _ = render(box(1.0), interpolation=interpolation)
    t.check(top[interpolation][16, 16, 3] == 255, "a box of 1 is opaque at the centre")
inf_nearest, _, _ = render(box(math.inf), interpolation=NEAREST)
t.check(np.array_equal(inf_nearest, top[NEAREST]),
        "nearest: a box of +Inf renders as the table's top end, pixel for pixel as a box of 1")
for fill, label in ((-math.inf, "-Inf"), (math.nan, "NaN")):
    rgba, errors, _ = render(box(fill), interpolation=NEAREST)
    t.check(rgba[..., 3].max() == 0 and not errors.errors,
            "nearest: a box of %s is transparent (the table's bottom end, opacity 0; max alpha %d)"
            % (label, rgba[..., 3].max()))
for fill, label in ((math.inf, "+Inf"), (-math.inf, "-Inf"), (math.nan, "NaN")):
    rgba, errors, _ = render(box(fill), interpolation=LINEAR)
    # A linear sample mixing an infinity with anything is NaN: transparent.
    # Only samples on exact voxel planes (weight 0 on the infinite corner)
    # escape; they are a sliver of the rays.
    t.check(rgba[..., 3].mean() < 0.02 * top[LINEAR][..., 3].mean() and not errors.errors,
            "linear: a box of %s is transparent (mean alpha %.2f against %.2f for a box of 1)"
            % (label, rgba[..., 3].mean(), top[LINEAR][..., 3].mean()))

t.finish()
