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
# Needs a build (scripts/build.sh), xwd (x11-apps) and Pillow (gui_walk.sh:
# the Xvfb, ParaView's settings without the welcome dialog, the capture).
set -euo pipefail
# shellcheck source-path=SCRIPTDIR source=gui_walk.sh
source "$(dirname "${BASH_SOURCE[0]}")/gui_walk.sh"
out="$(realpath -m "$1")"
gui_walk_start
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
port=$(( 20000 + RANDOM % 20000 ))
gui_walk_background "$work/pvserver.log" pvserver --server-port="$port"
sleep 4
gui_walk_paraview --server-url="cs://localhost:$port" --script="$work/show.py"
sleep "${MCVOL_GUI_WAIT:-45}"
gui_walk_grab "$out"
