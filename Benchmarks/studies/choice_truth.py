"""The automatic estimator's test scene measured (Testing/Python/
TestAutomaticEstimator.py: microscopy phantom 128x112x64, 256x224, camera
azimuth 30 / elevation 20, CPU): MSE of premultiplied RGB (unclipped /
clipped to [0, 1]) against --ref-spp samples of expected value (another
seed) after N samples per pixel, for expected value and the unbiased march
at 4, 3, 2, 1.5, 1.25 and 1 per voxel (two seeds each), then the median time of a 1-sample
render of each, and the automatic choice at 35 dB and at RMSE 0.01.

  PYTHONPATH=build/lib/python3.11/site-packages xvfb-run -a /usr/bin/python3 \\
      Benchmarks/studies/choice_truth.py [--linear] [--centres] [--ref-spp 512]
"""
import argparse
import statistics
import time

import numpy as np
import vtkmodules.vtkRenderingOpenGL2  # noqa: F401
from vtkmodules.util.numpy_support import vtk_to_numpy
from vtkmodules.vtkCommonCore import vtkFloatArray
from vtkmodules.vtkCommonDataModel import vtkPiecewiseFunction
from vtkmodules.vtkRenderingCore import (vtkColorTransferFunction, vtkRenderer, vtkRenderWindow, vtkVolume,
                                         vtkVolumeProperty)

from mcvol import vtkMultiChannelDemoSource, vtkMultiChannelVolumeMapper

p = argparse.ArgumentParser(description=__doc__.split("\n")[0])
p.add_argument("--linear", action="store_true", help="linear instead of nearest-voxel sampling")
p.add_argument("--centres", action="store_true", help="rays through pixel centres (SetPixelJitter(False))")
p.add_argument("--ref-spp", type=int, default=512)
args = p.parse_args()

src = vtkMultiChannelDemoSource()
src.SetDataset("microscopy")
src.SetDimensions(128, 112, 64)
src.Update()


def prop():
    q = vtkVolumeProperty()
    if args.linear:
        q.SetInterpolationTypeToLinear()
    for c in range(src.GetNumberOfOutputChannels()):
        col, op = vtkColorTransferFunction(), vtkPiecewiseFunction()
        src.GetSuggestedTransferFunction(c, col, op, None)
        q.SetColor(c, col)
        q.SetScalarOpacity(c, op)
        q.SetScalarOpacityUnitDistance(c, src.GetSuggestedUnitDistance(c))
    return q


def view(setup, seed=3):
    m = vtkMultiChannelVolumeMapper()
    m.SetInputConnection(src.GetOutputPort())
    m.SetSeed(seed)
    m.SetPixelJitter(not args.centres)
    setup(m)
    v = vtkVolume()
    v.SetMapper(m)
    v.SetProperty(prop())
    r = vtkRenderer()
    r.AddVolume(v)
    w = vtkRenderWindow()
    w.SetOffScreenRendering(1)
    w.SetMultiSamples(0)
    w.SetSize(256, 224)
    w.AddRenderer(r)
    r.ResetCamera()
    r.GetActiveCamera().Azimuth(30)
    r.GetActiveCamera().Elevation(20)
    return m, w


def img(m):
    a = vtkFloatArray()
    m.GetAccumulatedImage(a)
    return vtk_to_numpy(a).astype(np.float64).reshape(-1, 4)[:, :3]


def ev(m):
    m.SetEstimatorToExpectedValue()


def march(rate):
    def f(m):
        m.SetEstimatorToUnbiasedMarch()
        m.SetMarchSamplesPerVoxel(rate)
    return f


print("scene: %s sampling, %s" % ("linear" if args.linear else "nearest",
                                   "pixel centres" if args.centres else "pixel jitter"))
m, w = view(ev, seed=99)
m.SetSamplesPerPixel(64)
for _ in range(args.ref_spp // 64):
    w.Render()
ref = img(m)
print("reference: expected value, %d samples" % m.GetTotalSamples())
print("MSE after N samples (unclipped/clipped):")
for name, setup, checkpoints in [("expected value", ev, [1, 2, 4, 8, 16, 23, 26, 32]),
                                 ("march 4", march(4.0), [1, 2]),
                                 ("march 3", march(3.0), [1, 2, 4]),
                                 ("march 2", march(2.0), [1, 2, 3, 4, 7]),
                                 ("march 1.5", march(1.5), [1, 2]),
                                 ("march 1.25", march(1.25), [1, 2]),
                                 ("march 1", march(1.0), [1, 2, 4])]:
    for seed in (3, 4):
        m, w = view(setup, seed)
        done, out = 0, []
        for k in checkpoints:
            while done < k:
                w.Render()
                done += 1
            x = img(m)
            out.append("%d: %.3g/%.3g" % (k, np.mean((x - ref) ** 2),
                                          np.mean((np.clip(x, 0, 1) - np.clip(ref, 0, 1)) ** 2)))
        print("  %s, seed %d: %s" % (name, seed, ", ".join(out)))
for name, setup in [("expected value", ev), ("march 1", march(1.0)), ("march 1.25", march(1.25)),
                    ("march 1.5", march(1.5)), ("march 2", march(2.0)), ("march 3", march(3.0)),
                    ("march 4", march(4.0))]:
    m, w = view(setup, 5)
    w.Render()
    ts = []
    for _ in range(8):
        t0 = time.perf_counter()
        w.Render()
        ts.append(time.perf_counter() - t0)
    print("%s: %.1f ms per 1-sample render (median of 8)" % (name, 1e3 * statistics.median(ts)))
for target in (0.0, 0.01):
    def auto(m):
        m.SetEstimatorToAutomatic()
        m.SetTargetError(target)
    m, w = view(auto)
    w.Render()
    print("automatic, %s: %s" % ("35 dB" if target == 0 else "RMSE %g" % target, m.GetChosenEstimatorAsString()))
    print(m.GetEstimatorReport())
