# SPDX-License-Identifier: BSD-3-Clause
"""OME-Zarr (OME-NGFF 0.4, zarr format 2) images as vtkImageData.

    from mcvol.omezarr import OMEZarrImage
    image = OMEZarrImage("cells.ome.zarr")
    print(image.describe())            # levels, axes, channels, time steps
    data = image.read(memory_budget=2 << 30, time=0)
    print(image.report)                # which level was read, and why

What the metadata gives:

- `multiscales[0].axes`: the axes by name and type, in the file's order. The
  `channel` axis becomes one point array per channel, the `time` axis time
  steps, the two or three `space` axes the grid: x, y and z by name when the
  axes are named so, else by position (the last is x). Any order is read.
- each dataset's `coordinateTransformations` (`scale`, then `translation`),
  followed by those of the multiscale: the level's spacing and origin (the
  position of voxel 0's centre). Lengths in another unit than the x axis's
  are converted to it.
- `omero.channels`: each channel's `label` names its array; `color`,
  `window.start`/`end` and `active` are the channel's default display
  (`channel_defaults`), carried in the output's field data as
  `mcvol_display/<array>` (components r, g, b, window start, window end,
  active; `display_array`), which mcvol-render and the ParaView
  representation read. A multi-component array's field array has these 6
  per component (an OME-TIFF's channel colours: mcvol.scenefile.readers).

Reading:

- Only the chunks that hold the requested level, time step and region are
  read, decoded in parallel (numcodecs; its codecs release the GIL), each
  straight into its place in the output.
- A chunk that is not stored holds the array's `fill_value` (the zarr
  format: writers leave out chunks that are all fill value); an array
  without a `fill_value` makes a missing chunk an error.
- Values keep their type where the mapper reads it (uint8, int16, uint16,
  float32, float64); others are converted without loss: bool to uint8, int8
  to int16, float16 to float32, wider integers to float32 when every value
  fits its 24-bit mantissa, else to float64. Byte order becomes native.

Every problem raises OMEZarrError with one line that names the file (or the
chunk): not an OME-Zarr image, an NGFF version other than 0.4 (0.5 is zarr
format 3), a labels image, a plate or well, a codec numcodecs cannot decode,
a missing or corrupt chunk, metadata that contradicts the arrays.
"""

import json
import math
import os
import threading

# Level choice: the finest level whose output fits the budget.
SUPPORTED_VERSIONS = ("0.4",)
# Length units (UDUNITS-2 names, as NGFF uses) in metres.
LENGTH_UNITS = {
    "angstrom": 1e-10, "attometer": 1e-18, "centimeter": 1e-2, "decimeter": 1e-1, "exameter": 1e18,
    "femtometer": 1e-15, "foot": 0.3048, "gigameter": 1e9, "hectometer": 1e2, "inch": 0.0254, "kilometer": 1e3,
    "megameter": 1e6, "meter": 1.0, "micrometer": 1e-6, "mile": 1609.344, "millimeter": 1e-3, "nanometer": 1e-9,
    "parsec": 3.0857e16, "petameter": 1e15, "picometer": 1e-12, "terameter": 1e12, "yard": 0.9144,
    "yoctometer": 1e-24, "yottameter": 1e24, "zeptometer": 1e-21, "zettameter": 1e21,
}
# Types the mapper reads in place (numpy names).
MAPPER_TYPES = ("uint8", "int16", "uint16", "float32", "float64")
DISPLAY_PREFIX = "mcvol_display/"
DISPLAY_COMPONENTS = ("red", "green", "blue", "window start", "window end", "active")


class OMEZarrError(Exception):
    """An OME-Zarr image that cannot be read; the message is one line."""


def _load_json(path, what):
    try:
        with open(path, "r", encoding="utf-8") as f:
            return json.load(f)
    except OSError as e:
        raise OMEZarrError("cannot read %s '%s': %s" % (what, path, e.strerror or e))
    except ValueError as e:
        raise OMEZarrError("%s '%s' is not valid JSON: %s" % (what, path, " ".join(str(e).split())))


def image_folder(path):
    """The image's folder from a path to it, or to its .zattrs/.zgroup."""
    path = os.path.abspath(path)
    if os.path.basename(path) in (".zattrs", ".zgroup", ".zarray") and os.path.isfile(path):
        path = os.path.dirname(path)
    return path


