#!/usr/bin/python3
# SPDX-License-Identifier: BSD-3-Clause
"""mcvol-render: renders a scene file with vtkMultiChannelVolumeMapper.

    mcvol-render SCENE.json -o out.png [--raw out.pfm] [--raw-alpha alpha.pfm]
                 [--spp N] [--size WxH] [--backend cpu|cuda|auto] [--quiet]

The scene format is documented in Documentation/scene-format.md. Errors in the
scene (unknown keys, bad values, missing files) are reported with the key that
holds them and exit with status 2; a failed render exits with status 1.

CMake copies this file into the build's bin/ as `mcvol-render`, with the
folder of the `mcvol` Python package and of the built-in presets filled in
below. Run from the source tree, it takes them from PYTHONPATH and ../Data.
"""

import argparse
import json
import math
import os
import sys
import time

# Filled in by configure_file(); left as they are in the source tree.
_CONFIGURED_PYTHON_DIR = "@MCVOL_RENDER_PYTHON_DIR@"
_CONFIGURED_PRESETS_FILE = "@MCVOL_RENDER_PRESETS_FILE@"


def _configured(value):
    return value if value and not value.startswith("@") else None


if _configured(_CONFIGURED_PYTHON_DIR) and _CONFIGURED_PYTHON_DIR not in sys.path:
    sys.path.insert(0, _CONFIGURED_PYTHON_DIR)

PROG = "mcvol-render"
DEMO_NAMES = ("figure3", "microscopy", "cosmology", "weather")
BLEND_MODES = ("density", "max", "mix", "composite")
TRACKING = ("1-dda", "n-dda")
BACKENDS = ("auto", "cpu", "cuda")
RENDERERS = ("montecarlo", "raymarch")
COMPOSITING = ("extinction", "opacity")
# Types the mapper reads in place (VTK type names as GetDataTypeAsString gives them).
SUPPORTED_TYPES = ("unsigned char", "short", "unsigned short", "float", "double")
MAX_CHANNELS = 32
VTK_MAX_VRCOMP = 4


class SceneError(Exception):
    """A bad scene: `key` is the path of the offending key ("channels[2].opacity")."""

    def __init__(self, key, message):
        super().__init__(message)
        self.key = key
        self.message = message


class RenderError(Exception):
    """The scene is valid but rendering failed (no device, mapper error)."""


# --------------------------------------------------------------------------
# Value checks. Each names the key path in its error.


def _join(path, key):
    if isinstance(key, int):
        return "%s[%d]" % (path, key)
    return "%s.%s" % (path, key) if path else key


def _type_name(v):
    if v is None:
        return "null"
    if isinstance(v, bool):
        return "a boolean"
    if isinstance(v, (int, float)):
        return "a number"
    if isinstance(v, str):
        return "a string"
    if isinstance(v, list):
        return "a list"
    if isinstance(v, dict):
        return "an object"
    return type(v).__name__


def check_keys(obj, path, allowed, required=()):
    if not isinstance(obj, dict):
        raise SceneError(path, "expected an object, got %s" % _type_name(obj))
    for k in obj:
        if k not in allowed:
            raise SceneError(
                _join(path, k), "unknown key (allowed here: %s)" % ", ".join(sorted(allowed))
            )
    for k in required:
        if k not in obj:
            raise SceneError(path, "missing required key '%s'" % k)


def get_number(v, path, lo=None, hi=None, lo_open=False, hi_open=False, integer=False):
    if isinstance(v, bool) or not isinstance(v, (int, float)):
        raise SceneError(path, "expected %s, got %s" % ("an integer" if integer else "a number", _type_name(v)))
    if integer and not (isinstance(v, int) or (isinstance(v, float) and v.is_integer())):
        raise SceneError(path, "expected an integer, got %r" % v)
    if not math.isfinite(v):
        raise SceneError(path, "expected a finite number, got %r" % v)
    if integer:
        v = int(v)
    if lo is not None and (v < lo or (lo_open and v == lo)):
        raise SceneError(path, "must be %s %s, got %r" % (">" if lo_open else ">=", lo, v))
    if hi is not None and (v > hi or (hi_open and v == hi)):
        raise SceneError(path, "must be %s %s, got %r" % ("<" if hi_open else "<=", hi, v))
    return v


def get_vector(v, path, n, what, **kw):
    if not isinstance(v, list) or len(v) != n:
        raise SceneError(path, "expected %s, got %s" % (what, json.dumps(v)))
    return [get_number(x, _join(path, i), **kw) for i, x in enumerate(v)]


def get_bool(v, path):
    if not isinstance(v, bool):
        raise SceneError(path, "expected true or false, got %s" % _type_name(v))
    return v


def get_string(v, path, choices=None):
    if not isinstance(v, str):
        raise SceneError(path, "expected a string, got %s" % _type_name(v))
    if choices is not None and v not in choices:
        raise SceneError(path, "expected one of %s, got %s" % (", ".join('"%s"' % c for c in choices), json.dumps(v)))
    return v


def get_points(v, path, width, what):
    """A list of control points [x, v1, ...], values (not x) in [0, 1]."""
    message = "expected a list of %s" % what
    if not isinstance(v, list) or not v:
        raise SceneError(path, message)
    points = []
    for i, p in enumerate(v):
        if not isinstance(p, list) or len(p) != width:
            raise SceneError(path, "%s; item %d is %s" % (message, i, json.dumps(p)))
        x = get_number(p[0], "%s[%d][0]" % (path, i))
        values = [get_number(p[k], "%s[%d][%d]" % (path, i, k), lo=0.0, hi=1.0) for k in range(1, width)]
        points.append([float(x)] + [float(c) for c in values])
    return points


# --------------------------------------------------------------------------
# Colour-map presets in ParaView's JSON format.


