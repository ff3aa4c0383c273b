"""OME-Zarr (OME-NGFF 0.4) input (mcvol.omezarr, Documentation/scene-format.md):
files written here with python3-zarr, read back and compared voxel by voxel
with the numpy arrays written.

- every axis order (yx, zyx, czyx, cyx, tczyx, tzyx, tcyx, ctzyx, and the
  non-standard xyz and zcyx): values, dimensions, spacing and origin from
  scale and translation (a level's and the multiscale's);
- types (uint8, uint16 both byte orders, float32, int8 -> int16, int32 ->
  float32) and codecs (blosc, zstd, gzip, none, a delta filter);
- several levels: by index, by path, by memory budget (the finest that
  fits, and said so), also for a file of 2 TiB at full resolution (only
  its metadata exists); a region reads only its chunks (a chunk outside it
  may be missing) and lands at its world position; serial and parallel
  decoding agree;
- omero: names, colours, windows, active flags as default channels;
- mcvol-render on the folder or its .zattrs, --time, --zarr-level,
  --memory-budget, "input" in a scene file;
- errors: a missing chunk without fill_value, a corrupt chunk, an unknown
  codec, NGFF 0.3, zarr format 3, a labels image, a plate, a group without
  multiscales, a time step or level that does not exist: exit status 2, one
  line naming the file, no image. A chunk not stored in an array with a
  fill_value reads as that value.

    TestOMEZarr.py [--mcvol-render PROGRAM] [--work DIR]
"""

import argparse
import json
import os
import shutil
import subprocess
import sys
import tempfile

import numpy as np

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))

try:
    import numcodecs
    import zarr  # noqa: F401
except ImportError:
    print("python3-zarr is not installed: skipped")
    sys.exit(125)

from vtkmodules.util.numpy_support import vtk_to_numpy

import omezarrWriter as W
from mcvolTesting import Checker, read_png_rgb

from mcvol.omezarr import OMEZarrError, OMEZarrImage, display_defaults

HERE = os.path.dirname(os.path.abspath(__file__))
SOURCE = os.path.dirname(os.path.dirname(HERE))
SIZES = {"t": 3, "c": 2, "z": 5, "y": 6, "x": 7}
SCALE = {"t": 0.5, "c": 1.0, "z": 2.0, "y": 0.5, "x": 0.25}
SHIFT = {"t": 10.0, "c": 0.0, "z": 10.0, "y": 20.0, "x": 30.0}


def channel_values(image, name):
    nx, ny, nz = image.GetDimensions()
    array = image.GetPointData().GetArray(name)
    return None if array is None else vtk_to_numpy(array).reshape(nz, ny, nx)


def expected(data, axes, t, c):
    """data (file order) -> the (z, y, x) block of time step t, channel c,
    by axis name (numpy only)."""
    names = list(axes)
    index = []
    for n in names:
        index.append(t if n == "t" else c if n == "c" else slice(None))
    block = data[tuple(index)]
    kept = [n for n in names if n not in "tc"]
    order = [kept.index(a) for a in "zyx" if a in kept]
    block = block.transpose(order)
    return block if "z" in kept else block[np.newaxis]


