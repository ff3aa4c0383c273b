"""mcvol-render, the scene-file renderer: every example scene under
Data/scenes renders (at a low sample count and a small size) to a PNG of the
requested size that is not blank, with --raw/--raw-alpha PFMs that agree with
it; a render is reproducible; bad scene files and arguments exit with status 2
and a message that names the offending key, without a Python traceback.

    TestSceneFile.py [--mcvol-render PROGRAM] [--scenes DIR] [--work DIR]

Registered by Tools/CMakeLists.txt (it runs the build's bin/mcvol-render).
"""

import argparse
import glob
import json
import os
import re
import subprocess
import sys
import tempfile

import numpy as np

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))

from vtkmodules.util.numpy_support import vtk_to_numpy
from vtkmodules.vtkIOImage import vtkPNGReader

from mcvolTesting import Checker

HERE = os.path.dirname(os.path.abspath(__file__))
SOURCE = os.path.dirname(os.path.dirname(HERE))
WIDTH, HEIGHT = 64, 48


def read_png(filename):
    reader = vtkPNGReader()
    if not reader.CanReadFile(filename):
        return None
    reader.SetFileName(filename)
    reader.Update()
    image = reader.GetOutput()
    w, h, _ = image.GetDimensions()
    pixels = vtk_to_numpy(image.GetPointData().GetScalars())
    return pixels.reshape(h, w, -1)


def read_pfm(filename):
    with open(filename, "rb") as f:
        data = f.read()
    kind, size, scale, body = data.split(b"\n", 3)
    w, h = (int(v) for v in size.split())
    channels = 3 if kind == b"PF" else 1
    order = "<" if float(scale) < 0 else ">"
    return np.frombuffer(body, order + "f4").reshape(h, w, channels)


def run(program, args):
    return subprocess.run(
        [sys.executable, program] + args, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, timeout=300
    )


