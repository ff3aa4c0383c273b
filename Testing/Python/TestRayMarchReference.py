"""vtkMultiChannelRayMarchMapper: image regressions of the Monte Carlo mapper
against the ray-marched reference, and the reference's own behaviour.

1. For each blend mode on two datasets (the paper's Figure 3 cubes, float32;
   the microscopy phantom, uint8), the ray-marched image (extinction model,
   a step of 1/256 voxel, where its own discretization error is far below the
   Monte Carlo noise: at 1/64 voxel it is not for the expected-value
   estimator, whose noise is 3-4 times lower than the collision estimator's
   (microscopy, 8192 spp: Z = 20 at 1/64 voxel, 0.05 at 1/256), and at 1/4
   voxel not for either) is compared with a baseline PNG (deterministic: at
   most 2 levels, mean under 0.1), and with the Monte Carlo mapper's image of
   the same scene at a fixed seed and sample count: K = 16 renders of 16 spp
   each (seeds 1..16, pixel jitter off so both sample pixel centres). The
   threshold comes from the measured Monte Carlo noise: with D the difference
   between the mean of the K renders and the reference and V the per-pixel
   variance of that mean estimated from the K renders, the statistic
   T = sum(D^2 - V) / sqrt(2 (1 + 1/(K - 1)) sum V^2) is about standard
   normal when the Monte Carlo image converges to the reference; the test
   fails if T > 4.06 (one-sided, 1e-3 / 40 per comparison and component:
   family-wise level 0.001 over the 10 comparisons of 4 components).
2. The reference traces once per change and redraws otherwise; empty-space
   skipping does not change the image but saves samples; the default step is
   the Nyquist rate; the two compositing models differ at a coarse step and
   agree at a fine one.

Run with --generate to write missing baselines for review.
"""
import os
import sys

import numpy as np

import vtkmodules.vtkRenderingOpenGL2  # noqa: F401
from vtkmodules.vtkCommonCore import vtkFloatArray
from vtkmodules.vtkCommonDataModel import vtkPiecewiseFunction
from vtkmodules.vtkRenderingCore import (vtkColorTransferFunction, vtkRenderer, vtkRenderWindow, vtkVolume,
                                         vtkVolumeProperty, vtkWindowToImageFilter)
from vtkmodules.util.numpy_support import vtk_to_numpy

from mcvol import vtkMultiChannelDemoSource, vtkMultiChannelRayMarchMapper, vtkMultiChannelVolumeMapper
from mcvolTesting import Checker, read_png_rgb, write_png_rgb, use_test_backend

HERE = os.path.dirname(os.path.abspath(__file__))
BASELINES = os.path.join(HERE, "..", "Data", "Baseline")
SIZE = 96
# "Mix" is Eq. 10 as published; "MixAverage" the default mix colour.
MODES = ["Density", "Max", "Mix", "MixAverage", "Composite"]
DATASETS = {"figure3": (32, 32, 32), "microscopy": (96, 96, 18)}
K = 16
SPP = 128
Z_LIMIT = 4.06  # one-sided normal quantile at 1e-3 / 40 (10 comparisons x 4 components)

WINDOW = None


def window():
    global WINDOW
    if WINDOW is None:
        WINDOW = vtkRenderWindow()
        WINDOW.SetOffScreenRendering(1)
        WINDOW.SetMultiSamples(0)
        WINDOW.SetSize(SIZE, SIZE)
    return WINDOW


