"""Frame times of the ParaView plugin (pvpython or [mpiexec -n N] pvbatch).

For each dataset and Samples Per Render value it measures, on the CPU backend:
- the still-render time while refining (median of 16 renders, nothing changed);
- the interactive frame time (the camera moves every frame, so every frame
  starts over and costs one batch): what rotating the view feels like;
- the wall time to reach 256 samples per pixel from a camera change.
Writes a Markdown table (and CSV) to --out.

  bash scripts/paraview.sh pvpython Benchmarks/studies/paraview_bench.py --out Benchmarks/results/paraview-plugin
  bash scripts/paraview.sh mpiexec -n 2 pvbatch Benchmarks/studies/paraview_bench.py --out ... --label 2ranks
"""
import argparse
import os
import statistics
import sys
import time

from paraview import simple
from paraview import servermanager as sm

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, os.path.join(os.path.dirname(os.path.dirname(HERE)), "Testing", "ParaView"))
import mcvolParaViewTesting as T  # noqa: E402


def main():
    p = argparse.ArgumentParser()
    p.add_argument("--out", required=True)
    p.add_argument("--size", type=int, default=512)
    p.add_argument("--label", default="pvpython")
    p.add_argument("--spp", type=int, nargs="+", default=[1, 4, 16])
    args = p.parse_args()
    T.load_plugin()
    ranks = sm.vtkProcessModule.GetProcessModule().GetNumberOfLocalPartitions()
    rows = []
    for name in ["microscopy", "weather"]:
        data = simple.XMLImageDataReader(FileName=[os.path.join(T.DATA, name + ".vti")])
        view = simple.CreateView("RenderView")
        view.ViewSize = [args.size, args.size]
        view.OrientationAxesVisibility = 0
        rep = simple.Show(data, view)
        rep.SetRepresentationType(T.REPRESENTATION)
        rep.Backend = "CPU"
        rep.ChannelSource = "Components of One Array"
        rep.ChannelComponentsArray = "channels"
        simple.ResetCamera(view)
        channels = len(rep.ChannelLookupTables)
        for spp in args.spp:
            rep.SamplesPerRender = spp
            rep.MaximumTotalSamples = 0
            simple.Render(view)
            still = []
            for _ in range(16):
                t0 = time.perf_counter()
                simple.Render(view)
                still.append(time.perf_counter() - t0)
            cam = view.GetActiveCamera()
            moving = []
            for i in range(16):
                cam.Azimuth(1.0)
                t0 = time.perf_counter()
                simple.Render(view)
                moving.append(time.perf_counter() - t0)
            rep.MaximumTotalSamples = 256
            cam.Azimuth(1.0)
            t0 = time.perf_counter()
            renders = 0
            while True:
                simple.Render(view)
                renders += 1
                if T.info(rep, "Converged"):
                    break
            full = time.perf_counter() - t0
            rows.append((name, channels, spp, 1e3 * statistics.median(still), 1e3 * statistics.median(moving),
                         full, renders))
            print(rows[-1])
            sys.stdout.flush()
        simple.Delete(rep)
        simple.Delete(view)
        simple.Delete(data)
    os.makedirs(args.out, exist_ok=True)
    base = os.path.join(args.out, "paraview_%s" % args.label)
    with open(base + ".csv", "w") as f:
        f.write("dataset,channels,samples_per_render,still_ms,interactive_ms,to_256spp_s,renders\n")
        for r in rows:
            f.write("%s,%d,%d,%.1f,%.1f,%.2f,%d\n" % r)
    with open(base + ".md", "w") as f:
        f.write("Plugin frame times, %s, %d rank(s), %dx%d, CPU backend, %s, %s\n\n"
                % (args.label, ranks, args.size, args.size, time.strftime("%Y-%m-%d"), os.uname().nodename))
        f.write("| dataset | channels | samples per render | still render (ms) | interactive frame (ms) "
                "| to 256 spp (s) | renders |\n|---|---|---|---|---|---|---|\n")
        for r in rows:
            f.write("| %s | %d | %d | %.1f | %.1f | %.2f | %d |\n" % r)
    print("wrote " + base + ".md")


main()
