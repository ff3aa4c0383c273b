"""Memory of a long ParaView session with the plugin (pvpython): the
figure3 channels shown, then N steps (default 10,000) that each edit a
channel's colour and opacity functions (as the colour map editor does), move
the camera, and render. The resident memory is written every --every steps
to --out/paraview-session.csv, with the samples the last render held.

  bash scripts/paraview.sh pvpython Benchmarks/studies/paraview_soak.py \\
      --out Benchmarks/results/accumulation-soak
"""
import argparse
import os
import sys
import time

from paraview import simple

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, os.path.join(os.path.dirname(os.path.dirname(HERE)), "Testing", "ParaView"))
import mcvolParaViewTesting as T  # noqa: E402


def resident_kib():
    with open("/proc/self/status") as f:
        for line in f:
            if line.startswith("VmRSS:"):
                return int(line.split()[1])
    return -1


def main():
    p = argparse.ArgumentParser()
    p.add_argument("--out", required=True)
    p.add_argument("--steps", type=int, default=10000)
    p.add_argument("--every", type=int, default=500)
    p.add_argument("--size", type=int, default=64)
    args = p.parse_args()
    T.load_plugin()
    split, view, rep, names = T.figure3_split_scene(size=(args.size, args.size))
    rep.SamplesPerRender = 1
    rep.MaximumTotalSamples = 0
    os.makedirs(args.out, exist_ok=True)
    rows = ["step,rss_kib,total_samples,seconds"]
    start = time.perf_counter()
    simple.Render(view)
    rows.append("0,%d,%d,0.0" % (resident_kib(), T.info(rep, "TotalSamples")))
    camera = view.GetActiveCamera()
    for step in range(1, args.steps + 1):
        name = names[step % len(names)]
        lut = simple.GetColorTransferFunction(name)
        shade = 0.5 + 0.5 * ((step * 37) % 100) / 100.0
        lut.RGBPoints = [0.0, shade, 0.2, 1.0 - shade, 1.0, shade, 0.2, 1.0 - shade]
        pwf = simple.GetOpacityTransferFunction(name)
        pwf.Points = [0.0, 0.0, 0.5, 0.0, 0.75, 0.2 + 0.2 * shade, 0.5, 0.0, 1.0, 0.35, 0.5, 0.0]
        camera.Azimuth(0.7)
        simple.Render(view)
        if step % args.every == 0:
            rows.append("%d,%d,%d,%.1f" % (step, resident_kib(), T.info(rep, "TotalSamples"),
                                           time.perf_counter() - start))
            print(rows[-1], flush=True)
    with open(os.path.join(args.out, "paraview-session.csv"), "w") as f:
        f.write("\n".join(rows) + "\n")


main()