class Presets:
    """Presets from Data/presets.json, preset files, and ParaView's own list."""

    def __init__(self, builtin_file):
        self.builtin_file = builtin_file
        self._files = {}
        self._paraview = None

    @staticmethod
    def _entries(data):
        if isinstance(data, dict):
            data = [data]
        if not isinstance(data, list):
            return None
        return [e for e in data if isinstance(e, dict) and isinstance(e.get("Name"), str)]

    def load_file(self, filename, path):
        if filename not in self._files:
            try:
                with open(filename, "r", encoding="utf-8") as f:
                    data = json.load(f)
            except OSError as e:
                raise SceneError(path, "cannot read preset file '%s': %s" % (filename, e.strerror))
            except ValueError as e:
                raise SceneError(path, "preset file '%s' is not valid JSON: %s" % (filename, e))
            entries = self._entries(data)
            if entries is None:
                raise SceneError(
                    path, "preset file '%s' is not in ParaView's format (a list of objects with \"Name\")" % filename
                )
            self._files[filename] = entries
        return self._files[filename]

    def _paraview_presets(self):
        if self._paraview is None:
            self._paraview = {}
            try:
                from paraview.modules.vtkRemotingViews import vtkSMTransferFunctionPresets
            except ImportError:
                return self._paraview
            presets = vtkSMTransferFunctionPresets.GetInstance()
            for i in range(presets.GetNumberOfPresets()):
                name = presets.GetPresetName(i)
                if name not in self._paraview:
                    self._paraview[name] = (presets, i)
        return self._paraview

    def find(self, name, path, filename=None):
        """Returns the preset object named `name` (from `filename` if given)."""
        if filename is not None:
            entries = self.load_file(filename, path)
            if name is None:
                if len(entries) != 1:
                    raise SceneError(
                        path, "preset file '%s' holds %d presets: give \"name\"" % (filename, len(entries))
                    )
                return entries[0]
            for e in entries:
                if e["Name"] == name:
                    return e
            raise SceneError(path, "no preset named '%s' in '%s'" % (name, filename))
        if self.builtin_file and os.path.isfile(self.builtin_file):
            for e in self.load_file(self.builtin_file, path):
                if e["Name"] == name:
                    return e
        pv = self._paraview_presets()
        if name in pv:
            presets, index = pv[name]
            entries = self._entries(json.loads(presets.GetPresetAsString(index)))
            if entries:
                return entries[0]
        raise SceneError(
            path,
            "unknown preset '%s' (see %s%s)"
            % (
                name,
                self.builtin_file or "Data/presets.json",
                ", or ParaView's presets" if pv else "",
            ),
        )


# --------------------------------------------------------------------------
# Scene parsing (syntax and types; what needs the data comes later).

TOP_KEYS = {
    "description",
    "input",
    "channels",
    "blend",
    "tracking",
    "backend",
    "samples_per_pixel",
    "samples_per_render",
    "image_size",
    "camera",
    "background",
    "seed",
    "macrocell_size",
    "renderer",
    "step",
    "compositing",
    "pixel_jitter",
    "lighting",
}
LIGHTING_KEYS = {"lights", "ambient", "shadows", "max_scattering_depth", "gradient_shading", "shininess"}
LIGHT_KEYS = {"type", "direction", "position", "color", "intensity"}
SHADOWS = ("ratio", "delta", "none")
CHANNEL_KEYS = {
    "name",
    "array",
    "component",
    "color",
    "opacity",
    "normalized",
    "range",
    "unit_distance",
    "mix_weight",
    "albedo",
    "anisotropy",
}
CAMERA_KEYS = {
    "position",
    "focal_point",
    "view_up",
    "view_angle",
    "parallel",
    "parallel_scale",
    "azimuth",
    "elevation",
    "zoom",
}


def parse_input(v, scene_dir):
    if isinstance(v, str):
        filename = v if os.path.isabs(v) else os.path.join(scene_dir, v)
        ext = os.path.splitext(v)[1].lower()
        if ext not in (".vti", ".mha", ".mhd", ".nrrd", ".nhdr"):
            raise SceneError("input", "unsupported file type '%s' (expected .vti, .mha, .mhd, .nrrd or .nhdr)" % ext)
        if not os.path.isfile(filename):
            raise SceneError("input", "file not found: %s" % filename)
        return {"file": filename, "ext": ext}
    if isinstance(v, dict):
        check_keys(v, "input", {"demo", "dimensions", "channels"}, required=("demo",))
        demo = {"demo": get_string(v["demo"], "input.demo", DEMO_NAMES), "dimensions": [0, 0, 0], "channels": 0}
        if "dimensions" in v:
            demo["dimensions"] = get_vector(
                v["dimensions"], "input.dimensions", 3, "[x, y, z] voxel counts", lo=1, hi=8192, integer=True
            )
        if "channels" in v:
            demo["channels"] = get_number(v["channels"], "input.channels", lo=1, hi=MAX_CHANNELS, integer=True)
        return demo
    raise SceneError(
        "input", 'expected a file name or {"demo": name, ...}, got %s' % _type_name(v)
    )


def parse_color(v, path, scene_dir, presets):
    """A list of [x, r, g, b] points, or a preset reference."""
    if isinstance(v, list):
        return {"points": get_points(v, path, 4, "[x, r, g, b] points"), "normalized": None}
    if isinstance(v, dict):
        if "preset_file" in v:
            check_keys(v, path, {"preset_file", "name", "normalized"})
            fn = get_string(v["preset_file"], _join(path, "preset_file"))
            fn = fn if os.path.isabs(fn) else os.path.join(scene_dir, fn)
            name = get_string(v["name"], _join(path, "name")) if "name" in v else None
            preset = presets.find(name, _join(path, "preset_file"), filename=fn)
            where = _join(path, "preset_file")
        else:
            check_keys(v, path, {"preset", "normalized"}, required=("preset",))
            name = get_string(v["preset"], _join(path, "preset"))
            preset = presets.find(name, _join(path, "preset"))
            where = _join(path, "preset")
        rgb = preset.get("RGBPoints")
        if not isinstance(rgb, list) or len(rgb) < 4 or len(rgb) % 4 != 0:
            raise SceneError(where, "preset '%s' has no usable RGBPoints (categorical presets are not supported)" % preset["Name"])
        try:
            points = [[float(c) for c in rgb[i : i + 4]] for i in range(0, len(rgb), 4)]
        except (TypeError, ValueError):
            raise SceneError(where, "preset '%s' has non-numeric RGBPoints" % preset["Name"])
        normalized = get_bool(v["normalized"], _join(path, "normalized")) if "normalized" in v else True
        return {
            "points": points,
            "normalized": normalized,
            "preset": preset["Name"],
            "color_space": preset.get("ColorSpace"),
        }
    raise SceneError(
        path, 'expected a list of [x, r, g, b] points, {"preset": name} or {"preset_file": file}, got %s' % _type_name(v)
    )