# (name, scene, key the message must name). Inputs are demos or Data files.
BAD_SCENES = [
    ("unknown-top-key", {"input": {"demo": "figure3"}, "colour": 1}, "colour: unknown key"),
    ("unknown-channel-key", {"input": {"demo": "figure3"}, "channels": [{"component": 0, "opacty": []}]},
     "channels[0].opacty: unknown key"),
    ("unknown-camera-key", {"input": {"demo": "figure3"}, "camera": {"pos": [0, 0, 1]}}, "camera.pos: unknown key"),
    ("missing-input", {"blend": "max"}, "missing required key 'input'"),
    ("bad-demo", {"input": {"demo": "galaxy"}}, "input.demo:"),
    ("bad-demo-dims", {"input": {"demo": "figure3", "dimensions": [8, 8]}}, "input.dimensions:"),
    ("missing-file", {"input": "no-such-file.vti", "channels": [{"component": 0}]}, "input: file not found"),
    ("bad-blend", {"input": {"demo": "figure3"}, "blend": "sum"}, "blend:"),
    ("bad-tracking", {"input": {"demo": "figure3"}, "tracking": "2-dda"}, "tracking:"),
    ("bad-sample-sequence", {"input": {"demo": "figure3"}, "sample_sequence": "halton"}, "sample_sequence:"),
    ("bad-estimator", {"input": {"demo": "figure3"}, "estimator": "track-length"}, "estimator:"),
    ("bad-min-samples", {"input": {"demo": "figure3"}, "min_samples_per_voxel": -1}, "min_samples_per_voxel"),
    ("bad-march-samples", {"input": {"demo": "figure3"}, "march_samples_per_voxel": 0}, "march_samples_per_voxel"),
    ("bad-march-control-variates", {"input": {"demo": "figure3"}, "march_control_variates": "sometimes"},
     "march_control_variates:"),
    ("bad-mix-color", {"input": {"demo": "figure3"}, "blend": "mix", "mix_color": "sum"}, "mix_color:"),
    ("bad-interpolation", {"input": {"demo": "figure3"}, "interpolation": "tricubic"}, "interpolation:"),
    ("cubic-opacity-model",
     {"input": {"demo": "figure3"}, "interpolation": "cubic", "renderer": "raymarch", "compositing": "opacity"},
     "interpolation:"),
    ("bad-spp-type", {"input": {"demo": "figure3"}, "samples_per_pixel": "many"}, "samples_per_pixel:"),
    ("bad-spp-range", {"input": {"demo": "figure3"}, "samples_per_pixel": 0}, "samples_per_pixel:"),
    ("bad-target-error", {"input": {"demo": "figure3"}, "target_error": -0.1}, "target_error:"),
    ("bad-size", {"input": {"demo": "figure3"}, "image_size": [64]}, "image_size:"),
    ("bad-background", {"input": {"demo": "figure3"}, "background": [0, 0, 2]}, "background[2]:"),
    ("bad-zoom", {"input": {"demo": "figure3"}, "camera": {"zoom": 0}}, "camera.zoom:"),
    ("bad-opacity-shape",
     {"input": {"demo": "figure3"}, "channels": [{"component": 0}, {"component": 1}, {"component": 2, "opacity": [0, 1]}]},
     "channels[2].opacity: expected a list of [x, a] pairs"),
    ("bad-opacity-value", {"input": {"demo": "figure3"}, "channels": [{"component": 0, "opacity": [[0, 0], [1, 2]]}]},
     "channels[0].opacity[1][1]:"),
    ("bad-color", {"input": {"demo": "figure3"}, "channels": [{"component": 0, "color": "red"}]},
     "channels[0].color:"),
    ("unknown-preset", {"input": {"demo": "figure3"}, "channels": [{"component": 0, "color": {"preset": "No Such Map"}}]},
     "channels[0].color.preset: unknown preset"),
    ("component-out-of-range", {"input": {"demo": "figure3"}, "channels": [{"component": 3}]},
     "channels[0].component: component 3 out of range"),
    ("unknown-component-name", {"input": {"demo": "figure3"}, "channels": [{"component": "purple_cube"}]},
     "channels[0].component: no component named"),
    ("unknown-array", {"input": {"demo": "figure3"}, "channels": [{"array": "nope"}]},
     "channels[0].array: no point array named"),
    ("bad-unit-distance", {"input": {"demo": "figure3"}, "channels": [{"component": 0, "unit_distance": -1}]},
     "channels[0].unit_distance:"),
    ("bad-mix-weight", {"input": {"demo": "figure3"}, "channels": [{"component": 0, "mix_weight": "heavy"}]},
     "channels[0].mix_weight:"),
    ("bad-level-of-detail", {"input": {"demo": "figure3"}, "level_of_detail": -2}, "level_of_detail:"),
    ("bad-level-of-detail-filter", {"input": {"demo": "figure3"}, "level_of_detail_filter": "gauss"},
     "level_of_detail_filter:"),
    ("bad-memory-budget", {"input": {"demo": "figure3"}, "memory_budget": -1}, "memory_budget:"),
    ("bad-half-precision", {"input": {"demo": "figure3"}, "level_of_detail_half_precision": "yes"},
     "level_of_detail_half_precision:"),
    ("file-needs-opacity", {"input": "../../Data/figure3.vti", "channels": [{"component": 0, "color": [[0, 1, 0, 0]]}]},
     "channels[0]: missing key 'opacity'"),
]


