"""Where progressive refinement should stop: the image at a target error
against the image at 256 samples per pixel (ParaView's Maximum Total Samples), on the
gallery scenes and the four paper-sized datasets at a small size, on the CPU.

Each scene is refined as the ParaView plugin refines it by default (a frame
time budget of 0.05 s per render), through vtkMultiChannelVolumeMapper:

- to 256 samples per pixel with no target error: its time and image;
- for each target error, until the estimate reaches it (at least 16 samples,
  at most 256): the samples, time and image at the stop;
- a reference of --reference-spp samples with another seed.

Errors are measured against the reference, on the linear premultiplied RGB
(the quantity TargetError bounds) and on the 8-bit image the view shows
(composited over the scene's background). The reference's own noise is
taken out of the squared errors ("corrected"), assuming the error falls as
1/N from the cap image to the reference. Times are the CPU time of the
process (all its threads), which other programs on the machine disturb less
than the wall time (both are recorded); time_ratio is the stop's CPU time
over the 256-sample image's. Run it with OMP_WAIT_POLICY=PASSIVE on a shared
machine (waiting OpenMP threads then sleep instead of spinning, which would
count as CPU time).

    xvfb-run -a python3 Benchmarks/studies/stop_rule.py --out DIR [--size 128]

(PYTHONPATH=build/lib/python3.11/site-packages). Writes DIR/stop_rule.csv and
prints a Markdown table. The gallery scenes need Debian's mricron-data and are
left out without it.
"""

import argparse
import copy
import csv
import json
import math
import os
import sys
import time

import numpy as np

HERE = os.path.dirname(os.path.abspath(__file__))
SOURCE = os.path.dirname(os.path.dirname(HERE))
GALLERY = os.path.join(SOURCE, "Data", "gallery")
PRESETS = os.path.join(SOURCE, "Data", "presets.json")

# The four paper-sized datasets (Benchmarks/gpu/bench.sh), scaled down.
PAPER_SETS = [
    ("NYX-like", "cosmology", (512, 512, 512), 4),
    ("Hurricane-like", "weather", (500, 500, 100), 4),
    ("Miranda-like", "cosmology", (256, 384, 384), 4),
    ("Zebrafish-like", "microscopy", (640, 640, 121), 3),
]


def scenes(args):
    out = []
    for name, demo, dims, channels in PAPER_SETS:
        small = [max(8, int(round(d * args.scale))) for d in dims]
        out.append((name + " %dx%dx%d" % tuple(small),
                    {"input": {"demo": demo, "dimensions": small, "channels": channels}}, SOURCE))
    if os.path.isdir("/usr/share/mricron/templates"):
        for fn in sorted(os.listdir(GALLERY)):
            if fn.endswith(".json"):
                with open(os.path.join(GALLERY, fn)) as f:
                    out.append(("gallery " + fn[:-5], json.load(f), GALLERY))
    else:
        print("mricron-data is not installed: the gallery scenes are left out", file=sys.stderr)
    return out


def run(scene, args, target, total, seed):
    """Refines the scene; returns ((wall seconds, CPU seconds of this
    process), samples, estimated RMSE, premultiplied RGBA (h, w, 4),
    background)."""
    from vtkmodules.vtkCommonCore import vtkFloatArray
    from vtkmodules.util.numpy_support import vtk_to_numpy
    from mcvol.scenefile import ErrorCollector, Presets, parse_scene
    from mcvol.scenefile.assemble import assemble

    data = copy.deepcopy(scene[1])
    data["image_size"] = [args.size, args.size]
    data["backend"] = "cpu"
    data["seed"] = seed
    data["samples_per_pixel"] = total
    data["samples_per_render"] = 1
    parsed = parse_scene(data, scene[2], Presets(PRESETS))
    errors = ErrorCollector()
    p = assemble(parsed, errors, "stop_rule.py")
    m = p.mapper
    m.SetInteractiveFrameTime(args.frame_time)
    m.SetMaximumTotalSamples(total)
    m.SetTargetError(target)
    start = time.perf_counter()
    cpu_start = time.process_time()
    while True:
        p.window.Render()
        if errors.messages:
            raise RuntimeError(errors.messages[-1])
        if m.IsConverged():
            break
    seconds = time.perf_counter() - start
    cpu_seconds = time.process_time() - cpu_start
    out = vtkFloatArray()
    m.GetAccumulatedImage(out)
    w, h = parsed["image_size"]
    img = vtk_to_numpy(out).reshape(h, w, 4).astype(np.float64)
    return (seconds, cpu_seconds), m.GetTotalSamples(), m.GetEstimatedError(), img, np.array(parsed["background"], dtype=float)


def display(img, background):
    """The 8-bit image the view shows: premultiplied colour over the background."""
    rgb = img[..., :3] + background[None, None, :] * (1.0 - img[..., 3:4])
    return np.clip(np.round(rgb * 255.0), 0, 255)


