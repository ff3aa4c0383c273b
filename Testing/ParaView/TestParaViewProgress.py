"""pvpython: progress is visible and refinement stops when done
(paraview.md, "Progress" and "When refinement stops").

- Python reads the progress as attributes of the representation (TotalSamples,
  EstimatedError, EstimatedPSNR, Converged, ChannelStatus, ProgressText),
  the same values as the information properties.
- The progress annotation in the view's corner says what the image under it
  holds after each Render (its sample count, not the one before), is drawn
  into the view's image, and disappears with Progress Annotation off.
- An incomplete channel list is reported in ChannelStatus and in the
  annotation.
- By default refinement stops at the target error (the estimate at most
  Target Error, after 16 samples) below the cap of 256 samples, and a
  finished image is not refined further.
"""
import numpy as np
from paraview import simple

import mcvolParaViewTesting as T

checks = T.Checks()
T.load_plugin()

split, view, rep, names = T.figure3_split_scene()
rep.ProgressAnnotation = 1

# Attributes read the same values as the information properties.
simple.Render(view)
simple.Render(view)
for name in ["TotalSamples", "EstimatedError", "EstimatedPSNR", "Converged", "ChannelStatus", "ProgressText"]:
    try:
        value = getattr(rep, name)
        ok = value == T.info(rep, name)
        checks.check(ok, "rep.%s reads %r, the information property %r" % (name, value, T.info(rep, name)))
    except AttributeError as e:
        checks.check(False, "rep.%s raises AttributeError: %s" % (name, e))

# The annotation describes the image it is drawn on.
text = T.info(rep, "ProgressText")
samples = T.info(rep, "TotalSamples")
psnr = T.info(rep, "EstimatedPSNR")
checks.check(samples == 16 and text.startswith("16 samples") and ("%.1f dB" % psnr) in text and "refining" in text,
             "after two renders of 8 the annotation reads %r (samples %d, PSNR %.2f)" % (text, samples, psnr))
T.render_converged(view, rep)
text = T.info(rep, "ProgressText")
checks.check(text.startswith("%d samples" % T.info(rep, "TotalSamples")) and text.endswith("converged"),
             "a finished image's annotation: %r" % text)
with_text = T.capture(view).astype(int)
rep.ProgressAnnotation = 0
simple.Render(view)
checks.check(T.info(rep, "ProgressText") == "", "Progress Annotation off: no text")
without = T.capture(view).astype(int)
corner = np.abs(with_text - without)[:24, -120:].max(axis=2)
rest = np.abs(with_text - without)[24:, :].max()
checks.check(corner.max() > 60 and rest == 0,
             "the annotation is drawn in the upper right corner only (corner max |diff| %d, elsewhere %d)"
             % (corner.max(), rest))
rep.ProgressAnnotation = 1

# An incomplete channel list: reported, in the annotation too.
rep.ChannelArrays = []
simple.Render(view)
status = rep.ChannelStatus
checks.check(status == "no channels selected" and T.info(rep, "ProgressText") == "Multi-Channel Volume: " + status,
             "no channels: ChannelStatus %r, annotation %r" % (status, T.info(rep, "ProgressText")))
rep.ChannelArrays = names

# The default stop: the target error below the cap of 256 samples.
fresh = simple.Show(simple.Wavelet(), T.make_view())
fresh.SetRepresentationType(T.REPRESENTATION)
default_target, default_cap = fresh.TargetError, fresh.MaximumTotalSamples
checks.check(default_target > 0.0 and default_cap == 256,
             "by default refinement stops at Target Error %g, capped at %d samples" % (default_target, default_cap))
rep.TargetError = default_target
rep.MaximumTotalSamples = default_cap
# ParaView's default sampling (show() pins the baselines' collision
# estimator and independent samples).
rep.Estimator = fresh.Estimator
rep.SampleSequence = fresh.SampleSequence
samples = T.render_converged(view, rep)
error = T.info(rep, "EstimatedError")
checks.check(16 <= samples < default_cap and 0.0 < error <= default_target,
             "the default stops at %d samples with an estimated error of %g (target %g)"
             % (samples, error, default_target))
simple.Render(view)
checks.check(T.info(rep, "TotalSamples") == samples and T.info(rep, "ProgressText").endswith("converged"),
             "a finished image is not refined further (%d samples)" % T.info(rep, "TotalSamples"))
# A target below what 256 samples reach: the cap stops it.
rep.TargetError = error / 100.0
samples = T.render_converged(view, rep)
checks.check(samples == default_cap, "a target out of reach stops at the cap (%d samples)" % samples)
checks.finish()