def test_axis_orders(t, work):
    rng = np.random.default_rng(1)
    for axes in ("yx", "zyx", "czyx", "cyx", "tczyx", "tzyx", "tcyx", "ctzyx", "xyz", "zcyx"):
        shape = [SIZES[a] for a in axes]
        data = rng.integers(0, 65535, shape).astype(np.uint16)
        folder = W.write(os.path.join(work, "order-%s.ome.zarr" % axes), [data], axes,
                         [[SCALE[a] for a in axes]], [[SHIFT[a] for a in axes]], chunks=[[2] * len(axes)])
        image = OMEZarrImage(folder)
        step = SIZES["t"] - 1 if "t" in axes else 0
        out = image.read(time=step)
        nz = SIZES["z"] if "z" in axes else 1
        t.check(out.GetDimensions() == (SIZES["x"], SIZES["y"], nz), "%s: dimensions %s" % (axes, out.GetDimensions()))
        spacing = (0.25, 0.5, 2.0 if "z" in axes else 1.0)
        origin = (30.0, 20.0, 10.0 if "z" in axes else 0.0)
        t.check(np.allclose(out.GetSpacing(), spacing) and np.allclose(out.GetOrigin(), origin),
                "%s: spacing %s origin %s, expected %s %s" % (axes, out.GetSpacing(), out.GetOrigin(), spacing, origin))
        channels = SIZES["c"] if "c" in axes else 1
        for c in range(channels):
            name = "channel %d" % c if "c" in axes else "image"
            values = channel_values(out, name)
            ok = values is not None and np.array_equal(values, expected(data, axes, step, c))
            t.check(ok, "%s: channel %d differs from the file (arrays: %s)" % (
                axes, c, [out.GetPointData().GetArrayName(k) for k in range(out.GetPointData().GetNumberOfArrays())]))
        if "t" in axes:
            t.check(np.allclose(image.time_values, [10.0, 10.5, 11.0]), "%s: time values %s" % (axes, image.time_values))


def test_types_and_codecs(t, work):
    rng = np.random.default_rng(2)
    base = rng.integers(0, 200, (2, 5, 6, 7))
    cases = [
        ("uint8", np.uint8, None, "unsigned char"),
        ("uint16-be", np.dtype(">u2"), numcodecs.Zstd(level=3), "unsigned short"),
        ("uint16", np.uint16, numcodecs.GZip(), "unsigned short"),
        ("float32", np.float32, numcodecs.Blosc(cname="lz4", shuffle=numcodecs.Blosc.BITSHUFFLE), "float"),
        ("int8", np.int8, None, "short"),
        ("int32", np.int32, numcodecs.Zlib(), "float"),
    ]
    for label, dtype, compressor, vtk_type in cases:
        data = (base - (100 if label == "int8" else 0)).astype(dtype)
        if label == "float32":
            data = data * np.float32(0.37) - np.float32(3.5)
        folder = W.write(os.path.join(work, "type-%s.ome.zarr" % label), [data], "czyx",
                         [[1, 1, 1, 1]], chunks=[[1, 2, 4, 3]], compressor=compressor)
        out = OMEZarrImage(folder).read()
        array = out.GetPointData().GetArray("channel 1")
        t.check(array.GetDataTypeAsString() == vtk_type, "%s: read as %s, expected %s" % (
            label, array.GetDataTypeAsString(), vtk_type))
        t.check(np.array_equal(channel_values(out, "channel 1").astype(np.float64), data[1].astype(np.float64)),
                "%s: values differ" % label)
    # A filter before the compressor (delta coding).
    data = np.cumsum(rng.integers(0, 3, (5, 6, 7)), axis=2).astype(np.uint16)
    group = zarr.open_group(os.path.join(work, "delta.ome.zarr"), mode="w")
    group.create_dataset("0", data=data, chunks=(2, 3, 4), filters=[numcodecs.Delta(dtype="u2")])
    group.attrs["multiscales"] = [{"version": "0.4", "axes": W.axes_metadata("zyx"), "datasets": [
        {"path": "0", "coordinateTransformations": [{"type": "scale", "scale": [1, 1, 1]}]}]}]
    out = OMEZarrImage(os.path.join(work, "delta.ome.zarr")).read()
    t.check(np.array_equal(channel_values(out, "delta"), data), "delta filter: values differ")


