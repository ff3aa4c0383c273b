# SPDX-License-Identifier: BSD-3-Clause
"""A parsed scene rendered to files: assemble the pipeline, accumulate the
samples, write the outputs."""

import time

from .assemble import assemble
from .errors import ErrorCollector, RenderError
from .output import write_png, write_raw


def accumulate(pipeline, errors):
    """Renders until the mapper holds the pipeline's total samples per pixel;
    returns the seconds it took."""
    mapper, total = pipeline.mapper, pipeline.total
    start = time.perf_counter()
    last = -1
    while True:
        pipeline.window.Render()
        if errors.messages:
            raise RenderError(errors.messages[-1])
        done = mapper.GetTotalSamples()
        if done >= total:
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
    seconds = accumulate(pipeline, errors)
    backend = mapper.GetBackendReport()
    if mapper.GetTotalSamples() != total:
        raise RenderError("accumulated %d samples per pixel, not %d" % (mapper.GetTotalSamples(), total))

    write_png(pipeline.window, output, errors)
    w, h = scene["image_size"]
    if raw or raw_alpha:
        write_raw(mapper, (w, h), scene["background"], raw, raw_alpha)
    if pipeline.reference:
        method = "ray march, step %g (%s compositing, %d samples)" % (
            mapper.GetLastStepSize(), scene["compositing"], mapper.GetLastSampleCount())
    else:
        method = "%d spp (%d per render), %s" % (total, per_render, scene["tracking"])
    return "%s at %dx%d, %d channel(s), %s blend, %s: %.2f s -> %s" % (
        method, w, h, len(pipeline.channels), scene["blend"], backend, seconds, output)