def is_omezarr(path):
    """True for a folder (or its .zattrs) that is a zarr group or array
    (holds .zattrs, .zgroup, or zarr.json): how a path is recognised as
    OME-Zarr whatever its name."""
    folder = image_folder(path)
    return os.path.isdir(folder) and any(
        os.path.isfile(os.path.join(folder, n)) for n in (".zattrs", ".zgroup", "zarr.json"))


def _hex_color(text):
    """omero's "RRGGBB" -> (r, g, b) in [0, 1], or None."""
    if not isinstance(text, str):
        return None
    t = text.strip().lstrip("#")
    if len(t) == 8:
        t = t[:6]  # RRGGBBAA
    if len(t) != 6:
        return None
    try:
        return tuple(int(t[i:i + 2], 16) / 255.0 for i in (0, 2, 4))
    except ValueError:
        return None


class Level:
    """One dataset of the multiscale: its zarr array metadata and its grid."""

    def __init__(self, folder, index, path, zarray, scale, translation):
        self.folder = folder
        self.index = index
        self.path = path
        self.shape = tuple(int(n) for n in zarray["shape"])
        self.chunks = tuple(int(n) for n in zarray["chunks"])
        self.dtype = zarray["dtype"]
        self.compressor = zarray.get("compressor")
        self.filters = zarray.get("filters") or []
        self.fill_value = zarray.get("fill_value")
        self.order = zarray.get("order", "C")
        self.separator = zarray.get("dimension_separator", ".") or "."
        self.scale = scale
        self.translation = translation


