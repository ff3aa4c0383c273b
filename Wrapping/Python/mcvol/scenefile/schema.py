# SPDX-License-Identifier: BSD-3-Clause
"""What a scene file may contain (Documentation/scene-format.md), and the
value checks that parse.py builds on.

Each check names the key path in its error, so that a message points at the
offending entry ("channels[2].opacity[1][1]: must be <= 1.0, got 2").
"""

import json
import math
import os

from .errors import SceneError

DEMO_NAMES = ("figure3", "microscopy", "cosmology", "weather")
BLEND_MODES = ("density", "max", "mix", "composite")
MIX_COLORS = ("average", "equation10")
INTERPOLATIONS = ("linear", "nearest", "cubic")
RANGE_MODES = ("auto", "data")  # a channel's "range" as a word
TRACKING = ("1-dda", "n-dda")
SAMPLE_SEQUENCES = ("sobol", "independent")
ESTIMATORS = ("expected-value", "collision", "unbiased-march", "automatic")
MARCH_CONTROL_VARIATES = ("by-rate", "never", "always")
BACKENDS = ("auto", "cpu", "cuda")
RENDERERS = ("montecarlo", "raymarch")
COMPOSITING = ("extinction", "opacity")
LOD_FILTERS = ("box4", "box2", "bspline")  # the first is the default
SHADOWS = ("ratio", "delta", "cached", "none")
MAX_CHANNELS = 32
# Array types the mapper reads in place (VTK type names as GetDataTypeAsString
# gives them): what a channel's array may hold.
SUPPORTED_TYPES = ("unsigned char", "short", "unsigned short", "float", "double")

# Input files by extension (readers.py reads them); ".nii.gz" counts as one.
FILE_FORMATS = {
    ".vti": "vti",
    ".mha": "meta",
    ".mhd": "meta",
    ".nrrd": "nrrd",
    ".nhdr": "nrrd",
    ".nii": "nifti",
    ".nii.gz": "nifti",
    ".tif": "tiff",
    ".tiff": "tiff",
    ".zarr": "omezarr",
}
# OME-Zarr: a folder (any name, when it holds .zattrs/.zgroup) or its .zattrs.
ZARR_METADATA_FILES = (".zattrs", ".zgroup")
RAW_TYPES = ("uint8", "int16", "uint16", "float32", "float64")
ENDIANNESS = ("little", "big")
RESAMPLING = ("linear", "nearest")
DEMO_INPUT_KEYS = {"demo", "dimensions", "channels"}
FILE_INPUT_KEYS = {"file", "name", "spacing", "origin", "resample", "level", "region", "time"}
OMEZARR_INPUT_KEYS = ("level", "region", "time")
RAW_INPUT_KEYS = {"raw", "dimensions", "type", "endianness", "components", "name", "spacing", "origin", "resample"}

TOP_KEYS = {
    "description",
    "input",
    "channels",
    "blend",
    "mix_color",
    "interpolation",
    "tracking",
    "sample_sequence",
    "estimator",
    "min_samples_per_voxel",
    "march_samples_per_voxel",
    "march_control_variates",
    "backend",
    "samples_per_pixel",
    "samples_per_render",
    "target_error",
    "image_size",
    "camera",
    "background",
    "seed",
    "macrocell_size",
    "renderer",
    "step",
    "compositing",
    "pixel_jitter",
    "level_of_detail",
    "level_of_detail_filter",
    "level_of_detail_half_precision",
    "memory_budget",
    "lighting",
    "visibility",
}
LIGHTING_KEYS = {"lights", "ambient", "shadows", "max_scattering_depth", "gradient_shading", "shininess"}
LIGHT_KEYS = {"type", "direction", "position", "color", "intensity"}
VISIBILITY_KEYS = {
    "enabled",
    "deviation_weight",
    "occlusion_weight",
    "clutter_weight",
    "emphasis",
    "merge_distance",
    "samples",
    "light_rays",
    "light_ray_samples",
}
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
    "importance",
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


def join_key(path, key):
    if isinstance(key, int):
        return "%s[%d]" % (path, key)
    return "%s.%s" % (path, key) if path else key


def split_extension(filename):
    """(stem, extension) of a file name, the extension lower case: "T1.nii.gz"
    -> ("T1", ".nii.gz"), "cells.ome.tif" -> ("cells", ".tif"),
    "cells.ome.zarr/.zattrs" -> ("cells", ".zarr")."""
    base = os.path.basename(filename.rstrip("/" + os.sep))
    if base in ZARR_METADATA_FILES:  # an OME-Zarr's metadata file: the folder's name
        return split_extension(os.path.dirname(filename.rstrip("/" + os.sep)))
    lower = base.lower()
    if lower.endswith(".ome.zarr"):
        return base[: -len(".ome.zarr")], ".zarr"
    for ext, kept in ((".nii.gz", ".nii.gz"), (".ome.tiff", ".tiff"), (".ome.tif", ".tif")):
        if lower.endswith(ext):
            return base[: -len(ext)], kept
    stem, ext = os.path.splitext(base)
    return stem, ext.lower()


def type_name(v):
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
        raise SceneError(path, "expected an object, got %s" % type_name(obj))
    for k in obj:
        if k not in allowed:
            raise SceneError(
                join_key(path, k), "unknown key (allowed here: %s)" % ", ".join(sorted(allowed))
            )
    for k in required:
        if k not in obj:
            raise SceneError(path, "missing required key '%s'" % k)


def get_number(v, path, lo=None, hi=None, lo_open=False, hi_open=False, integer=False):
    if isinstance(v, bool) or not isinstance(v, (int, float)):
        raise SceneError(path, "expected %s, got %s" % ("an integer" if integer else "a number", type_name(v)))
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
    return [get_number(x, join_key(path, i), **kw) for i, x in enumerate(v)]


def get_bool(v, path):
    if not isinstance(v, bool):
        raise SceneError(path, "expected true or false, got %s" % type_name(v))
    return v


def get_string(v, path, choices=None):
    if not isinstance(v, str):
        raise SceneError(path, "expected a string, got %s" % type_name(v))
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