def parse_lighting(v):
    """The "lighting" object: lights, ambient radiance and scattering settings
    (Documentation/scene-format.md). Its presence turns ShadeOn."""
    if not isinstance(v, dict):
        raise SceneError("lighting", "expected an object, got %s" % json.dumps(v))
    for k in v:
        if k not in LIGHTING_KEYS:
            raise SceneError(_join("lighting", k), "unknown key (known: %s)" % ", ".join(sorted(LIGHTING_KEYS)))
    out = {"lights": [], "ambient": [0.2, 0.2, 0.2], "shadows": "ratio", "max_scattering_depth": 1,
           "gradient_shading": False, "shininess": 32.0}
    lights = v.get("lights", [])
    if not isinstance(lights, list) or len(lights) > 8:
        raise SceneError("lighting.lights", "expected a list of at most 8 light objects")
    for i, l in enumerate(lights):
        path = "lighting.lights[%d]" % i
        if not isinstance(l, dict):
            raise SceneError(path, "expected a light object")
        for k in l:
            if k not in LIGHT_KEYS:
                raise SceneError(_join(path, k), "unknown key (known: %s)" % ", ".join(sorted(LIGHT_KEYS)))
        kind = get_string(l.get("type", "directional"), _join(path, "type"), ("directional", "point"))
        key = "direction" if kind == "directional" else "position"
        if key not in l:
            raise SceneError(path, "a %s light needs \"%s\"" % (kind, key))
        vec = get_vector(l[key], _join(path, key), 3, "[x, y, z]")
        if kind == "directional" and not any(vec):
            raise SceneError(_join(path, key), "the direction must not be zero")
        out["lights"].append({
            "type": kind, "vector": vec,
            "color": get_vector(l["color"], _join(path, "color"), 3, "[r, g, b] >= 0", lo=0.0) if "color" in l
            else [1.0, 1.0, 1.0],
            "intensity": get_number(l["intensity"], _join(path, "intensity"), lo=0.0) if "intensity" in l else 1.0,
        })
    if "ambient" in v:
        out["ambient"] = get_vector(v["ambient"], "lighting.ambient", 3, "[r, g, b] >= 0", lo=0.0)
    if "shadows" in v:
        out["shadows"] = get_string(v["shadows"], "lighting.shadows", SHADOWS)
    if "max_scattering_depth" in v:
        out["max_scattering_depth"] = get_number(v["max_scattering_depth"], "lighting.max_scattering_depth", lo=1,
                                                 hi=1024, integer=True)
    if "gradient_shading" in v:
        if not isinstance(v["gradient_shading"], bool):
            raise SceneError("lighting.gradient_shading", "expected true or false")
        out["gradient_shading"] = v["gradient_shading"]
    if "shininess" in v:
        out["shininess"] = get_number(v["shininess"], "lighting.shininess", lo=0.0, hi=1e4)
    return out


def parse_channel(v, path, scene_dir, presets):
    check_keys(v, path, CHANNEL_KEYS)
    ch = {"path": path}
    if "name" in v:
        ch["name"] = get_string(v["name"], _join(path, "name"))
    if "array" in v:
        ch["array"] = get_string(v["array"], _join(path, "array"))
    if "component" in v:
        c = v["component"]
        if isinstance(c, str):
            ch["component"] = c
        else:
            ch["component"] = get_number(c, _join(path, "component"), lo=0, integer=True)
    if "color" in v:
        ch["color"] = parse_color(v["color"], _join(path, "color"), scene_dir, presets)
    if "opacity" in v:
        ch["opacity"] = get_points(v["opacity"], _join(path, "opacity"), 2, "[x, a] pairs")
    ch["normalized"] = get_bool(v["normalized"], _join(path, "normalized")) if "normalized" in v else False
    if "range" in v:
        r = get_vector(v["range"], _join(path, "range"), 2, "[min, max]")
        if not r[0] < r[1]:
            raise SceneError(_join(path, "range"), "min must be less than max, got %s" % json.dumps(v["range"]))
        ch["range"] = r
    if "unit_distance" in v:
        ch["unit_distance"] = get_number(v["unit_distance"], _join(path, "unit_distance"), lo=0, lo_open=True)
    if "mix_weight" in v:
        ch["mix_weight"] = get_number(v["mix_weight"], _join(path, "mix_weight"), lo=0)
    if "albedo" in v:
        ch["albedo"] = get_number(v["albedo"], _join(path, "albedo"), lo=0.0, hi=1.0)
    if "anisotropy" in v:
        ch["anisotropy"] = get_number(v["anisotropy"], _join(path, "anisotropy"), lo=-1.0, hi=1.0, lo_open=True,
                                      hi_open=True)
    return ch


def parse_camera(v):
    check_keys(v, "camera", CAMERA_KEYS)
    cam = {}
    for k in ("position", "focal_point", "view_up"):
        if k in v:
            cam[k] = get_vector(v[k], _join("camera", k), 3, "[x, y, z]")
    if "view_up" in cam and all(c == 0 for c in cam["view_up"]):
        raise SceneError("camera.view_up", "must not be the zero vector")
    if "position" in cam and "focal_point" in cam and cam["position"] == cam["focal_point"]:
        raise SceneError("camera.position", "must differ from camera.focal_point")
    if "view_angle" in v:
        cam["view_angle"] = get_number(v["view_angle"], "camera.view_angle", lo=0, hi=180, lo_open=True, hi_open=True)
    if "parallel" in v:
        cam["parallel"] = get_bool(v["parallel"], "camera.parallel")
    if "parallel_scale" in v:
        cam["parallel_scale"] = get_number(v["parallel_scale"], "camera.parallel_scale", lo=0, lo_open=True)
    for k in ("azimuth", "elevation"):
        if k in v:
            cam[k] = get_number(v[k], _join("camera", k))
    if "zoom" in v:
        cam["zoom"] = get_number(v["zoom"], "camera.zoom", lo=0, lo_open=True)
    return cam


