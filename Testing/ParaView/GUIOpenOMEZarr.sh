#!/usr/bin/env bash
# The ParaView GUI walk of the user guide's OME-Zarr screenshot
# (Documentation/images/paraview-omezarr.png): in the real GUI under a
# private Xvfb, File > Open of an OME-Zarr folder (the file dialog given the
# folder), Apply, then a capture of the whole window once the image has
# refined for a while.
#
#   bash Testing/ParaView/GUIOpenOMEZarr.sh OUT.png [FOLDER.ome.zarr]
#
# Without a folder it writes Data/cells_omezarr.py's volume to a temporary
# one. Needs a build (scripts/build.sh), xwd (x11-apps) and Pillow. The
# playback (ParaView's QtTesting XML) clicks File > Open, selects the folder
# and clicks Apply, as a user does (gui_walk.sh: the Xvfb, ParaView's
# settings without the welcome dialog, the capture).
set -euo pipefail
# shellcheck source-path=SCRIPTDIR source=gui_walk.sh
source "$(dirname "${BASH_SOURCE[0]}")/gui_walk.sh"
out="$(realpath -m "$1")"
gui_walk_start
folder="${2:-$work/cells.ome.zarr}"
if [ $# -lt 2 ]; then
  /usr/bin/python3 "$top/Data/cells_omezarr.py" "$folder" > /dev/null
fi
folder="$(realpath "$folder")"
cat > "$work/open.xml" <<XML
<?xml version="1.0" ?>
<pqevents>
  <pqevent object="pqClientMainWindow/MainControlsToolbar/actionOpenData" command="activate" arguments="" />
  <pqevent object="pqClientMainWindow/FileOpenDialog" command="filesSelected" arguments="$folder" />
  <pqevent object="pqClientMainWindow/propertiesDock/propertiesPanel/Accept" command="activate" arguments="" />
</pqevents>
XML
gui_walk_paraview --test-script="$work/open.xml"
sleep "${MCVOL_GUI_WAIT:-60}"
gui_walk_grab "$out"
