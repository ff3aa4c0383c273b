#!/usr/bin/python3
"""Time to a target error through the VTK API: vtkMultiChannelVolumeMapper
(Monte Carlo, progressive) against vtkMultiChannelRayMarchMapper at its
default step. The target: on the CPU (2 cores), through the VTK API, unlit,
Monte Carlo reaches RMSE 0.01 within 2x the ray marcher's time at its
default step; lit, it beats the ray marcher.

Scene: the generated microscopy set (3 uint8 channels) of --dims (default
128 x 112 x 64), the demo source's suggested transfer
functions, independent components, linear interpolation, density blend, one
camera (azimuth 35, elevation 25), a --size window (default 256 x 256),
pixel centres for every image (Monte Carlo with pixel jitter off, as the
march samples them).

- Unlit: the reference is the ray march at 1/16 voxel without early
  termination. Monte Carlo renders 1 spp per window render; each render is
  timed (window.Render(), so the mapper's whole frame: setup, trace,
  accumulation and draw), the accumulated image is scored after it (not
  timed) until its RMSE (premultiplied RGB, over black, clipped to [0, 1])
  is at most --target. A series shorter than 2 s is run --reps times
  (reset in between: the same seed gives the same images) and its median
  total kept. The march is timed at its default step (median of --reps
  renders after a warm-up, the camera nudged to force a new trace) and
  scored against the same reference.
- Lit (ShadeOn, every lighting setting at its default): the reference is a
  Monte Carlo image of --lit-reference-spp samples of another seed (the
  lit march is single scattering with a 32-direction ambient quadrature, an
  approximation of the same image: TestLitDefaults.py); Monte Carlo is timed
  to --target against it, and the march's time and error at its default
  step are printed.

Variants of the Monte Carlo mapper (--variants, comma separated):
  default               the mapper's defaults
  min<N>                SetMinimumSamplesPerVoxel(N) (expected-value estimator)
  collision             SetEstimatorToCollision()
  march                 SetEstimatorToUnbiasedMarch() (default 2 strata per voxel)
  march<N>              the same with SetMarchSamplesPerVoxel(N)
  auto                  SetEstimatorToAutomatic() (aiming at 35 dB, the default)
  autotarget            the same with SetTargetError(--target): the choice aims
                        at the target (the image also stops there: adaptive
                        stopping)
The automatic variants' pilots run in the warm-up render (once per data and
transfer functions, as in an application); their time is printed after the
table, with the choice.
Prints a Markdown table; --csv writes the rows.

Usage (from the repository, after scripts/build.sh):
  PYTHONPATH=build/lib/python3.11/site-packages xvfb-run -a python3 \\
      Benchmarks/studies/cpu_time_to_error.py --out Benchmarks/results/cpu-time-to-error
"""
import argparse
import csv
import os
import platform
import statistics
import time

import numpy as np

import vtkmodules.vtkRenderingOpenGL2  # noqa: F401  (OpenGL factory overrides)
from vtkmodules.vtkCommonCore import vtkFloatArray
from vtkmodules.vtkCommonDataModel import vtkPiecewiseFunction
from vtkmodules.vtkRenderingCore import (vtkColorTransferFunction, vtkRenderer, vtkRenderWindow, vtkVolume,
                                         vtkVolumeProperty)
from vtkmodules.util.numpy_support import vtk_to_numpy

from mcvol import vtkMultiChannelDemoSource, vtkMultiChannelRayMarchMapper, vtkMultiChannelVolumeMapper


def parse():
    p = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    p.add_argument("--dataset", default="microscopy")
    p.add_argument("--dims", type=int, nargs=3, default=[128, 112, 64])
    p.add_argument("--size", type=int, nargs=2, default=[256, 256])
    p.add_argument("--target", type=float, default=0.01)
    p.add_argument("--max-spp", type=int, default=1024)
    p.add_argument("--reps", type=int, default=5)
    p.add_argument("--lit-reference-spp", type=int, default=1024)
    p.add_argument("--variants", default="default,collision")
    p.add_argument("--cases", default="unlit,lit")
    p.add_argument("--backend", default="cpu", choices=["cpu", "cuda", "auto"])
    p.add_argument("--out", default="")
    return p.parse_args()


