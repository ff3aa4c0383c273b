#!/usr/bin/env bash
# The ParaView GUI walk of the user guide's pvserver screenshot
# (Documentation/images/paraview-pvserver-progress.png): a pvserver and the
# GUI connected to it on a private Xvfb; the GUI's startup script loads the
# plugin on both, shows figure3.vti with the multi-channel representation,
# and the plugin refines the server's image while the GUI is idle. The
# capture, once it has converged, shows the server's progress in the view's
# corner and on the status line.
#
#   bash Testing/ParaView/GUIClientServerProgress.sh OUT.png
#
# Needs a build (scripts/build.sh), xwd (x11-apps) and Pillow.
set -euo pipefail
top="$(cd "$(dirname "${BASH_SOURCE[0]}")/../.." && pwd)"
out="$(realpath -m "$1")"
work="$(mktemp -d)"
export PYTHONPATH="$top/build/lib/python3.11/site-packages${PYTHONPATH:+:$PYTHONPATH}"
export PV_PLUGIN_PATH="$top/build/lib/paraview-5.11/plugins/mcvolPlugin"
mkdir -p "$work/home/.config/ParaView"
printf '[General]\nGeneralSettings.ShowWelcomeDialog=false\n' > "$work/home/.config/ParaView/ParaView5.11.0.ini"
cat > "$work/show.py" <<PYTHON
import sys
sys.path.insert(0, "$top/Testing/ParaView")
from paraview import simple
import mcvolParaViewTesting as T
T.load_plugin()
reader = simple.XMLImageDataReader(FileName=[T.DATA + "/figure3.vti"])
view = simple.GetActiveViewOrCreate("RenderView")
rep = simple.Show(reader, view)
rep.Representation = "Multi-Channel Volume (Monte Carlo)"
rep.ChannelSource = "Components of One Array"
rep.ChannelComponentsArray = "channels"
T.set_channel_functions(["channels:0", "channels:1", "channels:2"])
view.ResetCamera()
simple.Render(view)
PYTHON
display=":$(( 90 + RANDOM % 100 ))"
port=$(( 20000 + RANDOM % 20000 ))
Xvfb "$display" -screen 0 1280x900x24 -noreset > "$work/xvfb.log" 2>&1 &
xvfb=$!
server=$xvfb
paraview=$xvfb
trap 'kill $paraview $server $xvfb 2>/dev/null || true; rm -rf "$work"' EXIT
sleep 2
DISPLAY="$display" pvserver --server-port="$port" > "$work/pvserver.log" 2>&1 &
server=$!
sleep 4
DISPLAY="$display" HOME="$work/home" paraview --server-url="cs://localhost:$port" --script="$work/show.py" \
  > "$work/paraview.log" 2>&1 &
paraview=$!
sleep "${MCVOL_GUI_WAIT:-45}"
xwd -root -display "$display" -out "$work/screen.xwd"
/usr/bin/python3 "$top/Testing/ParaView/xwd_to_png.py" "$work/screen.xwd" "$out"
echo "wrote $out"
