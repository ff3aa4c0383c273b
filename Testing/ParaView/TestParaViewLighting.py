"""pvpython: Shade on with ParaView's default lights (the render view's light
kit) gives a picture about as bright as ParaView's own Volume representation
with Shade on, on the same field and transfer functions (lighting.md, "Lights
from programs made for surfaces").

The Wavelet source's RTData, one transfer function (a constant light grey
and an opacity ramp), the same camera; ParaView's Volume (its GPU ray caster
with gradient shading) against the Monte Carlo representation with its
defaults (Light Intensity Scale 4 pi, Light Sampling One Light). The mean
brightness of the two images must be within a factor 2 of each other. Power:
the physical scale (Light Intensity Scale 1) is outside the factor 2.
Monte Carlo renders are
seeded; the means are over 40 000 pixels of a 64-sample image, whose noise
moves the mean by far less than the margin.
"""
import numpy as np
from paraview import simple

import mcvolParaViewTesting as T

checks = T.Checks()
T.load_plugin()

wavelet = simple.Wavelet()
lut = simple.GetColorTransferFunction("RTData")
lut.RGBPoints = [37.0, 0.85, 0.85, 0.85, 277.0, 0.85, 0.85, 0.85]
lut.AutomaticRescaleRangeMode = "Never"
pwf = simple.GetOpacityTransferFunction("RTData")
pwf.Points = [37.0, 0.0, 0.5, 0.0, 150.0, 0.0, 0.5, 0.0, 277.0, 0.6, 0.5, 0.0]


def setup_view():
    view = T.make_view((200, 200))
    view.CameraPosition = [40.0, 30.0, 55.0]
    view.CameraFocalPoint = [0.0, 0.0, 0.0]
    view.CameraViewUp = [0.0, 1.0, 0.0]
    return view


def lights(view):
    collection = view.GetRenderer().GetLights()
    return [collection.GetItemAsObject(i) for i in range(collection.GetNumberOfItems())
            if collection.GetItemAsObject(i).GetSwitch()]


# ParaView's own Volume representation, Shade on.
pv_view = setup_view()
pv = simple.Show(wavelet, pv_view)
pv.SetRepresentationType("Volume")
simple.ColorBy(pv, ("POINTS", "RTData"))
pv.LookupTable = lut
pv.ScalarOpacityFunction = pwf
pv.Shade = 1
simple.Render(pv_view)
on = lights(pv_view)
checks.check(len(on) >= 4, "the render view lights with its light kit (%d lights on)" % len(on))
pv_image = T.capture(pv_view).astype(float)
pv_mean = pv_image.mean()
checks.check(pv_mean > 5.0, "ParaView's lit volume is visible (mean %.1f)" % pv_mean)

# The Monte Carlo representation, Shade on, its defaults otherwise.
mc_view = setup_view()
mc = T.show(wavelet, mc_view)
mc.ChannelArrays = ["RTData"]
mc.Shade = 1
mc.Estimator = "Expected Value"
mc.MaximumTotalSamples = 64
mc.SamplesPerRender = 16
checks.check(abs(mc.LightIntensityScale - 4.0 * np.pi) < 1e-9 and mc.LightSampling == "One Light",
             "the defaults under test: Light Intensity Scale 4 pi (%g), Light Sampling %s"
             % (mc.LightIntensityScale, mc.LightSampling))


def mean_brightness(scale):
    mc.LightIntensityScale = scale
    T.render_converged(mc_view, mc)
    return T.capture(mc_view).astype(float).mean()


mc_mean = mean_brightness(4.0 * np.pi)
ratio = mc_mean / pv_mean
print("mean brightness: ParaView Volume %.2f, Monte Carlo %.2f (ratio %.2f)" % (pv_mean, mc_mean, ratio))
checks.check(0.5 <= ratio <= 2.0, "Shade on with the default lights: Monte Carlo within 0.5-2x of ParaView's Volume"
             " (ratio %.2f)" % ratio)
physical = mean_brightness(1.0) / pv_mean
print("with Light Intensity Scale 1 (physical units): ratio %.2f" % physical)
checks.check(not 0.5 <= physical <= 2.0, "the check has power: physical units are outside 0.5-2x (ratio %.2f)"
             % physical)
checks.finish()
