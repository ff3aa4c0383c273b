# SPDX-License-Identifier: BSD-3-Clause
"""Scene file (its JSON, already loaded) -> plain data: dicts and lists, no VTK.

Only syntax and types are checked here; what needs the data (array names,
component counts, data ranges) is checked when the scene is assembled
(assemble.py), so that a scene can be validated without reading its input.
"""

import json
import os

from .errors import SceneError
from .schema import (
    BACKENDS,
    BLEND_MODES,
    MIX_COLORS,
    INTERPOLATIONS,
    RANGE_MODES,
    CAMERA_KEYS,
    CHANNEL_KEYS,
    COMPOSITING,
    DEMO_INPUT_KEYS,
    DEMO_NAMES,
    ENDIANNESS,
    FILE_FORMATS,
    FILE_INPUT_KEYS,
    OMEZARR_INPUT_KEYS,
    LIGHT_KEYS,
    LIGHTING_KEYS,
    MAX_CHANNELS,
    RAW_INPUT_KEYS,
    RAW_TYPES,
    RENDERERS,
    RESAMPLING,
    SAMPLE_SEQUENCES,
    ESTIMATORS,
    MARCH_CONTROL_VARIATES,
    SHADOWS,
    TOP_KEYS,
    TRACKING,
    VISIBILITY_KEYS,
    check_keys,
    get_bool,
    get_number,
    get_points,
    get_string,
    get_vector,
    join_key,
    split_extension,
    type_name,
    LOD_FILTERS,
)


def parse_demo(v):
    check_keys(v, "input", DEMO_INPUT_KEYS, required=("demo",))
    demo = {"demo": get_string(v["demo"], "input.demo", DEMO_NAMES), "dimensions": [0, 0, 0], "channels": 0}
    if "dimensions" in v:
        demo["dimensions"] = get_vector(
            v["dimensions"], "input.dimensions", 3, "[x, y, z] voxel counts", lo=1, hi=8192, integer=True
        )
    if "channels" in v:
        demo["channels"] = get_number(v["channels"], "input.channels", lo=1, hi=MAX_CHANNELS, integer=True)
    return demo


def parse_file_input(v, path, scene_dir):
    """One file: a name, {"file": name, ...} or a raw file {"raw": name, ...}.
    `key` is where it is in the scene, `file_key` the key naming the file."""
    if isinstance(v, str):
        v, file_key = {"file": v}, path
    elif isinstance(v, dict) and "demo" in v:
        raise SceneError(path, "a demo cannot be one of several inputs")
    elif isinstance(v, dict) and "raw" in v:
        check_keys(v, path, RAW_INPUT_KEYS, required=("raw", "dimensions", "type"))
        file_key = join_key(path, "raw")
    elif isinstance(v, dict) and "file" in v:
        check_keys(v, path, FILE_INPUT_KEYS)
        file_key = join_key(path, "file")
    elif isinstance(v, dict):
        raise SceneError(path, 'an input object needs "file", "raw" or "demo"')
    else:
        raise SceneError(path, "expected a file name or an input object, got %s" % type_name(v))
    name = get_string(v["raw"] if "raw" in v else v["file"], file_key)
    stem, ext = split_extension(name)
    entry = {"key": path, "file_key": file_key, "name": stem, "resample": None}
    if "raw" in v:
        entry["format"] = "raw"
        entry["raw"] = {
            "dimensions": get_vector(v["dimensions"], join_key(path, "dimensions"), 3, "[x, y, z] voxel counts", lo=1,
                                     hi=1 << 20, integer=True),
            "type": get_string(v["type"], join_key(path, "type"), RAW_TYPES),
            "endianness": get_string(v["endianness"], join_key(path, "endianness"), ENDIANNESS)
            if "endianness" in v else "little",
            "components": get_number(v["components"], join_key(path, "components"), lo=1, hi=MAX_CHANNELS,
                                     integer=True) if "components" in v else 1,
        }
    elif ext in FILE_FORMATS:
        entry["format"] = FILE_FORMATS[ext]
    elif is_omezarr(name if os.path.isabs(name) else os.path.join(scene_dir, name)):
        entry["format"] = "omezarr"  # a zarr folder of any name, or its .zattrs
    else:
        raise SceneError(file_key, "unsupported file type '%s' (expected %s, or an OME-Zarr folder; raw files: "
                                   "{\"raw\": name, ...})" % (ext, ", ".join(FILE_FORMATS)))
    entry["file"] = name if os.path.isabs(name) else os.path.join(scene_dir, name)
    if entry["format"] == "omezarr":
        if not os.path.exists(entry["file"]):
            raise SceneError(file_key, "folder not found: %s" % entry["file"])
        parse_omezarr_keys(v, path, entry)
    elif os.path.isdir(entry["file"]):
        raise SceneError(file_key, "%s is a folder, not a data file" % entry["file"])
    elif not os.path.isfile(entry["file"]):
        raise SceneError(file_key, "file not found: %s" % entry["file"])
    else:
        for k in OMEZARR_INPUT_KEYS:
            if k in v:
                raise SceneError(join_key(path, k), "only OME-Zarr inputs have resolution levels, regions and time "
                                                    "steps (this is %s)" % entry["format"])
    if "name" in v:
        entry["name"] = get_string(v["name"], join_key(path, "name"))
        if not entry["name"]:
            raise SceneError(join_key(path, "name"), "must not be empty")
    if "spacing" in v:
        entry["spacing"] = get_vector(v["spacing"], join_key(path, "spacing"), 3, "[x, y, z] > 0", lo=0.0,
                                      lo_open=True)
    if "origin" in v:
        entry["origin"] = get_vector(v["origin"], join_key(path, "origin"), 3, "[x, y, z]")
    if "resample" in v:
        r = v["resample"]
        if isinstance(r, bool):
            entry["resample"] = "auto" if r else None
        else:
            entry["resample"] = get_string(r, join_key(path, "resample"), RESAMPLING)
    return entry


