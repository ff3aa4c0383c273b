"""What lighting across ranks costs: memory per rank, gather time and time
per frame of each stand-in variant (off, exact with the image split or
sort-last, coarse levels), with
`mpiexec -n RANKS pvbatch --symmetric`, the Monte Carlo mapper on the CPU,
the lit split scene of the parallel tests (Testing/ParaView/
mcvolLitSplitScene.py) with every axis SCALE times finer; and each
variant's error against the serial image.

    python3 Benchmarks/studies/lighting_across_ranks.py --scale 4 --out Benchmarks/results/lighting-across-ranks

Needs pvbatch and mpiexec, the mcvol Python package on PYTHONPATH
(build/lib/python3.11/site-packages; the script drives the mapper through
its Python wrapping, not the plugin) and an X server (xvfb-run -a). Writes
ranks.csv (one row
per variant and rank) and error.csv (RMS colour difference of the
composited image to the serial one, the same for a second serial image of
another seed, the Monte Carlo noise, and the ratio of their squares, which
the parallel tests bound).
"""
import argparse
import csv
import os
import re
import subprocess
import tempfile

import numpy as np

HERE = os.path.dirname(os.path.abspath(__file__))
SCRIPT = os.path.join(os.path.dirname(os.path.dirname(HERE)), "Testing", "ParaView", "ParallelLitMapper.py")
LINE = re.compile(r"rank (\d+): extent (\[.*?\]), stand-in: (.*?), memory (\d+) bytes, gathers (\d+), "
                  r"gather ([0-9.]+) s, first frame ([0-9.]+) s, frame ([0-9.]+) s")


def main():
    p = argparse.ArgumentParser()
    p.add_argument("--pvbatch", default="pvbatch")
    p.add_argument("--mpiexec", default="mpiexec")
    p.add_argument("--ranks", type=int, default=2)
    p.add_argument("--scale", type=int, default=4)
    p.add_argument("--spp", type=int, default=4)
    p.add_argument("--frames", type=int, default=5)
    p.add_argument("--error-spp", type=int, default=256)
    p.add_argument("--out", required=True)
    args = p.parse_args()
    env = dict(os.environ)
    env["PYTHONPATH"] = os.path.dirname(SCRIPT) + os.pathsep + env.get("PYTHONPATH", "")
    env.setdefault("OMPI_ALLOW_RUN_AS_ROOT", "1")
    env.setdefault("OMPI_ALLOW_RUN_AS_ROOT_CONFIRM", "1")
    tmp = tempfile.mkdtemp(prefix="mcvol-lit-ranks-")
    os.makedirs(args.out, exist_ok=True)

    def run(level, ranks, seed, spp, frames):
        out = os.path.join(tmp, "img.npy")
        cmd = [args.pvbatch, "--symmetric", SCRIPT, out, "mc", str(seed), str(level), str(spp), "2", "0.05",
               str(frames), str(args.scale)]
        if ranks > 1:
            cmd = [args.mpiexec, "--oversubscribe", "-n", str(ranks)] + cmd
        res = subprocess.run(cmd, env=env, stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True, check=True)
        rows = [m.groups() for m in map(LINE.match, res.stdout.splitlines()) if m]
        print("$ " + " ".join(cmd) + "\n" + "\n".join(l for l in res.stdout.splitlines() if l.startswith("rank")))
        return rows, np.load(out)

    # The exact stand-in splits the image by default; ":sort-last" turns that off.
    variants = [("off", -1), ("exact, image split", 0), ("exact, sort-last", "0:sort-last"), ("level 1", 1),
                ("level 2", 2)]
    with open(os.path.join(args.out, "ranks.csv"), "w", newline="") as f:
        w = csv.writer(f)
        w.writerow(["variant", "ranks", "scale", "rank", "extent", "stand-in", "stand-in bytes", "gather s",
                    "first frame s", "frame s (%d spp)" % args.spp])
        serial, _ = run(-1, 1, 0, args.spp, args.frames)
        for r in serial:
            w.writerow(["serial", 1, args.scale, r[0], r[1], r[2], r[3], r[5], r[6], r[7]])
        for name, level in variants:
            rows, _ = run(level, args.ranks, 0, args.spp, args.frames)
            for r in rows:
                w.writerow([name, args.ranks, args.scale, r[0], r[1], r[2], r[3], r[5], r[6], r[7]])
    _, ref = run(-1, 1, 7, args.error_spp, 0)
    _, ref2 = run(-1, 1, 8, args.error_spp, 0)

    def rms(a):
        return float(np.sqrt(((a - ref)[..., :3] ** 2).mean()))

    with open(os.path.join(args.out, "error.csv"), "w", newline="") as f:
        w = csv.writer(f)
        w.writerow(["variant", "spp", "rms to serial(7)", "rms serial(8) to serial(7)",
                    "msd ratio (the tests' statistic)", "mean colour"])
        for name, level in variants:
            _, img = run(level, args.ranks, 9, args.error_spp, 0)
            w.writerow([name, args.error_spp, "%.6f" % rms(img), "%.6f" % rms(ref2),
                        "%.3f" % (rms(img) / rms(ref2)) ** 2, "%.6f" % ref[..., :3].mean()])


if __name__ == "__main__":
    main()