class Scene:
    """One dataset and blend mode, rendered by either mapper in one window."""

    def __init__(self, dataset, mode):
        self.src = vtkMultiChannelDemoSource()
        self.src.SetDataset(dataset)
        self.src.SetDimensions(*DATASETS[dataset])
        self.src.Update()
        self.n = self.src.GetNumberOfOutputChannels()
        self.prop = vtkVolumeProperty()
        self.prop.IndependentComponentsOn()
        for c in range(self.n):
            ctf, otf, u = vtkColorTransferFunction(), vtkPiecewiseFunction(), [0.0]
            self.src.GetSuggestedTransferFunction(c, ctf, otf, u)
            self.prop.SetColor(c, ctf)
            self.prop.SetScalarOpacity(c, otf)
            self.prop.SetScalarOpacityUnitDistance(c, u[0])
        self.mode = mode
        self.spacing = min(self.src.GetOutput().GetSpacing())

    def setup(self, mapper):
        mapper.SetInputConnection(self.src.GetOutputPort())
        getattr(mapper, "SetChannelBlendModeTo" + ("Mix" if self.mode == "MixAverage" else self.mode))()
        if self.mode == "Mix":
            mapper.SetMixColorModeToEquation10()
        if self.mode in ("Mix", "MixAverage"):
            for c in range(self.n):
                mapper.SetMixWeight(c, 1.0 + c)
        vol = vtkVolume()
        vol.SetMapper(mapper)
        vol.SetProperty(self.prop)
        ren = vtkRenderer()
        ren.SetBackground(0.1, 0.1, 0.15)
        ren.AddVolume(vol)
        win = window()
        win.AddRenderer(ren)
        ren.ResetCamera()
        ren.GetActiveCamera().Azimuth(30)
        ren.GetActiveCamera().Elevation(20)
        ren.ResetCameraClippingRange()
        return ren


def float_image(mapper):
    a = vtkFloatArray()
    mapper.GetAccumulatedImage(a)
    return vtk_to_numpy(a).reshape(-1, 4).astype(np.float64)


def grab():
    g = vtkWindowToImageFilter()
    g.SetInput(window())
    g.ReadFrontBufferOff()
    g.SetInputBufferTypeToRGB()
    g.Update()
    return vtk_to_numpy(g.GetOutput().GetPointData().GetScalars()).reshape(SIZE, SIZE, 3).astype(np.float64)


def reference(scene, step_voxels=1.0 / 256, compositing="Extinction", skipping=True):
    m = vtkMultiChannelRayMarchMapper()
    m.SetStepSize(step_voxels * scene.spacing)
    getattr(m, "SetCompositingModelTo" + compositing)()
    m.SetEmptySpaceSkipping(skipping)
    ren = scene.setup(m)
    window().Render()
    out = (float_image(m), grab(), m.GetLastSampleCount())
    window().RemoveRenderer(ren)
    return out


def monte_carlo(scene):
    m = vtkMultiChannelVolumeMapper()
    use_test_backend(m)
    m.PixelJitterOff()
    m.SetSamplesPerPixel(SPP)
    ren = scene.setup(m)
    images = []
    for seed in range(1, K + 1):
        m.SetSeed(seed)  # a parameter change: the mean starts over
        window().Render()
        images.append(float_image(m))
    window().RemoveRenderer(ren)
    return np.stack(images)


def convergence_statistic(mc, ref):
    """Z-score of sum_p t_p^2, t_p = D_p / sqrt(V_p) (D: mean of the K renders
    minus the reference; V: the variance of that mean estimated from the K
    renders). Under convergence each t_p is Student-t with K - 1 degrees of
    freedom, so E[t^2] = nu / (nu - 2) and Var[t^2] = 3 nu^2 / ((nu - 2)(nu - 4))
    - E[t^2]^2; over P values the sum is normal (central limit). Values whose
    reference alpha a makes hits rare or nearly certain within one render
    (SPP a (1 - a) < 10), where a render's mean is far from normal, are left
    out, and so are values that never varied."""
    nu = K - 1
    e1 = nu / (nu - 2.0)
    var_t2 = 3.0 * nu * nu / ((nu - 2.0) * (nu - 4.0)) - e1 * e1
    mean = mc.mean(axis=0)
    v = mc.var(axis=0, ddof=1) / K
    d = mean - ref
    a = np.clip(ref[:, 3:4], 0.0, 1.0) * np.ones_like(ref)
    usable = (SPP * a * (1.0 - a) >= 10.0) & (v > 1e-14)
    # One Z per component: a pixel's R, G, B and A come from the same samples
    # and are correlated, pixels are independent.
    zs = []
    for c in range(4):
        u = usable[:, c]
        t2 = d[u, c] ** 2 / v[u, c]
        P = t2.size
        zs.append((t2.sum() - e1 * P) / np.sqrt(var_t2 * P) if P > 0 else 0.0)
    return max(zs), np.sqrt((d ** 2).mean()), np.sqrt(v.mean()), int(usable.sum())





