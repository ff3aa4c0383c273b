"""An OME-Zarr file's own levels against the mapper's extinction pyramid.

A file's coarser levels average the intensities of 2x2x2 blocks; the
mapper's levels of detail average the extinction of the classified voxels
(Kraus and Buerger; Documentation/user-guide/levels-of-detail.md). Both give
a volume with half the voxels per axis, but an opacity computed from averaged
intensities is not the averaged opacity: where a thin bright structure
(membrane, punctum) meets background, averaging the intensity first dilutes
it below the opacity ramp.

On Data/cells_omezarr.py's volume (256x256x64, 3 channels, 3 levels), each
image rendered by the ray-marching reference (deterministic) with the
file's omero transfer functions and one camera:

    reference   file level 0, mapper level 0
    file-L      file level L, mapper level 0 (what reading level L gives)
    mapper-L    file level 0, mapper level L (the extinction pyramid)

and the RMSE (linear RGB over the black background, and alpha) and PSNR of
each against the reference.

    python3 Benchmarks/studies/omezarr_file_levels.py --out DIR [--size 384]

(the build's mcvol package on PYTHONPATH, under xvfb-run). Writes
file_levels.csv, the images (PNG) and meta.txt into --out.
"""

import argparse
import json
import os
import subprocess
import sys

import numpy as np

HERE = os.path.dirname(os.path.abspath(__file__))
TOP = os.path.dirname(os.path.dirname(HERE))


def read_pfm(path):
    with open(path, "rb") as f:
        kind = f.readline().strip()
        w, h = (int(v) for v in f.readline().split())
        scale = float(f.readline())
        values = np.frombuffer(f.read(), "<f4" if scale < 0 else ">f4")
    return values.reshape(h, w, 3 if kind == b"PF" else 1)


def main():
    p = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    p.add_argument("--out", required=True)
    p.add_argument("--size", type=int, default=384)
    p.add_argument("--render", default=os.path.join(TOP, "build", "bin", "mcvol-render"))
    args = p.parse_args()
    os.makedirs(args.out, exist_ok=True)
    sys.path.insert(0, os.path.join(TOP, "Data"))
    import cells_omezarr

    folder = cells_omezarr.write(os.path.join(args.out, "cells.ome.zarr"))
    # One camera for all: level 0's centre, seen from the front and above.
    centre = [25.5, 25.5, 25.2]
    camera = {"focal_point": centre, "position": [centre[0] + 60.0, centre[1] - 80.0, centre[2] + 70.0],
              "view_up": [0, 0, 1], "view_angle": 30}
    cases = [("reference", 0, 0)] + [(kind + "-%d" % level, level if kind == "file" else 0,
                                      level if kind == "mapper" else 0)
                                     for level in (1, 2) for kind in ("file", "mapper")]
    images = {}
    for name, file_level, mapper_level in cases:
        scene = {"input": {"file": folder, "level": file_level}, "renderer": "raymarch",
                 "level_of_detail": mapper_level, "image_size": [args.size, args.size], "camera": camera,
                 "backend": "cpu"}
        fn = os.path.join(args.out, name + ".json")
        with open(fn, "w") as f:
            json.dump(scene, f)
        rgb, alpha = os.path.join(args.out, name + ".pfm"), os.path.join(args.out, name + "-alpha.pfm")
        r = subprocess.run([args.render, fn, "-o", os.path.join(args.out, name + ".png"), "--raw", rgb,
                            "--raw-alpha", alpha, "--quiet"], stderr=subprocess.PIPE, text=True)
        if r.returncode != 0:
            raise SystemExit("%s: %s" % (name, r.stderr))
        images[name] = (read_pfm(rgb), read_pfm(alpha))
        for path in (rgb, alpha, fn):
            os.remove(path)
    ref_rgb, ref_alpha = images["reference"]
    rows = []
    for name, _, _ in cases[1:]:
        rgb, alpha = images[name]
        rmse = float(np.sqrt(np.mean((rgb - ref_rgb) ** 2)))
        rmse_alpha = float(np.sqrt(np.mean((alpha - ref_alpha) ** 2)))
        mean_alpha = float(alpha.mean())
        rows.append((name, rmse, 20 * np.log10(1.0 / rmse) if rmse > 0 else float("inf"), rmse_alpha, mean_alpha))
    with open(os.path.join(args.out, "file_levels.csv"), "w") as f:
        f.write("image,rmse_rgb,psnr_db,rmse_alpha,mean_alpha\n")
        f.write("reference,0,inf,0,%.5f\n" % float(ref_alpha.mean()))
        for row in rows:
            f.write("%s,%.5f,%.2f,%.5f,%.5f\n" % row)
    with open(os.path.join(args.out, "meta.txt"), "w") as f:
        f.write("Data/cells_omezarr.py volume, 256x256x64, levels averaged 2x2x2; ray-marching reference, %dx%d, "
                "CPU; transfer functions from the file's omero windows\n" % (args.size, args.size))
    print(open(os.path.join(args.out, "file_levels.csv")).read())


if __name__ == "__main__":
    main()
