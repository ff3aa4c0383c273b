"""Reading an OME-Zarr level against reading the same voxels from raw files.

A real-looking 4-channel uint16 volume (cells: smooth blobs of signal over a
camera-like background, Poisson noise; generated here) is written once as
an OME-Zarr (zarr's default compressor, blosc lz4 with byte shuffle; chunks
of 64x256x256 voxels of one channel) and as raw files. Then, page cache warm
(each file read once before the timed runs), the time to a vtkImageData
with the four channels:

- omezarr-parallel: mcvol.omezarr (chunks decoded in parallel, one thread per core)
- omezarr-serial:   the same with one thread
- raw-vtk:          mcvol-render's raw reader (vtkImageReader2), one file, 4 interleaved components
- raw-numpy:        four planar raw files read with numpy.fromfile into one buffer (the reader's output layout)

    python3 Benchmarks/studies/omezarr_read.py --dims 1024 1024 256 --work DIR --out DIR [--repeat 3]

The methods run in rounds, each method once per round, so that a busy
machine slows them alike; meta.txt gives the best time of each and the
median over the rounds of the ratio within a round. Writes omezarr_read.csv
(method, round, seconds, GB/s of output) and meta.txt into --out.
"""

import argparse
import os
import platform
import sys
import time

import numpy as np

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, os.path.join(HERE, "..", "..", "Testing", "Python"))