def parse_scene(data, scene_dir, presets):
    check_keys(data, "", TOP_KEYS, required=("input",))
    s = {}
    if "description" in data:
        get_string(data["description"], "description")
    s["input"] = parse_input(data["input"], scene_dir)
    if "channels" in data:
        chs = data["channels"]
        if not isinstance(chs, list) or not chs:
            raise SceneError("channels", "expected a non-empty list of channel objects, got %s" % json.dumps(chs))
        if len(chs) > MAX_CHANNELS:
            raise SceneError("channels", "at most %d channels, got %d" % (MAX_CHANNELS, len(chs)))
        s["channels"] = [parse_channel(c, "channels[%d]" % i, scene_dir, presets) for i, c in enumerate(chs)]
    s["blend"] = get_string(data["blend"], "blend", BLEND_MODES) if "blend" in data else "density"
    s["tracking"] = get_string(data["tracking"], "tracking", TRACKING) if "tracking" in data else "1-dda"
    s["backend"] = get_string(data["backend"], "backend", BACKENDS) if "backend" in data else "auto"
    s["samples_per_pixel"] = (
        get_number(data["samples_per_pixel"], "samples_per_pixel", lo=1, hi=1 << 24, integer=True)
        if "samples_per_pixel" in data
        else 64
    )
    s["samples_per_render"] = (
        get_number(data["samples_per_render"], "samples_per_render", lo=1, hi=4096, integer=True)
        if "samples_per_render" in data
        else 16
    )
    s["image_size"] = (
        get_vector(data["image_size"], "image_size", 2, "[width, height]", lo=1, hi=16384, integer=True)
        if "image_size" in data
        else [512, 512]
    )
    s["camera"] = parse_camera(data["camera"]) if "camera" in data else {}
    s["background"] = (
        get_vector(data["background"], "background", 3, "[r, g, b] in [0, 1]", lo=0.0, hi=1.0)
        if "background" in data
        else [0.0, 0.0, 0.0]
    )
    s["seed"] = get_number(data["seed"], "seed", lo=0, hi=2**32 - 1, integer=True) if "seed" in data else 0
    s["macrocell_size"] = (
        get_number(data["macrocell_size"], "macrocell_size", lo=1, hi=256, integer=True)
        if "macrocell_size" in data
        else 8
    )
    s["renderer"] = get_string(data["renderer"], "renderer", RENDERERS) if "renderer" in data else "montecarlo"
    s["step"] = get_number(data["step"], "step", lo=0.0, hi=1e300) if "step" in data else 0.0
    s["step_voxels"] = None
    s["compositing"] = (
        get_string(data["compositing"], "compositing", COMPOSITING) if "compositing" in data else "extinction"
    )
    s["lighting"] = parse_lighting(data["lighting"]) if "lighting" in data else None
    if "pixel_jitter" in data:
        if not isinstance(data["pixel_jitter"], bool):
            raise SceneError("pixel_jitter", "expected true or false, got %s" % json.dumps(data["pixel_jitter"]))
        s["pixel_jitter"] = data["pixel_jitter"]
    else:
        s["pixel_jitter"] = True
    return s


# --------------------------------------------------------------------------
# Input and channels (these need VTK).


class ErrorCollector:
    """Collects vtkErrorMacro messages of the objects it observes."""

    def __init__(self):
        self.messages = []
        from vtkmodules.util.misc import calldata_type
        from vtkmodules.util.vtkConstants import VTK_STRING

        @calldata_type(VTK_STRING)
        def on_error(obj, event, message):
            # "ERROR: In file, line N\nvtkClass (0x...): text": keep the text.
            text = str(message).strip()
            lines = text.split("\n")
            if len(lines) > 1 and lines[0].startswith("ERROR: In "):
                text = "\n".join(lines[1:])
            head, sep, rest = text.partition("): ")
            if sep and head.startswith("vtk") and " (" in head:
                text = rest
            self.messages.append(text.strip())

        self._callback = on_error

    def watch(self, obj):
        obj.AddObserver("ErrorEvent", self._callback)
        return obj


def load_input(spec, errors, need_arrays=True):
    """Returns (vtkImageData, demo source or None)."""
    if "demo" in spec:
        from mcvol import vtkMultiChannelDemoSource

        src = errors.watch(vtkMultiChannelDemoSource())
        src.SetDataset(spec["demo"])
        src.SetDimensions(*spec["dimensions"])
        src.SetNumberOfChannels(spec["channels"])
        # The per-channel named arrays only when a channel asks for one: they
        # double the memory of a large demo (4 x 512^3 float is 2 GB).
        src.SetSeparateArrays(need_arrays)
        src.Update()
        if errors.messages:
            raise SceneError("input", "cannot generate the demo: %s" % errors.messages[-1])
        return src.GetOutput(), src
    ext = spec["ext"]
    if ext == ".vti":
        from vtkmodules.vtkIOXML import vtkXMLImageDataReader

        reader = vtkXMLImageDataReader()
    elif ext in (".mha", ".mhd"):
        from vtkmodules.vtkIOImage import vtkMetaImageReader

        reader = vtkMetaImageReader()
    else:
        from vtkmodules.vtkIOImage import vtkNrrdReader

        reader = vtkNrrdReader()
    errors.watch(reader)
    reader.SetFileName(spec["file"])
    if not reader.CanReadFile(spec["file"]):
        raise SceneError("input", "cannot read '%s' as %s" % (spec["file"], ext))
    reader.Update()
    image = reader.GetOutput()
    if errors.messages or image is None or image.GetNumberOfPoints() == 0:
        detail = (": " + errors.messages[-1]) if errors.messages else ""
        raise SceneError("input", "cannot read image data from '%s'%s" % (spec["file"], detail))
    return image, None