def is_omezarr(path):
    from ..omezarr import is_omezarr as check

    return check(path)


def parse_omezarr_keys(v, path, entry):
    """An OME-Zarr input's "level" (index or dataset path), "region"
    (level-0 voxel extent [x0, x1, y0, y1, z0, z1]) and "time" (step)."""
    if "level" in v:
        level = v["level"]
        if isinstance(level, str):
            entry["level"] = level
        else:
            entry["level"] = get_number(level, join_key(path, "level"), lo=0, integer=True)
    if "region" in v:
        region = get_vector(v["region"], join_key(path, "region"), 6, "[x0, x1, y0, y1, z0, z1] voxel indices of "
                            "the full resolution", lo=0, integer=True)
        for k, axis in enumerate("xyz"):
            if region[2 * k] > region[2 * k + 1]:
                raise SceneError(join_key(path, "region"), "%s0 must be <= %s1, got %s" % (axis, axis,
                                                                                       json.dumps(v["region"])))
        entry["region"] = region
    if "time" in v:
        entry["time"] = get_number(v["time"], join_key(path, "time"), lo=0, integer=True)


def parse_input(v, scene_dir):
    """A demo ({"demo": ...}), or {"inputs": [file entries], "list": bool}:
    one file, or a list of files whose arrays make up one image."""
    if isinstance(v, dict) and "demo" in v:
        return parse_demo(v)
    if isinstance(v, list):
        if not v or len(v) > MAX_CHANNELS:
            raise SceneError("input", "expected a list of 1 to %d inputs, got %d" % (MAX_CHANNELS, len(v)))
        entries = [parse_file_input(x, "input[%d]" % i, scene_dir) for i, x in enumerate(v)]
        if entries[0]["resample"]:
            raise SceneError("input[0].resample", "the first input is the grid that the others are resampled onto")
        names = {}
        for e in entries:
            if e["name"] in names:
                raise SceneError(e["key"], "'%s' and '%s' (%s) are both named '%s': give one a \"name\""
                                 % (e["file"], names[e["name"]]["file"], names[e["name"]]["key"], e["name"]))
            names[e["name"]] = e
        return {"inputs": entries, "list": True}
    if isinstance(v, (str, dict)):
        entry = parse_file_input(v, "input", scene_dir)
        if entry["resample"]:
            raise SceneError("input.resample", "only the inputs of a list after the first are resampled")
        return {"inputs": [entry], "list": False}
    raise SceneError("input", 'expected a file name, an input object or a list of inputs, got %s' % type_name(v))


