"""pvpython: every property of the representation reaches the mapper: the
image changes when the property changes what is drawn, and stays the same,
pixel for pixel, when it does not (same seed, same samples)."""
import numpy as np
from paraview import simple

import mcvolParaViewTesting as T

checks = T.Checks()
T.load_plugin()

# With Shade on the view's light lights the volume; with Shade off the
# volume is emission-absorption only.
split, view, rep, names = T.figure3_split_scene()


def image():
    T.render_converged(view, rep)
    return T.capture(view)


def differs(a, b):
    return np.abs(a.astype(int) - b.astype(int)).mean()


reference = image()
checks.check((reference.sum(axis=2) > 30).mean() > 0.05, "the reference image shows the volume")


def expect(label, change, should_change, restore=None):
    """Applies `change`, renders, compares with the current reference."""
    global reference
    change()
    img = image()
    d = differs(img, reference)
    if should_change:
        # Rendering is deterministic (same seed and samples: the "unchanged"
        # cases differ by exactly 0), so any difference comes from the change.
        checks.check(d > 0.0, "%s changes the image (mean |diff| %.3f)" % (label, d))
    else:
        checks.check(d == 0.0, "%s leaves the image unchanged (mean |diff| %.3f)" % (label, d))
    if restore:
        restore()
        back = image()
        checks.check(differs(back, reference) == 0.0, "%s: restoring it restores the image" % label)


def setter(name, value):
    return lambda: setattr(rep, name, value)


def current(name):
    value = getattr(rep, name)
    if hasattr(value, "__len__") and not isinstance(value, str):
        return list(value)
    return value


def expect_property(name, value, should_change, label=None):
    """Sets a property, compares, and sets it back to what it was."""
    saved = current(name)
    expect(label or name, setter(name, value), should_change, setter(name, saved))


# Frame Time Budget: ParaView's default keeps interaction fluid (a budget,
# not a fixed batch); set, it reaches the mapper: once the cost is measured a
# render takes more than Samples Per Render (8) samples, up to Maximum Total
# Samples (32), and the finished image is the same 8-bit image (within 1 level:
# the float mean rounds differently).
wavelet = simple.Wavelet()
other = simple.Show(wavelet, view)
other.SetRepresentationType(T.REPRESENTATION)
default_budget = other.InteractiveFrameTime
simple.Hide(wavelet, view)
simple.Delete(wavelet)
checks.check(default_budget == 0.05, "the default frame time budget is 0.05 s (%g)" % default_budget)
rep.InteractiveFrameTime = 0.5
simple.Render(view)
simple.Render(view)
checks.check(T.info(rep, "TotalSamples") == 32, "a 0.5 s budget reaches 32 samples in two renders (%d)"
             % T.info(rep, "TotalSamples"))
T.render_converged(view, rep)
d = np.abs(T.capture(view).astype(int) - reference.astype(int)).max()
checks.check(d <= 1, "the budgeted image equals the fixed-batch one (max |diff| %d)" % d)
rep.InteractiveFrameTime = 0
reference = image()

expect_property("Seed", 8, True)
expect_property("SampleSequence", "Sobol", True)
expect_property("Estimator", "Expected Value", True)
# Minimum Samples Per Voxel: nothing with the collision estimator (show()
# pins it: an effect that is off costs nothing and changes nothing), a new
# image with the expected-value estimator.
expect_property("MinimumSamplesPerVoxel", 2.0, False, "MinimumSamplesPerVoxel with the collision estimator")
rep.Estimator = "Expected Value"
reference = image()
expect_property("MinimumSamplesPerVoxel", 2.0, True, "MinimumSamplesPerVoxel with the expected-value estimator")
rep.Estimator = "Collision"
reference = image()
# Automatic: a new image (expected value or the march instead of the pinned
# collision estimator), and the information property says which.
checks.check(T.info(rep, "ChosenEstimator") == "Collision", "ChosenEstimator with the collision estimator (%s)"
             % T.info(rep, "ChosenEstimator"))