def resolve_channels(scene, image, demo):
    """Finds each channel's array, component and data range."""
    pd = image.GetPointData()
    scalars = pd.GetScalars()
    entries = scene.get("channels")
    if entries is None:
        if demo is None:
            raise SceneError("channels", "required for a file input (only demo inputs have suggested transfer functions)")
        if scalars is None:
            raise SceneError("input", "the demo has no point scalars")
        entries = [{"path": "channels[%d]" % i, "normalized": False} for i in range(scalars.GetNumberOfComponents())]
        if len(entries) > MAX_CHANNELS:
            raise SceneError("input", "the demo has more than %d channels" % MAX_CHANNELS)
    resolved = []
    for i, e in enumerate(entries):
        path = e["path"]
        if "array" in e:
            array = pd.GetArray(e["array"])
            if array is None:
                names = [pd.GetArrayName(k) for k in range(pd.GetNumberOfArrays())]
                raise SceneError(
                    _join(path, "array"),
                    "no point array named '%s' (the input has: %s)" % (e["array"], ", ".join(n for n in names if n) or "none"),
                )
            where = "array '%s'" % e["array"]
            key = _join(path, "array")
        else:
            array = scalars
            if array is None:
                raise SceneError(path, "the input has no point scalars: give \"array\"")
            where = "the point scalars '%s'" % (array.GetName() or "")
            key = path
        ncomp = array.GetNumberOfComponents()
        comp = e.get("component")
        if isinstance(comp, str):
            names = [array.GetComponentName(k) for k in range(ncomp)]
            if comp not in names:
                raise SceneError(
                    _join(path, "component"),
                    "no component named '%s' in %s (names: %s)" % (comp, where, ", ".join(n for n in names if n) or "none"),
                )
            comp = names.index(comp)
        elif comp is None:
            if "array" in e:
                if ncomp != 1:
                    raise SceneError(path, "%s has %d components: give \"component\"" % (where, ncomp))
                comp = 0
            else:
                comp = i
                if comp >= ncomp:
                    raise SceneError(
                        path, "no component %d in %s (%d components): give \"component\" or \"array\"" % (i, where, ncomp)
                    )
        elif comp >= ncomp:
            raise SceneError(
                _join(path, "component"), "component %d out of range: %s has %d component(s)" % (comp, where, ncomp)
            )
        if array.GetDataTypeAsString() not in SUPPORTED_TYPES:
            raise SceneError(
                key,
                "%s has type %s, which the mapper does not read (%s)"
                % (where, array.GetDataTypeAsString(), ", ".join(SUPPORTED_TYPES)),
            )
        rng = [0.0, 0.0]
        array.GetFiniteRange(rng, comp)
        if not (math.isfinite(rng[0]) and math.isfinite(rng[1])) or rng[0] > rng[1]:
            rng = [0.0, 0.0]
        # The demo channel this is (for suggested transfer functions).
        demo_channel = None
        if demo is not None:
            if array is scalars or array.GetName() == "channels":
                demo_channel = comp
            else:
                for k in range(demo.GetNumberOfOutputChannels()):
                    if demo.GetChannelName(k) == array.GetName():
                        demo_channel = k
        resolved.append(dict(e, array_obj=array, comp=comp, data_range=rng, demo_channel=demo_channel))
    return resolved


def build_transfer_functions(channels, demo):
    from vtkmodules.vtkCommonDataModel import vtkPiecewiseFunction
    from vtkmodules.vtkRenderingCore import vtkColorTransferFunction

    out = []
    for ch in channels:
        path = ch["path"]
        color = vtkColorTransferFunction()
        opacity = vtkPiecewiseFunction()
        unit = None
        dc = ch["demo_channel"]
        if ("color" not in ch or "opacity" not in ch or "unit_distance" not in ch) and dc is not None:
            demo.GetSuggestedTransferFunction(dc, color, opacity, None)
            unit = demo.GetSuggestedUnitDistance(dc)
        for key in ("color", "opacity"):
            if key not in ch and dc is None:
                raise SceneError(path, "missing key '%s' (required unless the channel is a demo channel)" % key)
        lo, hi = ch.get("range", ch["data_range"])
        if not hi > lo:
            hi = lo + 1.0  # constant channel: keep the points apart

        def place(x, normalized):
            return lo + x * (hi - lo) if normalized else x

        if "color" in ch:
            c = ch["color"]
            color.RemoveAllPoints()
            pts = c["points"]
            if c["normalized"] is None:  # a plain point list
                xs = [place(p[0], ch["normalized"]) for p in pts]
            elif c["normalized"]:  # a preset: its span onto the range
                x0 = min(p[0] for p in pts)
                x1 = max(p[0] for p in pts)
                xs = [lo + ((p[0] - x0) / (x1 - x0) if x1 > x0 else 0.0) * (hi - lo) for p in pts]
            else:
                xs = [p[0] for p in pts]
            for x, p in zip(xs, pts):
                color.AddRGBPoint(x, min(max(p[1], 0.0), 1.0), min(max(p[2], 0.0), 1.0), min(max(p[3], 0.0), 1.0))
            space = c.get("color_space")
            if space in ("Diverging",):
                color.SetColorSpaceToDiverging()
            elif space in ("Lab", "CIELAB"):
                color.SetColorSpaceToLab()
            elif space == "Lab/CIEDE2000":
                color.SetColorSpaceToLabCIEDE2000()
            elif space == "HSV":
                color.SetColorSpaceToHSV()
            elif space == "Step":
                color.SetColorSpaceToStep()
            else:
                color.SetColorSpaceToRGB()
        if "opacity" in ch:
            opacity.RemoveAllPoints()
            for p in ch["opacity"]:
                opacity.AddPoint(place(p[0], ch["normalized"]), p[1])
        if "unit_distance" in ch:
            unit = ch["unit_distance"]
        if unit is None or not unit > 0:
            unit = 1.0
        out.append((color, opacity, unit))
    return out