def parse_color(v, path, scene_dir, presets):
    """A list of [x, r, g, b] points, or a preset reference."""
    if isinstance(v, list):
        return {"points": get_points(v, path, 4, "[x, r, g, b] points"), "normalized": None}
    if isinstance(v, dict):
        if "preset_file" in v:
            check_keys(v, path, {"preset_file", "name", "normalized"})
            fn = get_string(v["preset_file"], join_key(path, "preset_file"))
            fn = fn if os.path.isabs(fn) else os.path.join(scene_dir, fn)
            name = get_string(v["name"], join_key(path, "name")) if "name" in v else None
            preset = presets.find(name, join_key(path, "preset_file"), filename=fn)
            where = join_key(path, "preset_file")
        else:
            check_keys(v, path, {"preset", "normalized"}, required=("preset",))
            name = get_string(v["preset"], join_key(path, "preset"))
            preset = presets.find(name, join_key(path, "preset"))
            where = join_key(path, "preset")
        rgb = preset.get("RGBPoints")
        if not isinstance(rgb, list) or len(rgb) < 4 or len(rgb) % 4 != 0:
            raise SceneError(where, "preset '%s' has no usable RGBPoints (categorical presets are not supported)" % preset["Name"])
        try:
            points = [[float(c) for c in rgb[i : i + 4]] for i in range(0, len(rgb), 4)]
        except (TypeError, ValueError):
            raise SceneError(where, "preset '%s' has non-numeric RGBPoints" % preset["Name"])
        normalized = get_bool(v["normalized"], join_key(path, "normalized")) if "normalized" in v else True
        return {
            "points": points,
            "normalized": normalized,
            "preset": preset["Name"],
            "color_space": preset.get("ColorSpace"),
        }
    raise SceneError(
        path, 'expected a list of [x, r, g, b] points, {"preset": name} or {"preset_file": file}, got %s' % type_name(v)
    )


