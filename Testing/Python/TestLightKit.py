"""The two mappers agree under a light kit with scaled lights and one light
sampled per scattering event (ParaView's lighting; lighting.md, "Lights from
programs made for surfaces").

A vtkLightKit (key, fill, head and two back lights, as in ParaView's render
view) lights the volume; both mappers take LightIntensityScale = 4 pi, and
the Monte Carlo mapper samples one light per scattering event
(LightSampling ONE_LIGHT) while the ray-marching reference sums all five.

Statistic (as TestLitDefaults.py): D the difference between the mean of K
Monte Carlo renders (seeds 1..K, pixel centres) and the reference, V the
per-pixel variance of that mean, T = sum(D^2 - V) / sqrt(2 (1 + 1/(K - 1))
sum V^2), about standard normal when the Monte Carlo image converges to the
reference; per RGB component, one-sided, family-wise level 1e-3 over the 3
components and 2 sampling modes (T < 3.34). Power: Monte Carlo against the
reference rendered without the scale must fail the same test.
"""

import os
import sys

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))

import math
import statistics

import numpy as np

import vtkmodules.vtkRenderingOpenGL2  # noqa: F401
from vtkmodules.vtkCommonCore import vtkFloatArray
from vtkmodules.vtkRenderingCore import vtkRenderer, vtkRenderWindow, vtkVolume
from vtkmodules.vtkRenderingCore import vtkLightKit
from vtkmodules.util.numpy_support import vtk_to_numpy

from mcvol import vtkMultiChannelDemoSource, vtkMultiChannelRayMarchMapper, vtkMultiChannelVolumeMapper
from mcvolTesting import Checker, suggested_property, use_test_backend

SIZE = 24
K = 8
SPP = 64
SCALE = 4.0 * math.pi
Z_LIMIT = statistics.NormalDist().inv_cdf(1.0 - 1e-3 / 6)

t = Checker()
src = vtkMultiChannelDemoSource()
src.SetDataset("microscopy")
src.SetDimensions(24, 24, 8)
src.Update()
n = src.GetNumberOfOutputChannels()
prop = suggested_property(src)
prop.ShadeOn()
spacing = min(src.GetOutput().GetSpacing())

window = vtkRenderWindow()
window.SetOffScreenRendering(1)
window.SetMultiSamples(0)
window.SetSize(SIZE, SIZE)


def render(mapper):
    """RGBA (SIZE, SIZE, 4) after one render (reference) or SPP samples."""
    mapper.SetInputConnection(src.GetOutputPort())
    mapper.SetAmbientRadiance(0.0, 0.0, 0.0)  # the lights alone
    vol = vtkVolume()
    vol.SetMapper(mapper)
    vol.SetProperty(prop)
    ren = vtkRenderer()
    ren.AddVolume(vol)
    kit = vtkLightKit()
    kit.AddLightsToRenderer(ren)
    window.AddRenderer(ren)
    ren.ResetCamera()
    ren.GetActiveCamera().Azimuth(35)
    ren.GetActiveCamera().Elevation(25)
    ren.ResetCameraClippingRange()
    window.Render()
    while not isinstance(mapper, vtkMultiChannelRayMarchMapper) and not mapper.IsConverged():
        window.Render()
    lights = ren.GetLights().GetNumberOfItems()
    window.RemoveRenderer(ren)
    out = vtkFloatArray()
    mapper.GetAccumulatedImage(out)
    return vtk_to_numpy(out).reshape(SIZE, SIZE, 4).astype(np.float64), lights


def reference(scale):
    m = vtkMultiChannelRayMarchMapper()
    # The march's step error must stay below what the statistic resolves:
    # at 1/4 voxel it is about 1e-4 of the mean, which the expected-value
    # estimator's K x SPP samples resolve (T near 5); at 1/16, T near 0.
    m.SetStepSize(spacing / 16.0)
    m.SetLightIntensityScale(scale)
    return render(m)


def monte_carlo(seed, sampling):
    m = vtkMultiChannelVolumeMapper()
    use_test_backend(m)
    m.SetPixelJitter(False)
    m.SetSeed(seed)
    m.SetSamplesPerPixel(16)
    m.SetMaximumTotalSamples(SPP)
    m.SetLightIntensityScale(SCALE)
    m.SetLightSampling(sampling)
    return render(m)[0]


def statistic(mc, ref):
    mean = mc.mean(axis=0)
    var = mc.var(axis=0, ddof=1) / mc.shape[0]
    out = []
    for c in range(3):
        D, V = mean[..., c] - ref[..., c], var[..., c]
        out.append(float((D ** 2 - V).sum() / np.sqrt(2.0 * (1.0 + 1.0 / (K - 1)) * (V ** 2).sum())))
    return out


m = vtkMultiChannelVolumeMapper()
t.check(m.GetLightIntensityScale() == 1.0 and m.GetLightSampling() == m.ALL_LIGHTS,
        "the VTK mapper's defaults are physical units and every light")
ref, lights = reference(SCALE)
t.check(lights == 5, "the light kit puts 5 lights in the renderer (%d)" % lights)
t.check(ref[..., :3].max() > 0.1, "the scaled light kit lights the volume (max %.3f)" % ref[..., :3].max())
for name, sampling in (("one light", m.ONE_LIGHT), ("all lights", m.ALL_LIGHTS)):
    mc = np.stack([monte_carlo(seed, sampling) for seed in range(1, K + 1)])
    T = statistic(mc, ref)
    print("%s: T = %s (limit %.2f); mean RGB MC %.5f, ray march %.5f" % (
        name, ", ".join("%.2f" % v for v in T), Z_LIMIT, mc.mean(axis=0)[..., :3].mean(), ref[..., :3].mean()))
    t.check(max(T) < Z_LIMIT, "Monte Carlo sampling %s converges to the ray march summing all five: T = %s"
            % (name, ", ".join("%.2f" % v for v in T)))
    if sampling == m.ONE_LIGHT:
        T0 = statistic(mc, reference(1.0)[0])
        t.check(max(T0) > Z_LIMIT, "the test has power: the reference without the scale differs (T = %s)"
                % ", ".join("%.2f" % v for v in T0))
t.finish()
