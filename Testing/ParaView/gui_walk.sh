# shellcheck shell=bash
# Shared parts of the ParaView GUI walks (Testing/ParaView/GUI*.sh), sourced
# by them: a scratch folder, a private Xvfb, ParaView settings without the
# welcome dialog (it would block playback and pause the refinement), the
# build's plugin and mcvol package on the paths, programs started in the
# background and ended on exit, and a capture of ParaView's main window as PNG.
#
#   source "$(dirname "${BASH_SOURCE[0]}")/gui_walk.sh"
#   gui_walk_start                       # sets $top, $work, $display; starts Xvfb
#   gui_walk_paraview ARG...             # paraview ARG... in the background; $! in $paraview
#   gui_walk_background LOG CMD...       # another program (pvserver) on the display
#   gui_walk_grab OUT.png [COLOURS]      # the main window, as a palette of COLOURS if given
#
# Needs a build (scripts/build.sh), Xvfb, xwd (x11-apps) and Pillow.

top="$(cd "$(dirname "${BASH_SOURCE[0]}")/../.." && pwd)"
export PYTHONPATH="$top/build/lib/python3.11/site-packages${PYTHONPATH:+:$PYTHONPATH}"
export PV_PLUGIN_PATH="$top/build/lib/paraview-5.11/plugins/mcvolPlugin"
gui_walk_pids=()

gui_walk_stop() {
  local pid
  for pid in "${gui_walk_pids[@]}"; do
    kill "$pid" 2>/dev/null || true
  done
  for pid in "${gui_walk_pids[@]}"; do
    wait "$pid" 2>/dev/null || true
  done
  rm -rf "$work"
}

gui_walk_start() {
  if [ ! -f "$PV_PLUGIN_PATH/mcvolPlugin.so" ]; then
    echo "$PV_PLUGIN_PATH/mcvolPlugin.so not found: build first (bash scripts/build.sh)" >&2
    exit 2
  fi
  work="$(mktemp -d)"
  trap gui_walk_stop EXIT
  mkdir -p "$work/home/.config/ParaView"
  printf '[General]\nGeneralSettings.ShowWelcomeDialog=false\n' > "$work/home/.config/ParaView/ParaView5.11.0.ini"
  # Xvfb picks a free display number and writes it to the descriptor.
  local fd
  exec {fd}> "$work/display"
  Xvfb -displayfd "$fd" -screen 0 1280x900x24 -noreset > "$work/xvfb.log" 2>&1 &
  gui_walk_pids+=($!)
  exec {fd}>&-
  for _ in $(seq 100); do
    [ -s "$work/display" ] && break
    sleep 0.1
  done
  if [ ! -s "$work/display" ]; then
    echo "Xvfb did not start:" >&2
    cat "$work/xvfb.log" >&2
    exit 2
  fi
  display=":$(head -n 1 "$work/display")"
}

gui_walk_background() {
  local log="$1"
  shift
  DISPLAY="$display" "$@" > "$log" 2>&1 &
  gui_walk_pids=($! "${gui_walk_pids[@]}")
}

gui_walk_paraview() {
  DISPLAY="$display" HOME="$work/home" paraview "$@" > "$work/paraview.log" 2>&1 &
  paraview=$!
  gui_walk_pids=("$paraview" "${gui_walk_pids[@]}")
}

gui_walk_grab() {
  xwd -root -display "$display" -out "$work/screen.xwd"
  /usr/bin/python3 "$top/Testing/ParaView/xwd_to_png.py" "$work/screen.xwd" "$1" ${2:+--colours "$2"}
  echo "wrote $1"
}
