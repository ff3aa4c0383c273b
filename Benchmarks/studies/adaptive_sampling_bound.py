"""What adaptive sampling could buy the refinement stop (stop_rule.py): the
image an oracle allocation of samples to tiles reaches in a fraction of the
time of 256 samples per pixel everywhere, on the scenes stop_rule.py uses, on
the CPU.

Optimal allocation: with pixel (or tile) i of per-sample variance s_i^2 and
cost c_i per sample, n_i samples give the image a squared error of
mean(s_i^2 / n_i) for a time of sum(c_i n_i); the best allocation for a given
time is n_i ~ s_i / sqrt(c_i), and its gain in error x time over the same
samples everywhere is

    G = sum(s_i^2) sum(c_i) / (sum(s_i sqrt(c_i)))^2.

An image within 1 dB of the 256-sample image in a third of its time needs
G >= 3 / 10^0.1 = 2.38.

For each scene:

- a reference of --reference-spp samples and the 256-sample image (seeds of
  their own), rendered whole;
- s_i^2 from --replicates images of --replicate-spp samples (independent
  seeds), per pixel and per tile of --tile x --tile pixels;
- c_i measured: every tile rendered alone (the same rays: the camera's
  view angle or parallel scale divided by the tiles per side, its window
  centre on the tile) with --replicate-spp samples, its process CPU time less
  that of the cheapest tile (the per-render overhead a tile renderer would
  not pay);
- the oracle: every tile rendered alone with n_i ~ s_i / sqrt(c_i) samples
  (at least 1), scaled so that sum(c_i n_i) is --time-fraction of 256
  samples everywhere, and the mosaic scored against the reference.

The oracle knows each tile's variance before it renders, which a renderer
does not, so its PSNR is an upper bound for tile-adaptive sampling at that
time; G per pixel (each tile's cost shared by its pixels) bounds finer
allocation, optimistically: per-pixel variances from a few replicates are
noisy, which inflates G.

    OMP_WAIT_POLICY=PASSIVE xvfb-run -a python3 Benchmarks/studies/adaptive_sampling_bound.py --out DIR

(PYTHONPATH=build/lib/python3.11/site-packages). Writes DIR/adaptive_bound.csv
and prints a Markdown table.
"""

import argparse
import copy
import json
import math
import os
import sys
import time

import numpy as np

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, HERE)
import stop_rule  # noqa: E402  (the scenes and the reference's noise correction)


def pipeline(scene, size, total, seed):
    from mcvol.scenefile import ErrorCollector, Presets, parse_scene
    from mcvol.scenefile.assemble import assemble

    data = copy.deepcopy(scene[1])
    data["image_size"] = [size, size]
    data["backend"] = "cpu"
    data["seed"] = seed
    data["samples_per_pixel"] = total
    data["samples_per_render"] = total
    parsed = parse_scene(data, scene[2], Presets(stop_rule.PRESETS))
    errors = ErrorCollector()
    p = assemble(parsed, errors, "adaptive_sampling_bound.py")
    p.mapper.SetInteractiveFrameTime(0)
    p.mapper.SetTargetError(0)
    return p, errors


def refine(p, errors, total, size):
    """Renders to `total` samples per pixel in one render; returns (process
    CPU seconds, premultiplied RGBA (size, size, 4))."""
    from vtkmodules.vtkCommonCore import vtkFloatArray
    from vtkmodules.util.numpy_support import vtk_to_numpy

    p.mapper.SetSamplesPerPixel(total)
    p.mapper.SetMaximumTotalSamples(total)
    start = time.process_time()
    while True:
        # At least one render: the sample count read before it is the
        # previous view's (a changed camera or seed restarts at the render).
        p.window.Render()
        if errors.messages:
            raise RuntimeError(errors.messages[-1])
        if p.mapper.GetTotalSamples() >= total:
            break
    seconds = time.process_time() - start
    out = vtkFloatArray()
    p.mapper.GetAccumulatedImage(out)
    return seconds, vtk_to_numpy(out).reshape(size, size, 4).astype(np.float64)


def whole(scene, size, total, seed):
    p, errors = pipeline(scene, size, total, seed)
    return refine(p, errors, total, size)


def tiles(scene, size, tile, counts, seed):
    """Renders tile (i, j) (i from the left, j from the bottom) alone with
    counts[j, i] samples (none where 0); returns (CPU seconds per tile,
    mosaic)."""
    per_side = size // tile
    p, errors = pipeline(scene, tile, 1, seed)
    cam = p.renderer.GetActiveCamera()
    if cam.GetParallelProjection():
        cam.SetParallelScale(cam.GetParallelScale() / per_side)
    else:
        half = math.radians(cam.GetViewAngle()) / 2.0
        cam.SetViewAngle(2.0 * math.degrees(math.atan(math.tan(half) / per_side)))
    mosaic = np.zeros((size, size, 4))
    cost = np.zeros((per_side, per_side))
    for j in range(per_side):
        for i in range(per_side):
            n = int(counts[j, i])
            if n <= 0:
                continue
            # The tile's centre in the whole image's normalised coordinates,
            # in units of the tile's half-width.
            cam.SetWindowCenter(-per_side + 2 * i + 1, -per_side + 2 * j + 1)
            p.mapper.SetSeed(seed + 7919 * (j * per_side + i))
            cost[j, i], img = refine(p, errors, n, tile)
            mosaic[j * tile:(j + 1) * tile, i * tile:(i + 1) * tile] = img
    return cost, mosaic


