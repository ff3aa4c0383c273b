#!/usr/bin/python3
# SPDX-License-Identifier: BSD-3-Clause
"""mcvol-render: renders a scene file with vtkMultiChannelVolumeMapper.

    mcvol-render SCENE.json -o out.png [--raw out.pfm] [--raw-alpha alpha.pfm]
                 [--spp N] [--target-error E] [--size WxH] [--backend cpu|cuda|auto]
                 [--time T] [--zarr-level L] [--memory-budget MIB] [--quiet]
    mcvol-render DATA... -o out.png [options]     (data files or OME-Zarr folders)

The scene format is documented in Documentation/scene-format.md. Errors in the
scene (unknown keys, bad values, missing files) are reported with the key that
holds them and exit with status 2; a failed render exits with status 1.

This file is the command line only: reading, checking and rendering the scene
is the `mcvol.scenefile` package (Wrapping/Python/mcvol/scenefile/), which
Python programs can use as well.

CMake copies this file into the build's bin/ as `mcvol-render`, with the
folder of the `mcvol` Python package and of the built-in presets filled in
below. Run from the source tree, it takes them from PYTHONPATH and ../Data.
"""

import argparse
import json
import os
import sys

# Filled in by configure_file(); left as they are in the source tree.
_CONFIGURED_PYTHON_DIR = "@MCVOL_RENDER_PYTHON_DIR@"
_CONFIGURED_PRESETS_FILE = "@MCVOL_RENDER_PRESETS_FILE@"


def _configured(value):
    return value if value and not value.startswith("@") else None


if _configured(_CONFIGURED_PYTHON_DIR) and _CONFIGURED_PYTHON_DIR not in sys.path:
    sys.path.insert(0, _CONFIGURED_PYTHON_DIR)

PROG = "mcvol-render"
IMPORT_FAILED = "%s: cannot import the mcvol Python package (%s); put the build's python folder on PYTHONPATH"

# Run from the source tree without PYTHONPATH, the package is not found: say
# where it is, rather than print a traceback.
try:
    from mcvol.scenefile import ErrorCollector, Presets, RenderError, SceneError, parse_scene, render
    from mcvol.scenefile.parse import is_omezarr
    from mcvol.scenefile.schema import BACKENDS, BLEND_MODES, COMPOSITING, FILE_FORMATS, split_extension
except ImportError as e:
    print(IMPORT_FAILED % (PROG, e), file=sys.stderr)
    sys.exit(1)


def parse_size(text):
    try:
        w, h = text.lower().split("x")
        w, h = int(w), int(h)
    except ValueError:
        raise argparse.ArgumentTypeError("expected WxH, for example 512x512, got '%s'" % text)
    if not (1 <= w <= 16384 and 1 <= h <= 16384):
        raise argparse.ArgumentTypeError("width and height must be in [1, 16384], got '%s'" % text)
    return [w, h]


def parse_spp(text):
    try:
        n = int(text)
    except ValueError:
        raise argparse.ArgumentTypeError("expected a positive integer, got '%s'" % text)
    if n < 1:
        raise argparse.ArgumentTypeError("expected a positive integer, got '%s'" % text)
    return n


def parse_target_error(text):
    try:
        e = float(text)
    except ValueError:
        raise argparse.ArgumentTypeError("expected a number in [0, 1], got '%s'" % text)
    if not (0.0 <= e <= 1.0):
        raise argparse.ArgumentTypeError("expected a number in [0, 1], got '%s'" % text)
    return e


def default_presets_file():
    env = os.environ.get("MCVOL_PRESETS")
    if env:
        return env
    if _configured(_CONFIGURED_PRESETS_FILE):
        return _CONFIGURED_PRESETS_FILE
    here = os.path.dirname(os.path.abspath(__file__))
    return os.path.join(os.path.dirname(here), "Data", "presets.json")


class OneLineParser(argparse.ArgumentParser):
    """Argument errors on one line, as every other user error (the usage is
    in --help)."""

    def error(self, message):
        print("%s: %s (%s --help shows the options)" % (self.prog, message, self.prog), file=sys.stderr)
        sys.exit(2)


