"""`mpiexec -n 2 pvbatch`: a lit volume split over two ranks, whose upper
piece shadows the lower one (mcvolLitSplitScene: an occluder above the split
at z = 32, a slab below it, the light straight down), composited by ParaView
(IceT) in visibility order, equals the single-rank render within the Monte
Carlo error with the default stand-in for lighting across ranks (automatic,
LightingStandInLevel -2: the exact one for this small volume), with which
the ranks split the image (SplitImageWithExactStandIn, default on), and
with the image split off (sort-last: each rank's camera rays in its piece). With the camera
inside the lower piece looking away from the upper one, which IceT then does
not render, the render still finishes (the stand-in is gathered in the pass
every rank runs). Shade on, one directional scene light, ambient
light, two scattering events: shadow rays and scattered rays cross the
pieces.

Run with the system Python (it starts pvbatch itself):
  python3 TestParaViewParallelLit.py --pvbatch pvbatch --mpiexec mpiexec

Statistic (as TestParaViewParallel). All images are 128-spp estimates with
fixed, independent seeds: 9 for the parallel renders, 7 and 8 for two serial
renders. If the parallel image is unbiased, the mean squared difference
parallel - serial(7) has the expectation of serial(8) - serial(7), so their
ratio is near 1. The test requires a ratio below 1.2. Significance: the
ratio's standard error (delta method over the pixels, printed) is about
0.03 here, so 1.2 lies more than 6 standard errors above 1 and a correct
image fails with probability below 1e-9 (one-sided, normal approximation).
With the image split the ranks leave their seed offsets out, so the
parallel render of seed 7 must be the serial image of seed 7: its mean
squared difference to it must be below 1% of serial(8) - serial(7)'s
(measured: 0, bit for bit). Power: the same parallel render with the stand-in off (light paths end at
the piece, so the occluder casts no shadow onto the slab) must give a ratio
above 1.5; this also proves that the scene's shadows cross the pieces. (The
coarse stand-ins' error is reported by TestParallelLitRayMarch, noise-free,
and measured for this mapper in Benchmarks/results/lighting-across-ranks.)
"""
import os
import subprocess
import sys

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, HERE)
sys.path.insert(0, os.path.join(os.path.dirname(HERE), "Python"))
from mcvolTesting import read_png_rgb  # noqa: E402
import mcvolLitSplitScene as S  # noqa: E402
import mcvolParallelDriver as D  # noqa: E402

SAMPLES = 128


