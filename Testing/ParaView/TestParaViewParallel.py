"""`mpiexec -n 2 pvbatch`: the figure3 scene split over two ranks, each
rendering its piece, composited by ParaView in visibility order, equals the
single-rank render within the Monte Carlo error. The channels' default
colour functions (the representation's robust ranges, shown before any are
set) and the robust range of a z^2 array span the same range in parallel as
in the single-rank run: those of the whole data set, not of rank 0's piece.

Run with the system Python (it starts pvbatch itself):
  python3 TestParaViewParallel.py --pvbatch pvbatch --mpiexec mpiexec

Statistic. Both sides are 1024-spp Monte Carlo estimates of the same image
with independent seeds (7 and 9 for the serial and parallel renders; 8 for a
second serial render). If the parallel image is unbiased, the mean squared
difference parallel-serial has the same expectation as serial(8)-serial(7),
so their ratio is near 1. The test requires a ratio below 1.2 over the whole
image and, for power, that a 10% error in extinction (the serial scene
rendered with the opacity unit distance scaled by 0.9) gives a ratio above
1.5 against the same serial image. The seeds are fixed, so the result is
reproducible. The ratio is also printed for the silhouette band (drawn
pixels within 2 pixels of the background), where rendering differences
would show first.

FXAA is off in these views (mcvolParaViewTesting.make_view): ParaView 5.11
turns it on by default, and it filters the composited image differently
from the serial one, which showed as differences along silhouettes.
"""
import os
import subprocess
import sys

import numpy as np

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, HERE)
sys.path.insert(0, os.path.join(os.path.dirname(HERE), "Python"))
from mcvolTesting import read_png_rgb  # noqa: E402
import mcvolParallelDriver as D  # noqa: E402


def main():
    args, env, tmp = D.setup("mcvol-parallel-")
    script = os.path.join(HERE, "ParallelRender.py")

    def run(name, seed, ranks=1, scale=1.0):
        out = os.path.join(tmp, name + ".png")
        cmd = [args.pvbatch, script, out, str(seed), repr(scale)]
        if ranks > 1:
            cmd = [args.mpiexec, "--oversubscribe", "-n", str(ranks)] + cmd
        res = subprocess.run(cmd, env=env, stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True, timeout=300)
        print("$ " + " ".join(cmd))
        lines = [l for l in res.stdout.splitlines() if l.startswith(("pieces:", "samples:"))]
        print("\n".join(lines))
        defaults = {}
        for l in res.stdout.splitlines():
            if l.startswith("default range "):
                head, values = l[len("default range "):].split(": ")
                defaults[head] = tuple(float(v) for v in values.split())
        if res.returncode != 0 or not os.path.exists(out):
            print(res.stdout[-20000:])
            raise SystemExit("FAIL: %s exited with %d" % (name, res.returncode))
        pieces = int([l for l in lines if l.startswith("pieces:")][0].split()[1])
        runs_defaults[name] = defaults
        return read_png_rgb(out).astype(float), pieces

    runs_defaults = {}
    parallel, pieces = run("parallel", 9, ranks=args.ranks)
    serial, serial_pieces = run("serial", 7)
    serial2, _ = run("serial2", 8)
    biased, _ = run("biased", 8, scale=0.9)

    failures = 0

    def check(ok, msg):
        nonlocal failures
        print(("PASS: " if ok else "FAIL: ") + msg)
        failures += 0 if ok else 1

    check(pieces == args.ranks and serial_pieces == 1,
          "the data is split into %d pieces in parallel (%d) and 1 serially (%d)" % (args.ranks, pieces, serial_pieces))
    serial_defaults = runs_defaults["serial"]
    parallel_defaults = runs_defaults["parallel"]
    for name in ("channels:0", "channels:1", "channels:2", "height"):
        want, got = serial_defaults.get(name), parallel_defaults.get(name)
        check(want is not None and want[0] < want[1] and got == want,
              "%s: the default range in parallel %s is the single-rank one %s" % (name, got, want))
    drawn = (serial.sum(axis=2) > 30).mean()
    check(drawn > 0.05, "the serial image shows the volume (%.1f%% of pixels)" % (100 * drawn))
    # Interior: drawn pixels more than 2 pixels away from the background;
    # the band: drawn pixels within 2 pixels of it (reported).
    background = serial.sum(axis=2) < 3
    padded = np.pad(background, 2, constant_values=True)
    near = np.zeros_like(background)
    for dy in range(5):
        for dx in range(5):
            near |= padded[dy:dy + background.shape[0], dx:dx + background.shape[1]]
    interior = ~near
    band = near & ~background

    def msd(a, mask):
        return ((a - serial) ** 2).mean(axis=2)[mask].mean()

    everything = np.ones_like(background)
    noise, par, bias = msd(serial2, everything), msd(parallel, everything), msd(biased, everything)
    ratio, bias_ratio = par / noise, bias / noise
    print("whole image, mean squared difference to serial(7): serial(8) %.3f, parallel %.3f, biased %.3f"
          % (noise, par, bias))
    for name, mask in [("interior", interior), ("silhouette band", band)]:
        print("%s (%d pixels): serial(8) %.3f, parallel %.3f, ratio %.3f"
              % (name, mask.sum(), msd(serial2, mask), msd(parallel, mask), msd(parallel, mask) / msd(serial2, mask)))
    check(ratio < 1.2, "parallel equals serial within the Monte Carlo error (ratio %.3f < 1.2)" % ratio)
    check(bias_ratio > 1.5, "the test sees a 10%% extinction error (ratio %.3f > 1.5)" % bias_ratio)
    mean_diff = np.abs(parallel.mean(axis=(0, 1)) - serial.mean(axis=(0, 1))).max()
    check(mean_diff < 0.5, "the whole image's mean colour agrees within 0.5/255 (%.3f)" % mean_diff)
    if failures:
        print("images in " + tmp)
        sys.exit(1)
    print("all checks passed")


if __name__ == "__main__":
    main()