def arrange_channels(image, channels, mapper):
    """Points the mapper at the channels; returns the image to render."""
    pd = image.GetPointData()
    scalars = pd.GetScalars()
    comps = [c["comp"] for c in channels]
    if scalars is not None and all(c["array_obj"] is scalars for c in channels) and comps == list(
        range(scalars.GetNumberOfComponents())
    ):
        return image  # the scalars' components, in order: read in place
    if all(c["array_obj"].GetNumberOfComponents() == 1 and c["array_obj"].GetName() for c in channels):
        for c in channels:
            mapper.AddChannelArray(c["array_obj"].GetName())
        return image
    # Components picked from multi-component arrays: copy them out.
    from vtkmodules.vtkCommonDataModel import vtkImageData

    copy = vtkImageData()
    copy.ShallowCopy(image)
    for i, c in enumerate(channels):
        src = c["array_obj"]
        if src.GetNumberOfComponents() == 1 and src.GetName():
            mapper.AddChannelArray(src.GetName())
            continue
        a = src.NewInstance()
        a.SetNumberOfComponents(1)
        a.SetNumberOfTuples(src.GetNumberOfTuples())
        a.CopyComponent(0, src, c["comp"])
        a.SetName("mcvol-render channel %d" % i)
        copy.GetPointData().AddArray(a)
        mapper.AddChannelArray(a.GetName())
    return copy


# --------------------------------------------------------------------------
# Rendering.


def setup_camera(renderer, cam):
    camera = renderer.GetActiveCamera()
    if "parallel" in cam:
        camera.SetParallelProjection(cam["parallel"])
    if "view_angle" in cam:
        camera.SetViewAngle(cam["view_angle"])
    if "position" in cam or "focal_point" in cam:
        renderer.ResetCamera()  # a focal point at the volume's centre when none is given
        if "focal_point" in cam:
            camera.SetFocalPoint(*cam["focal_point"])
        if "position" in cam:
            camera.SetPosition(*cam["position"])
        camera.SetViewUp(*cam.get("view_up", [0.0, 1.0, 0.0]))
        camera.OrthogonalizeViewUp()
        azimuth, elevation = cam.get("azimuth", 0.0), cam.get("elevation", 0.0)
    else:
        if "view_up" in cam:
            # VTK's default view direction (-z), or from the front (+y) when
            # the up vector is about z.
            up = cam["view_up"]
            norm = math.sqrt(sum(c * c for c in up))
            camera.SetFocalPoint(0.0, 0.0, 0.0)
            camera.SetPosition(*((0.0, -1.0, 0.0) if abs(up[2]) > 0.9 * norm else (0.0, 0.0, 1.0)))
            camera.SetViewUp(*up)
            camera.OrthogonalizeViewUp()
        renderer.ResetCamera()
        azimuth, elevation = cam.get("azimuth", 30.0), cam.get("elevation", 20.0)
    camera.Azimuth(azimuth)
    camera.Elevation(elevation)
    camera.OrthogonalizeViewUp()
    if "parallel_scale" in cam:
        camera.SetParallelScale(cam["parallel_scale"])
    if "zoom" in cam:
        camera.Zoom(cam["zoom"])
    renderer.ResetCameraClippingRange()


def samples_per_render(total, wanted):
    """The largest divisor of `total` not above `wanted`, so that the total is
    reached exactly (changing SamplesPerPixel would restart the mean)."""
    for n in range(min(total, wanted), 0, -1):
        if total % n == 0:
            return n
    return 1


def write_pfm(filename, width, height, channels, values):
    """PFM: "PF" (RGB) or "Pf" (gray), little-endian floats, bottom row first
    (the order OpenGL reads pixels in). `values`: a numpy array."""
    import numpy

    header = "%s\n%d %d\n-1.0\n" % ("PF" if channels == 3 else "Pf", width, height)
    with open(filename, "wb") as f:
        f.write(header.encode("ascii"))
        f.write(numpy.ascontiguousarray(values, dtype="<f4").tobytes())