def write_rows(path, rows):
    """The rows (dicts of one set of keys) as a CSV file."""
    with open(path, "w", newline="") as f:
        w = csv.DictWriter(f, fieldnames=list(rows[0].keys()))
        w.writeheader()
        w.writerows(rows)


def psnr(mse, peak=1.0):
    return float("inf") if mse <= 0 else 10.0 * math.log10(peak * peak / mse)


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--out", required=True)
    ap.add_argument("--size", type=int, default=128, help="image width and height (default 128)")
    ap.add_argument("--scale", type=float, default=0.25, help="paper-sized datasets scaled by this (default 1/4)")
    ap.add_argument("--targets", default="0.002,0.003,0.004,0.005", help="target errors (RMSE) to try")
    ap.add_argument("--cap", type=int, default=256, help="the fixed sample count compared against (default 256)")
    ap.add_argument("--reference-spp", type=int, default=2048)
    ap.add_argument("--frame-time", type=float, default=0.05, help="seconds per render (ParaView's default 0.05)")
    args = ap.parse_args()
    os.makedirs(args.out, exist_ok=True)
    targets = [float(x) for x in args.targets.split(",")]
    rows = []
    for scene in scenes(args):
        name = scene[0]
        ref_s, ref_n, ref_err, ref, bg = run(scene, args, 0.0, args.reference_spp, 12345)
        ref8 = display(ref, bg)
        cap_s, cap_n, cap_err, cap, _ = run(scene, args, 0.0, args.cap, 1)
        # The reference's own noise: with the error falling as 1/N, the
        # squared difference of the cap image and the reference (independent
        # seeds) is MSE_cap (1 + r), r = cap / reference samples, of which
        # MSE_cap r is the reference's.
        r = float(cap_n) / float(ref_n)
        raw_cap = float(np.mean((cap[..., :3] - ref[..., :3]) ** 2))
        raw_cap8 = float(np.mean((display(cap, bg) - ref8) ** 2))
        ref_mse, ref_mse8 = raw_cap * r / (1.0 + r), raw_cap8 * r / (1.0 + r)

        def scores(img):
            mse = float(np.mean((img[..., :3] - ref[..., :3]) ** 2))
            mse8 = float(np.mean((display(img, bg) - ref8) ** 2))
            return mse, max(mse - ref_mse, 1e-30), mse8, max(mse8 - ref_mse8, 1e-30)

        cap_scores = scores(cap)
        for target in targets:
            s, n, err, img, _ = run(scene, args, target, args.cap, 1)
            sc = scores(img)
            row = {
                "scene": name, "target_error": target, "stop_spp": n, "stop_s": round(s[0], 3),
                "cap_spp": cap_n, "cap_s": round(cap_s[0], 3), "stop_cpu_s": round(s[1], 3),
                "cap_cpu_s": round(cap_s[1], 3), "time_ratio": round(s[1] / cap_s[1], 3),
                "sample_ratio": round(n / float(cap_n), 3),
                "stop_estimated_psnr": round(psnr(err ** 2), 2) if err > 0 else "",
                "stop_psnr": round(psnr(sc[0]), 2), "cap_psnr": round(psnr(cap_scores[0]), 2),
                "stop_psnr_corrected": round(psnr(sc[1]), 2), "cap_psnr_corrected": round(psnr(cap_scores[1]), 2),
                "stop_psnr_8bit": round(psnr(sc[2], 255.0), 2), "cap_psnr_8bit": round(psnr(cap_scores[2], 255.0), 2),
                "stop_psnr_8bit_corrected": round(psnr(sc[3], 255.0), 2),
                "cap_psnr_8bit_corrected": round(psnr(cap_scores[3], 255.0), 2),
                "stop_vs_cap_psnr_8bit": round(psnr(float(np.mean((display(img, bg) - display(cap, bg)) ** 2)), 255.0), 2),
                "reference_spp": ref_n,
            }
            rows.append(row)
            print(json.dumps(row))
            sys.stdout.flush()
    write_rows(os.path.join(args.out, "stop_rule.csv"), rows)
    print("\n| scene | target | stop spp | time / 256's | PSNR stop | PSNR 256 | 8-bit PSNR stop | 8-bit PSNR 256 |")
    print("|---|---|---|---|---|---|---|---|")
    for r in rows:
        print("| %s | %g | %d | %.2f | %.1f | %.1f | %.1f | %.1f |" % (
            r["scene"], r["target_error"], r["stop_spp"], r["time_ratio"], r["stop_psnr_corrected"],
            r["cap_psnr_corrected"], r["stop_psnr_8bit_corrected"], r["cap_psnr_8bit_corrected"]))


if __name__ == "__main__":
    main()
