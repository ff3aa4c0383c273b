#!/usr/bin/python3
"""The visibility optimization through the VTK API, as the paper's evaluation
(Lerzer and Dachsbacher 2025, Sec. 6.2 and 6.5), on the built-in microscopy
phantom with the nuclei important:

- equal time (Fig. 5): the Monte Carlo mapper against the optimized ray march
  at its default (Nyquist) step, both against a fine-step optimized ray
  march; RMSE and SSIM (scikit-image);
- the clutter weight r from 0 to 70 (Fig. 10): pictures and how much of the
  image the important channel holds.

Prints Markdown tables and writes the pictures to --out.

    PYTHONPATH=build/lib/python3.11/site-packages xvfb-run -a \\
        /usr/bin/python3 Benchmarks/studies/visibility_study.py --out Benchmarks/results/visibility-optimization
"""
import argparse
import os
import time

import numpy as np
import vtkmodules.vtkRenderingOpenGL2  # noqa: F401
from vtkmodules.vtkCommonCore import vtkFloatArray
from vtkmodules.vtkCommonDataModel import vtkPiecewiseFunction
from vtkmodules.vtkRenderingCore import (vtkColorTransferFunction, vtkRenderer, vtkRenderWindow, vtkVolume,
                                         vtkVolumeProperty)
from vtkmodules.util.numpy_support import vtk_to_numpy

from mcvol import vtkMultiChannelDemoSource, vtkMultiChannelRayMarchMapper, vtkMultiChannelVolumeMapper


def scene(args):
    src = vtkMultiChannelDemoSource()
    src.SetDataset("microscopy")
    src.SetDimensions(*args.dims)
    src.Update()
    image = src.GetOutput()
    prop = vtkVolumeProperty()
    prop.IndependentComponentsOn()
    for c in range(3):
        ctf, otf = vtkColorTransferFunction(), vtkPiecewiseFunction()
        src.GetSuggestedTransferFunction(c, ctf, otf, None)
        prop.SetColor(c, ctf)
        prop.SetScalarOpacity(c, otf)
        prop.SetScalarOpacityUnitDistance(c, src.GetSuggestedUnitDistance(c))
    lo, hi = image.GetPointData().GetScalars().GetRange(1)
    important = vtkPiecewiseFunction()  # nuclei above 0.3 of their range
    important.AddPoint(lo, 0.0)
    important.AddPoint(lo + 0.3 * (hi - lo), 0.0)
    important.AddPoint(lo + 0.31 * (hi - lo), 1.0)
    important.AddPoint(hi, 1.0)
    return image, prop, important


LIT = False


def render(mapper, image, prop, size, renders):
    mapper.SetInputData(image)
    if LIT:
        # The ray march has no ambient term: none for either.
        mapper.SetAmbientRadiance(0, 0, 0)
    volume = vtkVolume()
    volume.SetMapper(mapper)
    volume.SetProperty(prop)
    ren = vtkRenderer()
    ren.AddVolume(volume)
    if LIT:
        from vtkmodules.vtkRenderingCore import vtkLight
        light = vtkLight()
        light.SetLightTypeToSceneLight()
        light.SetPositional(False)
        light.SetPosition(1, 1, 2)
        light.SetFocalPoint(0, 0, 0)
        light.SetIntensity(12.0)
        ren.AddLight(light)
    win = vtkRenderWindow()
    win.SetOffScreenRendering(1)
    win.SetSize(size, size)
    win.AddRenderer(ren)
    ren.ResetCamera()
    ren.GetActiveCamera().Azimuth(30)
    ren.GetActiveCamera().Elevation(20)
    ren.ResetCameraClippingRange()
    t0 = time.perf_counter()
    for _ in range(renders):
        win.Render()
    seconds = time.perf_counter() - t0
    out = vtkFloatArray()
    mapper.GetAccumulatedImage(out)
    rgba = vtk_to_numpy(out).reshape(size, size, 4).astype(np.float64)
    return rgba, seconds


def optimize(mapper, important, r=30.0):
    mapper.VisibilityOptimizationOn()
    mapper.SetChannelImportance(1, important)
    mapper.SetClutterWeight(r)


def rmse(a, b):
    return float(np.sqrt(np.mean((a[..., :3] - b[..., :3]) ** 2)))


def ssim(a, b):
    from skimage.metrics import structural_similarity
    return float(structural_similarity(np.clip(a[..., :3], 0, 1), np.clip(b[..., :3], 0, 1), channel_axis=2,
                                       data_range=1.0))