def render(scene, args, errors, log):
    import vtkmodules.vtkRenderingOpenGL2  # noqa: F401  (OpenGL render window)
    import vtkmodules.vtkRenderingVolumeOpenGL2  # noqa: F401
    from vtkmodules.vtkCommonCore import vtkFloatArray
    from vtkmodules.vtkIOImage import vtkPNGWriter
    from vtkmodules.vtkRenderingCore import (
        vtkRenderer,
        vtkRenderWindow,
        vtkVolume,
        vtkVolumeProperty,
        vtkWindowToImageFilter,
    )

    from mcvol import vtkMultiChannelRayMarchMapper, vtkMultiChannelVolumeMapper

    need_arrays = any("array" in ch for ch in scene.get("channels", []))
    image, demo = load_input(scene["input"], errors, need_arrays)
    channels = resolve_channels(scene, image, demo)
    tfs = build_transfer_functions(channels, demo)

    reference = scene["renderer"] == "raymarch"
    mapper = errors.watch(vtkMultiChannelRayMarchMapper() if reference else vtkMultiChannelVolumeMapper())
    render_image = arrange_channels(image, channels, mapper)
    mapper.SetInputData(render_image)
    prop = vtkVolumeProperty()
    prop.IndependentComponentsOn()
    for i, (color, opacity, unit) in enumerate(tfs):
        if i < VTK_MAX_VRCOMP:
            prop.SetColor(i, color)
            prop.SetScalarOpacity(i, opacity)
            prop.SetScalarOpacityUnitDistance(i, unit)
        else:
            mapper.SetChannelColor(i, color)
            mapper.SetChannelScalarOpacity(i, opacity)
            mapper.SetChannelScalarOpacityUnitDistance(i, unit)
        if "mix_weight" in channels[i]:
            mapper.SetMixWeight(i, channels[i]["mix_weight"])
        if "albedo" in channels[i]:
            mapper.SetChannelAlbedo(i, channels[i]["albedo"])
        if "anisotropy" in channels[i]:
            mapper.SetChannelAnisotropy(i, channels[i]["anisotropy"])
    {
        "density": mapper.SetChannelBlendModeToDensity,
        "max": mapper.SetChannelBlendModeToMax,
        "mix": mapper.SetChannelBlendModeToMix,
        "composite": mapper.SetChannelBlendModeToComposite,
    }[scene["blend"]]()
    mapper.SetTrackingMethod(mapper.N_DDA if scene["tracking"] == "n-dda" else mapper.ONE_DDA)
    if not reference:  # the reference always marches on the CPU
        {"auto": mapper.SetBackendToAuto, "cpu": mapper.SetBackendToCPU, "cuda": mapper.SetBackendToCUDA}[
            scene["backend"]
        ]()
    mapper.SetSeed(scene["seed"])
    mapper.SetMacrocellSize(scene["macrocell_size"])
    mapper.SetPixelJitter(scene["pixel_jitter"])
    total = scene["samples_per_pixel"]
    per_render = samples_per_render(total, scene["samples_per_render"])
    mapper.SetSamplesPerPixel(per_render)
    if reference:
        # One deterministic image: the ray march through pixel centres.
        total = per_render = 1
        step = scene["step"]
        if scene["step_voxels"] is not None:
            spacing = [abs(x) for x in render_image.GetSpacing()]
            step = scene["step_voxels"] * min(spacing)
        mapper.SetStepSize(step)
        mapper.SetCompositingModel(
            mapper.OPACITY_COMPOSITING if scene["compositing"] == "opacity" else mapper.EXTINCTION_COMPOSITING
        )

    volume = vtkVolume()
    volume.SetMapper(mapper)
    volume.SetProperty(prop)
    renderer = vtkRenderer()
    renderer.SetBackground(*scene["background"])
    renderer.AddVolume(volume)
    lighting = scene.get("lighting")
    if lighting is not None:
        # The lighting object turns shading on; its lights replace VTK's
        # headlight (none listed: the headlight).
        from vtkmodules.vtkRenderingCore import vtkLight

        prop.ShadeOn()
        mapper.SetAmbientRadiance(*lighting["ambient"])
        mapper.SetShadowMode({"none": mapper.NO_SHADOWS, "ratio": mapper.RATIO_TRACKING_SHADOWS,
                              "delta": mapper.DELTA_TRACKING_SHADOWS}[lighting["shadows"]])
        mapper.SetMaxScatteringDepth(lighting["max_scattering_depth"])
        mapper.SetGradientShading(lighting["gradient_shading"])
        mapper.SetShininess(lighting["shininess"])
        if lighting["lights"]:
            renderer.AutomaticLightCreationOff()
            for l in lighting["lights"]:
                light = vtkLight()
                light.SetLightTypeToSceneLight()
                light.SetColor(*l["color"])
                light.SetIntensity(l["intensity"])
                if l["type"] == "point":
                    light.PositionalOn()
                    light.SetConeAngle(180.0)
                    light.SetPosition(*l["vector"])
                else:
                    light.SetFocalPoint(0.0, 0.0, 0.0)
                    light.SetPosition(*l["vector"])
                renderer.AddLight(light)
    window = vtkRenderWindow()
    if window.GetClassName() == "vtkXOpenGLRenderWindow" and not os.environ.get("DISPLAY"):
        raise RenderError("no X display: run under an X server (for example `xvfb-run -a %s ...`)" % PROG)
    window.SetOffScreenRendering(1)
    window.SetMultiSamples(0)
    window.SetSize(*scene["image_size"])
    window.AddRenderer(renderer)
    setup_camera(renderer, scene["camera"])

    start = time.perf_counter()
    last = -1
    while True:
        window.Render()
        if errors.messages:
            raise RenderError(errors.messages[-1])
        done = mapper.GetTotalSamples()
        if done >= total:
            break
        if done <= last:
            raise RenderError("the mapper stopped accumulating at %d samples per pixel" % done)
        last = done
    seconds = time.perf_counter() - start
    backend = mapper.GetBackendReport()
    if mapper.GetTotalSamples() != total:
        raise RenderError("accumulated %d samples per pixel, not %d" % (mapper.GetTotalSamples(), total))

    grab = vtkWindowToImageFilter()
    grab.SetInput(window)
    grab.SetInputBufferTypeToRGB()
    grab.ReadFrontBufferOff()
    grab.ShouldRerenderOff()
    grab.Update()
    writer = vtkPNGWriter()
    errors.watch(writer)
    writer.SetFileName(args.output)
    writer.SetInputConnection(grab.GetOutputPort())
    writer.Write()
    if errors.messages:
        raise RenderError("cannot write '%s': %s" % (args.output, errors.messages[-1]))

    w, h = scene["image_size"]
    if args.raw or args.raw_alpha:
        # Full float precision from the mapper's accumulation buffer
        # (premultiplied), not the 8-bit window.
        rgba = vtkFloatArray()
        mapper.GetAccumulatedImage(rgba)
        if (mapper.GetAccumulatedImageWidth(), mapper.GetAccumulatedImageHeight()) != (w, h):
            raise RenderError("the accumulated image is %dx%d, expected %dx%d" % (
                mapper.GetAccumulatedImageWidth(), mapper.GetAccumulatedImageHeight(), w, h))
        import numpy
        from vtkmodules.util.numpy_support import vtk_to_numpy

        values = vtk_to_numpy(rgba).reshape(-1, 4).astype(numpy.float32)
        alpha = values[:, 3]
        if args.raw:
            bg = numpy.asarray(scene["background"], dtype=numpy.float32)
            write_pfm(args.raw, w, h, 3, values[:, :3] + bg[None, :] * (1.0 - alpha[:, None]))
        if args.raw_alpha:
            write_pfm(args.raw_alpha, w, h, 1, alpha)
    if reference:
        method = "ray march, step %g (%s compositing, %d samples)" % (
            mapper.GetLastStepSize(), scene["compositing"], mapper.GetLastSampleCount())
        backend = "CPU"
    else:
        method = "%d spp (%d per render), %s" % (total, per_render, scene["tracking"])
    log(
        "%s: %s at %dx%d, %d channel(s), %s blend, %s: %.2f s -> %s"
        % (PROG, method, w, h, len(channels), scene["blend"], backend, seconds, args.output)
    )