def pyramid(work, name="levels.ome.zarr", fill_value=0):
    """Three levels of a 2-channel 16x12x8 uint16 image, each half the
    previous along every axis, the voxel centres of a level at the centres
    of the 2x2x2 blocks of the one before (translation +0.5 voxel)."""
    rng = np.random.default_rng(3)
    full = rng.integers(0, 60000, (2, 8, 12, 16)).astype(np.uint16)
    levels = [full, full[:, ::2, ::2, ::2].copy(), full[:, ::4, ::4, ::4].copy()]
    scales, shifts = [], []
    for k in range(3):
        f = 2 ** k
        scales.append([1, 1.5 * f, 1.0 * f, 0.5 * f])
        shifts.append([0, 100 + 0.75 * (f - 1), 0.5 * (f - 1), -4 + 0.25 * (f - 1)])
    return W.write(os.path.join(work, name), levels, "czyx", scales, shifts, chunks=[[1, 4, 4, 4]] * 3,
                   fill_value=fill_value), levels


def test_levels(t, work):
    folder, levels = pyramid(work)
    image = OMEZarrImage(folder)
    t.check(len(image.levels) == 3, "three levels, found %d" % len(image.levels))
    for ask in (2, "2"):
        out = image.read(level=ask)
        t.check(out.GetDimensions() == (4, 3, 2) and np.allclose(out.GetSpacing(), (2.0, 4.0, 6.0))
                and np.allclose(out.GetOrigin(), (-3.25, 1.5, 102.25)),
                "level %r: %s spacing %s origin %s" % (ask, out.GetDimensions(), out.GetSpacing(), out.GetOrigin()))
        t.check(np.array_equal(channel_values(out, "channel 0"), levels[2][0]), "level %r: values" % ask)
    full_bytes = 2 * 8 * 12 * 16 * 2
    out = image.read(memory_budget=full_bytes - 1)
    t.check(image.level == 1 and "finest that fits the memory budget" in image.report and "level 1" in image.report,
            "a budget just under level 0 reads level 1: %r" % image.report)
    image.read(memory_budget=full_bytes)
    t.check(image.level == 0, "a budget of exactly level 0 reads level 0 (%d)" % image.level)
    image.read(memory_budget=10)
    t.check(image.level == 2 and "coarsest" in image.report, "a budget no level fits: the coarsest (%r)" % image.report)
    # A region: full-resolution voxels x 4..11, y 2..9, z 1..6.
    region = [4, 11, 2, 9, 1, 6]
    out = image.read(region=region)
    t.check(out.GetDimensions() == (8, 8, 6) and np.allclose(out.GetOrigin(), (-4 + 4 * 0.5, 2.0, 100 + 1.5)),
            "region at level 0: %s origin %s" % (out.GetDimensions(), out.GetOrigin()))
    t.check(np.array_equal(channel_values(out, "channel 1"), levels[0][1, 1:7, 2:10, 4:12]), "region at level 0: values")
    out = image.read(region=region, level=1)
    # Level 1's voxels whose cells overlap it: x 1..6, y 0..5, z 0..3.
    t.check(out.GetDimensions() == (6, 6, 4), "region at level 1 covers it: %s" % (out.GetDimensions(),))
    t.check(np.array_equal(channel_values(out, "channel 1"), levels[1][1, 0:4, 0:6, 1:7]), "region at level 1: values")
    # Only the region's chunks are read: a chunk far outside it may be gone.
    serial = image.read(threads=1)
    parallel = image.read(threads=4)
    t.check(all(np.array_equal(channel_values(serial, n), channel_values(parallel, n)) for n in image.channel_names),
            "serial and parallel decoding agree")
    gone, _ = pyramid(work, "gone.ome.zarr", fill_value=None)
    os.remove(os.path.join(gone, "0", "1.1.2.3"))  # channel 1, z 4..7, y 8..11, x 12..15
    try:
        OMEZarrImage(gone).read(region=[0, 7, 0, 7, 0, 3])
        t.check(True, "")
    except OMEZarrError as e:
        t.check(False, "a region away from a missing chunk reads: %s" % e)
    try:
        OMEZarrImage(gone).read()
        t.check(False, "the whole level with a chunk missing and no fill_value must fail")
    except OMEZarrError as e:
        t.check("1.1.2.3" in str(e) and "missing" in str(e), "missing chunk message: %s" % e)
    # With a fill_value, a chunk not stored holds it.
    filled, levels = pyramid(work, "filled.ome.zarr", fill_value=7)
    os.remove(os.path.join(filled, "0", "1.1.2.3"))
    image = OMEZarrImage(filled)
    out = image.read()
    want = levels[0][1].copy()
    want[4:8, 8:12, 12:16] = 7
    t.check(np.array_equal(channel_values(out, "channel 1"), want), "a chunk not stored reads as the fill value")
    t.check("1 of 48 chunks not stored" in image.report, "and the report says so: %r" % image.report)