def block_mean(a, t):
    h, w = a.shape[:2]
    return a.reshape(h // t, t, w // t, t).mean((1, 3))


def gain(var, cost):
    s = np.sqrt(var)
    return float(var.sum() * cost.sum() / (s * np.sqrt(cost)).sum() ** 2)


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--out", required=True)
    ap.add_argument("--size", type=int, default=128, help="image width and height (default 128)")
    ap.add_argument("--scale", type=float, default=0.25, help="paper-sized datasets scaled by this (default 1/4)")
    ap.add_argument("--tile", type=int, default=8, help="tile width in pixels (default 8)")
    ap.add_argument("--reference-spp", type=int, default=1024)
    ap.add_argument("--replicates", type=int, default=4)
    ap.add_argument("--replicate-spp", type=int, default=64)
    ap.add_argument("--time-fraction", type=float, default=1.0 / 3.0)
    args = ap.parse_args()
    if args.size % args.tile:
        ap.error("--size must be a multiple of --tile")
    os.makedirs(args.out, exist_ok=True)
    args.frame_time = 0.0
    per_side = args.size // args.tile
    rows = []
    for scene in stop_rule.scenes(args):
        _, ref = whole(scene, args.size, args.reference_spp, 12345)
        _, cap = whole(scene, args.size, 256, 1)
        reps = np.stack([whole(scene, args.size, args.replicate_spp, 100 + r)[1] for r in range(args.replicates)])
        var_pixel = args.replicate_spp * reps[..., :3].var(0, ddof=1).mean(-1)
        var_tile = block_mean(var_pixel, args.tile)
        spent, _ = tiles(scene, args.size, args.tile, np.full((per_side, per_side), args.replicate_spp), 500)
        cost = np.maximum(spent - spent.min(), 1e-6) / args.replicate_spp
        weight = np.sqrt(var_tile / cost)
        scale = args.time_fraction * 256.0 * cost.sum() / (weight * cost).sum()
        counts = np.clip(np.round(scale * weight), 1, 4096)
        _, oracle = tiles(scene, args.size, args.tile, counts, 900)
        # The reference's own noise, as stop_rule.py takes it out.
        r = 256.0 / args.reference_spp
        ref_mse = float(np.mean((cap[..., :3] - ref[..., :3]) ** 2)) * r / (1.0 + r)
        cap_mse = float(np.mean((cap[..., :3] - ref[..., :3]) ** 2)) - ref_mse
        oracle_mse = float(np.mean((oracle[..., :3] - ref[..., :3]) ** 2)) - ref_mse
        pixel_cost = np.repeat(np.repeat(cost / args.tile ** 2, args.tile, 0), args.tile, 1)
        row = {
            "scene": scene[0],
            "psnr_256": round(stop_rule.psnr(cap_mse), 2),
            "oracle_psnr": round(stop_rule.psnr(oracle_mse), 2),
            "oracle_time_ratio": round(float((counts * cost).sum() / (256.0 * cost.sum())), 3),
            "oracle_minus_256_db": round(stop_rule.psnr(oracle_mse) - stop_rule.psnr(cap_mse), 2),
            "uniform_minus_256_db": round(10.0 * math.log10(args.time_fraction), 2),
            "gain_tiles": round(gain(var_tile, cost), 2),
            "gain_pixels": round(gain(var_pixel, pixel_cost), 2),
            "gain_needed": round(1.0 / (args.time_fraction * 10 ** 0.1), 2),
            "tile_overhead_s": round(float(spent.min()), 4),
        }
        rows.append(row)
        print(json.dumps(row))
        sys.stdout.flush()
    stop_rule.write_rows(os.path.join(args.out, "adaptive_bound.csv"), rows)
    print("\n| scene | PSNR at 256 | oracle at %.2f of the time | oracle - 256 (dB) | G tiles | G pixels | G needed |"
          % args.time_fraction)
    print("|---|---|---|---|---|---|---|")
    for r in rows:
        print("| %s | %.1f | %.1f | %.1f | %.2f | %.2f | %.2f |" % (
            r["scene"], r["psnr_256"], r["oracle_psnr"], r["oracle_minus_256_db"], r["gain_tiles"],
            r["gain_pixels"], r["gain_needed"]))


if __name__ == "__main__":
    main()