def parse_size(text):
    try:
        w, h = text.lower().split("x")
        w, h = int(w), int(h)
    except ValueError:
        raise argparse.ArgumentTypeError("expected WxH, for example 512x512, got '%s'" % text)
    if not (1 <= w <= 16384 and 1 <= h <= 16384):
        raise argparse.ArgumentTypeError("width and height must be in [1, 16384], got '%s'" % text)
    return [w, h]


def parse_spp(text):
    try:
        n = int(text)
    except ValueError:
        raise argparse.ArgumentTypeError("expected a positive integer, got '%s'" % text)
    if n < 1:
        raise argparse.ArgumentTypeError("expected a positive integer, got '%s'" % text)
    return n


def default_presets_file():
    env = os.environ.get("MCVOL_PRESETS")
    if env:
        return env
    if _configured(_CONFIGURED_PRESETS_FILE):
        return _CONFIGURED_PRESETS_FILE
    here = os.path.dirname(os.path.abspath(__file__))
    return os.path.join(os.path.dirname(here), "Data", "presets.json")


def main(argv=None):
    parser = argparse.ArgumentParser(
        prog=PROG,
        description="Renders a multi-channel volume scene file with vtkMultiChannelVolumeMapper "
        "(Monte Carlo, multi-density Woodcock tracking). Scene format: Documentation/scene-format.md.",
    )
    parser.add_argument("scene", help="scene file (JSON)")
    parser.add_argument("-o", "--output", required=True, help="output PNG (RGB over the background)")
    parser.add_argument(
        "--raw", metavar="FILE.pfm", help="also write the linear RGB image (over the background) as a float PFM"
    )
    parser.add_argument("--raw-alpha", metavar="FILE.pfm", help="also write the alpha as a 1-channel float PFM")
    parser.add_argument("--spp", type=parse_spp, help="total samples per pixel (overrides samples_per_pixel)")
    parser.add_argument("--size", type=parse_size, metavar="WxH", help="image size (overrides image_size)")
    parser.add_argument("--backend", choices=BACKENDS, help="overrides backend")
    parser.add_argument(
        "--reference",
        action="store_true",
        help="render with the ray-marching reference (vtkMultiChannelRayMarchMapper) instead of Monte Carlo",
    )
    step = parser.add_mutually_exclusive_group()
    step.add_argument("--step", type=float, metavar="S", help="ray-marching step in world units (0 = Nyquist)")
    step.add_argument(
        "--step-voxels", type=float, metavar="V", help="ray-marching step in units of the smallest voxel spacing"
    )
    parser.add_argument("--compositing", choices=COMPOSITING, help="ray-marching compositing model")
    parser.add_argument(
        "--no-pixel-jitter",
        action="store_true",
        help="Monte Carlo samples through pixel centres (as the reference) instead of over the pixel area",
    )
    parser.add_argument("--quiet", action="store_true", help="print nothing on success")
    args = parser.parse_args(argv)
    for opt, v in (("--step", args.step), ("--step-voxels", args.step_voxels)):
        if v is not None and not (v >= 0.0 and v < float("inf")):
            parser.error("%s: expected a finite number >= 0, got %s" % (opt, v))
    if args.step_voxels is not None and args.step_voxels == 0.0:
        parser.error("--step-voxels: must be > 0 (use --step 0 for the Nyquist rate)")

    for opt, fn in (("-o", args.output), ("--raw", args.raw), ("--raw-alpha", args.raw_alpha)):
        if fn is None:
            continue
        if opt != "-o" and not fn.lower().endswith(".pfm"):
            parser.error("%s: expected a .pfm file name, got '%s'" % (opt, fn))
        folder = os.path.dirname(os.path.abspath(fn))
        if not os.path.isdir(folder):
            parser.error("%s: folder does not exist: %s" % (opt, folder))

    name = args.scene
    try:
        with open(args.scene, "r", encoding="utf-8") as f:
            text = f.read()
    except OSError as e:
        print("%s: %s: cannot read: %s" % (PROG, name, e.strerror), file=sys.stderr)
        return 2
    try:
        data = json.loads(text)
    except ValueError as e:
        print("%s: invalid JSON: %s" % (name, e), file=sys.stderr)
        return 2

    log = (lambda msg: None) if args.quiet else (lambda msg: print(msg, file=sys.stderr))
    try:
        scene = parse_scene(data, os.path.dirname(os.path.abspath(args.scene)), Presets(default_presets_file()))
        if args.spp is not None:
            scene["samples_per_pixel"] = args.spp
        if args.size is not None:
            scene["image_size"] = args.size
        if args.backend is not None:
            scene["backend"] = args.backend
        if args.reference:
            scene["renderer"] = "raymarch"
        if args.step is not None:
            scene["step"] = args.step
        if args.step_voxels is not None:
            scene["step_voxels"] = args.step_voxels
        if args.compositing is not None:
            scene["compositing"] = args.compositing
        if args.no_pixel_jitter:
            scene["pixel_jitter"] = False
        if scene["renderer"] != "raymarch" and (
            args.step is not None or args.step_voxels is not None or args.compositing is not None
        ):
            print("%s: --step, --step-voxels and --compositing apply to the ray-marching reference: add --reference "
                  "(or \"renderer\": \"raymarch\" in the scene)" % PROG, file=sys.stderr)
            return 2
        render(scene, args, ErrorCollector(), log)
    except SceneError as e:
        print("%s: %s: %s" % (name, e.key or "(top level)", e.message), file=sys.stderr)
        return 2
    except RenderError as e:
        print("%s: %s: rendering failed: %s" % (PROG, name, e), file=sys.stderr)
        return 1
    except ImportError as e:
        print(
            "%s: cannot import the mcvol Python package (%s); put the build's python folder on PYTHONPATH" % (PROG, e),
            file=sys.stderr,
        )
        return 1
    return 0


if __name__ == "__main__":
    sys.exit(main())
