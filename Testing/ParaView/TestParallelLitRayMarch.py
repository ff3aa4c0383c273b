"""`mpiexec -n 2 pvbatch --symmetric`: the ray-marching reference mapper
(vtkMultiChannelRayMarchMapper) lights across ranks as the Monte Carlo mapper
does. Each rank marches its piece of the lit split scene (mcvolLitSplitScene:
an occluder in the upper piece shadowing a slab in the lower one, the light
straight down, single scattering, no ambient light) through
ParallelLitMapper.py, which composites the pieces' float images front to
back.

Run with the system Python (it starts pvbatch itself):
  python3 TestParallelLitRayMarch.py --pvbatch pvbatch --mpiexec mpiexec

Statistic. The march is deterministic, so the agreement test compares both
march images with one 256-spp Monte Carlo image of the whole volume
(seed 7): the mean squared difference parallel march - Monte Carlo over
serial march - Monte Carlo must be below 1.2, i.e. the parallel march agrees
with the Monte Carlo mapper as well as the serial march does. Significance:
the ratio's standard error (delta method over the pixels, printed) is about
0.01, so 1.2 lies more than 10 standard errors above 1 (a correct image fails
with probability below 1e-20, one-sided normal approximation). Power: the
parallel march with the stand-in off must give a ratio above 1.5. The
coarse stand-ins' error is reported against the exact one (root mean square
of the colour difference, noise-free since the march is deterministic).
With the exact stand-in the ranks split the image by default
(SplitImageWithExactStandIn), each marching the whole volume for its rows:
the composite must then be the serial march (RMS difference below 1e-5).
Sort-last with the exact stand-in restarts the march's lattice at the piece
boundary and must still be 4x closer to the serial march than no stand-in.
"""
import os
import subprocess
import sys

import numpy as np

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, HERE)
import mcvolLitSplitScene as S  # noqa: E402
import mcvolParallelDriver as D  # noqa: E402


def main():
    args, env, tmp = D.setup("mcvol-parallel-march-")
    script = os.path.join(HERE, "ParallelLitMapper.py")

    def run(name, mapper, level=0, ranks=1, seed=0, spp=1):
        out = os.path.join(tmp, name + ".npy")
        cmd = [args.pvbatch, "--symmetric", script, out, mapper, str(seed), str(level), str(spp), "1", "0"]
        if ranks > 1:
            cmd = [args.mpiexec, "--oversubscribe", "-n", str(ranks)] + cmd
        res = subprocess.run(cmd, env=env, stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True, timeout=300)
        print("$ " + " ".join(cmd))
        print("\n".join(l for l in res.stdout.splitlines() if l.startswith("rank ")))
        if res.returncode != 0 or not os.path.exists(out):
            print(res.stdout[-20000:])
            raise SystemExit("FAIL: %s exited with %d" % (name, res.returncode))
        return np.load(out)

    parallel = run("march-parallel", "march", ranks=args.ranks)
    sort_last = run("march-parallel-sort-last", "march", level="0:sort-last", ranks=args.ranks)
    off = run("march-parallel-off", "march", level=-1, ranks=args.ranks)
    coarse = {k: run("march-parallel-level%d" % k, "march", level=k, ranks=args.ranks) for k in (1, 2)}
    # The automatic level within 100,000 bytes: the exact stand-in of the
    # 40 x 40 x 64 float volume takes 409,600, level 1 204,800 and level 2
    # 25,600, so it must be level 2; within 1e12 bytes, the exact one.
    auto_small = run("march-parallel-auto-100k", "march", level="auto:100000", ranks=args.ranks)
    auto_large = run("march-parallel-auto-1e12", "march", level="auto:1e12", ranks=args.ranks)
    serial = run("march-serial", "march")
    mc = run("mc-serial", "mc", seed=7, spp=256)

    failures = 0

    def check(ok, msg):
        nonlocal failures
        print(("PASS: " if ok else "FAIL: ") + msg)
        failures += 0 if ok else 1

    check(serial[..., 3].max() > 0.5, "the serial march shows the volume")
    ratio, se = S.msd_ratio(parallel, serial, mc)
    off_ratio, off_se = S.msd_ratio(off, serial, mc)
    print("mean squared difference to the Monte Carlo image over the serial march's: parallel %.3f +- %.3f, "
          "off %.3f +- %.3f (1 standard error)" % (ratio, se, off_ratio, off_se))
    check(ratio < 1.2, "the parallel march agrees with the Monte Carlo mapper as the serial march does "
          "(ratio %.3f < 1.2)" % ratio)
    check(off_ratio > 1.5, "without the stand-in the shadows across pieces are missing (ratio %.3f > 1.5)" % off_ratio)

    def rms(a, b):
        return float(np.sqrt(((a - b)[..., :3] ** 2).mean()))

    print("root mean square colour difference to the serial march: exact stand-in %.5f (sort-last %.5f), "
          "level 1 %.5f, level 2 %.5f, off %.5f (mean colour %.5f)"
          % (rms(parallel, serial), rms(sort_last, serial), rms(coarse[1], serial), rms(coarse[2], serial),
             rms(off, serial), serial[..., :3].mean()))
    # With the exact stand-in the ranks split the image by default: each
    # marches the whole volume for its rows, as the serial march does, so
    # only float rounding of the composite's blending of empty pixels is
    # left. Sort-last restarts the march's lattice at the piece boundary.
    check(rms(parallel, serial) < 1e-5,
          "the exact stand-in with the image split gives the serial march (RMS difference %.2g < 1e-5)"
          % rms(parallel, serial))
    check(rms(sort_last, serial) < 0.25 * rms(off, serial),
          "sort-last with the exact stand-in is closer to the serial march than no stand-in by 4x (%.5f, %.5f)"
          % (rms(sort_last, serial), rms(off, serial)))
    check(np.array_equal(auto_small, coarse[2]) and not np.array_equal(auto_small, coarse[1]),
          "the automatic level within 100,000 bytes is level 2 (the same image bit for bit)")
    check(np.array_equal(auto_large, parallel), "the automatic level within 1e12 bytes is the exact stand-in")
    if failures:
        print("images in " + tmp)
        sys.exit(1)
    print("all checks passed")


if __name__ == "__main__":
    main()
