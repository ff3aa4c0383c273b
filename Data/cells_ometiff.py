#!/usr/bin/python3
# SPDX-License-Identifier: BSD-3-Clause
"""Writes the fluorescence-microscopy-like volume of cells_omezarr.py as one
OME-TIFF: the ParaView guide's OME-TIFF walk uses it.

    python3 Data/cells_ometiff.py OUT.ome.tif [--dims 128 128 40]

The same cells, noise and channels as cells_omezarr.py (DAPI: nuclei,
membrane: cell borders, puncta: small bright dots; 16-bit photon counts over
a background of about 100 with Poisson noise), written by tifffile as a
CZYX uint16 stack whose OME-XML names the channels and gives the physical
pixel sizes (0.2 x 0.2 x 0.8 um). Deterministic. Needs the build's mcvol
package and tifffile.
"""

import argparse
import os
import sys

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))

from cells_omezarr import CHANNELS, SPACING, cells  # noqa: E402


def write(path, dims=(128, 128, 40)):
    import tifffile

    data = cells(dims)
    metadata = {
        "axes": "CZYX",
        "PhysicalSizeX": SPACING[0], "PhysicalSizeXUnit": "µm",
        "PhysicalSizeY": SPACING[1], "PhysicalSizeYUnit": "µm",
        "PhysicalSizeZ": SPACING[2], "PhysicalSizeZUnit": "µm",
        "Channel": {"Name": [label for _, label, _, _ in CHANNELS]},
    }
    tifffile.imwrite(path, data, ome=True, photometric="minisblack", metadata=metadata)
    return path


def main():
    p = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    p.add_argument("out")
    p.add_argument("--dims", type=int, nargs=3, default=[128, 128, 40], metavar=("X", "Y", "Z"))
    args = p.parse_args()
    write(os.path.abspath(args.out), tuple(args.dims))
    print("wrote", args.out)


if __name__ == "__main__":
    main()
