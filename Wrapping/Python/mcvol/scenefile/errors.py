# SPDX-License-Identifier: BSD-3-Clause
"""The two ways a scene can fail, and the VTK error messages behind them.

A SceneError is the user's to fix (mcvol-render exits with status 2); a
RenderError means the scene is fine but this machine could not render it
(status 1).
"""


class SceneError(Exception):
    """A bad scene: `key` is the path of the offending key ("channels[2].opacity")."""

    def __init__(self, key, message):
        super().__init__(message)
        self.key = key
        self.message = message


class RenderError(Exception):
    """The scene is valid but rendering failed (no device, mapper error)."""


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
