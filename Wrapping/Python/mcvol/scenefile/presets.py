# SPDX-License-Identifier: BSD-3-Clause
"""Colour-map presets in ParaView's JSON format, for {"preset": name} and
{"preset_file": file} colours."""

import json
import os

from .errors import SceneError


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