def main():
    p = argparse.ArgumentParser()
    p.add_argument("--mcvol-render", default=os.path.join(SOURCE, "Tools", "mcvol-render.py"))
    p.add_argument("--scenes", default=os.path.join(SOURCE, "Data", "scenes"))
    p.add_argument("--work", default=None)
    args = p.parse_args()
    work = args.work or tempfile.mkdtemp(prefix="TestSceneFile-")
    os.makedirs(work, exist_ok=True)
    program = args.mcvol_render
    t = Checker()

    scenes = sorted(glob.glob(os.path.join(args.scenes, "*.json")))
    t.check(len(scenes) >= 5, "expected at least 5 example scenes in %s, found %d" % (args.scenes, len(scenes)))
    blends = set()
    for scene in scenes:
        name = os.path.splitext(os.path.basename(scene))[0]
        with open(scene) as f:
            blends.add(json.load(f).get("blend", "density"))
        png = os.path.join(work, name + ".png")
        pfm = os.path.join(work, name + ".pfm")
        alpha = os.path.join(work, name + "-alpha.pfm")
        for fn in (png, pfm, alpha):
            if os.path.exists(fn):
                os.remove(fn)
        r = run(
            program,
            [scene, "-o", png, "--spp", "2", "--size", "%dx%d" % (WIDTH, HEIGHT), "--raw", pfm, "--raw-alpha", alpha,
             "--backend", "cpu"],
        )
        if not t.check(r.returncode == 0, "%s: exit status %d: %s" % (name, r.returncode, r.stderr.strip())):
            continue
        image = read_png(png)
        if not t.check(image is not None, "%s: no PNG written" % name):
            continue
        t.check(image.shape == (HEIGHT, WIDTH, 3), "%s: PNG is %s, expected %dx%d RGB" % (name, image.shape, WIDTH, HEIGHT))
        # Not blank: the volume covers part of the frame, so pixels differ.
        spread = float(image.reshape(-1, 3).astype(float).std(axis=0).max())
        t.check(spread > 2.0, "%s: PNG looks blank (pixel std %.2f)" % (name, spread))
        rgb, a = read_pfm(pfm), read_pfm(alpha)
        t.check(rgb.shape == (HEIGHT, WIDTH, 3) and a.shape == (HEIGHT, WIDTH, 1), "%s: PFM sizes %s %s" % (name, rgb.shape, a.shape))
        if rgb.shape == (HEIGHT, WIDTH, 3):
            # The PFM is the float mean composited over the background; the
            # PNG is the same blend done by OpenGL in an 8-bit framebuffer,
            # which saturates at 1 (composite sums can exceed it) and rounds
            # three times: the background as stored (<= 0.5 level), the
            # source colour, which Mesa's llvmpipe converts to the 8-bit
            # target's precision before blending (<= 0.5 level; seen as 1.046
            # levels at a pixel of alpha 0.5), and the result (<= 0.5 level).
            # Same row order (bottom first).
            err = float(np.abs(np.clip(rgb, 0.0, 1.0) * 255.0 - image.astype(np.float32)).max())
            t.check(err <= 1.5 + 1e-3, "%s: PFM and PNG differ by %.3f levels" % (name, err))
        t.check(bool(np.all(np.isfinite(rgb))) and float(a.max()) > 0.0 and float(a.min()) >= 0.0,
                "%s: alpha range [%g, %g]" % (name, float(a.min()), float(a.max())))
    t.check(blends >= {"density", "max", "mix", "composite"}, "example scenes cover blend modes %s" % sorted(blends))

    # Reproducible: the same scene, seed and backend give the same PNG.
    if scenes:
        outs = []
        for i in range(2):
            out = os.path.join(work, "repeat%d.png" % i)
            r = run(program, [scenes[0], "-o", out, "--spp", "2", "--size", "32x32", "--backend", "cpu", "--quiet"])
            t.check(r.returncode == 0 and r.stderr == "", "repeat %d: status %d, output %r" % (i, r.returncode, r.stderr))
            outs.append(read_png(out))
        if outs[0] is not None and outs[1] is not None:
            t.check(np.array_equal(outs[0], outs[1]), "two renders of %s differ" % scenes[0])

    # Data files instead of a scene: default channels, one per array, each
    # visible; several files are several channels; a scene and a data file
    # together are refused.
    micro = os.path.join(SOURCE, "Data", "microscopy.vti")
    if os.path.exists(micro):
        out = os.path.join(work, "datafile.png")
        r = run(program, [micro, "-o", out, "--spp", "4", "--size", "48x48", "--backend", "cpu"])
        t.check(r.returncode == 0 and "3 channel(s)" in r.stderr, "a data file as the scene: %d %r" % (r.returncode, r.stderr))
        img = read_png(out) if r.returncode == 0 else None
        t.check(img is not None and float(img.reshape(-1, 3).astype(float).std(axis=0).max()) > 2.0,
                "a data file with default channels is not blank")
        r = run(program, [micro, "-o", os.path.join(work, "datafile2.png"), "--spp", "2", "--size", "32x32",
                          "--backend", "cpu", "--blend", "max"])
        t.check(r.returncode == 0 and "max blend" in r.stderr, "--blend: %d %r" % (r.returncode, r.stderr))
        r = run(program, [scenes[0] if scenes else micro, micro, "-o", os.path.join(work, "mixed.png")])
        t.check(r.returncode == 2 and not os.path.exists(os.path.join(work, "mixed.png")),
                "a scene file and a data file together are refused: %d %r" % (r.returncode, r.stderr))

    # Levels of detail: the keys reach the mapper (the summary carries its
    # report); a budget in MiB below level 0 falls back to a coarser level.
    fn = os.path.join(work, "lod.json")
    with open(fn, "w") as f:
        json.dump({"input": {"demo": "figure3", "dimensions": [32, 32, 32]}, "level_of_detail": 2,
                   "level_of_detail_filter": "bspline", "seed": 3}, f)
    r = run(program, [fn, "-o", os.path.join(work, "lod.png"), "--spp", "2", "--size", "32x32", "--backend", "cpu"])
    t.check(r.returncode == 0 and "level 2 of 5 (8x8x8" in r.stderr, "level_of_detail 2: %d %r" % (r.returncode, r.stderr))
    r = run(program, [fn, "-o", os.path.join(work, "lod1.png"), "--spp", "2", "--size", "32x32", "--backend", "cpu",
                      "--level-of-detail", "1"])
    t.check(r.returncode == 0 and "level 1 of 5" in r.stderr, "--level-of-detail 1: %d %r" % (r.returncode, r.stderr))
    with open(fn, "w") as f:
        json.dump({"input": {"demo": "figure3", "dimensions": [32, 32, 32]}, "level_of_detail": 2,
                   "level_of_detail_half_precision": False, "seed": 3}, f)
    r = run(program, [fn, "-o", os.path.join(work, "lodf.png"), "--spp", "2", "--size", "32x32", "--backend", "cpu"])
    t.check(r.returncode == 0 and "level 2 of 5 (8x8x8" in r.stderr,
            "level_of_detail_half_precision false: %d %r" % (r.returncode, r.stderr))
    with open(fn, "w") as f:
        json.dump({"input": {"demo": "figure3", "dimensions": [32, 32, 32]}, "memory_budget": 0.1, "seed": 3}, f)
    r = run(program, [fn, "-o", os.path.join(work, "lodmem.png"), "--spp", "2", "--size", "32x32", "--backend", "cpu"])
    t.check(r.returncode == 0 and "memory fallback" in r.stderr, "memory_budget 0.1 MiB: %d %r" % (r.returncode, r.stderr))
    r = run(program, [fn, "-o", os.path.join(work, "lodbad.png"), "--level-of-detail", "-3"])
    t.check(r.returncode == 2 and "--level-of-detail" in r.stderr, "--level-of-detail -3: %d %r" % (r.returncode, r.stderr))

    # min_samples_per_voxel reaches the mapper: the same seed with a floor of
    # 4 tentative collisions per voxel gives other samples (another image).
    imgs = []
    for floor in (0, 4):
        with open(fn, "w") as f:
            json.dump({"input": {"demo": "figure3", "dimensions": [32, 32, 32]}, "seed": 3,
                       "min_samples_per_voxel": floor}, f)
        out = os.path.join(work, "minrate%d.png" % floor)
        r = run(program, [fn, "-o", out, "--spp", "2", "--size", "32x32", "--backend", "cpu", "--quiet"])
        t.check(r.returncode == 0, "min_samples_per_voxel %d: %d %r" % (floor, r.returncode, r.stderr))
        imgs.append(read_png(out) if r.returncode == 0 else None)
    t.check(imgs[0] is not None and imgs[1] is not None and not np.array_equal(imgs[0], imgs[1]),
            "min_samples_per_voxel changes the samples")

    # estimator unbiased-march and march_samples_per_voxel reach the mapper:
    # other samples than the expected-value estimator's and than each other's,
    # and, at 256 spp, the same image as the ray march within 8-bit noise
    # (mean absolute difference below 2 of 255).
    imgs = {}
    for key, extra in (("ev", {}), ("um2", {"estimator": "unbiased-march"}),
                       ("um4", {"estimator": "unbiased-march", "march_samples_per_voxel": 4}),
                       ("march", {"renderer": "raymarch"})):
        with open(fn, "w") as f:
            json.dump(dict({"input": {"demo": "figure3", "dimensions": [32, 32, 32]}, "seed": 3}, **extra), f)
        out = os.path.join(work, "est-%s.png" % key)
        spp = "256" if key in ("um2", "march") else "2"
        r = run(program, [fn, "-o", out, "--spp", spp, "--size", "32x32", "--backend", "cpu", "--quiet"])
        t.check(r.returncode == 0, "estimator %s: %d %r" % (key, r.returncode, r.stderr))
        imgs[key] = read_png(out).astype(np.float64) if r.returncode == 0 else None
    if all(v is not None for v in imgs.values()):
        t.check(not np.array_equal(imgs["ev"], imgs["um4"]), "unbiased-march gives other samples")
        diff = float(np.mean(np.abs(imgs["um2"] - imgs["march"])))
        t.check(diff < 2.0, "unbiased-march at 256 spp against the ray march: mean |difference| %.3f" % diff)

    # march_control_variates reaches the mapper: at pixel centres and 2 strata
    # per voxel the march takes control variates by rate, so "never" gives
    # other samples and "always" the same ones; with jittered pixels "never"
    # changes nothing (the plain strata either way).
    fn = os.path.join(work, "cv.json")
    imgs = {}
    for key, extra in (("by-rate", {}), ("never", {"march_control_variates": "never"}),
                       ("always", {"march_control_variates": "always"}),
                       ("jitter", {"pixel_jitter": True}),
                       ("jitter-never", {"pixel_jitter": True, "march_control_variates": "never"})):
        with open(fn, "w") as f:
            json.dump(dict({"input": {"demo": "figure3", "dimensions": [32, 32, 32]}, "seed": 3,
                            "estimator": "unbiased-march", "pixel_jitter": False}, **extra), f)
        out = os.path.join(work, "cv-%s.png" % key)
        r = run(program, [fn, "-o", out, "--spp", "1", "--size", "32x32", "--backend", "cpu", "--quiet"])
        t.check(r.returncode == 0, "march_control_variates %s: %d %r" % (key, r.returncode, r.stderr))
        imgs[key] = read_png(out) if r.returncode == 0 else None
    if all(v is not None for v in imgs.values()):
        t.check(not np.array_equal(imgs["by-rate"], imgs["never"]), "march_control_variates never: other samples")
        t.check(np.array_equal(imgs["by-rate"], imgs["always"]), "march_control_variates always at 2 per voxel: the same")
        t.check(np.array_equal(imgs["jitter"], imgs["jitter-never"]), "jittered pixels: the plain strata either way")

    # mix_color: a channel alone is dimmed by Eq. 10 (3 equal weights: 1/3 of
    # its colour) and not by the default weighted average.
    means = {}
    for mix_color in ("average", "equation10"):
        fn = os.path.join(work, "mix-%s.json" % mix_color)
        with open(fn, "w") as f:
            json.dump({"input": {"demo": "figure3", "dimensions": [16, 16, 16]}, "blend": "mix",
                       "mix_color": mix_color, "seed": 3}, f)
        out = os.path.join(work, "mix-%s.png" % mix_color)
        r = run(program, [fn, "-o", out, "--spp", "8", "--size", "32x32", "--backend", "cpu", "--quiet"])
        t.check(r.returncode == 0, "mix_color %s: %d %r" % (mix_color, r.returncode, r.stderr))
        means[mix_color] = read_png(out)[..., :3].astype(float).mean() if r.returncode == 0 else 0.0
    t.check(means["average"] > 1.5 * means["equation10"],
            "mix_color average is brighter than equation10 (%.1f vs %.1f)" % (means["average"], means["equation10"]))

    # The ray-marching reference from the command line and from the scene
    # file: one deterministic image, close to a Monte Carlo render of the
    # same scene through pixel centres.
    if scenes:
        ref_out = os.path.join(work, "reference.png")
        r = run(program, [scenes[0], "-o", ref_out, "--size", "48x48", "--reference", "--step-voxels", "0.5",
                          "--raw", os.path.join(work, "reference.pfm")])
        t.check(r.returncode == 0 and "ray march, step" in r.stderr, "--reference: %d %r" % (r.returncode, r.stderr))
        r2 = run(program, [scenes[0], "-o", os.path.join(work, "reference2.png"), "--size", "48x48", "--reference",
                           "--step-voxels", "0.5", "--quiet"])
        t.check(r2.returncode == 0, "--reference again: %r" % r2.stderr)
        t.check(np.array_equal(read_png(ref_out), read_png(os.path.join(work, "reference2.png"))),
                "the reference image is deterministic")
        r = run(program, [scenes[0], "-o", os.path.join(work, "mc.png"), "--size", "48x48", "--spp", "256",
                          "--no-pixel-jitter", "--backend", "cpu", "--raw", os.path.join(work, "mc.pfm"), "--quiet"])
        t.check(r.returncode == 0, "--no-pixel-jitter: %r" % r.stderr)
        if r.returncode == 0:
            ref = read_pfm(os.path.join(work, "reference.pfm"))
            mc = read_pfm(os.path.join(work, "mc.pfm"))
            rmse = float(np.sqrt(((ref - mc) ** 2).mean()))
            # 256 spp leave a noise of a few hundredths; a different scene,
            # camera or blend mode would differ by tenths.
            t.check(rmse < 0.05, "reference and Monte Carlo renders differ: RMSE %.4f" % rmse)
        with open(scenes[0]) as f:
            data = json.load(f)
        if isinstance(data.get("input"), str):  # relative to the scene's folder
            data["input"] = os.path.join(os.path.dirname(os.path.abspath(scenes[0])), data["input"])
        data.update({"renderer": "raymarch", "step": 0.0, "compositing": "opacity"})
        fn = os.path.join(work, "reference-scene.json")
        with open(fn, "w") as f:
            json.dump(data, f)
        r = run(program, [fn, "-o", os.path.join(work, "ref-scene.png"), "--size", "32x32"])
        t.check(r.returncode == 0 and "opacity compositing" in r.stderr, "renderer key: %d %r" % (r.returncode, r.stderr))
        data.update({"renderer": "raytrace"})
        with open(fn, "w") as f:
            json.dump(data, f)
        r = run(program, [fn, "-o", os.path.join(work, "ref-bad.png"), "--size", "32x32"])
        t.check(r.returncode == 2 and "renderer:" in r.stderr, "bad renderer: %d %r" % (r.returncode, r.stderr))

        # target_error: stops at the estimate, the samples per pixel a cap;
        # the summary prints the estimate.
        r = run(program, [scenes[0], "-o", os.path.join(work, "target.png"), "--size", "48x48", "--spp", "1024",
                          "--target-error", "0.02", "--backend", "cpu"])
        m = re.search(r"(\d+) spp .*target error 0.02 reached, estimated RMSE ([0-9.e-]+)", r.stderr)
        t.check(r.returncode == 0 and m is not None and 16 <= int(m.group(1)) < 1024 and float(m.group(2)) <= 0.02,
                "--target-error 0.02: %d %r" % (r.returncode, r.stderr))
        r = run(program, [scenes[0], "-o", os.path.join(work, "target-cap.png"), "--size", "32x32", "--spp", "32",
                          "--target-error", "1e-6", "--backend", "cpu"])
        t.check(r.returncode == 0 and "32 spp" in r.stderr and "not reached (capped)" in r.stderr,
                "an unreachable target stops at the cap: %d %r" % (r.returncode, r.stderr))

    # Bad scenes: status 2, one line naming the key, no traceback, no image.
    bad_dir = os.path.join(work, "bad")
    os.makedirs(bad_dir, exist_ok=True)
    for name, scene, expected in BAD_SCENES:
        # Inputs resolve against the scene's folder: point Data files at Data/.
        if isinstance(scene.get("input"), str) and scene["input"].startswith("../../Data/"):
            scene = dict(scene, input=os.path.join(SOURCE, "Data", os.path.basename(scene["input"])))
        fn = os.path.join(bad_dir, name + ".json")
        with open(fn, "w") as f:
            json.dump(scene, f)
        out = os.path.join(bad_dir, name + ".png")
        r = run(program, [fn, "-o", out, "--spp", "1", "--size", "16x16"])
        t.check(r.returncode == 2, "%s: exit status %d, expected 2 (%s)" % (name, r.returncode, r.stderr.strip()))
        t.check(expected in r.stderr, "%s: message %r does not contain %r" % (name, r.stderr.strip(), expected))
        t.check(len(r.stderr.strip().splitlines()) == 1, "%s: not one line: %r" % (name, r.stderr.strip()[:300]))
        t.check("Traceback" not in r.stderr, "%s: traceback printed" % name)
        t.check(not os.path.exists(out), "%s: an image was written" % name)

    # User errors beyond the scene's keys: status 2, one line, no image.
    folder_vti = os.path.join(bad_dir, "folder.vti")
    os.makedirs(folder_vti, exist_ok=True)
    deep = os.path.join(bad_dir, "deep.json")
    with open(deep, "w") as f:
        f.write('{"input": {"demo": "figure3"}, "camera": {"position": ' + "[" * 100000 + "]" * 100000 + "}}")
    nested = os.path.join(bad_dir, "nested.json")
    with open(nested, "w") as f:
        f.write('{"input": {"demo": "figure3"}, "camera": {"position": ' + "[" * 40 + "]" * 40 + "}}")
    figure3 = os.path.join(SOURCE, "Data", "figure3.vti")
    user_errors = [
        ("nesting beyond Python's recursion", [deep], "nested deeper than Python can read"),
        ("nesting beyond 32 levels", [nested], "nested more than 32 levels"),
        ("-o names a folder", [nested.replace("nested", "ok"), "-o", bad_dir], "is a folder"),
        ("a data file that is a folder", [{"input": "folder.vti"}], "is a folder, not a data file"),
        ("a data file that is a folder, on the command line", [folder_vti], "is a folder, not a data file"),
        ("origin 1e30", [{"input": {"file": figure3, "origin": [1e30, 1e30, 1e30]}}], "from the world origin"),
        ("spacing 1e-25", [{"input": {"file": figure3, "spacing": [1e-25, 1e-25, 1e-25]}}], "world units across"),
    ]
    with open(nested.replace("nested", "ok"), "w") as f:
        json.dump({"input": {"demo": "figure3"}}, f)
    for name, args, expected in user_errors:
        out = os.path.join(bad_dir, "user-error.png")
        if isinstance(args[0], dict):
            fn = os.path.join(bad_dir, "user-error.json")
            with open(fn, "w") as f:
                json.dump(args[0], f)
            args = [fn] + args[1:]
        if "-o" not in args:
            args = args + ["-o", out]
        r = run(program, args + ["--spp", "1", "--size", "16x16"])
        lines = r.stderr.strip().splitlines()
        t.check(r.returncode == 2, "%s: exit status %d, expected 2 (%s)" % (name, r.returncode, r.stderr.strip()[:300]))
        t.check(len(lines) == 1 and expected in r.stderr,
                "%s: expected one line with %r, got %r" % (name, expected, r.stderr.strip()[:300]))
        t.check(not os.path.exists(out), "%s: an image was written" % name)

    # Invalid JSON, a missing scene and bad arguments: status 2, one line,
    # no image, too.
    fn = os.path.join(bad_dir, "invalid.json")
    with open(fn, "w") as f:
        f.write('{"input": {"demo": "figure3"},\n "blend": }\n')
    out = os.path.join(bad_dir, "invalid.png")
    r = run(program, [fn, "-o", out])
    t.check(r.returncode == 2 and "invalid JSON" in r.stderr and "line 2" in r.stderr, "invalid JSON: %d %r" % (r.returncode, r.stderr))
    t.check(len(r.stderr.strip().splitlines()) == 1 and not os.path.exists(out),
            "invalid JSON: one line and no image (%r)" % r.stderr.strip()[:300])
    out = os.path.join(bad_dir, "missing.png")
    r = run(program, [os.path.join(bad_dir, "no-such-scene.json"), "-o", out])
    t.check(r.returncode == 2 and len(r.stderr.strip().splitlines()) == 1 and "no-such-scene.json" in r.stderr
            and not os.path.exists(out), "a missing scene file: %d %r" % (r.returncode, r.stderr.strip()[:300]))
    if scenes:
        for extra, what in ((["--size", "64"], "--size"), (["--spp", "0"], "--spp"), (["--raw", "x.exr"], "--raw"),
                            (["--step", "1"], "--reference"), (["--reference", "--step-voxels", "0"], "--step-voxels"),
                            (["--no-such-option"], "--no-such-option")):
            out = os.path.join(bad_dir, "arg.png")
            r = run(program, [scenes[0], "-o", out] + extra)
            t.check(r.returncode == 2 and what in r.stderr, "argument %s: %d %r" % (extra, r.returncode, r.stderr.strip()))
            t.check(len(r.stderr.strip().splitlines()) == 1 and not os.path.exists(out),
                    "argument %s: one line and no image (%r)" % (extra, r.stderr.strip()[:300]))
    t.finish()


if __name__ == "__main__":
    main()
