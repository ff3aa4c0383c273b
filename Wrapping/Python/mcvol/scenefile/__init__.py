# SPDX-License-Identifier: BSD-3-Clause
"""Scene files (Documentation/scene-format.md): reading, checking, rendering.

The steps, one module each, in the order a scene goes through them:

    parse.py     the JSON of a scene file -> plain data (dicts, lists), every
                 value checked, defaults filled in; no VTK. Builds on
                 schema.py (what may appear where; the value checks) and
                 presets.py (colour maps by name, ParaView's JSON format).
    assemble.py  plain data -> a VTK pipeline: the input read or generated,
                 its channels found, transfer functions, mapper, lights,
                 camera, an offscreen window. Builds on readers.py (the
                 input files, one or several, as one vtkImageData).
    render.py    accumulates the samples and writes the outputs (output.py:
                 PNG and PFM).

errors.py holds the two failures, SceneError (the scene's fault; it names the
key) and RenderError (the machine's), and ErrorCollector, which turns VTK
error messages into either. mcvol-render (Tools/mcvol-render.py) is this
package behind a command line:

    scene = parse_scene(json.load(f), scene_dir, Presets(presets_file))
    summary = render(scene, "out.png")

`import mcvol` does not import this subpackage; importing it loads no VTK
module beyond what `import mcvol` does (each step imports VTK as it needs it).
"""

from .errors import ErrorCollector, RenderError, SceneError
from .parse import parse_scene
from .presets import Presets
from .render import render

__all__ = ["ErrorCollector", "Presets", "RenderError", "SceneError", "parse_scene", "render"]
