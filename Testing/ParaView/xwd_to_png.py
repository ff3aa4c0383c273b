"""Converts an `xwd -root` capture of a private Xvfb screen to PNG, cut to
ParaView's main window at its default size (the GUI walks' screenshots).

    python3 xwd_to_png.py SCREEN.xwd OUT.png
"""
import struct
import sys

import numpy as np
from PIL import Image

data = open(sys.argv[1], "rb").read()
h = struct.unpack(">25I", data[:100])  # XWD header: sizes, byte order, bits per pixel, line length
header, width, height, order, bpp, line, ncolors = h[0], h[4], h[5], h[7], h[11], h[12], h[19]
n = bpp // 8
start = header + 12 * ncolors
pixels = np.frombuffer(data[start:start + line * height], np.uint8).reshape(height, line)[:, :width * n]
pixels = pixels.reshape(height, width, n)
rgb = pixels[..., [2, 1, 0]] if order == 0 else pixels[..., [n - 3, n - 2, n - 1]]
window = rgb[:762, :1152]  # ParaView's main window at its default size
Image.fromarray(np.ascontiguousarray(window)).save(sys.argv[2])