def save(path, rgba):
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    plt.imsave(path, np.clip(rgba[::-1, :, :3], 0, 1))


def main():
    p = argparse.ArgumentParser(description=__doc__)
    p.add_argument("--dims", type=int, nargs=3, default=[128, 128, 40])
    p.add_argument("--size", type=int, default=256)
    p.add_argument("--ref-step-voxels", type=float, default=0.125)
    p.add_argument("--out", default=".")
    p.add_argument("--lit", action="store_true", help="one directional light (ShadeOn), light rays optimized too")
    args = p.parse_args()
    global LIT
    LIT = args.lit
    os.makedirs(args.out, exist_ok=True)
    image, prop, important = scene(args)
    if LIT:
        prop.ShadeOn()

    # Reference: the optimized ray march at a fine step.
    ref_mapper = vtkMultiChannelRayMarchMapper()
    optimize(ref_mapper, important)
    ref_mapper.SetStepSize(args.ref_step_voxels * min(image.GetSpacing()))
    ref, ref_s = render(ref_mapper, image, prop, args.size, 1)
    # The ray march at its default step (the Nyquist rate).
    rm = vtkMultiChannelRayMarchMapper()
    optimize(rm, important)
    rm_img, rm_s = render(rm, image, prop, args.size, 1)
    # Monte Carlo: as many samples as fit the ray march's time (1 per render).
    # Both times are from scratch (binding, grids, tables included): one
    # render and nine renders of fresh mappers give the set-up and the cost
    # of a sample.
    def fresh_mc(renders):
        m = vtkMultiChannelVolumeMapper()
        optimize(m, important)
        m.SetBackendToCPU()
        m.SetSamplesPerPixel(1)
        return render(m, image, prop, args.size, renders)[1]

    t1, t9 = fresh_mc(1), fresh_mc(9)
    per_sample = max(1e-6, (t9 - t1) / 8.0)
    spp = max(1, int(round((rm_s - (t1 - per_sample)) / per_sample)))
    mc2 = vtkMultiChannelVolumeMapper()
    optimize(mc2, important)
    mc2.SetBackendToCPU()
    mc2.SetSamplesPerPixel(1)
    mc_img, mc_s = render(mc2, image, prop, args.size, spp)
    print("## Equal time, %s, microscopy %s at %dx%d (2 CPU cores)\n" % (
        "lit (one light)" if LIT else "unlit", "x".join(map(str, args.dims)), args.size, args.size))
    print("Reference: the optimized ray march at %.3g voxels (%.1f s).\n" % (args.ref_step_voxels, ref_s))
    print("| renderer | s | RMSE | SSIM |\n|---|---|---|---|")
    print("| ray march, Nyquist step | %.2f | %.5f | %.4f |" % (rm_s, rmse(rm_img, ref), ssim(rm_img, ref)))
    print("| Monte Carlo, %d spp | %.2f | %.5f | %.4f |" % (spp, mc_s, rmse(mc_img, ref), ssim(mc_img, ref)))
    tag = "lit-" if LIT else ""
    save(os.path.join(args.out, tag + "equal-time-raymarch.png"), rm_img)
    save(os.path.join(args.out, tag + "equal-time-montecarlo.png"), mc_img)
    save(os.path.join(args.out, tag + "equal-time-reference.png"), ref)
    if LIT:
        return

    # The clutter weight r (Fig. 10), on the ray-marched reference (no noise).
    print("\n## Clutter weight r (ray march, default step)\n")
    print("| r | share of the nuclei's colour (blue) | mean alpha |\n|---|---|---|")
    for r in (0, 10, 30, 50, 70):
        m = vtkMultiChannelRayMarchMapper()
        optimize(m, important, r)
        img, _ = render(m, image, prop, args.size, 1)
        blue = img[..., 2].sum() / max(1e-12, img[..., :3].sum())
        print("| %g | %.4f | %.4f |" % (r, blue, img[..., 3].mean()))
        save(os.path.join(args.out, "r-sweep-%02d.png" % r), img)
    plain = vtkMultiChannelRayMarchMapper()
    img, _ = render(plain, image, prop, args.size, 1)
    print("| (unoptimized) | %.4f | %.4f |" % (img[..., 2].sum() / max(1e-12, img[..., :3].sum()), img[..., 3].mean()))


if __name__ == "__main__":
    main()