def cells(dims, channels, seed=0):
    """(channels, z, y, x) uint16: blobs of signal (nuclei, membranes-like
    shells, granules) over a background of ~100 counts, Poisson noise."""
    from scipy import ndimage

    nx, ny, nz = dims
    rng = np.random.default_rng(seed)
    out = np.empty((channels, nz, ny, nx), np.uint16)
    for c in range(channels):
        # A coarse random field, smoothed and upsampled: blobs of a few tens of voxels.
        coarse = rng.gamma(0.6, 1.0, (max(2, nz // 8), max(2, ny // 16), max(2, nx // 16))).astype(np.float32)
        coarse = ndimage.gaussian_filter(coarse, 1.0)
        for z0 in range(0, nz, 32):
            z1 = min(nz, z0 + 32)
            zz = (np.arange(z0, z1, dtype=np.float32) + 0.5) * coarse.shape[0] / nz - 0.5
            yy = (np.arange(ny, dtype=np.float32) + 0.5) * coarse.shape[1] / ny - 0.5
            xx = (np.arange(nx, dtype=np.float32) + 0.5) * coarse.shape[2] / nx - 0.5
            grid = np.meshgrid(zz, yy, xx, indexing="ij")
            field = ndimage.map_coordinates(coarse, grid, order=1, mode="nearest")
            signal = np.clip(field - 0.8, 0, None) * (3000.0 + 1500.0 * c)
            out[c, z0:z1] = np.minimum(rng.poisson(100.0 + signal), 65535).astype(np.uint16)
    return out


def write_inputs(work, dims, channels):
    import omezarrWriter as W
    import numcodecs

    data = cells(dims, channels)
    folder = os.path.join(work, "cells.ome.zarr")
    W.write(folder, [data], "czyx", [[1, 1.0, 0.2, 0.2]], chunks=[[1, 64, 256, 256]],
            compressor=numcodecs.Blosc(cname="lz4", clevel=5, shuffle=numcodecs.Blosc.SHUFFLE))
    interleaved = os.path.join(work, "cells-interleaved.raw")
    np.ascontiguousarray(np.moveaxis(data, 0, -1)).tofile(interleaved)
    planar = []
    for c in range(channels):
        planar.append(os.path.join(work, "cells-%d.raw" % c))
        data[c].tofile(planar[-1])
    return folder, interleaved, planar


def du(path):
    total = 0
    for root, _, files in os.walk(path):
        total += sum(os.path.getsize(os.path.join(root, f)) for f in files)
    return total


def main():
    p = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    p.add_argument("--dims", type=int, nargs=3, default=[1024, 1024, 256])
    p.add_argument("--channels", type=int, default=4)
    p.add_argument("--repeat", type=int, default=3)
    p.add_argument("--work", required=True, help="folder for the generated files (reused when present)")
    p.add_argument("--out", required=True)
    args = p.parse_args()
    os.makedirs(args.work, exist_ok=True)
    os.makedirs(args.out, exist_ok=True)
    folder = os.path.join(args.work, "cells.ome.zarr")
    interleaved = os.path.join(args.work, "cells-interleaved.raw")
    planar = [os.path.join(args.work, "cells-%d.raw" % c) for c in range(args.channels)]
    if not (os.path.isdir(folder) and os.path.isfile(interleaved) and all(map(os.path.isfile, planar))):
        start = time.perf_counter()
        write_inputs(args.work, args.dims, args.channels)
        print("generated in %.1f s" % (time.perf_counter() - start))

    from mcvol.omezarr import OMEZarrImage
    from mcvol.scenefile.errors import ErrorCollector
    from mcvol.scenefile.readers import read_raw

    nx, ny, nz = args.dims
    nbytes = args.channels * nx * ny * nz * 2

    def omezarr(threads):
        return lambda: OMEZarrImage(folder).read(threads=threads)

    def raw_vtk():
        entry = {"file": interleaved, "file_key": "input", "key": "input", "name": "cells",
                 "raw": {"dimensions": args.dims, "type": "uint16", "endianness": "little",
                         "components": args.channels}}
        return read_raw(entry, ErrorCollector())

    def raw_numpy():
        out = np.empty((args.channels, nz, ny, nx), np.uint16)
        for c, fn in enumerate(planar):
            with open(fn, "rb") as f:
                f.readinto(memoryview(out[c]).cast("B"))
        return out

    methods = [("omezarr-parallel", omezarr(None)), ("omezarr-serial", omezarr(1)), ("raw-vtk", raw_vtk),
               ("raw-numpy", raw_numpy)]
    load_before = " ".join("%.2f" % v for v in os.getloadavg())
    for _, fn in methods:
        fn()  # warm the page cache
    # Rounds of every method in turn, so that a busy machine slows all of
    # them alike; the ratios are taken within a round.
    rows = []
    for r in range(args.repeat):
        for name, fn in methods:
            start = time.perf_counter()
            result = fn()
            seconds = time.perf_counter() - start
            del result
            rows.append((name, r, seconds, nbytes / seconds / 1e9))
            print("%-17s %.3f s  %.2f GB/s" % (name, seconds, nbytes / seconds / 1e9))
    best = {name: min(s for n, _, s, _ in rows if n == name) for name, _ in methods}
    per_round = {(n, r): s for n, r, s, _ in rows}

    def median_ratio(a, b):
        return float(np.median([per_round[(a, r)] / per_round[(b, r)] for r in range(args.repeat)]))
    with open(os.path.join(args.out, "omezarr_read.csv"), "w") as f:
        f.write("method,repeat,seconds,output_GB_per_s\n")
        for name, r, s, g in rows:
            f.write("%s,%d,%.4f,%.3f\n" % (name, r, s, g))
    with open(os.path.join(args.out, "meta.txt"), "w") as f:
        f.write("dims %s, %d channels uint16, %.2f GiB of voxels\n" % (" ".join(map(str, args.dims)), args.channels,
                                                                       nbytes / 2**30))
        f.write("OME-Zarr on disk: %.2f GiB (blosc lz4 shuffle, chunks 1x64x256x256)\n" % (du(folder) / 2**30))
        f.write("page cache warm; best of %d repeats; load average before/after: %s / %s\n"
                % (args.repeat, load_before, " ".join("%.2f" % v for v in os.getloadavg())))
        f.write("machine: %s, %d cores, Python %s\n" % (platform.processor() or platform.machine(), os.cpu_count(),
                                                       platform.python_version()))
        for name, _ in methods:
            f.write("%s: %.3f s\n" % (name, best[name]))
        for raw in ("raw-vtk", "raw-numpy"):
            f.write("omezarr-parallel / %s: %.2f (best against best), %.2f (median of the rounds' ratios)\n"
                    % (raw, best["omezarr-parallel"] / best[raw], median_ratio("omezarr-parallel", raw)))
        f.write("omezarr-parallel / omezarr-serial: %.2f (median of the rounds' ratios)\n"
                % median_ratio("omezarr-parallel", "omezarr-serial"))
    print(open(os.path.join(args.out, "meta.txt")).read())


if __name__ == "__main__":
    main()