def main():
    generate = "--generate" in sys.argv
    t = Checker()
    for dataset in DATASETS:
        for mode in MODES:
            scene = Scene(dataset, mode)
            ref, ref8, _ = reference(scene)
            t.check(np.isfinite(ref).all(), "%s %s: non-finite reference" % (dataset, mode))
            t.check(ref[:, 3].mean() > 0.02, "%s %s: the reference is nearly empty" % (dataset, mode))
            # 1a. The reference against its baseline.
            name = "TestRayMarch_%s_%s.png" % (dataset, mode.lower())
            path = os.path.join(BASELINES, name)
            if not os.path.exists(path):
                if generate:
                    write_png_rgb(path, ref8)
                    print("generated", path)
                else:
                    t.check(False, "%s: baseline missing (run with --generate, review, commit)" % name)
            else:
                diff = np.abs(ref8 - read_png_rgb(path))
                t.check(diff.max() <= 2.0 and diff.mean() < 0.1,
                        "%s: differs from the baseline: max %.1f, mean %.3f" % (name, diff.max(), diff.mean()))
            # 1b. Monte Carlo against the reference, threshold from its noise.
            mc = monte_carlo(scene)
            stat, rmse, noise, used = convergence_statistic(mc, ref)
            print("%-10s %-9s RMSE %.5f, Monte Carlo noise %.5f (%d spp), %d values tested, Z = %+.2f" %
                  (dataset, mode, rmse, noise, K * SPP, used, stat))
            t.check(stat < Z_LIMIT, "%s %s: the Monte Carlo image does not converge to the reference: Z = %.2f, "
                    "RMSE %.5f against noise %.5f" % (dataset, mode, stat, rmse, noise))

    # 2. Behaviour of the reference.
    scene = Scene("microscopy", "Density")
    m = vtkMultiChannelRayMarchMapper()
    ren = scene.setup(m)
    window().Render()
    t.check(m.GetTotalSamples() == 1, "one image: %d" % m.GetTotalSamples())
    t.check(abs(m.GetLastStepSize() - 0.5 * scene.spacing) < 1e-12,
            "default step is half the smallest spacing: %g" % m.GetLastStepSize())
    t.check(m.GetLastTraceSeconds() > 0, "the first render traces")
    first = float_image(m)
    window().Render()
    t.check(m.GetLastTraceSeconds() == 0.0, "an unchanged scene is redrawn, not traced again")
    t.check(np.array_equal(first, float_image(m)), "the redrawn image is the same")
    m.SetStepSize(scene.spacing)
    window().Render()
    t.check(m.GetLastTraceSeconds() > 0, "a new step traces again")
    window().RemoveRenderer(ren)

    cubes = Scene("figure3", "Density")  # cubes in empty space
    a, _, na = reference(cubes, 1.0, skipping=True)
    b, _, nb = reference(cubes, 1.0, skipping=False)
    t.check(np.array_equal(a, b), "empty-space skipping must not change the image")
    t.check(na < nb, "skipping saves samples: %d vs %d" % (na, nb))

    ext_coarse, _, _ = reference(scene, 2.0, "Extinction")
    opa_coarse, _, _ = reference(scene, 2.0, "Opacity")
    ext_fine, _, _ = reference(scene, 0.125, "Extinction")
    opa_fine, _, _ = reference(scene, 0.125, "Opacity")
    coarse = np.sqrt(((ext_coarse - opa_coarse) ** 2).mean())
    fine = np.sqrt(((ext_fine - opa_fine) ** 2).mean())
    err_ext = np.sqrt(((ext_coarse - ext_fine) ** 2).mean())
    err_opa = np.sqrt(((opa_coarse - ext_fine) ** 2).mean())
    print("models differ by RMSE %.5f at 2 voxels, %.5f at 1/8 voxel; error at 2 voxels: extinction %.5f, "
          "opacity %.5f" % (coarse, fine, err_ext, err_opa))
    t.check(fine < 0.5 * coarse, "the compositing models converge together as the step shrinks")
    t.check(err_ext < err_opa, "extinction-based compositing is closer to the fine reference at a coarse step")
    return t.finish()


if __name__ == "__main__":
    sys.exit(main())
