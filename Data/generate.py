#!/usr/bin/python3
# SPDX-License-Identifier: BSD-3-Clause
"""Writes mcvol's small built-in datasets as Data/<name>.vti.

    PYTHONPATH=<build>/lib/python3.11/site-packages /usr/bin/python3 Data/generate.py [--out DIR]
        [--only NAME ...] [--dimensions X Y Z] [--channels N] [--presets]

The data come from vtkMultiChannelDemoSource (mcvol::makeDemo), which is
deterministic: the same name, size and channel count give the same values on
every machine. Each file holds one point-scalars array named "channels" with
one component per channel, the components named after the channels
(LZMA-compressed, raw binary appended data).

--presets (re)writes Data/presets.json from ParaView's own colour-map presets
(needs ParaView's Python modules) plus mcvol's solid colours.
"""

import argparse
import json
import os
import sys

HERE = os.path.dirname(os.path.abspath(__file__))

# The stored sizes. Cosmology is stored at 64^3, below the generator's default
# 96^3: its noise-like float fields hardly compress (96^3 would be 11 MB).
STORED = {
    "figure3": (64, 64, 64),
    "microscopy": (128, 128, 40),
    "cosmology": (64, 64, 64),
    "weather": (100, 100, 20),
}

# ParaView presets copied into Data/presets.json (ParaView's JSON format).
PARAVIEW_PRESETS = [
    "Grayscale",
    "X Ray",
    "Reds",
    "Greens",
    "Blues",
    "Purples",
    "Oranges",
    "Viridis (matplotlib)",
    "Inferno (matplotlib)",
    "Plasma (matplotlib)",
    "Magma (matplotlib)",
    "Cividis",
    "Cool to Warm",
    "Black-Body Radiation",
    "Turbo",
    "Jet",
]
# Constant colours, the usual look of fluorescence-microscopy channels.
SOLID = {
    "Solid Red": (1, 0, 0),
    "Solid Green": (0, 1, 0),
    "Solid Blue": (0, 0, 1),
    "Solid Cyan": (0, 1, 1),
    "Solid Magenta": (1, 0, 1),
    "Solid Yellow": (1, 1, 0),
    "Solid White": (1, 1, 1),
}


def write_dataset(name, out_dir, dims, channels):
    from mcvol import vtkMultiChannelDemoSource
    from vtkmodules.vtkIOXML import vtkXMLImageDataWriter

    src = vtkMultiChannelDemoSource()
    src.SetDataset(name)
    src.SetDimensions(*dims)
    src.SetNumberOfChannels(channels)
    src.SeparateArraysOff()  # the interleaved "channels" array only, with component names
    src.InterleavedOn()
    src.Update()
    image = src.GetOutput()
    if image.GetNumberOfPoints() == 0:
        raise SystemExit("generate.py: could not generate '%s'" % name)
    filename = os.path.join(out_dir, name + ".vti")
    writer = vtkXMLImageDataWriter()
    writer.SetInputData(image)
    writer.SetFileName(filename)
    # Binary (base64 inside each DataArray), not appended: with appended data,
    # raw or base64, VTK 9.2's reader fails under the expat security updates of
    # Debian bookworm (2.5.0-1+deb12u2 and later: "not well-formed (invalid
    # token)" or "junk after document element" at <AppendedData>).
    writer.SetDataModeToBinary()
    writer.SetCompressorTypeToLZMA()
    writer.SetCompressionLevel(5)
    if not writer.Write():
        raise SystemExit("generate.py: could not write '%s'" % filename)
    scalars = image.GetPointData().GetScalars()
    print(
        "%s: %s, %d x %s, %.2f MB"
        % (
            filename,
            "x".join(str(d) for d in image.GetDimensions()),
            scalars.GetNumberOfComponents(),
            scalars.GetDataTypeAsString(),
            os.path.getsize(filename) / 1e6,
        )
    )


def write_presets(filename):
    from paraview.modules.vtkRemotingViews import vtkSMTransferFunctionPresets

    presets = vtkSMTransferFunctionPresets.GetInstance()
    found = {}
    for i in range(presets.GetNumberOfPresets()):
        name = presets.GetPresetName(i)
        if name in PARAVIEW_PRESETS and name not in found:
            found[name] = json.loads(presets.GetPresetAsString(i))
    missing = [n for n in PARAVIEW_PRESETS if n not in found]
    if missing:
        raise SystemExit("generate.py: ParaView lacks the presets %s" % ", ".join(missing))
    out = []
    for name in PARAVIEW_PRESETS:
        p = found[name]
        entry = {"Name": name}
        for key in ("ColorSpace", "NanColor", "RGBPoints"):
            if key in p:
                entry[key] = p[key]
        out.append(entry)
    for name, (r, g, b) in SOLID.items():
        out.append({"Name": name, "ColorSpace": "RGB", "RGBPoints": [0, r, g, b, 1, r, g, b]})
    with open(filename, "w", encoding="utf-8") as f:
        f.write("[\n")
        for i, e in enumerate(out):
            f.write("  " + json.dumps(e, separators=(", ", ": ")) + (",\n" if i + 1 < len(out) else "\n"))
        f.write("]\n")
    print("%s: %d presets" % (filename, len(out)))


def main():
    p = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("--out", default=HERE, help="output folder (default: this folder)")
    p.add_argument("--only", nargs="+", choices=sorted(STORED), help="datasets to write (default: all)")
    p.add_argument(
        "--dimensions", nargs=3, type=int, metavar=("X", "Y", "Z"), help="size instead of the stored one"
    )
    p.add_argument("--channels", type=int, default=0, help="channel count (0: the dataset's own)")
    p.add_argument("--presets", action="store_true", help="write presets.json from ParaView's presets instead")
    args = p.parse_args()
    os.makedirs(args.out, exist_ok=True)
    if args.presets:
        write_presets(os.path.join(args.out, "presets.json"))
        return 0
    for name in args.only or sorted(STORED):
        write_dataset(name, args.out, args.dimensions or STORED[name], args.channels)
    return 0


if __name__ == "__main__":
    sys.exit(main())
