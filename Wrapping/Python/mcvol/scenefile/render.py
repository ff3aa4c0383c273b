# SPDX-License-Identifier: BSD-3-Clause
"""A parsed scene rendered to files: assemble the pipeline, accumulate the
samples, write the outputs."""

import time

from .assemble import assemble
from .errors import ErrorCollector, RenderError
from .output import write_png, write_raw


def accumulate(pipeline, errors, adaptive=False):
    """Renders until the mapper holds the pipeline's total samples per pixel,
    or, `adaptive` (a target_error), until the mapper says the image is
    converged; returns the seconds it took."""
    mapper, total = pipeline.mapper, pipeline.total
    start = time.perf_counter()
    last = -1
    while True:
        pipeline.window.Render()
        if errors.messages:
            raise RenderError(errors.messages[-1])
        done = mapper.GetTotalSamples()
        if done >= total or (adaptive and mapper.IsConverged()):
            break
        if done <= last:
            raise RenderError("the mapper stopped accumulating at %d samples per pixel" % done)
        last = done
    return time.perf_counter() - start


def render(scene, output, raw=None, raw_alpha=None, errors=None, prog="mcvol-render"):
    """Renders `scene` (parse.parse_scene) to the PNG `output` and, if given,
    the PFMs `raw` (RGB) and `raw_alpha`. Returns a one-line summary: method,
    size, channels, blend, backend, seconds and output.

    Raises SceneError for what only the data shows to be wrong (a missing
    array, say), RenderError when rendering fails. `prog` names the program in
    messages."""
    if errors is None:
        errors = ErrorCollector()
    pipeline = assemble(scene, errors, prog)
    mapper, total, per_render = pipeline.mapper, pipeline.total, pipeline.per_render
    target = 0.0 if pipeline.reference else scene.get("target_error", 0.0)
    seconds = accumulate(pipeline, errors, adaptive=target > 0.0)
    backend = mapper.GetBackendReport()
    done = mapper.GetTotalSamples()
    if done != total and not (target > 0.0 and mapper.IsConverged() and done < total):
        raise RenderError("accumulated %d samples per pixel, not %d" % (done, total))

    write_png(pipeline.window, output, errors)
    w, h = scene["image_size"]
    if raw or raw_alpha:
        write_raw(mapper, (w, h), scene["background"], raw, raw_alpha)
    if pipeline.reference:
        method = "ray march, step %g (%s compositing, %d samples)" % (
            mapper.GetLastStepSize(), scene["compositing"], mapper.GetLastSampleCount())
    else:
        method = "%d spp (%d per render), %s" % (done, per_render, scene["tracking"])
        rmse = mapper.GetEstimatedError()
        if target > 0.0:
            reached = 0.0 <= rmse <= target and done >= mapper.TARGET_ERROR_MINIMUM_SAMPLES
            method += ", target error %g %s" % (target, "reached" if reached else "not reached (capped)")
        if rmse >= 0.0:
            method += ", estimated RMSE %.4g (PSNR %.1f dB)" % (rmse, mapper.GetEstimatedPSNR())
    if scene.get("level_of_detail", 0) != 0 or scene.get("memory_budget", 0.0) > 0.0:
        method += ", " + mapper.GetLevelOfDetailReport()
    for entry in scene["input"].get("inputs", []):
        if entry.get("report"):
            method += ", " + entry["report"]
    return "%s at %dx%d, %d channel(s), %s blend, %s: %.2f s -> %s" % (
        method, w, h, len(pipeline.channels), scene["blend"], backend, seconds, output)
