#!/usr/bin/env bash
# Runs a ParaView program with the mcvol plugin found (PV_PLUGIN_PATH points
# at the build's plugin folder, so it loads at start-up) and the mcvol Python
# package importable:
#   bash scripts/paraview.sh paraview
#   bash scripts/paraview.sh pvpython my_script.py
#   bash scripts/paraview.sh mpiexec -n 2 pvbatch my_script.py
#   bash scripts/paraview.sh pvserver        (then connect a client started the same way)
# Build first (bash scripts/build.sh).
set -euo pipefail
top="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
plugin_dir="$top/build/lib/paraview-5.11/plugins/mcvolPlugin"
if [ ! -f "$plugin_dir/mcvolPlugin.so" ]; then
  echo "mcvol: $plugin_dir/mcvolPlugin.so not found; run bash scripts/build.sh first" >&2
  exit 2
fi
export PV_PLUGIN_PATH="$plugin_dir${PV_PLUGIN_PATH:+:$PV_PLUGIN_PATH}"
export PYTHONPATH="$top/build/lib/python3.11/site-packages${PYTHONPATH:+:$PYTHONPATH}"
if [ "$(id -u)" -eq 0 ]; then
  # OpenMPI refuses to start as root without these.
  export OMPI_ALLOW_RUN_AS_ROOT=1 OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1
fi
if [ $# -eq 0 ]; then
  set -- paraview
fi
exec "$@"
