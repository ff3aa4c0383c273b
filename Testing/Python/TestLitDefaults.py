"""The two mappers agree with default lit settings.

vtkMultiChannelVolumeMapper and vtkMultiChannelRayMarchMapper render the same
lit scene with every lighting setting at its default (ShadeOn, VTK's
automatic headlight, ambient radiance 0.2, single scattering, ratio-tracked
shadows, albedo 1): the Monte Carlo image converges to the ray-marched one,
whose ambient term is a fixed 32-direction quadrature (RayMarch.h, marchLit).

Statistic (as TestRayMarchReference.py): D the difference between the mean
of K Monte Carlo renders (seeds 1..K, pixel centres) and the reference, V the
per-pixel variance of that mean estimated from the K renders,
T = sum(D^2 - V) / sqrt(2 (1 + 1/(K - 1)) sum V^2), about standard normal when
the Monte Carlo image converges to the reference; per RGBA component,
one-sided, family-wise level 1e-3 over the 4 components (T < 3.48). Power:
the reference without its ambient term (the mappers' old disagreement) must
fail the same test. With cached shadows (SetShadowMode(CACHED_SHADOWS)) on
both, the two mappers look up the same grid and agree by the same test. The
reference refuses a scattering depth above 1 with an error instead of
differing silently.
"""

import os
import sys

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))

import numpy as np
import statistics

import vtkmodules.vtkRenderingOpenGL2  # noqa: F401
from vtkmodules.util.misc import calldata_type
from vtkmodules.vtkCommonCore import VTK_STRING, vtkCommand, vtkFloatArray
from vtkmodules.vtkRenderingCore import vtkRenderer, vtkRenderWindow, vtkVolume
from vtkmodules.util.numpy_support import vtk_to_numpy

from mcvol import vtkMultiChannelDemoSource, vtkMultiChannelRayMarchMapper, vtkMultiChannelVolumeMapper
from mcvolTesting import Checker, suggested_property, use_test_backend

SIZE = 24
K = 8
SPP = 64
Z_LIMIT = statistics.NormalDist().inv_cdf(1.0 - 1e-3 / 4)

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
    """The mapper's accumulated RGBA after one window render (the reference)
    or after SPP samples (Monte Carlo), as a (SIZE, SIZE, 4) array."""
    mapper.SetInputConnection(src.GetOutputPort())
    errors = []

    @calldata_type(VTK_STRING)
    def on_error(obj, event, message):
        errors.append(message)

    mapper.AddObserver(vtkCommand.ErrorEvent, on_error, 1.0)
    vol = vtkVolume()
    vol.SetMapper(mapper)
    vol.SetProperty(prop)
    ren = vtkRenderer()
    ren.AddVolume(vol)
    window.AddRenderer(ren)
    ren.ResetCamera()
    ren.GetActiveCamera().Azimuth(35)
    ren.GetActiveCamera().Elevation(25)
    ren.ResetCameraClippingRange()
    window.Render()
    # The reference traces once per change; Monte Carlo adds batches up to
    # its MaximumTotalSamples.
    while not errors and isinstance(mapper, vtkMultiChannelVolumeMapper) and not isinstance(
            mapper, vtkMultiChannelRayMarchMapper) and not mapper.IsConverged():
        window.Render()
    window.RemoveRenderer(ren)
    out = vtkFloatArray()
    mapper.GetAccumulatedImage(out)
    return (vtk_to_numpy(out).reshape(SIZE, SIZE, 4).astype(np.float64) if out.GetNumberOfTuples() else None), errors


def reference(ambient=True, shadows=None):
    m = vtkMultiChannelRayMarchMapper()
    if shadows is not None:
        m.SetShadowMode(shadows)
    # A quarter of a voxel leaves a bias in alpha (about 31 standard errors of
    # the expected-value estimator's alpha, the default when lit, whose
    # variance is far below the collision estimator's); 1/16 is below the
    # Monte Carlo noise.
    m.SetStepSize(spacing / 16.0)
    if not ambient:
        m.SetAmbientRadiance(0.0, 0.0, 0.0)
    img, errors = render(m)
    t.check(not errors, "the reference renders: %s" % errors)
    return img


def monte_carlo(seed, shadows=None):
    m = vtkMultiChannelVolumeMapper()
    use_test_backend(m)
    if shadows is not None:
        m.SetShadowMode(shadows)
    m.SetPixelJitter(False)  # the reference samples pixel centres
    m.SetSeed(seed)
    m.SetSamplesPerPixel(16)
    m.SetMaximumTotalSamples(SPP)
    img, errors = render(m)
    t.check(not errors, "Monte Carlo renders: %s" % errors)
    return img


def statistic(mc, ref):
    mean = mc.mean(axis=0)
    var = mc.var(axis=0, ddof=1) / mc.shape[0]
    out = []
    for c in range(4):
        D, V = mean[..., c] - ref[..., c], var[..., c]
        out.append(float((D ** 2 - V).sum() / np.sqrt(2.0 * (1.0 + 1.0 / (K - 1)) * (V ** 2).sum())))
    return out


m = vtkMultiChannelVolumeMapper()
t.check(tuple(m.GetAmbientRadiance()) == (0.2, 0.2, 0.2) and m.GetMaxScatteringDepth() == 1,
        "the defaults under test: ambient 0.2, scattering depth 1")
ref = reference()
mc = np.stack([monte_carlo(seed) for seed in range(1, K + 1)])
t.check(ref is not None and mc.mean(axis=0)[..., 3].max() > 0.3, "the lit volume is visible")
T = statistic(mc, ref)
print("default lit settings, Monte Carlo against the ray march: T = %s (limit %.2f)" % (
    ", ".join("%.2f" % v for v in T), Z_LIMIT))
t.check(max(T) < Z_LIMIT, "Monte Carlo converges to the ray-marched image with default lit settings: T = %s"
        % ", ".join("%.2f" % v for v in T))
T0 = statistic(mc, reference(ambient=False))
print("the reference without its ambient term: T = %s" % ", ".join("%.2f" % v for v in T0))
t.check(max(T0) > Z_LIMIT, "the test has power: without the ambient term the reference differs (T = %s)"
        % ", ".join("%.2f" % v for v in T0))
diff = float(np.abs(mc.mean(axis=0) - ref).mean())
print("mean |MC - ray march| = %.5f (RGBA, %d x %d spp)" % (diff, K, SPP))

cached = vtkMultiChannelVolumeMapper.CACHED_SHADOWS
mc_cached = np.stack([monte_carlo(seed, cached) for seed in range(1, K + 1)])
Tc = statistic(mc_cached, reference(shadows=cached))
print("cached shadows in both mappers: T = %s" % ", ".join("%.2f" % v for v in Tc))
t.check(max(Tc) < Z_LIMIT, "with cached shadows Monte Carlo converges to the cached ray march: T = %s"
        % ", ".join("%.2f" % v for v in Tc))

deep = vtkMultiChannelRayMarchMapper()
deep.SetMaxScatteringDepth(3)
img, errors = render(deep)
t.check(errors and "single scattering" in str(errors[-1]),
        "the reference refuses a scattering depth of 3 with an error: %s" % errors)
t.finish()
