# SPDX-License-Identifier: BSD-3-Clause
"""Parsed scene (parse.py) -> a VTK pipeline ready to render: the input
image, its channels with their transfer functions, the mapper and its
settings, the renderer with its lights and camera, and an offscreen window.

VTK is imported inside the functions, as each needs it.
"""

import math
import os

from .errors import RenderError, SceneError
from .readers import read_inputs
from .schema import MAX_CHANNELS, SUPPORTED_TYPES, join_key

VTK_MAX_VRCOMP = 4


def load_input(spec, errors, need_arrays=True):
    """Returns (vtkImageData, demo source or None): the demo generated, or
    the files read (readers.py)."""
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
    return read_inputs(spec, errors), None


# Colours of the default channels of a file input, in channel order: one
# channel alone is warm white; several get fluorescence-like hues.
DEFAULT_COLORS = [(0.2, 1.0, 0.3), (1.0, 0.25, 0.9), (0.25, 0.7, 1.0), (1.0, 0.85, 0.2), (1.0, 0.35, 0.2),
                  (0.6, 0.4, 1.0), (0.3, 1.0, 0.9), (1.0, 1.0, 1.0)]
DEFAULT_ALONE = (1.0, 0.92, 0.82)


def default_channels(image):
    """The channels of a file input whose scene names none: every point array
    of the mapper's types (each component of a multi-component one), in
    order, each a ramp of its colour and of opacity (0 below 15 % of its
    "auto" range, 0.3 at its top per 4 voxels) over its robust range.

    An image that carries default displays (an OME-Zarr's omero metadata,
    an OME-TIFF's channel colours: mcvol.omezarr.component_displays) shows
    its active channels only, each in its colour (where the file gives one),
    the ramps over its window (opacity 0 at the window's start)."""
    from ..omezarr import component_displays
    from .parse import parse_channel

    pd = image.GetPointData()
    displays = {n: d[0] for n, d in component_displays(image).items() if len(d) == 1}
    if displays and not any(d["active"] for d in displays.values()):
        displays = {n: dict(d, active=True) for n, d in displays.items()}  # all off: show them all
    per_component = component_displays(image)
    picks = []
    for k in range(pd.GetNumberOfArrays()):
        a = pd.GetArray(k)
        if a is None or not a.GetName() or a.GetDataTypeAsString() not in SUPPORTED_TYPES:
            continue
        if a.GetName() in displays and not displays[a.GetName()]["active"]:
            continue
        for c in range(a.GetNumberOfComponents()):
            picks.append((a.GetName(), c, a.GetNumberOfComponents()))
    if not picks:
        raise SceneError("input", "no point array that the mapper reads (%s): give \"channels\""
                         % ", ".join(SUPPORTED_TYPES))
    if len(picks) > MAX_CHANNELS:
        raise SceneError("channels", "the input has %d arrays and components, more than %d channels: give "
                                     "\"channels\"" % (len(picks), MAX_CHANNELS))
    unit = 4.0 * min(image.GetSpacing())
    out = []
    for i, (name, comp, ncomp) in enumerate(picks):
        rgb = DEFAULT_ALONE if len(picks) == 1 else DEFAULT_COLORS[i % len(DEFAULT_COLORS)]
        raw = {"array": name, "normalized": True, "unit_distance": unit,
               "color": [[0.0] + [0.35 * v for v in rgb], [1.0] + list(rgb)],
               "opacity": [[0.0, 0.0], [0.15, 0.0], [1.0, 0.3]]}
        entries = per_component.get(name)
        display = (displays.get(name) if ncomp == 1 else None) or (
            entries[comp] if entries is not None and len(entries) == ncomp else None)
        if display is not None:
            if display["color"] is not None:
                rgb = display["color"]
                raw["color"] = [[0.0] + [0.35 * v for v in rgb], [1.0] + list(rgb)]
            if display["window"] is not None:
                raw["range"] = display["window"]
                raw["opacity"] = [[0.0, 0.0], [1.0, 0.3]]
        if ncomp > 1:
            raw["component"] = comp
        out.append(parse_channel(raw, "channels[%d] (default)" % i, ".", None))
    return out