class Scene:
    def __init__(self, args, lit):
        self.args = args
        self.src = vtkMultiChannelDemoSource()
        self.src.SetDataset(args.dataset)
        self.src.SetDimensions(*args.dims)
        self.src.Update()
        self.prop = vtkVolumeProperty()
        self.prop.IndependentComponentsOn()
        self.prop.SetInterpolationTypeToLinear()
        if lit:
            self.prop.ShadeOn()
        for c in range(self.src.GetNumberOfOutputChannels()):
            ctf, otf, u = vtkColorTransferFunction(), vtkPiecewiseFunction(), [0.0]
            self.src.GetSuggestedTransferFunction(c, ctf, otf, u)
            self.prop.SetColor(c, ctf)
            self.prop.SetScalarOpacity(c, otf)
            self.prop.SetScalarOpacityUnitDistance(c, u[0])
        self.spacing = min(self.src.GetOutput().GetSpacing())
        self.window = vtkRenderWindow()
        self.window.SetOffScreenRendering(1)
        self.window.SetMultiSamples(0)
        self.window.SetSize(*args.size)

    def attach(self, mapper):
        mapper.SetInputConnection(self.src.GetOutputPort())
        if self.args.backend == "cpu":
            mapper.SetBackendToCPU()
        elif self.args.backend == "cuda":
            mapper.SetBackendToCUDA()
        vol = vtkVolume()
        vol.SetMapper(mapper)
        vol.SetProperty(self.prop)
        ren = vtkRenderer()
        ren.AddVolume(vol)
        for r in list(self.window.GetRenderers()):
            self.window.RemoveRenderer(r)
        self.window.AddRenderer(ren)
        ren.ResetCamera()
        ren.GetActiveCamera().Azimuth(35)
        ren.GetActiveCamera().Elevation(25)
        ren.ResetCameraClippingRange()
        return ren


def image(mapper, size):
    out = vtkFloatArray()
    mapper.GetAccumulatedImage(out)
    return vtk_to_numpy(out).reshape(size[1], size[0], 4).astype(np.float64)


def rmse(img, ref):
    a = np.clip(img[..., :3], 0.0, 1.0)
    b = np.clip(ref[..., :3], 0.0, 1.0)
    return float(np.sqrt(np.mean((a - b) ** 2)))


def march(scene, step=0.0, terminate=None):
    """A march's image and its median time over --reps renders (after one
    untimed render), the camera nudged between renders to force a trace."""
    m = vtkMultiChannelRayMarchMapper()
    m.SetStepSize(step)
    if terminate is not None:
        m.SetTerminationTransmittance(terminate)
    ren = scene.attach(m)
    scene.window.Render()
    times = []
    cam = ren.GetActiveCamera()
    for k in range(scene.args.reps if step == 0.0 else 1):
        cam.Azimuth(1e-4 if k % 2 == 0 else -1e-4)
        t0 = time.perf_counter()
        scene.window.Render()
        times.append(1e3 * (time.perf_counter() - t0))
    return image(m, scene.args.size), statistics.median(times), m.GetLastStepSize()


def configure(m, variant, seed):
    m.SetPixelJitter(False)
    m.SetSeed(seed)
    m.SetSamplesPerPixel(1)
    if variant.startswith("min"):
        m.SetMinimumSamplesPerVoxel(float(variant[3:]))
    elif variant == "collision":
        m.SetEstimatorToCollision()
    elif variant == "march":
        m.SetEstimatorToUnbiasedMarch()
    elif variant.startswith("march"):
        m.SetEstimatorToUnbiasedMarch()
        m.SetMarchSamplesPerVoxel(float(variant[5:]))
    elif variant in ("auto", "autotarget"):
        m.SetEstimatorToAutomatic()
    elif variant != "default":
        raise SystemExit("unknown variant " + variant)


