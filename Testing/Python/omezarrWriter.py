"""Writes small OME-Zarr images (OME-NGFF 0.4, zarr format 2) with
python3-zarr, for the tests of mcvol.omezarr, the ParaView reader, the
benchmark and the gallery's generated volume.

    write(folder, levels, axes, scales, translations=None, omero=None, chunks=None,
          compressor="default", dimension_separator=".", fill_value=0, multiscale_transform=None)

`levels`: numpy arrays in the file's axis order, finest first; `axes`: the
axis names ("t", "c", "z", "y", "x" get their NGFF types; others are space);
`scales`/`translations`: per level, one number per axis.
"""

import zarr

AXIS_TYPES = {"t": "time", "c": "channel"}
UNITS = {"time": "second", "space": "micrometer"}


def axes_metadata(axes):
    out = []
    for name in axes:
        kind = AXIS_TYPES.get(name, "space")
        entry = {"name": name, "type": kind}
        if kind in UNITS:
            entry["unit"] = UNITS[kind]
        out.append(entry)
    return out


def write(folder, levels, axes, scales, translations=None, omero=None, chunks=None, compressor="default",
          dimension_separator=".", fill_value=0, multiscale_transform=None, version="0.4"):
    group = zarr.open_group(folder, mode="w")
    datasets = []
    for i, data in enumerate(levels):
        kw = {"dimension_separator": dimension_separator, "fill_value": fill_value,
              "chunks": chunks[i] if isinstance(chunks, list) else (chunks or True)}
        if compressor != "default":
            kw["compressor"] = compressor
        group.create_dataset(str(i), data=data, **kw)
        transforms = [{"type": "scale", "scale": [float(s) for s in scales[i]]}]
        if translations is not None:
            transforms.append({"type": "translation", "translation": [float(t) for t in translations[i]]})
        datasets.append({"path": str(i), "coordinateTransformations": transforms})
    multiscale = {"version": version, "name": "image", "axes": axes_metadata(axes), "datasets": datasets}
    if multiscale_transform is not None:
        multiscale["coordinateTransformations"] = multiscale_transform
    group.attrs["multiscales"] = [multiscale]
    if omero is not None:
        group.attrs["omero"] = omero
    return folder


def omero_channel(label, color, start, end, active=True):
    return {"label": label, "color": color, "active": active,
            "window": {"start": start, "end": end, "min": 0, "max": 65535}}
