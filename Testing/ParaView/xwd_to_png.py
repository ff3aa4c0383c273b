"""Converts an `xwd -root` capture of a private Xvfb screen to PNG, cut to
ParaView's main window at its default size (the GUI walks' screenshots).

    python3 xwd_to_png.py SCREEN.xwd OUT.png [--colours N]

--colours N stores the picture with a palette of N colours (a third of the
size of a true-colour PNG of the window with 256), for pictures in the docs.
"""
import argparse
import struct

import numpy as np
from PIL import Image

parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
parser.add_argument("xwd")
parser.add_argument("png")
parser.add_argument("--colours", type=int, default=0)
args = parser.parse_args()
data = open(args.xwd, "rb").read()
h = struct.unpack(">25I", data[:100])  # XWD header: sizes, byte order, bits per pixel, line length
header, width, height, order, bpp, line, ncolors = h[0], h[4], h[5], h[7], h[11], h[12], h[19]
n = bpp // 8
start = header + 12 * ncolors
pixels = np.frombuffer(data[start:start + line * height], np.uint8).reshape(height, line)[:, :width * n]
pixels = pixels.reshape(height, width, n)
rgb = pixels[..., [2, 1, 0]] if order == 0 else pixels[..., [n - 3, n - 2, n - 1]]
window = Image.fromarray(np.ascontiguousarray(rgb[:762, :1152]))  # ParaView's main window at its default size
if args.colours:
    window = window.quantize(args.colours)
window.save(args.png, optimize=bool(args.colours))
