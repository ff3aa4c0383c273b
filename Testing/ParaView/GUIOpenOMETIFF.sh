#!/usr/bin/env bash
# The ParaView GUI walk of the user guide's OME-TIFF section
# (Documentation/user-guide/paraview.md, "A 3-channel OME-TIFF, step by
# step") and its two screenshots, as a microscopist does it, in the real GUI
# under a private Xvfb:
#
#   1. File > Open of a 3-channel uint16 OME-TIFF (Data/cells_ometiff.py:
#      DAPI, membrane, puncta; Poisson noise over a dark background; 0.2 x
#      0.2 x 0.8 um voxels); ParaView asks which reader: "Mcvol Channel
#      Files"; OK; Apply. The image shows as Multi-Channel Volume (Monte
#      Carlo) and refines while the GUI is idle: OUTDIR/paraview-ometiff-open.png.
#   2. Properties search "Edit Channel", Edit Channel = 1: the colour map
#      editor opens on the second channel (membrane). Its legend on (the
#      range), the preset "Black-Body Radiation" from the editor's preset
#      list, the top opacity 0.5 in the editor's opacity table (advanced
#      view); the image starts over and refines again:
#      OUTDIR/paraview-ometiff-edit-channel.png.
#
#   bash Testing/ParaView/GUIOpenOMETIFF.sh OUTDIR
#
# Every click is ParaView's QtTesting playback (XML events on the widgets,
# the reader dialog's list and the editor's preset list and opacity table
# included; the playback checks that the list's row it picks says "Mcvol
# Channel Files"); nothing needs Python to be driven. Python typed into the
# console of the GUI's Python shell (GUIOpenOMETIFF.py; the shell stays
# closed, so that the view keeps its size and its image) only checks what the
# clicks did, finishes the refinement and says when to take each screenshot.
# Exits non-zero when a click finds no widget, a check fails, or the walk
# does not finish. About 70 s on 2 cores: a script for the guide's pictures,
# not a ctest test. Needs a build (scripts/build.sh), tifffile, Xvfb, xwd
# (x11-apps) and Pillow.
set -euo pipefail
# shellcheck source-path=SCRIPTDIR source=gui_walk.sh
source "$(dirname "${BASH_SOURCE[0]}")/gui_walk.sh"
out="$(realpath -m "${1:?usage: GUIOpenOMETIFF.sh OUTDIR}")"
mkdir -p "$out"
gui_walk_start
export MCVOL_WALK_OUT="$work"
export PYTHONPATH="$top/Testing/ParaView:$PYTHONPATH"
file="$work/cells.ome.tif"
/usr/bin/python3 "$top/Data/cells_ometiff.py" "$file" > /dev/null

idle_ms=${MCVOL_GUI_IDLE_MS:-15000}  # the GUI refines on its own for this long
main=pqClientMainWindow
props=$main/propertiesDock/propertiesPanel
panel=$props/scrollArea/qt_scrollarea_viewport/scrollAreaWidgetContents/DisplayFrame/ProxyPanel
editor=$main/colorMapEditorDock/colorMapEditorPanel
tf=$editor/scrollArea/qt_scrollarea_viewport/scrollAreaWidgetContents/PropertiesFrame/Properties/ColorOpacityEditor
shell=$main/pythonShellDock/pythonShell/consoleWidget
cat > "$work/walk.xml" <<XML
<?xml version="1.0" ?>
<pqevents>
  <pqevent object="$main/MainControlsToolbar/actionOpenData" command="activate" arguments="" />
  <pqevent object="$main/FileOpenDialog" command="filesSelected" arguments="$file" />
  <pqcheck object="$main/pqSelectReaderDialog/listWidget" property="modelItemData" arguments="1.0,Mcvol Channel Files" />
  <pqevent object="$main/pqSelectReaderDialog/listWidget" command="setCurrent" arguments="1.0" />
  <pqevent object="$main/pqSelectReaderDialog/okButton" command="activate" arguments="" />
  <pqevent object="$props/Accept" command="activate" arguments="" />
  <pqevent object="$main" command="process_events" arguments="$idle_ms" />
  <pqevent object="$shell" command="executeCommand" arguments="import GUIOpenOMETIFF as walk" />
  <pqevent object="$shell" command="executeCommand" arguments="walk.opened()" />
  <pqevent object="$main" command="process_events" arguments="5000" />
  <pqevent object="$props/SearchBox/SearchLineEdit" command="set_string" arguments="Edit Channel" />
  <pqevent object="$panel/ActiveChannel/IntRangeWidget/LineEdit" command="set_string" arguments="1" />
  <pqevent object="$main" command="process_events" arguments="500" />
  <pqevent object="$editor/ShowScalarBar" command="activate" arguments="" />
  <pqevent object="$tf/DefaultPresetsComboBox" command="set_string" arguments="Black-Body Radiation" />
  <pqevent object="$editor/SearchBox/AdvancedButton" command="set_boolean" arguments="true" />
  <pqevent object="$tf/OpacityTable" command="editAccepted" arguments="2.1,0.5" />
  <pqevent object="$shell" command="executeCommand" arguments="walk.edit_applied()" />
  <pqevent object="$editor/SearchBox/AdvancedButton" command="set_boolean" arguments="false" />
  <pqevent object="$main" command="process_events" arguments="$idle_ms" />
  <pqevent object="$shell" command="executeCommand" arguments="walk.edited()" />
  <pqevent object="$main" command="process_events" arguments="5000" />
</pqevents>
XML

start=$SECONDS
gui_walk_paraview --test-script="$work/walk.xml" --exit
# Each screenshot once the walk's Python says the image has converged.
for step in open edit-channel; do
  ready="$work/${step%-channel}.ready"
  while [ ! -f "$ready" ] && kill -0 "$paraview" 2>/dev/null && [ $((SECONDS - start)) -lt 300 ]; do
    sleep 0.5
  done
  if [ ! -f "$ready" ]; then
    break
  fi
  sleep 2  # the window repaints after the Python shell returns
  gui_walk_grab "$out/paraview-ometiff-$step.png" 256
done
status=0
wait "$paraview" || status=$?
cat "$work/checks.txt" 2>/dev/null || true
echo "GUI walk: ParaView exited with $status after $((SECONDS - start)) s"
if [ "$status" -ne 0 ] || [ ! -f "$work/edit.ready" ] || grep -q '^FAIL' "$work/checks.txt"; then
  grep -v '^ *[0-9]* *0x' "$work/paraview.log" | tail -n 30 >&2
  echo "GUI walk: FAILED" >&2
  exit 1
fi
echo "GUI walk: passed"
