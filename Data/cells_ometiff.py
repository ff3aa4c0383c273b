#!/usr/bin/python3
# SPDX-License-Identifier: BSD-3-Clause
"""Writes the fluorescence-microscopy-like volume of cells_omezarr.py as one
OME-TIFF: the ParaView guide's OME-TIFF walk uses it.

    python3 Data/cells_ometiff.py OUT.ome.tif [--dims 128 128 40]

The same cells, noise and channels as cells_omezarr.py (DAPI: nuclei,
membrane: cell borders, puncta: small bright dots; 16-bit photon counts over
a background of about 100 with Poisson noise), written by tifffile as a
CZYX uint16 stack whose OME-XML names the channels, gives their colours as
microscope software exports them (Color: a signed 32-bit RGBA integer; DAPI
blue, membrane magenta, puncta green) and the physical pixel sizes
(0.2 x 0.2 x 0.8 um). Deterministic. Needs the build's mcvol
package and tifffile.
"""

import argparse
import os
import sys

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))

from cells_omezarr import CHANNELS, SPACING, cells  # noqa: E402


# The channels' OME colours (r, g, b), in the order of CHANNELS.
COLORS = [(0, 0, 255), (255, 0, 255), (0, 255, 0)]


def ome_color(r, g, b, a=255):
    """OME-XML's Color: RGBA packed into a signed 32-bit integer."""
    value = (r << 24) | (g << 16) | (b << 8) | a
    return value - (1 << 32) if value >= (1 << 31) else value


def write(path, dims=(128, 128, 40)):
    import tifffile

    data = cells(dims)
    metadata = {
        "axes": "CZYX",
        "PhysicalSizeX": SPACING[0], "PhysicalSizeXUnit": "µm",
        "PhysicalSizeY": SPACING[1], "PhysicalSizeYUnit": "µm",
        "PhysicalSizeZ": SPACING[2], "PhysicalSizeZUnit": "µm",
        "Channel": {"Name": [label for _, label, _, _ in CHANNELS], "Color": [ome_color(*c) for c in COLORS]},
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
