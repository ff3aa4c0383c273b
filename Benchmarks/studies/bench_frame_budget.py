#!/usr/bin/python3
"""Time-budgeted progression (vtkMultiChannelVolumeMapper::SetInteractiveFrameTime).

A user drags the camera: every render moves it a little (the image restarts),
as ParaView's interaction does. For each budget the table gives the render
time (median and 95th percentile over the moving renders, drawing included),
the samples per pixel each moving render took, and, once the camera stops, the
time to reach a total of --spp samples per pixel. Budget 0 is the fixed
SamplesPerPixel = 1 of before.

    PYTHONPATH=build/lib/python3.11/site-packages xvfb-run -a /usr/bin/python3 \\
        Benchmarks/studies/bench_frame_budget.py --dims 256 256 256 --size 512 [--backend cpu]
"""
import argparse
import platform
import statistics
import time

import vtkmodules.vtkRenderingOpenGL2  # noqa: F401
from vtkmodules.vtkRenderingCore import vtkColorTransferFunction, vtkRenderer, vtkRenderWindow, vtkVolume, vtkVolumeProperty
from vtkmodules.vtkCommonDataModel import vtkPiecewiseFunction

from mcvol import vtkMultiChannelDemoSource, vtkMultiChannelVolumeMapper


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--dataset", default="cosmology")
    ap.add_argument("--dims", type=int, nargs=3, default=[256, 256, 256])
    ap.add_argument("--size", type=int, default=512)
    ap.add_argument("--budgets", default="0,0.02,0.05,0.1")
    ap.add_argument("--moves", type=int, default=20)
    ap.add_argument("--spp", type=int, default=64, help="samples per pixel to converge to once the camera stops")
    ap.add_argument("--backend", default="cpu", choices=["cpu", "cuda", "auto"])
    args = ap.parse_args()

    src = vtkMultiChannelDemoSource()
    src.SetDataset(args.dataset)
    src.SetDimensions(*args.dims)
    src.Update()
    n = src.GetNumberOfOutputChannels()
    prop = vtkVolumeProperty()
    prop.IndependentComponentsOn()
    prop.SetInterpolationTypeToLinear()
    for c in range(n):
        ctf, otf, u = vtkColorTransferFunction(), vtkPiecewiseFunction(), [0.0]
        src.GetSuggestedTransferFunction(c, ctf, otf, u)
        prop.SetColor(c, ctf)
        prop.SetScalarOpacity(c, otf)
        prop.SetScalarOpacityUnitDistance(c, u[0])

    print("# Frame time budget: %s %dx%dx%d, %d channels, %dx%d, backend %s" % (
        args.dataset, *args.dims, n, args.size, args.size, args.backend))
    print("")
    print("%s, %s, %s" % (platform.processor() or platform.machine(), time.strftime("%Y-%m-%d"),
                          "moving renders: %d, then converging to %d spp" % (args.moves, args.spp)))
    print("")
    print("| budget (s) | moving render ms (median) | 95th pct ms | spp per moving render (median, min-max) "
          "| time to %d spp after stopping (s) | renders to %d spp |" % (args.spp, args.spp))
    print("|---|---|---|---|---|---|")
    for budget in [float(b) for b in args.budgets.split(",")]:
        mapper = vtkMultiChannelVolumeMapper()
        mapper.SetInputConnection(src.GetOutputPort())
        getattr(mapper, "SetBackendTo" + {"cpu": "CPU", "cuda": "CUDA", "auto": "Auto"}[args.backend])()
        mapper.SetSamplesPerPixel(1)
        mapper.SetInteractiveFrameTime(budget)
        vol = vtkVolume()
        vol.SetMapper(mapper)
        vol.SetProperty(prop)
        ren = vtkRenderer()
        ren.AddVolume(vol)
        win = vtkRenderWindow()
        win.SetOffScreenRendering(1)
        win.SetMultiSamples(0)
        win.SetSize(args.size, args.size)
        win.AddRenderer(ren)
        ren.ResetCamera()
        cam = ren.GetActiveCamera()
        for _ in range(3):  # upload and first measurements
            cam.Azimuth(1.0)
            win.Render()
        times, spps = [], []
        for _ in range(args.moves):
            cam.Azimuth(1.0)
            t0 = time.perf_counter()
            win.Render()
            times.append(1e3 * (time.perf_counter() - t0))
            spps.append(mapper.GetLastSamplesPerRender())
        mapper.SetMaximumTotalSamples(args.spp)
        cam.Azimuth(1.0)
        t0 = time.perf_counter()
        renders = 0
        while True:
            win.Render()
            renders += 1
            if mapper.IsConverged() or renders > 100000:
                break
        converge = time.perf_counter() - t0
        times.sort()
        p95 = times[min(len(times) - 1, int(round(0.95 * (len(times) - 1))))]
        print("| %g | %.1f | %.1f | %d (%d-%d) | %.2f | %d |" % (
            budget, statistics.median(times), p95, statistics.median(spps), min(spps), max(spps), converge, renders))
        win.Finalize()


if __name__ == "__main__":
    main()
