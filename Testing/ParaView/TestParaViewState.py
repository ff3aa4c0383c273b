"""pvpython: a state file (.pvsm) keeps every property of the representation
and every channel's transfer functions; the loaded scene renders the same
image, pixel for pixel."""
import os
import tempfile

import numpy as np
from paraview import simple

import mcvolParaViewTesting as T

checks = T.Checks()
T.load_plugin()

split, view, rep, names = T.figure3_split_scene()
simple.GetOpacityTransferFunction("green").Points = [0.0, 0.0, 0.5, 0.0, 0.6, 0.2, 0.5, 0.0, 1.0, 0.8, 0.5, 0.0]
simple.GetColorTransferFunction("blue").RGBPoints = [0.0, 0.0, 0.0, 1.0, 1.0, 0.0, 1.0, 1.0]

# Every property away from its default.
settings = {
    "ChannelBlendMode": "Mix",
    "MixWeights": [0.5, 1.0, 2.0],
    "TrackingMethod": "N DDA",
    "SampleSequence": "Sobol",  # show() pins Independent
    "Estimator": "Expected Value",  # show() pins Collision
    "SamplesPerRender": 4,
    "ProgressiveRefinement": 1,
    "MaximumTotalSamples": 24,
    "MacrocellSize": 4,
    "Seed": 11,
    "PixelJitter": 0,
    "Shade": 1,
    "ShadowMode": "Delta Tracking",
    "AmbientRadiance": [0.3, 0.2, 0.1],
    "MaxScatteringDepth": 3,
    "GradientShading": 1,
    "Shininess": 12.0,
    "ChannelAlbedos": [0.9, 0.8, 0.7],
    "ChannelAnisotropies": [0.1, -0.2, 0.3],
    "ScalarOpacityUnitDistance": 2.5,
    "VisibilityOptimization": 1,
    "ChannelImportanceLevels": [0.0, 1.0, 0.5],
    "ChannelImportanceThresholds": [0.0, 0.5, 0.7],
    "DeviationWeight": 2.0,
    "OcclusionWeight": 60.0,
    "ClutterWeight": 20.0,
    "ImportanceEmphasis": 1.5,
    "ImportanceMergeDistance": 0.05,
    "ImportanceSamples": 16,
    "OptimizeLightRays": 0,
    "LightRayImportanceSamples": 64,
}
for name, value in settings.items():
    setattr(rep, name, value)
# Channel 3's importance from its function (it wins over the lists' entry).
importance3 = [0.0, 0.0, 0.5, 0.0, 0.6, 0.0, 0.5, 0.0, 0.6001, 0.75, 0.5, 0.0, 1.0, 0.75, 0.5, 0.0]
rep.ChannelImportanceFunction3.Points = importance3
T.render_converged(view, rep)
before = T.capture(view)
# The importance must matter here, or losing it on load would go unnoticed.
rep.VisibilityOptimization = 0
T.render_converged(view, rep)
d = np.abs(T.capture(view).astype(int) - before.astype(int)).mean()
checks.check(d > 0.1, "the visibility optimization changes this scene's image (mean |diff| %.3f)" % d)
rep.VisibilityOptimization = 1
functions = {n: (list(simple.GetColorTransferFunction(n).RGBPoints), list(simple.GetOpacityTransferFunction(n).Points))
             for n in names}

handle, state = tempfile.mkstemp(suffix=".pvsm")
os.close(handle)
simple.SaveState(state)
simple.ResetSession()
T.load_plugin()
checks.check(len(simple.GetSources()) == 0, "the session is empty before loading")
simple.LoadState(state)
os.remove(state)

view = simple.GetRenderViews()[0]
view.ViewSize = [160, 160]
source = [s for s in simple.GetSources().values() if s.GetXMLName() == "ExtractComponent"
          and s.OutputArrayName == "blue"][0]
rep = simple.GetDisplayProperties(source, view)
checks.check(rep.Representation == T.REPRESENTATION, "the representation type is kept")
checks.check(list(rep.ChannelArrays) == names, "the channel arrays are kept (%s)" % list(rep.ChannelArrays))
for name, value in settings.items():
    got = getattr(rep, name)
    if isinstance(value, str):
        got = rep.GetProperty(name).GetData()
    elif hasattr(got, "__len__"):
        got = list(got)
    ok = np.allclose(got, value) if isinstance(value, (list, float)) else got == value
    checks.check(ok, "%s is kept (%s)" % (name, got))
checks.check(np.allclose(list(rep.ChannelImportanceFunction3.Points), importance3),
             "channel 3's importance function is kept (%s)" % list(rep.ChannelImportanceFunction3.Points))
checks.check(max(list(rep.ChannelImportanceFunction1.Points)[1::4]) == 0.0,
             "an untouched importance function is kept at 0")
checks.check(list(rep.ChannelLookupTables) == [simple.GetColorTransferFunction(n) for n in names],
             "ChannelLookupTables point at the loaded transfer functions of the channels")
for n in names:
    rgb, opacity = functions[n]
    checks.check(np.allclose(list(simple.GetColorTransferFunction(n).RGBPoints), rgb)
                 and np.allclose(list(simple.GetOpacityTransferFunction(n).Points), opacity),
                 "the transfer functions of '%s' are kept" % n)

T.render_converged(view, rep)
after = T.capture(view)
T.write_png(os.path.join(tempfile.gettempdir(), "ParaViewState_before.png"), before)
T.write_png(os.path.join(tempfile.gettempdir(), "ParaViewState_after.png"), after)
d = np.abs(after.astype(int) - before.astype(int))
checks.check(d.max() == 0, "the loaded state renders the same image (max |diff| %d)" % d.max())
checks.finish()