def monte_carlo(scene, variant, ref, target, max_spp):
    """Renders 1 spp at a time until the RMSE against ref is at most target:
    (spp, ms, rmse reached)."""
    m = vtkMultiChannelVolumeMapper()
    configure(m, variant, 1)
    if variant == "autotarget":
        m.SetTargetError(target)
    m.SetMaximumTotalSamples(max_spp)
    scene.attach(m)
    # Warm-up on a throw-away mapper state: the first render builds the
    # acceleration structures; start the timed series after a reset.
    scene.window.Render()

    def series():
        m.ResetAccumulation()
        total, spp, err = 0.0, 0, float("inf")
        while spp < max_spp:
            t0 = time.perf_counter()
            scene.window.Render()
            total += 1e3 * (time.perf_counter() - t0)
            previous, spp = spp, m.GetTotalSamples()
            err = rmse(image(m, scene.args.size), ref)
            if err <= target or spp == previous:  # reached, or stopped by TargetError
                break
        return total, spp, err

    total, spp, err = series()
    if total < SHORT_SERIES_MS:
        # A short series is timed --reps times, as the march is, and its
        # median kept: the same seed gives the same images, samples and
        # error each time, only the time varies with the machine's load.
        totals = [total] + [series()[0] for _ in range(scene.args.reps - 1)]
        total = statistics.median(totals)
    if variant in ("auto", "autotarget"):
        CHOICES.append("%s: %s\n%s" % (variant, m.GetChosenEstimatorAsString(), m.GetEstimatorReport()))
    return spp, total, err


CHOICES = []
# Series shorter than this (ms) are repeated --reps times (median).
SHORT_SERIES_MS = 2000.0


def mc_reference(scene, spp):
    m = vtkMultiChannelVolumeMapper()
    configure(m, "default", 4242)
    m.SetSamplesPerPixel(64)
    m.SetMaximumTotalSamples(spp)
    scene.attach(m)
    while m.GetTotalSamples() < spp:
        scene.window.Render()
    return image(m, scene.args.size)


def main():
    args = parse()
    rows = []
    print("# Time to RMSE %.3g through the VTK API (%s)\n" % (args.target, time.strftime("%Y-%m-%d")))
    print("%s %dx%dx%d, %dx%d window, backend %s, %s, %d CPUs\n" % (
        args.dataset, *args.dims, *args.size, args.backend, platform.processor() or platform.machine(),
        os.cpu_count()))
    print("| case | renderer | spp | ms | RMSE reached | x march |")
    print("|---|---|---|---|---|---|")
    for case in args.cases.split(","):
        lit = case == "lit"
        scene = Scene(args, lit)
        if lit:
            ref = mc_reference(scene, args.lit_reference_spp)
            ref_name = "Monte Carlo %d spp" % args.lit_reference_spp
        else:
            ref, _, _ = march(scene, scene.spacing / 16.0, terminate=0.0)
            ref_name = "ray march 1/16 voxel"
        img, march_ms, step = march(scene)
        march_err = rmse(img, ref)
        print("| %s | ray march, default step (%.3g voxel) | - | %.1f | %.4f | 1.00 |" % (
            case, step / scene.spacing, march_ms, march_err))
        rows.append([case, "march", "", march_ms, march_err, 1.0, ref_name])
        for variant in args.variants.split(","):
            spp, ms, err = monte_carlo(scene, variant, ref, args.target, args.max_spp)
            reached = err <= args.target
            print("| %s | Monte Carlo, %s | %d%s | %.1f | %.4f | %.2f |" % (
                case, variant, spp, "" if reached else " (not reached)", ms, err, ms / march_ms))
            rows.append([case, "mc-" + variant, spp, ms, err, ms / march_ms, ref_name])
        print("")
    if CHOICES:
        print("Automatic choices (pilots in the warm-up render, not in the times above):\n\n```")
        for c in CHOICES:
            print(c)
        print("```")
    if args.out:
        os.makedirs(args.out, exist_ok=True)
        with open(os.path.join(args.out, "time_to_error.csv"), "w", newline="") as f:
            w = csv.writer(f)
            w.writerow(["case", "renderer", "spp", "ms", "rmse", "x_march", "reference"])
            w.writerows(rows)


if __name__ == "__main__":
    main()
