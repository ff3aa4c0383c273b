#!/usr/bin/python3
# SPDX-License-Identifier: BSD-3-Clause
"""Writes a fluorescence-microscopy-like volume as OME-Zarr (OME-NGFF 0.4):
the gallery's OME-Zarr entry, the ParaView guide's screenshot and the file
levels study use it.

    python3 Data/cells_omezarr.py OUT.ome.zarr [--dims 256 256 64] [--levels 3]

The cells are the "microscopy" demo (vtkMultiChannelDemoSource: a jittered
Voronoi tessellation with membranes, a nucleus per cell, bright puncta),
generated at the pixel size along every axis and turned into what a confocal
microscope records: every 4th slice (a z step of 0.8 um against pixels of
0.2 um), 16-bit photon counts over a background of about 100, Poisson
noise. Channels: DAPI (nuclei, blue), membrane (orange) and
puncta (green), each with an omero colour and a display window (from 4 noise standard
deviations above the background to the 99.9th percentile of its counts). Levels 1, 2, ... average 2x2x2 blocks
of the level before (as image pyramids of microscopy files do). Chunks of
1x32x128x128 voxels, zarr's default compressor (blosc lz4). Deterministic:
the same bytes of data on every machine. Needs the build's mcvol package
and python3-zarr.
"""

import argparse
import os
import shutil

import numpy as np

CHANNELS = [("nuclei", "DAPI", "3366FF", 3000.0), ("membranes", "membrane", "FF9933", 2200.0),
            ("puncta", "puncta", "33FF66", 4000.0)]
SPACING = (0.2, 0.2, 0.8)  # x, y, z in micrometres
Z_STEP = 4  # the z step in pixel sizes
BACKGROUND = 100.0  # photon counts where there is no dye


def cells(dims):
    """(channels, z, y, x) uint16 photon counts."""
    from vtkmodules.util.numpy_support import vtk_to_numpy

    from mcvol import vtkMultiChannelDemoSource

    # The demo at the pixel size along z too, then every Z_STEP-th slice:
    # the cells keep their shape in micrometres, sampled as a microscope's
    # z stack is.
    nx, ny, nz = dims
    source = vtkMultiChannelDemoSource()
    source.SetDataset("microscopy")
    source.SetDimensions(nx, ny, nz * Z_STEP)
    source.Update()
    image = source.GetOutput()
    array = image.GetPointData().GetArray("channels")
    names = [array.GetComponentName(c) for c in range(array.GetNumberOfComponents())]
    values = vtk_to_numpy(array).reshape(nz * Z_STEP, ny, nx, -1)[::Z_STEP].astype(np.float64)
    scale = float(np.iinfo(vtk_to_numpy(array).dtype).max) if vtk_to_numpy(array).dtype.kind == "u" else 1.0
    rng = np.random.default_rng(2024)
    out = np.empty((len(CHANNELS), nz, ny, nx), np.uint16)
    for c, (demo_name, _, _, peak) in enumerate(CHANNELS):
        signal = values[..., names.index(demo_name)] / scale * peak
        out[c] = np.minimum(rng.poisson(BACKGROUND + signal), 65535).astype(np.uint16)
    return out


def mean_down(level):
    """2x2x2 block means (an axis of odd length drops its last voxel)."""
    c, z, y, x = level.shape
    z2, y2, x2 = max(1, z // 2), y // 2, x // 2
    block = level[:, :2 * z2 if z > 1 else 1, :2 * y2, :2 * x2].astype(np.float64)
    if z > 1:
        block = block.reshape(c, z2, 2, y2, 2, x2, 2).mean(axis=(2, 4, 6))
    else:
        block = block.reshape(c, 1, y2, 2, x2, 2).mean(axis=(3, 5))
    return np.rint(block).astype(np.uint16)


def write(path, dims=(256, 256, 64), levels=3):
    import zarr

    data = cells(dims)
    shutil.rmtree(path, ignore_errors=True)
    group = zarr.open_group(path, mode="w")
    datasets, level = [], data
    for k in range(levels):
        group.create_dataset(str(k), data=level, chunks=(1, 32, 128, 128))
        f = 2 ** k
        scale = [1.0, SPACING[2] * f, SPACING[1] * f, SPACING[0] * f]
        shift = [0.0] + [s * (f - 1) / 2.0 for s in (SPACING[2], SPACING[1], SPACING[0])]
        datasets.append({"path": str(k), "coordinateTransformations": [
            {"type": "scale", "scale": scale}, {"type": "translation", "translation": shift}]})
        level = mean_down(level)
    axes = [{"name": "c", "type": "channel"}] + [{"name": a, "type": "space", "unit": "micrometer"} for a in "zyx"]
    group.attrs["multiscales"] = [{"version": "0.4", "name": "cells", "axes": axes, "datasets": datasets}]
    channels = []
    for c, (_, label, color, _) in enumerate(CHANNELS):
        lo, hi = BACKGROUND + 4.0 * np.sqrt(BACKGROUND), float(np.percentile(data[c], 99.9))
        channels.append({"label": label, "color": color, "active": True,
                         "window": {"start": lo, "end": hi, "min": 0.0, "max": 65535.0}})
    group.attrs["omero"] = {"channels": channels, "rdefs": {"model": "color"}}
    return path


def main():
    p = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    p.add_argument("out")
    p.add_argument("--dims", type=int, nargs=3, default=[256, 256, 64], metavar=("X", "Y", "Z"))
    p.add_argument("--levels", type=int, default=3)
    args = p.parse_args()
    write(os.path.abspath(args.out), tuple(args.dims), args.levels)
    print("wrote", args.out)


if __name__ == "__main__":
    main()