def resolve_channels(scene, image, demo):
    """Finds each channel's array, component and data range."""
    pd = image.GetPointData()
    scalars = pd.GetScalars()
    entries = scene.get("channels")
    if entries is None and demo is None:
        entries = default_channels(image)
    if entries is None:
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
                    join_key(path, "array"),
                    "no point array named '%s' (the input has: %s)" % (e["array"], ", ".join(n for n in names if n) or "none"),
                )
            where = "array '%s'" % e["array"]
            key = join_key(path, "array")
        else:
            array = scalars
            if array is None:
                names = [pd.GetArrayName(k) for k in range(pd.GetNumberOfArrays())]
                raise SceneError(path, "the input has no point scalars: give \"array\" (the input has: %s)"
                                 % (", ".join(n for n in names if n) or "none"))
            where = "the point scalars '%s'" % (array.GetName() or "")
            key = path
        ncomp = array.GetNumberOfComponents()
        comp = e.get("component")
        if isinstance(comp, str):
            names = [array.GetComponentName(k) for k in range(ncomp)]
            if comp not in names:
                raise SceneError(
                    join_key(path, "component"),
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
                join_key(path, "component"), "component %d out of range: %s has %d component(s)" % (comp, where, ncomp)
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


# "range": "auto": the [0.1, 99.9] percentiles of the channel's finite
# values, or min..max for data of at most this many distinct values (labels,
# masks), whose rare labels percentiles would cut off.
AUTO_PERCENTILES = (0.1, 99.9)
AUTO_MAX_DISTINCT = 256


def few_distinct(values, lo, hi, limit=AUTO_MAX_DISTINCT):
    """True when the 1-D numpy array `values` (finite, min `lo`, max `hi`)
    holds at most `limit` distinct values. Exact, and fast for the usual
    answer "no": a strided sample of a million values decides it first."""
    import numpy

    if numpy.issubdtype(values.dtype, numpy.integer) and hi - lo < limit:
        return True  # uint8, or integers over a short span
    step = max(1, values.size // 1000000)
    seen = numpy.unique(values[::step])
    if seen.size > limit:
        return False
    rest = values[~numpy.isin(values, seen)]
    return rest.size == 0 or seen.size + numpy.unique(rest).size <= limit


def auto_range(array, comp):
    """The robust range of component `comp` of vtkDataArray `array`: [lo, hi]
    of its finite values at the AUTO_PERCENTILES, or their min..max when
    they take few distinct values or the percentiles coincide; None when no
    value is finite. A handful of extreme voxels (a 16-bit volume whose
    tissue lies in 0..2000 with a few voxels at 65535) then does not squash
    normalised transfer functions into the first few per cent of the range."""
    import numpy
    from vtkmodules.util.numpy_support import vtk_to_numpy

    values = vtk_to_numpy(array).reshape(array.GetNumberOfTuples(), array.GetNumberOfComponents())[:, comp]
    if numpy.issubdtype(values.dtype, numpy.floating):
        finite = numpy.isfinite(values)
        if not finite.all():
            values = values[finite]
    if values.size == 0:
        return None
    lo, hi = float(values.min()), float(values.max())
    if lo == hi or few_distinct(values, lo, hi):
        return [lo, hi]
    plo, phi = (float(p) for p in numpy.percentile(values, AUTO_PERCENTILES))
    if not plo < phi:
        return [lo, hi]  # a constant majority (sparse data): the percentiles say nothing
    return [plo, phi]


def channel_range(ch):
    """The range normalised points and presets of channel `ch` are spread
    over: its "range" ([min, max], "data" or "auto"), computed once."""
    r = ch.get("range", "auto")
    if isinstance(r, list):
        return r
    if r == "data":
        return ch["data_range"]
    if ch.get("auto_range") is None:
        ch["auto_range"] = auto_range(ch["array_obj"], ch["comp"]) or list(ch["data_range"])
    return ch["auto_range"]


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
        def span(ch=ch):
            # Only normalised points and presets need the range ("auto"
            # reads the whole channel).
            lo, hi = channel_range(ch)
            if not hi > lo:
                hi = lo + 1.0  # constant channel: keep the points apart
            return lo, hi

        def place(x, normalized):
            if not normalized:
                return x
            lo, hi = span()
            return lo + x * (hi - lo)

        if "color" in ch:
            c = ch["color"]
            color.RemoveAllPoints()
            pts = c["points"]
            if c["normalized"] is None:  # a plain point list
                xs = [place(p[0], ch["normalized"]) for p in pts]
            elif c["normalized"]:  # a preset: its span onto the range
                x0 = min(p[0] for p in pts)
                x1 = max(p[0] for p in pts)
                lo, hi = span()
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
        importance = None
        if "importance" in ch:
            importance = vtkPiecewiseFunction()
            for p in ch["importance"]:
                importance.AddPoint(place(p[0], ch["normalized"]), p[1])
        out.append((color, opacity, unit, importance))
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



class Pipeline:
    """What assemble() built; render.py accumulates it and reads it back.

    `total` is the samples per pixel to accumulate, `per_render` those of one
    window.Render(); `reference` is true for the ray-marching reference.
    `image` and `demo` are held so that the input outlives the render.
    """

    def __init__(self, image, demo, channels, mapper, volume, renderer, window, reference, total, per_render):
        self.image = image
        self.demo = demo
        self.channels = channels
        self.mapper = mapper
        self.volume = volume
        self.renderer = renderer
        self.window = window
        self.reference = reference
        self.total = total
        self.per_render = per_render


def setup_mapper(mapper, prop, scene, channels, tfs, render_image, reference):
    """Transfer functions and per-channel settings, blend mode, sampling.
    The mapper tabulates the functions over the data's range clipped to the
    functions' (its default, DATA_RANGE), so a percentile "range" over data
    with outliers keeps the table's resolution. Returns (total, per_render)
    samples per pixel."""
    for i, (color, opacity, unit, importance) in enumerate(tfs):
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
        if importance is not None:
            mapper.SetChannelImportance(i, importance)
    vis = scene.get("visibility")
    if vis is not None:
        mapper.SetVisibilityOptimization(vis["enabled"])
        mapper.SetDeviationWeight(vis["deviation_weight"])
        mapper.SetOcclusionWeight(vis["occlusion_weight"])
        mapper.SetClutterWeight(vis["clutter_weight"])
        mapper.SetImportanceEmphasis(vis["emphasis"])
        mapper.SetImportanceMergeDistance(vis["merge_distance"])
        mapper.SetImportanceSamples(vis["samples"])
        mapper.SetOptimizeLightRays(vis["light_rays"])
        mapper.SetLightRayImportanceSamples(vis["light_ray_samples"])
    {
        "density": mapper.SetChannelBlendModeToDensity,
        "max": mapper.SetChannelBlendModeToMax,
        "mix": mapper.SetChannelBlendModeToMix,
        "composite": mapper.SetChannelBlendModeToComposite,
    }[scene["blend"]]()
    mapper.SetTrackingMethod(mapper.N_DDA if scene["tracking"] == "n-dda" else mapper.ONE_DDA)
    if scene["estimator"] == "collision":
        mapper.SetEstimatorToCollision()
    elif scene["estimator"] == "unbiased-march":
        mapper.SetEstimatorToUnbiasedMarch()
    elif scene["estimator"] == "automatic":
        mapper.SetEstimatorToAutomatic()
    else:
        mapper.SetEstimatorToExpectedValue()
    mapper.SetMinimumSamplesPerVoxel(scene["min_samples_per_voxel"])
    mapper.SetMarchSamplesPerVoxel(scene["march_samples_per_voxel"])
    {
        "never": mapper.SetMarchControlVariatesToNever,
        "by-rate": mapper.SetMarchControlVariatesToByRate,
        "always": mapper.SetMarchControlVariatesToAlways,
    }[scene["march_control_variates"]]()
    if scene["sample_sequence"] == "independent":
        mapper.SetSampleSequenceToIndependent()
    else:
        mapper.SetSampleSequenceToSobol()
    mapper.SetMixColorMode(mapper.MIX_EQUATION_10 if scene["mix_color"] == "equation10" else mapper.MIX_AVERAGE)
    # Both mappers: the reference marches on the backend chosen (the same
    # per-ray code on the CPU and on CUDA).
    {"auto": mapper.SetBackendToAuto, "cpu": mapper.SetBackendToCPU, "cuda": mapper.SetBackendToCUDA}[
        scene["backend"]
    ]()
    mapper.SetSeed(scene["seed"])
    mapper.SetMacrocellSize(scene["macrocell_size"])
    mapper.SetPixelJitter(scene["pixel_jitter"])
    mapper.SetLevelOfDetail(scene.get("level_of_detail", 0))
    {"box2": mapper.SetLevelOfDetailFilterToBox2, "box4": mapper.SetLevelOfDetailFilterToBox4,
     "bspline": mapper.SetLevelOfDetailFilterToBSpline}[scene.get("level_of_detail_filter", "box4")]()
    mapper.SetLevelOfDetailHalfPrecision(scene.get("level_of_detail_half_precision", True))
    mapper.SetMemoryBudget(scene.get("memory_budget", 0.0) * 1048576.0)  # MiB -> bytes
    total = scene["samples_per_pixel"]
    per_render = samples_per_render(total, scene["samples_per_render"])
    mapper.SetSamplesPerPixel(per_render)
    if not reference and scene.get("target_error", 0.0) > 0.0:
        # Adaptive stopping: the mapper stops tracing once its estimated RMSE
        # reaches the target, samples_per_pixel still capping the total.
        mapper.SetTargetError(scene["target_error"])
        mapper.SetMaximumTotalSamples(total)
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
    return total, per_render


def setup_lighting(renderer, prop, mapper, lighting):
    # The lighting object turns shading on; its lights replace VTK's
    # headlight (none listed: the headlight).
    from vtkmodules.vtkRenderingCore import vtkLight

    prop.ShadeOn()
    mapper.SetAmbientRadiance(*lighting["ambient"])
    mapper.SetShadowMode({"none": mapper.NO_SHADOWS, "ratio": mapper.RATIO_TRACKING_SHADOWS,
                          "delta": mapper.DELTA_TRACKING_SHADOWS,
                          "cached": mapper.CACHED_SHADOWS}[lighting["shadows"]])
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


def assemble(scene, errors, prog):
    """Builds the pipeline of a parsed scene. `prog` names the program in the
    hint given when there is no X display."""
    import vtkmodules.vtkRenderingOpenGL2  # noqa: F401  (OpenGL render window)
    import vtkmodules.vtkRenderingVolumeOpenGL2  # noqa: F401
    from vtkmodules.vtkRenderingCore import vtkRenderer, vtkRenderWindow, vtkVolume, vtkVolumeProperty

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
    if scene["interpolation"] == "nearest":
        prop.SetInterpolationTypeToNearest()
    else:
        prop.SetInterpolationTypeToLinear()
    if scene["interpolation"] == "cubic":
        # The mapper holds the cubic choice (VTK 9.1's property clamps its type to linear).
        mapper.SetInterpolationTypeToCubic()
    total, per_render = setup_mapper(mapper, prop, scene, channels, tfs, render_image, reference)

    volume = vtkVolume()
    volume.SetMapper(mapper)
    volume.SetProperty(prop)
    renderer = vtkRenderer()
    renderer.SetBackground(*scene["background"])
    renderer.AddVolume(volume)
    lighting = scene.get("lighting")
    if lighting is not None:
        setup_lighting(renderer, prop, mapper, lighting)
    window = vtkRenderWindow()
    if window.GetClassName() == "vtkXOpenGLRenderWindow" and not os.environ.get("DISPLAY"):
        raise RenderError("no X display: run under an X server (for example `xvfb-run -a %s ...`)" % prog)
    window.SetOffScreenRendering(1)
    window.SetMultiSamples(0)
    window.SetSize(*scene["image_size"])
    window.AddRenderer(renderer)
    setup_camera(renderer, scene["camera"])
    pipeline = Pipeline(image, demo, channels, mapper, volume, renderer, window, reference, total, per_render)
    return pipeline