class OMEZarrImage:
    """An OME-Zarr image (one multiscale). The metadata is read and checked
    on construction; read() reads the data."""

    def __init__(self, path):
        self.path = path
        folder = image_folder(path)
        if not os.path.isdir(folder):
            raise OMEZarrError("'%s' is not an OME-Zarr folder (no such folder)" % path)
        if os.path.isfile(os.path.join(folder, "zarr.json")):
            attrs = _load_json(os.path.join(folder, "zarr.json"), "zarr.json")
            version = (attrs.get("attributes", {}).get("ome", {}) or {}).get("version", "")
            raise OMEZarrError("'%s' is zarr format 3%s, which is not read (OME-NGFF 0.4, zarr format 2, is)"
                               % (folder, " (OME-NGFF %s)" % version if version else ""))
        zattrs = os.path.join(folder, ".zattrs")
        if not os.path.isfile(zattrs):
            raise OMEZarrError("'%s' is not an OME-Zarr image: it has no .zattrs" % folder)
        attrs = _load_json(zattrs, ".zattrs")
        if not isinstance(attrs, dict):
            raise OMEZarrError("'%s' is not an OME-Zarr image: its .zattrs is not a JSON object" % folder)
        self.series_note = ""
        if "multiscales" not in attrs and "bioformats2raw.layout" in attrs:
            # bioformats2raw's layout: the images are the groups 0, 1, ...
            series = os.path.join(folder, "0")
            if os.path.isfile(os.path.join(series, ".zattrs")):
                folder, attrs = series, _load_json(os.path.join(series, ".zattrs"), ".zattrs")
                self.series_note = "series 0 of a bioformats2raw layout"
        if "image-label" in attrs:
            raise OMEZarrError("'%s' is a labels image (image-label), which is not read: open the image it labels"
                               % folder)
        for kind in ("plate", "well"):
            if kind in attrs:
                raise OMEZarrError("'%s' is an OME-Zarr %s, which is not read: open one of its images (a field "
                                   "folder such as A/1/0)" % (folder, kind))
        if "multiscales" not in attrs:
            raise OMEZarrError("'%s' is not an OME-Zarr image: its .zattrs has no \"multiscales\" (keys: %s)"
                               % (folder, ", ".join(sorted(attrs)) or "none"))
        self.folder = folder
        multiscales = attrs["multiscales"]
        if not isinstance(multiscales, list) or not multiscales or not isinstance(multiscales[0], dict):
            raise OMEZarrError("'%s': \"multiscales\" must be a non-empty list of objects" % folder)
        ms = multiscales[0]
        version = str(ms.get("version", attrs.get("version", "")))
        if version not in SUPPORTED_VERSIONS:
            raise OMEZarrError("'%s' is OME-NGFF version %s, which is not read (read: %s)"
                               % (folder, version or "(none given)", ", ".join(SUPPORTED_VERSIONS)))
        self.version = version
        self.name = ms.get("name") or os.path.basename(folder.rstrip("/")).split(".")[0] or "image"
        self._parse_axes(ms.get("axes"))
        self._parse_levels(ms)
        self._parse_omero(attrs.get("omero"))
        self.report = ""

    # -- metadata ------------------------------------------------------------------------------------------
    def _fail(self, text):
        raise OMEZarrError("'%s': %s" % (self.folder, text))

    def _parse_axes(self, axes):
        if not isinstance(axes, list) or not 2 <= len(axes) <= 5:
            self._fail("\"axes\" must list 2 to 5 axes")
        names, types, units = [], [], []
        for a in axes:
            if isinstance(a, str):  # not 0.4, but written by some tools
                a = {"name": a}
            if not isinstance(a, dict) or not isinstance(a.get("name"), str):
                self._fail("each axis needs a \"name\" (got %s)" % json.dumps(a))
            name = a["name"]
            kind = a.get("type") or {"t": "time", "c": "channel", "x": "space", "y": "space", "z": "space"}.get(
                name.lower())
            names.append(name)
            types.append(kind)
            units.append(a.get("unit"))
        if len(set(names)) != len(names):
            self._fail("axis names repeat: %s" % ", ".join(names))
        space = [i for i, t in enumerate(types) if t == "space"]
        others = [names[i] for i, t in enumerate(types) if t not in ("space", "time", "channel")]
        if others:
            self._fail("axis %s has type %s; read: space, channel, time" % (others[0], json.dumps(types[names.index(
                others[0])])))
        if not 2 <= len(space) <= 3 or types.count("time") > 1 or types.count("channel") > 1:
            self._fail("axes %s: 2 or 3 space axes and at most one channel and one time axis are read"
                       % ", ".join("%s (%s)" % (n, t) for n, t in zip(names, types)))
        self.axes = names
        self.ndim = len(names)
        # x, y, z: by name when the space axes are named so, else by position.
        lower = [names[i].lower() for i in space]
        if sorted(lower) == sorted("xyz"[:len(space)]):
            self.space = [space[lower.index(c)] for c in "xyz"[:len(space)]]
        else:
            self.space = list(reversed(space))
        self.channel_axis = types.index("channel") if "channel" in types else None
        self.time_axis = types.index("time") if "time" in types else None
        # Space units: converted to the x axis's unit where both are known.
        ux = units[self.space[0]]
        self.unit = ux or ""
        self.unit_factor = [1.0] * len(self.space)
        for k, i in enumerate(self.space):
            u = units[i]
            if u != ux and u in LENGTH_UNITS and ux in LENGTH_UNITS:
                self.unit_factor[k] = LENGTH_UNITS[u] / LENGTH_UNITS[ux]
        self.time_unit = units[self.time_axis] if self.time_axis is not None else None

    def _transforms(self, transforms, where):
        """(scale, translation) of a coordinateTransformations list."""
        scale, translation = [1.0] * self.ndim, [0.0] * self.ndim
        if transforms is None:
            return scale, translation
        if not isinstance(transforms, list):
            self._fail("%s: coordinateTransformations must be a list" % where)
        for t in transforms:
            kind = t.get("type") if isinstance(t, dict) else None
            if kind == "identity":
                continue
            if kind not in ("scale", "translation"):
                self._fail("%s: coordinate transformation %s is not read (scale, translation are)"
                           % (where, json.dumps(t)))
            values = t.get(kind)
            if "path" in t and values is None:
                self._fail("%s: a %s given by a path is not read" % (where, kind))
            if (not isinstance(values, list) or len(values) != self.ndim
                    or not all(isinstance(v, (int, float)) and not isinstance(v, bool) and math.isfinite(v)
                               for v in values)):
                self._fail("%s: %s must list %d finite numbers, one per axis, got %s"
                           % (where, kind, self.ndim, json.dumps(values)))
            if kind == "scale":
                if any(v <= 0 for v in values):
                    self._fail("%s: scale must be > 0, got %s" % (where, json.dumps(values)))
                scale = [s * v for s, v in zip(scale, values)]
                translation = [o * v for o, v in zip(translation, values)]
            else:
                translation = [o + v for o, v in zip(translation, values)]
        return scale, translation

    def _parse_levels(self, ms):
        datasets = ms.get("datasets")
        if not isinstance(datasets, list) or not datasets:
            self._fail("\"datasets\" must list the resolution levels")
        outer = ms.get("coordinateTransformations")
        oscale, otrans = self._transforms(outer, "multiscales")
        self.levels = []
        for i, d in enumerate(datasets):
            if not isinstance(d, dict) or not isinstance(d.get("path"), str):
                self._fail("datasets[%d] needs a \"path\"" % i)
            scale, trans = self._transforms(d.get("coordinateTransformations"), "datasets[%d]" % i)
            scale = [s * o for s, o in zip(scale, oscale)]
            trans = [t * o + u for t, o, u in zip(trans, oscale, otrans)]
            zfile = os.path.join(self.folder, d["path"], ".zarray")
            if not os.path.isfile(zfile):
                self._fail("level '%s' has no .zarray (missing folder or not a zarr array)" % d["path"])
            zarray = _load_json(zfile, ".zarray")
            if not isinstance(zarray, dict) or zarray.get("zarr_format") != 2:
                self._fail("level '%s' is not a zarr format 2 array" % d["path"])
            try:
                level = Level(self.folder, i, d["path"], zarray, scale, trans)
            except (KeyError, TypeError, ValueError) as e:
                self._fail("level '%s': .zarray lacks or garbles %s" % (d["path"], e))
            if len(level.shape) != self.ndim or len(level.chunks) != self.ndim:
                self._fail("level '%s' has %d dimensions, the axes name %d"
                           % (d["path"], len(level.shape), self.ndim))
            if any(c < 1 for c in level.chunks):
                self._fail("level '%s': chunk sizes must be >= 1, got %s" % (d["path"], list(level.chunks)))
            self._check_codecs(level)
            self.levels.append(level)
        full = self.levels[0]
        self.channels = full.shape[self.channel_axis] if self.channel_axis is not None else 1
        self.time_steps = full.shape[self.time_axis] if self.time_axis is not None else 1
        for level in self.levels[1:]:
            for axis in (self.channel_axis, self.time_axis):
                if axis is not None and level.shape[axis] != full.shape[axis]:
                    self._fail("level '%s' has %d along %s, level '%s' %d" % (
                        level.path, level.shape[axis], self.axes[axis], full.path, full.shape[axis]))
        if self.time_axis is not None:
            self.time_values = [full.translation[self.time_axis] + k * full.scale[self.time_axis]
                                for k in range(self.time_steps)]
        else:
            self.time_values = []

    def _check_codecs(self, level):
        import numpy
        from numcodecs import registry

        where = "level '%s'" % level.path
        for codec in ([level.compressor] if level.compressor else []) + list(level.filters):
            cid = codec.get("id") if isinstance(codec, dict) else None
            if cid not in registry.codec_registry:
                self._fail("%s uses codec %s, which numcodecs cannot decode (it can: %s)" % (
                    where, json.dumps(cid if cid else codec), ", ".join(sorted(registry.codec_registry))))
        try:
            dtype = numpy.dtype(level.dtype)
        except TypeError:
            self._fail("%s has data type %s, which is not read" % (where, json.dumps(level.dtype)))
        if dtype.kind not in "biuf" or dtype.itemsize > 8 or dtype.shape:
            self._fail("%s has data type %s (%s), which is not read (bool, integers and floats are)"
                       % (where, json.dumps(level.dtype), dtype))
        if level.order not in ("C", "F"):
            self._fail("%s has order %s (C or F)" % (where, json.dumps(level.order)))
        level.numpy_dtype = dtype

    def _parse_omero(self, omero):
        """Channel names and default displays (omero), one per channel."""
        entries = omero.get("channels") if isinstance(omero, dict) else None
        if not isinstance(entries, list) or len(entries) != self.channels:
            entries = [None] * self.channels
        names, self.channel_defaults = [], []
        for c, e in enumerate(entries):
            e = e if isinstance(e, dict) else {}
            label = e.get("label") if isinstance(e.get("label"), str) and e.get("label").strip() else None
            if label is None:
                label = self.name if self.channels == 1 and self.channel_axis is None else "channel %d" % c
            name, k = label, 2
            while name in names:
                name, k = "%s (%d)" % (label, k), k + 1
            names.append(name)
            window = e.get("window") if isinstance(e.get("window"), dict) else {}
            start, end = window.get("start"), window.get("end")
            good = all(isinstance(v, (int, float)) and not isinstance(v, bool) and math.isfinite(v)
                       for v in (start, end)) and start < end
            color = _hex_color(e.get("color"))
            self.channel_defaults.append({
                "name": name,
                "color": color,
                "window": [float(start), float(end)] if good else None,
                "active": bool(e.get("active", True)),
            })
        self.channel_names = names

    # -- questions -----------------------------------------------------------------------------------------
    def level_index(self, level):
        """A level by index (int, or a string of digits that is no path) or
        by its dataset path."""
        for lv in self.levels:
            if isinstance(level, str) and lv.path == level:
                return lv.index
        if isinstance(level, str) and level.lstrip("-").isdigit():
            level = int(level)
        if isinstance(level, int) and not isinstance(level, bool) and 0 <= level < len(self.levels):
            return level
        raise OMEZarrError("'%s' has no level %s (levels: %s)" % (
            self.folder, json.dumps(level), ", ".join("%d ('%s')" % (lv.index, lv.path) for lv in self.levels)))

    def space_shape(self, level):
        """(nx, ny, nz) of a level."""
        lv = self.levels[level]
        dims = [lv.shape[i] for i in self.space]
        return tuple(dims + [1] * (3 - len(dims)))

    def _box(self, level, region):
        """The level's voxel box [(lo, hi) for x, y, z], inclusive, covering
        `region` (level-0 voxel extent [x0, x1, y0, y1, z0, z1]); the whole
        level when region is None."""
        shape = self.space_shape(level)
        if region is None:
            return [(0, n - 1) for n in shape]
        full, lv = self.levels[0], self.levels[level]
        box = []
        for k in range(3):
            lo, hi = region[2 * k], region[2 * k + 1]
            if k >= len(self.space):
                box.append((0, 0))
                continue
            a = self.space[k]
            # Level-0 voxel centres -> world -> this level's voxel index.
            wlo = full.translation[a] + lo * full.scale[a]
            whi = full.translation[a] + hi * full.scale[a]
            ilo = (wlo - lv.translation[a]) / lv.scale[a]
            ihi = (whi - lv.translation[a]) / lv.scale[a]
            ilo, ihi = max(0, int(math.floor(ilo + 1e-6))), min(shape[k] - 1, int(math.ceil(ihi - 1e-6)))
            if ilo > ihi:
                raise OMEZarrError("'%s': the region %s lies outside level '%s' (%s voxels)" % (
                    self.folder, list(region), lv.path, "x".join(map(str, shape))))
            box.append((ilo, ihi))
        return box

    def output_dtype(self, level):
        import numpy

        dt = self.levels[level].numpy_dtype
        if dt.newbyteorder("=").name in MAPPER_TYPES:
            return numpy.dtype(dt.newbyteorder("=").name)
        if dt.kind == "b" or dt.name == "uint8":
            return numpy.dtype(numpy.uint8)
        if dt.kind == "f":
            return numpy.dtype(numpy.float32 if dt.itemsize <= 4 else numpy.float64)
        if dt.itemsize == 1:
            return numpy.dtype(numpy.int16)
        return None  # wider integers: decided by the values

    def level_bytes(self, level, region=None):
        """Bytes of one time step of a level (region) as read."""
        box = self._box(level, region)
        voxels = 1
        for lo, hi in box:
            voxels *= hi - lo + 1
        dt = self.output_dtype(level)
        return voxels * self.channels * (dt.itemsize if dt is not None else 4)

    def choose_level(self, level=None, memory_budget=0, region=None):
        """(level index, why): the level named, or the finest whose output
        fits `memory_budget` bytes (0: no budget, level 0), or the coarsest
        when none fits."""
        if level is not None and level != -1:
            return self.level_index(level), "as asked"
        if not memory_budget or memory_budget <= 0:
            return 0, "full resolution"
        for lv in self.levels:
            if self.level_bytes(lv.index, region) <= memory_budget:
                return lv.index, "finest that fits the memory budget of %s" % _mib(memory_budget)
        return len(self.levels) - 1, "coarsest: no level fits the memory budget of %s" % _mib(memory_budget)

    def describe(self):
        lines = ["%s: OME-NGFF %s, axes %s%s" % (self.folder, self.version, " ".join(self.axes),
                                                  ", " + self.series_note if self.series_note else "")]
        for lv in self.levels:
            nx, ny, nz = self.space_shape(lv.index)
            sp = [lv.scale[i] for i in self.space]
            lines.append("  level %d ('%s'): %dx%dx%d voxels, spacing %s %s, %s" % (
                lv.index, lv.path, nx, ny, nz, " ".join("%g" % s for s in sp), self.unit, lv.numpy_dtype))
        lines.append("  channels: %s" % ", ".join(self.channel_names))
        if self.time_axis is not None:
            lines.append("  time steps: %d" % self.time_steps)
        return "\n".join(lines)

    # -- reading -------------------------------------------------------------------------------------------
    def _decode(self, lv, key, codecs, nbytes, scratch=None):
        """One chunk as a numpy array of the chunk's shape, or None when it
        is not stored. `scratch`: a uint8 buffer of `nbytes` that a single
        codec decodes into (reused by a thread: no fresh pages per chunk)."""
        import numpy

        fn = os.path.join(lv.folder, lv.path, *key.split("/"))
        try:
            with open(fn, "rb") as f:
                data = f.read()
        except FileNotFoundError:
            return None
        except OSError as e:
            raise OMEZarrError("chunk '%s' of level '%s' in '%s': %s" % (key, lv.path, self.folder,
                                                                        e.strerror or e))
        try:
            if codecs and codecs[0].codec_id == "blosc":
                # Blosc trusts its header: a truncated chunk would decode
                # past its end.
                from numcodecs.blosc import cbuffer_sizes

                if len(data) < 16 or cbuffer_sizes(data)[1] != len(data):
                    raise ValueError("%d bytes, the blosc header says %d" % (
                        len(data), cbuffer_sizes(data)[1] if len(data) >= 16 else 16))
            if scratch is not None and len(codecs) == 1:
                data = codecs[0].decode(data, out=scratch)
            else:
                for codec in codecs:
                    data = codec.decode(data)
            buf = numpy.frombuffer(data, dtype=numpy.uint8) if not isinstance(data, numpy.ndarray) else data
            buf = buf.view(numpy.uint8).reshape(-1)
        except Exception as e:  # codecs raise what their libraries raise
            raise OMEZarrError("chunk '%s' of level '%s' in '%s' cannot be decoded (%s): %s" % (
                key, lv.path, self.folder, "/".join(type(c).codec_id for c in codecs) or "no compression",
                " ".join(str(e).split()) or type(e).__name__))
        if buf.size != nbytes:
            raise OMEZarrError("chunk '%s' of level '%s' in '%s' holds %d bytes, its shape needs %d (corrupt or "
                               "truncated)" % (key, lv.path, self.folder, buf.size, nbytes))
        return buf.view(lv.numpy_dtype).reshape(lv.chunks, order=lv.order)

    def read(self, level=None, time=0, region=None, memory_budget=0, threads=None):
        """vtkImageData of one time step: a point array per channel (named
        after the channel), spacing and origin from the metadata, the
        default displays in field data. `level`: index or path (None: by
        `memory_budget` bytes, 0 = no budget); `region`: level-0 voxel
        extent [x0, x1, y0, y1, z0, z1] (inclusive); `threads`: decoding
        threads (None: one per core). Sets self.report."""
        import numpy
        from numcodecs import registry

        index, why = self.choose_level(level, memory_budget, region)
        lv = self.levels[index]
        if not isinstance(time, int) or isinstance(time, bool) or not 0 <= time < self.time_steps:
            raise OMEZarrError("'%s' has %s: time step %s does not exist" % (
                self.folder, "%d time steps (0 to %d)" % (self.time_steps, self.time_steps - 1)
                if self.time_axis is not None else "no time axis (time step 0 only)", json.dumps(time)))
        if region is not None:
            if len(region) != 6 or any(region[2 * k] > region[2 * k + 1] for k in range(3)):
                raise OMEZarrError("region %s must be [x0, x1, y0, y1, z0, z1] with each low <= high"
                                   % json.dumps(list(region)))
        box = self._box(index, region)
        # Index ranges per file axis: [lo, hi) of the wanted voxels.
        want = [None] * self.ndim
        for k, a in enumerate(self.space):
            want[a] = (box[k][0], box[k][1] + 1)
        if self.time_axis is not None:
            want[self.time_axis] = (time, time + 1)
        if self.channel_axis is not None:
            want[self.channel_axis] = (0, self.channels)
        nx, ny, nz = (hi - lo + 1 for lo, hi in box)
        native = lv.numpy_dtype.newbyteorder("=")
        out = numpy.empty((self.channels, nz, ny, nx), dtype=native)
        # Output axes for the file's axes: channel -> 0, z -> 1, y -> 2, x -> 3.
        out_axis = {}
        if self.channel_axis is not None:
            out_axis[self.channel_axis] = 0
        for k, a in enumerate(self.space):
            out_axis[a] = 3 - k
        codecs = [registry.get_codec(c) for c in reversed(lv.filters)]
        if lv.compressor:
            codecs.insert(0, registry.get_codec(lv.compressor))
        nbytes = int(numpy.prod(lv.chunks)) * lv.numpy_dtype.itemsize
        ranges = [range(lo // c, (hi - 1) // c + 1) for (lo, hi), c in zip(want, lv.chunks)]
        import itertools

        keys = list(itertools.product(*ranges))
        fill = lv.fill_value
        missing = []

        local = threading.local()

        def place(cidx):
            key = lv.separator.join(str(i) for i in cidx)
            if not hasattr(local, "scratch"):
                local.scratch = numpy.empty(nbytes, numpy.uint8)
            block = self._decode(lv, key, codecs, nbytes, local.scratch)
            src, dst = [], [slice(None)] * 4
            for a, (ci, (lo, hi), c) in enumerate(zip(cidx, want, lv.chunks)):
                start, stop = max(lo, ci * c), min(hi, (ci + 1) * c)
                src.append(slice(start - ci * c, stop - ci * c))
                if a in out_axis:
                    dst[out_axis[a]] = slice(start - lo, stop - lo)
            if block is None:
                missing.append(key)
                if fill is None:
                    return
                view = out[tuple(dst)]
                view[...] = numpy.array(fill, dtype=lv.numpy_dtype).astype(native)
                return
            part = block[tuple(src)]
            if self.time_axis is not None:
                part = numpy.take(part, 0, axis=self.time_axis)
            # Remaining file axes (time dropped) -> output order.
            kept = [a for a in range(self.ndim) if a != self.time_axis]
            order = sorted(range(len(kept)), key=lambda j: out_axis[kept[j]])
            part = part.transpose(order)
            if self.channel_axis is None:
                part = part[numpy.newaxis]
            while part.ndim < 4:  # two space axes: a z axis of one voxel
                part = part[:, numpy.newaxis]
            out[tuple(dst)] = part

        threads = threads or os.cpu_count() or 1
        if threads > 1 and len(keys) > 1:
            from concurrent.futures import ThreadPoolExecutor

            with ThreadPoolExecutor(max_workers=threads) as pool:
                for f in [pool.submit(place, k) for k in keys]:
                    f.result()
        else:
            for k in keys:
                place(k)
        if missing and fill is None:
            raise OMEZarrError("chunk '%s' of level '%s' in '%s' is missing (%d of %d chunks), and the array has "
                               "no fill_value" % (sorted(missing)[0], lv.path, self.folder, len(missing), len(keys)))
        image = self._image(index, box, self._convert(out))
        self.level = index
        sizes = "x".join(str(n) for n in (nx, ny, nz))
        self.report = "OME-Zarr level %d ('%s', %s voxels%s) of %d: %s" % (
            index, lv.path, sizes, ", region" if region is not None else "", len(self.levels), why)
        if self.time_axis is not None:
            self.report += ", time step %d of %d" % (time, self.time_steps)
        if missing:
            self.report += ", %d of %d chunks not stored (fill value %s)" % (len(missing), len(keys), fill)
        return image

    def _convert(self, out):
        """Values as a type the mapper reads, without loss."""
        import numpy

        if out.dtype.name in MAPPER_TYPES:
            return out
        if out.dtype.kind == "b":
            return out.astype(numpy.uint8)
        if out.dtype.kind == "f":
            return out.astype(numpy.float32)
        if out.dtype.itemsize == 1:
            return out.astype(numpy.int16)
        big = out.size and max(abs(int(out.min())), abs(int(out.max()))) > (1 << 24)
        return out.astype(numpy.float64 if big else numpy.float32)

    def grid(self, level=None, memory_budget=0, region=None):
        """(level index, dimensions, spacing, origin) of what read() with
        these arguments returns, without reading data."""
        index, _ = self.choose_level(level, memory_budget, region)
        box = self._box(index, region)
        spacing, origin = self._frame(index, box)
        return index, [hi - lo + 1 for lo, hi in box], spacing, origin

    def _frame(self, index, box):
        lv = self.levels[index]
        spacing, origin = [1.0, 1.0, 1.0], [0.0, 0.0, 0.0]
        for k, a in enumerate(self.space):
            spacing[k] = lv.scale[a] * self.unit_factor[k]
            origin[k] = (lv.translation[a] + box[k][0] * lv.scale[a]) * self.unit_factor[k]
        return spacing, origin

    def _image(self, index, box, out):
        from vtkmodules.util.numpy_support import numpy_to_vtk
        from vtkmodules.vtkCommonDataModel import vtkImageData

        spacing, origin = self._frame(index, box)
        image = vtkImageData()
        nx, ny, nz = (hi - lo + 1 for lo, hi in box)
        image.SetDimensions(nx, ny, nz)
        image.SetSpacing(*spacing)
        image.SetOrigin(*origin)
        pd = image.GetPointData()
        for c, name in enumerate(self.channel_names):
            array = numpy_to_vtk(out[c].reshape(-1), deep=False)
            array._mcvol_values = out  # the numpy buffer lives as long as the array
            array.SetName(name)
            pd.AddArray(array)
        if self.channels == 1:
            pd.SetActiveScalars(self.channel_names[0])
        for d in self.channel_defaults:
            if d["color"] is None and d["window"] is None and d["active"]:
                continue
            image.GetFieldData().AddArray(display_array(d["name"], [dict(d, color=d["color"] or (1.0, 1.0, 1.0))]))
        return image


def _mib(nbytes):
    return "%.4g MiB" % (nbytes / 1048576.0)


def display_array(name, displays):
    """The field array `mcvol_display/<name>` that carries the default
    displays of point array `name`, one per component: dicts with "color"
    ((r, g, b) in [0, 1], or None: the reader's own colour), "window"
    ([start, end] or None) and "active". One tuple of 6 values per component
    (r, g, b, window start, window end, active; NaN for what is not given),
    component after component."""
    from vtkmodules.vtkCommonCore import vtkDoubleArray

    display = vtkDoubleArray()
    display.SetName(DISPLAY_PREFIX + name)
    display.SetNumberOfComponents(len(DISPLAY_COMPONENTS) * len(displays))
    values = []
    for c, d in enumerate(displays):
        for k, n in enumerate(DISPLAY_COMPONENTS):
            display.SetComponentName(c * len(DISPLAY_COMPONENTS) + k, n if len(displays) == 1 else "%d %s" % (c, n))
        color = d.get("color") or (float("nan"),) * 3
        window = d.get("window") or (float("nan"), float("nan"))
        values += list(color) + list(window) + [1.0 if d.get("active", True) else 0.0]
    display.InsertNextTuple(values)
    return display


def component_displays(image):
    """The default displays an image carries in its field data, per point
    array and component: {array name: [{"color": (r, g, b) or None,
    "window": [start, end] or None, "active": bool}, one per component]}."""
    out = {}
    fd = image.GetFieldData()
    size = len(DISPLAY_COMPONENTS)
    for k in range(fd.GetNumberOfArrays()):
        a = fd.GetArray(k)
        name = a.GetName() if a is not None else None
        if not name or not name.startswith(DISPLAY_PREFIX) or a.GetNumberOfTuples() < 1 \
                or a.GetNumberOfComponents() == 0 or a.GetNumberOfComponents() % size:
            continue
        values = a.GetTuple(0)
        entries = []
        for c in range(a.GetNumberOfComponents() // size):
            v = values[c * size:(c + 1) * size]
            color = tuple(v[:3]) if all(math.isfinite(x) and 0.0 <= x <= 1.0 for x in v[:3]) else None
            window = [v[3], v[4]] if math.isfinite(v[3]) and math.isfinite(v[4]) and v[3] < v[4] else None
            entries.append({"color": color, "window": window, "active": v[5] > 0.5})
        out[name[len(DISPLAY_PREFIX):]] = entries
    return out


def display_defaults(image):
    """The default displays of an image's single-component point arrays
    (OMEZarrImage.read's field data): {array name: {"color": (r, g, b) or
    None, "window": [start, end] or None, "active": bool}}."""
    return {name: entries[0] for name, entries in component_displays(image).items() if len(entries) == 1}