def parse_lighting(v):
    """The "lighting" object: lights, ambient radiance and scattering settings
    (Documentation/scene-format.md). Its presence turns ShadeOn."""
    if not isinstance(v, dict):
        raise SceneError("lighting", "expected an object, got %s" % json.dumps(v))
    for k in v:
        if k not in LIGHTING_KEYS:
            raise SceneError(join_key("lighting", k), "unknown key (known: %s)" % ", ".join(sorted(LIGHTING_KEYS)))
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
                raise SceneError(join_key(path, k), "unknown key (known: %s)" % ", ".join(sorted(LIGHT_KEYS)))
        kind = get_string(l.get("type", "directional"), join_key(path, "type"), ("directional", "point"))
        key = "direction" if kind == "directional" else "position"
        if key not in l:
            raise SceneError(path, "a %s light needs \"%s\"" % (kind, key))
        vec = get_vector(l[key], join_key(path, key), 3, "[x, y, z]")
        if kind == "directional" and not any(vec):
            raise SceneError(join_key(path, key), "the direction must not be zero")
        out["lights"].append({
            "type": kind, "vector": vec,
            "color": get_vector(l["color"], join_key(path, "color"), 3, "[r, g, b] >= 0", lo=0.0) if "color" in l
            else [1.0, 1.0, 1.0],
            "intensity": get_number(l["intensity"], join_key(path, "intensity"), lo=0.0) if "intensity" in l else 1.0,
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


def parse_visibility(v):
    """The "visibility" object: the view-dependent visibility optimization
    (Lerzer and Dachsbacher) and its weights. Its presence turns it on unless "enabled" is
    false; the channels' "importance" functions say what is important."""
    if not isinstance(v, dict):
        raise SceneError("visibility", "expected an object, got %s" % json.dumps(v))
    check_keys(v, "visibility", VISIBILITY_KEYS)
    out = {"enabled": True, "deviation_weight": 1.0, "occlusion_weight": 70.0, "clutter_weight": 30.0,
           "emphasis": 1.0, "merge_distance": 0.0, "samples": 32, "light_rays": True, "light_ray_samples": 200}
    for k in ("enabled", "light_rays"):
        if k in v:
            out[k] = get_bool(v[k], join_key("visibility", k))
    if "deviation_weight" in v:
        out["deviation_weight"] = get_number(v["deviation_weight"], "visibility.deviation_weight", lo=0.0,
                                             lo_open=True, hi=1e12)
    for k in ("occlusion_weight", "clutter_weight"):
        if k in v:
            out[k] = get_number(v[k], join_key("visibility", k), lo=0.0, hi=1e12)
    if "emphasis" in v:
        out["emphasis"] = get_number(v["emphasis"], "visibility.emphasis", lo=0.0, hi=1e3)
    if "merge_distance" in v:
        out["merge_distance"] = get_number(v["merge_distance"], "visibility.merge_distance", lo=0.0, hi=1e6)
    if "samples" in v:
        out["samples"] = get_number(v["samples"], "visibility.samples", lo=1, hi=64, integer=True)
    if "light_ray_samples" in v:
        out["light_ray_samples"] = get_number(v["light_ray_samples"], "visibility.light_ray_samples", lo=2,
                                              hi=4096, integer=True)
    return out


def parse_channel(v, path, scene_dir, presets):
    check_keys(v, path, CHANNEL_KEYS)
    ch = {"path": path}
    if "name" in v:
        ch["name"] = get_string(v["name"], join_key(path, "name"))
    if "array" in v:
        ch["array"] = get_string(v["array"], join_key(path, "array"))
    if "component" in v:
        c = v["component"]
        if isinstance(c, str):
            ch["component"] = c
        else:
            ch["component"] = get_number(c, join_key(path, "component"), lo=0, integer=True)
    if "color" in v:
        ch["color"] = parse_color(v["color"], join_key(path, "color"), scene_dir, presets)
    if "opacity" in v:
        ch["opacity"] = get_points(v["opacity"], join_key(path, "opacity"), 2, "[x, a] pairs")
    ch["normalized"] = get_bool(v["normalized"], join_key(path, "normalized")) if "normalized" in v else False
    # "auto" (default): a robust range (percentiles, see assemble.auto_range);
    # "data": the finite min..max; or [min, max].
    ch["range"] = "auto"
    if "range" in v:
        if isinstance(v["range"], str):
            ch["range"] = get_string(v["range"], join_key(path, "range"), RANGE_MODES)
        else:
            r = get_vector(v["range"], join_key(path, "range"), 2, '[min, max], "auto" or "data"')
            if not r[0] < r[1]:
                raise SceneError(join_key(path, "range"), "min must be less than max, got %s" % json.dumps(v["range"]))
            ch["range"] = r
    if "unit_distance" in v:
        ch["unit_distance"] = get_number(v["unit_distance"], join_key(path, "unit_distance"), lo=0, lo_open=True)
    if "mix_weight" in v:
        ch["mix_weight"] = get_number(v["mix_weight"], join_key(path, "mix_weight"), lo=0)
    if "albedo" in v:
        ch["albedo"] = get_number(v["albedo"], join_key(path, "albedo"), lo=0.0, hi=1.0)
    if "anisotropy" in v:
        ch["anisotropy"] = get_number(v["anisotropy"], join_key(path, "anisotropy"), lo=-1.0, hi=1.0, lo_open=True,
                                      hi_open=True)
    if "importance" in v:
        pts = get_points(v["importance"], join_key(path, "importance"), 2, "[x, importance] pairs")
        for p in pts:
            if not 0.0 <= p[1] <= 1.0:
                raise SceneError(join_key(path, "importance"), "importance values must be in [0, 1], got %s" % p[1])
        ch["importance"] = pts
    return ch


def parse_camera(v):
    check_keys(v, "camera", CAMERA_KEYS)
    cam = {}
    for k in ("position", "focal_point", "view_up"):
        if k in v:
            cam[k] = get_vector(v[k], join_key("camera", k), 3, "[x, y, z]")
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
            cam[k] = get_number(v[k], join_key("camera", k))
    if "zoom" in v:
        cam["zoom"] = get_number(v["zoom"], "camera.zoom", lo=0, lo_open=True)
    return cam


MAX_NESTING = 32


def check_depth(data):
    """A scene nests a few levels (channels, their points, a point's values);
    deeper nesting is refused before anything walks it (a value in a message
    is printed recursively)."""
    stack = [(data, 1)]
    while stack:
        v, depth = stack.pop()
        if depth > MAX_NESTING:
            raise SceneError("", "arrays or objects nested more than %d levels deep; a scene needs a few"
                             % MAX_NESTING)
        if isinstance(v, dict):
            stack.extend((x, depth + 1) for x in v.values())
        elif isinstance(v, list):
            stack.extend((x, depth + 1) for x in v)


def parse_scene(data, scene_dir, presets):
    """The scene as a dict with every setting filled in, defaults included.

    "channels" is there only when the file lists channels: without them a
    demo input gets one channel per demo channel, with the demo's suggested
    transfer functions (assemble.resolve_channels). File names are resolved
    against `scene_dir`, the scene file's folder. "step_voxels" has no key in
    the file: it is for the command line's --step-voxels.
    """
    check_depth(data)
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
    s["mix_color"] = get_string(data["mix_color"], "mix_color", MIX_COLORS) if "mix_color" in data else "average"
    s["interpolation"] = (
        get_string(data["interpolation"], "interpolation", INTERPOLATIONS) if "interpolation" in data else "linear"
    )
    s["tracking"] = get_string(data["tracking"], "tracking", TRACKING) if "tracking" in data else "1-dda"
    s["sample_sequence"] = (
        get_string(data["sample_sequence"], "sample_sequence", SAMPLE_SEQUENCES)
        if "sample_sequence" in data
        else "sobol"
    )
    s["estimator"] = (
        get_string(data["estimator"], "estimator", ESTIMATORS) if "estimator" in data else "expected-value"
    )
    s["min_samples_per_voxel"] = (
        get_number(data["min_samples_per_voxel"], "min_samples_per_voxel", lo=0.0, hi=1e6)
        if "min_samples_per_voxel" in data
        else 0.0
    )
    s["march_samples_per_voxel"] = (
        get_number(data["march_samples_per_voxel"], "march_samples_per_voxel", lo=0.01, hi=1024.0)
        if "march_samples_per_voxel" in data
        else 2.0
    )
    s["march_control_variates"] = (
        get_string(data["march_control_variates"], "march_control_variates", MARCH_CONTROL_VARIATES)
        if "march_control_variates" in data
        else "by-rate"
    )
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
    # 0: off; else stop once the estimated RMSE reaches it (samples_per_pixel
    # is then the cap).
    s["target_error"] = (
        get_number(data["target_error"], "target_error", lo=0.0, hi=1.0) if "target_error" in data else 0.0
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
    # Levels of detail (vtkMultiChannelVolumeMapper::SetLevelOfDetail): 0 full
    # resolution, L > 0 level L, -1 automatic; the budget in MiB (0: no cap).
    s["level_of_detail"] = (
        get_number(data["level_of_detail"], "level_of_detail", lo=-1, hi=64, integer=True)
        if "level_of_detail" in data
        else 0
    )
    s["level_of_detail_filter"] = (
        get_string(data["level_of_detail_filter"], "level_of_detail_filter", LOD_FILTERS)
        if "level_of_detail_filter" in data
        else LOD_FILTERS[0]
    )
    s["level_of_detail_half_precision"] = (
        get_bool(data["level_of_detail_half_precision"], "level_of_detail_half_precision")
        if "level_of_detail_half_precision" in data
        else True
    )
    s["memory_budget"] = (
        get_number(data["memory_budget"], "memory_budget", lo=0.0, hi=1e12) if "memory_budget" in data else 0.0
    )
    for entry in s["input"].get("inputs", []):
        if entry["format"] == "omezarr":
            # The level read is the finest that fits the mapper's budget.
            entry["memory_budget"] = s["memory_budget"] * 1048576.0
    if s["interpolation"] == "cubic" and s["renderer"] == "raymarch" and s["compositing"] == "opacity":
        # The opacity model interpolates voxel opacities trilinearly; it has no B-spline variant.
        raise SceneError("interpolation", 'cubic needs "compositing": "extinction" with the ray marcher')
    s["lighting"] = parse_lighting(data["lighting"]) if "lighting" in data else None
    s["visibility"] = parse_visibility(data["visibility"]) if "visibility" in data else None
    if "pixel_jitter" in data:
        if not isinstance(data["pixel_jitter"], bool):
            raise SceneError("pixel_jitter", "expected true or false, got %s" % json.dumps(data["pixel_jitter"]))
        s["pixel_jitter"] = data["pixel_jitter"]
    else:
        s["pixel_jitter"] = True
    return s