def main():
    args, env, tmp = D.setup("mcvol-parallel-lit-")
    script = os.path.join(HERE, "ParallelLitRender.py")
    from vtkmodules.vtkIOXML import vtkXMLImageDataWriter
    scene = os.path.join(tmp, "scene.vti")
    writer = vtkXMLImageDataWriter()
    writer.SetInputData(S.image())
    writer.SetFileName(scene)
    writer.Write()

    reports = {}

    def run(name, seed, level="default", ranks=1, samples=SAMPLES, camera="scene", split="split", timeout=300):
        out = os.path.join(tmp, name + ".png")
        cmd = [args.pvbatch, script, scene, out, str(seed), str(level), str(samples), camera, split]
        if ranks > 1:
            cmd = [args.mpiexec, "--oversubscribe", "-n", str(ranks)] + cmd
        print("$ " + " ".join(cmd), flush=True)
        try:
            res = subprocess.run(cmd, env=env, stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True,
                                 timeout=timeout)
        except subprocess.TimeoutExpired:
            raise SystemExit("FAIL: %s did not finish within %d s (a rank waits for another)" % (name, timeout))
        lines = [l for l in res.stdout.splitlines() if l.startswith(("pieces:", "samples:", "stand-in:"))]
        print("\n".join(lines))
        if res.returncode != 0 or not os.path.exists(out):
            print(res.stdout[-20000:])
            raise SystemExit("FAIL: %s exited with %d" % (name, res.returncode))
        reports[name] = lines
        pieces = int([l for l in lines if l.startswith("pieces:")][0].split()[1])
        return read_png_rgb(out).astype(float), pieces

    # The camera inside the lower piece, looking away from the upper one:
    # IceT renders only the lower piece's rank, and the stand-in's gather
    # must not wait for the other (it runs in the pass every rank runs).
    run("inside-lower", 9, ranks=args.ranks, samples=16, camera="inside-lower", timeout=120)
    # Lighting Across Ranks Memory 0.1 MiB: the exact stand-in of the
    # 40 x 40 x 64 float volume takes 409,600 bytes, level 1 204,800 and
    # level 2 25,600, so the automatic level must be 2.
    run("parallel-auto-small", 9, level="auto:0.1", ranks=args.ranks, samples=16)
    parallel, pieces = run("parallel", 9, ranks=args.ranks)
    sort_last, _ = run("parallel-sort-last", 9, ranks=args.ranks, split="sort-last")
    off, _ = run("parallel-off", 9, level=-1, ranks=args.ranks)
    # The split image with the serial render's seed: the ranks leave their
    # seed offsets out (they share no pixel), so this is the serial image.
    parallel7, _ = run("parallel-seed7", 7, ranks=args.ranks)
    serial, serial_pieces = run("serial", 7)
    serial2, _ = run("serial2", 8)

    failures = 0

    def check(ok, msg):
        nonlocal failures
        print(("PASS: " if ok else "FAIL: ") + msg)
        failures += 0 if ok else 1

    check(any(l == "samples: 16" for l in reports["inside-lower"]),
          "with one rank's piece out of view the render finishes with all its samples")
    check(any("automatic" in l and "exact stand-in" in l for l in reports["parallel"]),
          "by default the stand-in is the automatic one, exact for this volume")
    check(any("split the image" in l for l in reports["parallel"]) and
          not any("split the image" in l for l in reports["parallel-sort-last"]),
          "with the exact stand-in the ranks split the image by default, and not with it turned off")
    check(any("automatic" in l and "level 2" in l for l in reports["parallel-auto-small"]),
          "within Lighting Across Ranks Memory 0.1 MiB the automatic stand-in is level 2")
    check(pieces == args.ranks and serial_pieces == 1,
          "the data is split into %d pieces in parallel (%d) and 1 serially (%d)" % (args.ranks, pieces, serial_pieces))
    drawn = (serial.sum(axis=2) > 30).mean()
    check(drawn > 0.05, "the serial image shows the volume (%.1f%% of pixels)" % (100 * drawn))
    ratio, se = S.msd_ratio(parallel, serial2, serial)
    sort_ratio, sort_se = S.msd_ratio(sort_last, serial2, serial)
    off_ratio, off_se = S.msd_ratio(off, serial2, serial)
    print("mean squared difference to serial(7) over serial(8)'s: exact stand-in %.3f +- %.3f (sort-last "
          "%.3f +- %.3f), off %.3f +- %.3f (1 standard error)" % (ratio, se, sort_ratio, sort_se, off_ratio, off_se))
    check(ratio < 1.2, "lit parallel equals serial within the Monte Carlo error (ratio %.3f < 1.2)" % ratio)
    check(sort_ratio < 1.2, "so does sort-last with the exact stand-in (ratio %.3f < 1.2)" % sort_ratio)
    same_msd = float(((parallel7 - serial) ** 2).mean())
    noise_msd = float(((serial2 - serial) ** 2).mean())
    check(same_msd < 0.01 * noise_msd,
          "the split image with seed 7 is the serial image of seed 7 (mean squared difference %.4g, under 1%% "
          "of two seeds' %.4g)" % (same_msd, noise_msd))
    check(off_ratio > 1.5, "without the stand-in the shadows across pieces are missing (ratio %.3f > 1.5)" % off_ratio)
    mean_diff = abs(parallel.mean() - serial.mean())
    check(mean_diff < 0.5, "the whole image's mean agrees within 0.5/255 (%.3f)" % mean_diff)
    if failures:
        print("images in " + tmp)
        sys.exit(1)
    print("all checks passed")


if __name__ == "__main__":
    main()
