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
# and clicks Apply, as a user does; ParaView's welcome dialog is turned off
# in a temporary HOME so that it does not block the playback.
set -euo pipefail
top="$(cd "$(dirname "${BASH_SOURCE[0]}")/../.." && pwd)"
out="$(realpath -m "$1")"
work="$(mktemp -d)"
export PYTHONPATH="$top/build/lib/python3.11/site-packages${PYTHONPATH:+:$PYTHONPATH}"
folder="${2:-$work/cells.ome.zarr}"
if [ $# -lt 2 ]; then
  /usr/bin/python3 "$top/Data/cells_omezarr.py" "$folder" > /dev/null
fi
folder="$(realpath "$folder")"
mkdir -p "$work/home/.config/ParaView"
printf '[General]\nGeneralSettings.ShowWelcomeDialog=false\n' > "$work/home/.config/ParaView/ParaView5.11.0.ini"
cat > "$work/open.xml" <<XML
<?xml version="1.0" ?>
<pqevents>
  <pqevent object="pqClientMainWindow/MainControlsToolbar/actionOpenData" command="activate" arguments="" />
  <pqevent object="pqClientMainWindow/FileOpenDialog" command="filesSelected" arguments="$folder" />
  <pqevent object="pqClientMainWindow/propertiesDock/propertiesPanel/Accept" command="activate" arguments="" />
</pqevents>
XML
display=":$(( 90 + RANDOM % 100 ))"
Xvfb "$display" -screen 0 1280x900x24 -noreset > "$work/xvfb.log" 2>&1 &
xvfb=$!
trap 'kill $paraview $xvfb 2>/dev/null || true; rm -rf "$work"' EXIT
paraview=$xvfb
sleep 2
DISPLAY="$display" HOME="$work/home" PV_PLUGIN_PATH="$top/build/lib/paraview-5.11/plugins/mcvolPlugin" \
  paraview --test-script="$work/open.xml" > "$work/paraview.log" 2>&1 &
paraview=$!
sleep "${MCVOL_GUI_WAIT:-60}"
xwd -root -display "$display" -out "$work/screen.xwd"
/usr/bin/python3 "$top/Testing/ParaView/xwd_to_png.py" "$work/screen.xwd" "$out"
echo "wrote $out"