def main(argv=None):
    parser = OneLineParser(
        prog=PROG,
        description="Renders a multi-channel volume scene file with vtkMultiChannelVolumeMapper "
        "(Monte Carlo, multi-density Woodcock tracking). Scene format: Documentation/scene-format.md.",
    )
    parser.add_argument(
        "scene",
        nargs="+",
        help="scene file (JSON), or one or more data files (NIfTI, TIFF, OME-TIFF, OME-Zarr, VTI, MHA, NRRD on one "
        "grid) to "
        "render with default channels: every array (or component) a channel with its own colour",
    )
    parser.add_argument("--blend", choices=BLEND_MODES, help="overrides blend")
    parser.add_argument("-o", "--output", required=True, help="output PNG (RGB over the background)")
    parser.add_argument(
        "--raw", metavar="FILE.pfm", help="also write the linear RGB image (over the background) as a float PFM"
    )
    parser.add_argument("--raw-alpha", metavar="FILE.pfm", help="also write the alpha as a 1-channel float PFM")
    parser.add_argument("--spp", type=parse_spp, help="total samples per pixel (overrides samples_per_pixel)")
    parser.add_argument(
        "--target-error",
        type=parse_target_error,
        metavar="E",
        help="stop once the estimated RMSE of the image reaches E (linear RGB in [0, 1]; overrides target_error; "
        "the samples per pixel are then the cap; 0 = off)",
    )
    parser.add_argument("--size", type=parse_size, metavar="WxH", help="image size (overrides image_size)")
    parser.add_argument("--backend", choices=BACKENDS, help="overrides backend")
    parser.add_argument(
        "--level-of-detail",
        type=int,
        metavar="L",
        help="render pyramid level L (0 = full resolution, -1 = automatic; overrides level_of_detail)",
    )
    parser.add_argument(
        "--reference",
        action="store_true",
        help="render with the ray-marching reference (vtkMultiChannelRayMarchMapper) instead of Monte Carlo",
    )
    step = parser.add_mutually_exclusive_group()
    step.add_argument("--step", type=float, metavar="S", help="ray-marching step in world units (0 = Nyquist)")
    step.add_argument(
        "--step-voxels", type=float, metavar="V", help="ray-marching step in units of the smallest voxel spacing"
    )
    parser.add_argument("--compositing", choices=COMPOSITING, help="ray-marching compositing model")
    parser.add_argument(
        "--no-pixel-jitter",
        action="store_true",
        help="Monte Carlo samples through pixel centres (as the reference) instead of over the pixel area",
    )
    parser.add_argument(
        "--time",
        type=int,
        metavar="T",
        help="time step T (0, 1, ...) of the OME-Zarr inputs (overrides their \"time\")",
    )
    parser.add_argument(
        "--zarr-level",
        metavar="L",
        help="resolution level of the OME-Zarr inputs: an index (0 = full resolution) or a dataset path "
        "(overrides their \"level\"; by default the finest that fits the memory budget)",
    )
    parser.add_argument(
        "--memory-budget",
        type=float,
        metavar="MIB",
        help="memory budget in MiB (overrides memory_budget): the mapper's, and the one that picks the OME-Zarr "
        "level read",
    )
    parser.add_argument("--quiet", action="store_true", help="print nothing on success")
    args = parser.parse_args(argv)
    for opt, v in (("--step", args.step), ("--step-voxels", args.step_voxels)):
        if v is not None and not (v >= 0.0 and v < float("inf")):
            parser.error("%s: expected a finite number >= 0, got %s" % (opt, v))
    if args.step_voxels is not None and args.step_voxels == 0.0:
        parser.error("--step-voxels: must be > 0 (use --step 0 for the Nyquist rate)")

    for opt, fn in (("-o", args.output), ("--raw", args.raw), ("--raw-alpha", args.raw_alpha)):
        if fn is None:
            continue
        if opt != "-o" and not fn.lower().endswith(".pfm"):
            parser.error("%s: expected a .pfm file name, got '%s'" % (opt, fn))
        if os.path.isdir(fn):
            parser.error("%s: '%s' is a folder; give a file name" % (opt, fn))
        folder = os.path.dirname(os.path.abspath(fn))
        if not os.path.isdir(folder):
            parser.error("%s: folder does not exist: %s" % (opt, folder))

    if args.time is not None and args.time < 0:
        parser.error("--time: expected a time step >= 0, got %d" % args.time)
    if args.memory_budget is not None and not (0.0 <= args.memory_budget < float("inf")):
        parser.error("--memory-budget: expected MiB >= 0, got %s" % args.memory_budget)
    data_files = [f for f in args.scene if split_extension(f)[1] in FILE_FORMATS or is_omezarr(f)]
    if data_files:
        # Data files: a scene of their own, with default channels.
        if len(data_files) != len(args.scene):
            parser.error("give one scene file (JSON), or data files only")
        name = data_files[0]
        data = {"input": data_files if len(data_files) > 1 else data_files[0]}
        scene_dir = os.getcwd()
    else:
        if len(args.scene) > 1:
            parser.error("one scene file at a time (several data files are several channels)")
        name = args.scene[0]
        scene_dir = os.path.dirname(os.path.abspath(name))
        try:
            with open(name, "r", encoding="utf-8") as f:
                text = f.read()
        except OSError as e:
            print("%s: %s: cannot read: %s" % (PROG, name, e.strerror), file=sys.stderr)
            return 2
        try:
            data = json.loads(text)
        except ValueError as e:
            print("%s: invalid JSON: %s" % (name, e), file=sys.stderr)
            return 2
        except RecursionError:
            print("%s: invalid scene: arrays or objects nested deeper than Python can read (a scene needs a few "
                  "levels)" % name, file=sys.stderr)
            return 2

    log = (lambda msg: None) if args.quiet else (lambda msg: print(msg, file=sys.stderr))
    try:
        scene = parse_scene(data, scene_dir, Presets(default_presets_file()))
        zarr_inputs = [e for e in scene["input"].get("inputs", []) if e["format"] == "omezarr"]
        if (args.time is not None or args.zarr_level is not None) and not zarr_inputs:
            print("%s: --time and --zarr-level apply to OME-Zarr inputs, and %s has none" % (PROG, name),
                  file=sys.stderr)
            return 2
        if args.memory_budget is not None:
            scene["memory_budget"] = args.memory_budget
        for entry in zarr_inputs:
            if args.time is not None:
                entry["time"] = args.time
            if args.zarr_level is not None:
                entry["level"] = int(args.zarr_level) if args.zarr_level.isdigit() else args.zarr_level
            entry["memory_budget"] = scene["memory_budget"] * 1048576.0
        if args.blend is not None:
            scene["blend"] = args.blend
        if args.spp is not None:
            scene["samples_per_pixel"] = args.spp
        if args.target_error is not None:
            scene["target_error"] = args.target_error
        if args.size is not None:
            scene["image_size"] = args.size
        if args.backend is not None:
            scene["backend"] = args.backend
        if args.level_of_detail is not None:
            if args.level_of_detail < -1:
                print("%s: --level-of-detail: %d is not a level (0, L > 0, or -1 automatic)"
                      % (PROG, args.level_of_detail), file=sys.stderr)
                return 2
            scene["level_of_detail"] = args.level_of_detail
        if args.reference:
            scene["renderer"] = "raymarch"
        if args.step is not None:
            scene["step"] = args.step
        if args.step_voxels is not None:
            scene["step_voxels"] = args.step_voxels
        if args.compositing is not None:
            scene["compositing"] = args.compositing
        if args.no_pixel_jitter:
            scene["pixel_jitter"] = False
        if scene["renderer"] != "raymarch" and (
            args.step is not None or args.step_voxels is not None or args.compositing is not None
        ):
            print("%s: --step, --step-voxels and --compositing apply to the ray-marching reference: add --reference "
                  "(or \"renderer\": \"raymarch\" in the scene)" % PROG, file=sys.stderr)
            return 2
        summary = render(scene, args.output, args.raw, args.raw_alpha, ErrorCollector(), PROG)
        log("%s: %s" % (PROG, summary))
    except SceneError as e:
        print("%s: %s: %s" % (name, e.key or "(top level)", e.message), file=sys.stderr)
        return 2
    except RenderError as e:
        print("%s: %s: rendering failed: %s" % (PROG, name, e), file=sys.stderr)
        return 1
    except ImportError as e:
        print(IMPORT_FAILED % (PROG, e), file=sys.stderr)
        return 1
    return 0


if __name__ == "__main__":
    sys.exit(main())