expect("Estimator = Automatic", setter("Estimator", "Automatic"), True)
chosen = T.info(rep, "ChosenEstimator")
checks.check(chosen == "ExpectedValue" or chosen.startswith("UnbiasedMarch("),
             "ChosenEstimator with Estimator = Automatic (%s)" % chosen)
# March Control Variates: nothing with jittered pixels (the march takes the
# plain strata there), a new image at pixel centres (2 strata per voxel: the
# control variates by default, the plain strata with Never).
rep.Estimator = "Unbiased March"
reference = image()
expect_property("MarchControlVariates", "Never", False, "MarchControlVariates = Never, jittered pixels")
rep.PixelJitter = 0
reference = image()
expect_property("MarchControlVariates", "Never", True, "MarchControlVariates = Never, pixel centres")
rep.PixelJitter = 1
rep.Estimator = "Collision"
reference = image()
expect_property("MultiChannelInterpolation", "Cubic B-Spline", True)
expect_property("MultiChannelInterpolation", "Nearest", True)
# The override set to what the volume property already says (Linear) draws
# the image the property draws.
expect_property("MultiChannelInterpolation", "Linear", False, "MultiChannelInterpolation = the property's Linear")
expect_property("SamplesPerRender", 4, False, "SamplesPerRender (same total)")
expect_property("MaximumTotalSamples", 64, True)
expect_property("ChannelBlendMode", "Mix", True)
expect_property("MixWeights", [1.0, 0.0, 0.0], False, "MixWeights outside Mix")
expect_property("MixColorMode", "Equation 10", False, "MixColorMode outside Mix")
rep.ChannelBlendMode = "Mix"
reference = image()
expect_property("MixColorMode", "Equation 10", True, "MixColorMode in Mix")
rep.MixWeights = [1.0, 0.0, 0.0]
reference = image()
expect_property("MixWeights", [1.0, 0.2, 0.2], True, "MixWeights in Mix")
rep.MixWeights = []
rep.ChannelBlendMode = "Density"
reference = image()
expect_property("TrackingMethod", "N DDA", True)
expect_property("MacrocellSize", 2, True)
if rep.Backend == "CUDA":  # MCVOL_TEST_BACKEND=cuda: the other backend is the CPU
    expect_property("Backend", "CPU", True, "Backend CPU (from CUDA)")
else:
    expect_property("Backend", "Auto", T.info(rep, "BackendReport").startswith("CUDA"),
                    "Backend Auto (the CPU here, as before)")
expect_property("PixelJitter", 0, True)
expect_property("ScalarOpacityUnitDistance", 3.0 * current("ScalarOpacityUnitDistance"), True)
expect_property("InterpolationType", "Nearest", True)
expect_property("ChannelArrays", ["red", "green"], True)

# Transfer functions: editing one channel's opacity or colour changes the image.
pwf = simple.GetOpacityTransferFunction("green")
saved = list(pwf.Points)
expect("the green opacity function", lambda: setattr(pwf, "Points", [0.0, 0.0, 0.5, 0.0, 1.0, 0.9, 0.5, 0.0]), True,
       lambda: setattr(pwf, "Points", saved))
lut = simple.GetColorTransferFunction("blue")
saved = list(lut.RGBPoints)
expect("the blue colour function", lambda: setattr(lut, "RGBPoints", [0.0, 1, 1, 1, 1.0, 1, 1, 1]), True,
       lambda: setattr(lut, "RGBPoints", saved))
# A transfer function of an array that is not a channel changes nothing.
expect("an unrelated array's transfer function",
       lambda: setattr(simple.GetOpacityTransferFunction("channels"), "Points", [0, 1, 0.5, 0, 1, 1, 0.5, 0]), False)