def test_larger_than_memory(t, work, program):
    """Level 0 of 2 x 16384 x 16384 x 2048 uint16 (2 TiB: only its metadata
    exists) and seven coarser levels: a budget of 1 MiB reads the finest
    that fits without touching the others, and says so."""
    group = zarr.open_group(os.path.join(work, "huge.ome.zarr"), mode="w")
    datasets = []
    rng = np.random.default_rng(7)
    for k in range(8):
        f = 2 ** k
        shape = (2, 2048 // f, 16384 // f, 16384 // f)
        if k == 7:
            values = rng.integers(0, 4000, shape).astype(np.uint16)
            group.create_dataset(str(k), data=values, chunks=(1, 16, 64, 64))
            small = values
        else:
            group.create_dataset(str(k), shape=shape, dtype=np.uint16, chunks=(1, 64, 256, 256), fill_value=0)
        datasets.append({"path": str(k), "coordinateTransformations": [{"type": "scale", "scale": [1, f, f, f]}]})
    group.attrs["multiscales"] = [{"version": "0.4", "axes": W.axes_metadata("czyx"), "datasets": datasets}]
    image = OMEZarrImage(os.path.join(work, "huge.ome.zarr"))
    out = image.read(memory_budget=1 << 20)
    t.check(image.level == 7 and out.GetDimensions() == (128, 128, 16) and "finest that fits" in image.report,
            "2 TiB at full resolution, 1 MiB budget: level 7 (%r)" % image.report)
    t.check(np.array_equal(channel_values(out, "channel 1"), small[1]), "level 7's values")
    png = os.path.join(work, "huge.png")
    r = run(program, [os.path.join(work, "huge.ome.zarr"), "-o", png, "--memory-budget", "1", "--spp", "1",
                      "--size", "32x32", "--backend", "cpu"])
    t.check(r.returncode == 0 and "OME-Zarr level 7 ('7', 128x128x16 voxels) of 8: finest that fits the memory "
            "budget of 1 MiB" in r.stderr, "mcvol-render --memory-budget 1 renders level 7 and says so: %r"
            % r.stderr)


def test_omero(t, work):
    data = np.zeros((3, 4, 5, 6), np.uint16)
    data[:, 1:3, 1:4, 1:5] = 1000
    omero = {"channels": [W.omero_channel("DAPI", "0000FF", 100, 900), W.omero_channel("GFP", "00FF00", 50, 500),
                          W.omero_channel("DAPI", "FF0000", 10, 20, active=False)]}
    folder = W.write(os.path.join(work, "omero.ome.zarr"), [data], "czyx", [[1, 1, 1, 1]], omero=omero)
    image = OMEZarrImage(folder)
    t.check(image.channel_names == ["DAPI", "GFP", "DAPI (2)"], "names from labels, made unique: %s"
            % image.channel_names)
    d = display_defaults(image.read())
    t.check(d.get("DAPI") == {"color": (0.0, 0.0, 1.0), "window": [100.0, 900.0], "active": True}
            and d.get("DAPI (2)", {}).get("active") is False and d.get("GFP", {}).get("color") == (0.0, 1.0, 0.0),
            "display defaults: %s" % d)
    from mcvol.scenefile.assemble import default_channels

    chans = default_channels(image.read())
    t.check([c["array"] for c in chans] == ["DAPI", "GFP"], "default channels are the active ones: %s"
            % [c["array"] for c in chans])
    dapi = chans[0]
    t.check(dapi["range"] == [100.0, 900.0] and dapi["color"]["points"][-1][1:] == [0.0, 0.0, 1.0],
            "DAPI's default channel: window and colour (%s, %s)" % (dapi["range"], dapi["color"]["points"]))


def run(program, args):
    return subprocess.run([sys.executable, program] + args, stdout=subprocess.PIPE, stderr=subprocess.PIPE,
                          text=True, timeout=300)


def test_render(t, work, program):
    folder, _ = pyramid(work, "render.ome.zarr")
    out = os.path.join(work, "render.png")
    for target, extra, want in ((folder, [], "OME-Zarr level 0"),
                                (os.path.join(folder, ".zattrs"), ["--memory-budget", "0.005"], "OME-Zarr level 1"),
                                (folder, ["--zarr-level", "2"], "OME-Zarr level 2")):
        if os.path.exists(out):
            os.remove(out)
        r = run(program, [target, "-o", out, "--spp", "2", "--size", "32x32", "--backend", "cpu"] + extra)
        t.check(r.returncode == 0 and want in r.stderr and r.stderr.count("\n") == 1,
                "mcvol-render %s %s: status %d, %r" % (os.path.basename(target), extra, r.returncode, r.stderr))
        t.check(os.path.exists(out) and read_png_rgb(out).std() > 1.0, "mcvol-render %s: an image" % extra)
    # Time steps: --time picks one (the images differ), a step past the end is an error.
    rng = np.random.default_rng(5)
    data = np.zeros((3, 6, 8, 9), np.uint16)
    for step in range(3):
        data[step, 1 + step:3 + step, 2:6, 2:7] = 30000 + rng.integers(0, 100, (2, 4, 5))
    timed = W.write(os.path.join(work, "time.ome.zarr"), [data], "tzyx", [[1, 1, 1, 1]])
    images = []
    for step in (0, 2):
        r = run(program, [timed, "-o", out, "--spp", "4", "--size", "32x32", "--backend", "cpu", "--time", str(step)])
        t.check(r.returncode == 0 and "time step %d of 3" % step in r.stderr, "--time %d: %r" % (step, r.stderr))
        images.append(read_png_rgb(out) if r.returncode == 0 else None)
    if images[0] is not None and images[1] is not None:
        t.check(np.abs(images[0] - images[1]).mean() > 1.0, "--time 0 and --time 2 render different steps")
    # A scene file naming the level by its path, with a region.
    scene = os.path.join(work, "scene.json")
    with open(scene, "w") as f:
        json.dump({"input": {"file": "render.ome.zarr", "level": "1", "region": [0, 7, 0, 11, 0, 7]},
                   "samples_per_pixel": 2, "image_size": [32, 32], "backend": "cpu"}, f)
    r = run(program, [scene, "-o", out])
    t.check(r.returncode == 0 and "OME-Zarr level 1 ('1', 5x6x4 voxels, region)" in r.stderr,
            "scene file with level and region: %r" % r.stderr)
    return timed


def check_error(t, program, work, name, target, expected, extra=()):
    out = os.path.join(work, name + ".png")
    if os.path.exists(out):
        os.remove(out)
    r = run(program, [target, "-o", out, "--spp", "1", "--size", "16x16", "--backend", "cpu"] + list(extra))
    lines = r.stderr.strip().split("\n")
    t.check(r.returncode == 2, "%s: exit status %d, expected 2 (%s)" % (name, r.returncode, r.stderr.strip()))
    t.check(len(lines) == 1 and all(e in lines[0] for e in expected),
            "%s: message %r should be one line containing %s" % (name, r.stderr, expected))
    t.check("Traceback" not in r.stderr, "%s: traceback printed" % name)
    t.check(not os.path.exists(out), "%s: an image was written" % name)


def copy(work, src, name):
    dst = os.path.join(work, name)
    shutil.rmtree(dst, ignore_errors=True)
    shutil.copytree(src, dst)
    return dst


def edit_json(path, change):
    with open(path) as f:
        data = json.load(f)
    change(data)
    with open(path, "w") as f:
        json.dump(data, f)


def test_errors(t, work, program, timed):
    good, _ = pyramid(work, "good.ome.zarr", fill_value=None)
    missing = copy(work, good, "missing.ome.zarr")
    os.remove(os.path.join(missing, "0", "0.1.1.1"))
    corrupt = copy(work, good, "corrupt.ome.zarr")
    with open(os.path.join(corrupt, "0", "1.0.0.0"), "r+b") as f:
        f.truncate(20)
    codec = copy(work, good, "codec.ome.zarr")
    edit_json(os.path.join(codec, "1", ".zarray"), lambda d: d.update(compressor={"id": "jpeg2k"}))
    old = copy(work, good, "old.ome.zarr")
    edit_json(os.path.join(old, ".zattrs"), lambda d: d["multiscales"][0].update(version="0.3"))
    v3 = os.path.join(work, "v3.ome.zarr")
    os.makedirs(v3, exist_ok=True)
    with open(os.path.join(v3, "zarr.json"), "w") as f:
        json.dump({"zarr_format": 3, "node_type": "group", "attributes": {"ome": {"version": "0.5"}}}, f)
    labels = copy(work, good, "labels.ome.zarr")
    edit_json(os.path.join(labels, ".zattrs"), lambda d: d.update({"image-label": {"colors": []}}))
    plate = os.path.join(work, "plate.ome.zarr")
    zarr.open_group(plate, mode="w").attrs["plate"] = {"rows": [{"name": "A"}], "columns": [{"name": "1"}]}
    plain = os.path.join(work, "plain.zarr")
    zarr.open_group(plain, mode="w").attrs["something"] = 1
    cases = [
        ("missing-chunk", missing, [missing, "0.1.1.1", "missing", "fill_value"]),
        ("corrupt-chunk", corrupt, [corrupt, "1.0.0.0"]),
        ("unknown-codec", codec, [codec, "jpeg2k", "numcodecs"]),
        ("version", old, [old, "version 0.3", "0.4"]),
        ("zarr-v3", v3, [v3, "zarr format 3", "0.5"]),
        ("labels", labels, [labels, "labels image"]),
        ("plate", plate, [plate, "plate"]),
        ("no-multiscales", plain, [plain, "multiscales"]),
    ]
    for name, target, expected in cases:
        check_error(t, program, work, name, target, expected)
    check_error(t, program, work, "time-step", timed, [timed, "time step 3", "3 time steps"], ["--time", "3"])
    check_error(t, program, work, "level", good, [good, "no level 5", "levels: 0 ('0')"], ["--zarr-level", "5"])
    scene = os.path.join(work, "outside.json")
    with open(scene, "w") as f:
        json.dump({"input": {"file": good, "region": [100, 120, 0, 1, 0, 1]}}, f)
    check_error(t, program, work, "region", scene, ["input.file:", "outside"])


def main():
    p = argparse.ArgumentParser()
    p.add_argument("--mcvol-render", default=os.path.join(SOURCE, "Tools", "mcvol-render.py"))
    p.add_argument("--work", default=None)
    args = p.parse_args()
    work = args.work or tempfile.mkdtemp(prefix="TestOMEZarr-")
    os.makedirs(work, exist_ok=True)
    t = Checker()
    test_axis_orders(t, work)
    test_types_and_codecs(t, work)
    test_levels(t, work)
    test_omero(t, work)
    test_larger_than_memory(t, work, args.mcvol_render)
    timed = test_render(t, work, args.mcvol_render)
    test_errors(t, work, args.mcvol_render, timed)
    t.finish()


if __name__ == "__main__":
    main()