# ActiveChannel only selects what the colour map editor edits.
expect("ActiveChannel", setter("ActiveChannel", 1), False)
checks.check(rep.LookupTable == simple.GetColorTransferFunction("green")
             and rep.ScalarOpacityFunction == simple.GetOpacityTransferFunction("green"),
             "ActiveChannel 1 puts the green channel's functions in LookupTable/ScalarOpacityFunction")

# Lighting: with Shade off nothing of it is simulated, so nothing changes.
for name, value in [("ShadowMode", "Delta Tracking"), ("ShadowMode", "Cached"), ("ShadowCacheSpacing", 4.0),
                    ("AmbientRadiance", [1.0, 0.0, 0.0]),
                    ("MaxScatteringDepth", 4), ("GradientShading", 1), ("Shininess", 5.0),
                    ("ChannelAlbedos", [0.2, 0.2, 0.2]), ("ChannelAnisotropies", [0.5, 0.5, 0.5])]:
    expect_property(name, value, False, "%s with Shade off" % name)
expect("Shade", setter("Shade", 1), True)
reference = image()
for name, value in [("ShadowMode", "None"), ("ShadowMode", "Cached"), ("AmbientRadiance", [1.0, 0.0, 0.0]),
                    ("MaxScatteringDepth", 4), ("GradientShading", 1), ("ChannelAlbedos", [0.2, 0.2, 0.2]),
                    ("ChannelAnisotropies", [0.6, 0.6, 0.6])]:
    expect_property(name, value, True, "%s with Shade on" % name)
# The cache's spacing matters only to cached shadows.
expect_property("ShadowCacheSpacing", 4.0, False, "ShadowCacheSpacing with ratio-tracking shadows")
rep.ShadowMode = "Cached"
reference = image()
expect_property("ShadowCacheSpacing", 4.0, True, "ShadowCacheSpacing with cached shadows")
rep.ShadowMode = "Ratio Tracking"
rep.Shade = 0
reference = image()

# Progressive refinement off: one trace of Samples Per Render per change.
rep.ProgressiveRefinement = 0
simple.Render(view)
first = T.info(rep, "TotalSamples")
simple.Render(view)
checks.check(first == 8 and T.info(rep, "TotalSamples") == 8 and T.info(rep, "Converged") == 1,
             "progressive refinement off: 8 samples per change, not refined further (%d)" % first)
rep.ProgressiveRefinement = 1
rep.MaximumTotalSamples = 0
for _ in range(5):
    simple.Render(view)
checks.check(T.info(rep, "TotalSamples") == 40 and T.info(rep, "Converged") == 0,
             "Maximum Total Samples 0: every render refines (%d after 5 renders)" % T.info(rep, "TotalSamples"))
# Estimated noise, next to the sample count: finite after some renders, the
# PSNR its 20 log10(1 / RMSE). Target Error (0: off, as show() sets it)
# stops the refinement once the estimate reaches it (after at least 16
# samples); TestParaViewProgress checks its default.
error, psnr = T.info(rep, "EstimatedError"), T.info(rep, "EstimatedPSNR")
checks.check(np.isfinite(error) and 0.0 < error < 0.5 and abs(psnr + 20.0 * np.log10(error)) < 1e-6,
             "Estimated Error %g and PSNR %g after 40 samples" % (error, psnr))
rep.TargetError = 1.5 * error
samples = T.render_converged(view, rep)
checks.check(16 <= samples < 40 and T.info(rep, "EstimatedError") <= 1.5 * error,
             "Target Error %g: converged at %d samples with %g" % (1.5 * error, samples, T.info(rep, "EstimatedError")))
simple.Render(view)
checks.check(T.info(rep, "TotalSamples") == samples, "Target Error reached: no further refinement")
rep.TargetError = 0.0
# Interaction (a camera change) starts the image over.
view.CameraPosition = [160.0, 100.0, 190.0]
simple.Render(view)
checks.check(T.info(rep, "TotalSamples") == 8, "a camera change starts the refinement over")

checks.finish()
