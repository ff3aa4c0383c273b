#!/usr/bin/env bash
# Takes the ParaView screenshots of the user guide's quick start
# (Documentation/user-guide/paraview-quick-start.md) in the GUI, under Xvfb:
# each shot starts `paraview --script=scripts/paraview_walk.py` with a fresh
# home folder (its settings: no welcome dialog), waits until the walk has set the scene
# up and the plugin has refined it, and grabs the screen.
#
#   bash scripts/paraview_screenshots.sh [OUTPUT_FOLDER]   (default Documentation/images)
#
# Needs a build (bash scripts/build.sh), xwd, netpbm and xdotool (installed
# here when missing: x11-apps, netpbm, xdotool).
set -euo pipefail
top="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
out="${1:-$top/Documentation/images}"
SUDO=""
if [ "$(id -u)" -ne 0 ]; then SUDO="sudo"; fi
if ! command -v xwd >/dev/null || ! command -v xwdtopnm >/dev/null || ! command -v xdotool >/dev/null; then
  echo "mcvol screenshots: installing x11-apps, netpbm and xdotool"
  $SUDO apt-get install -y -q --no-install-recommends x11-apps netpbm xdotool
fi
mkdir -p "$out"
work="$(mktemp -d)"
trap 'rm -rf "$work"' EXIT

shot() { # name seconds-to-refine
  local name="$1" wait="$2" display=":$((90 + RANDOM % 9))"
  local home="$work/home-$name"
  mkdir -p "$home/.config/ParaView"
  # No welcome dialog (a modal dialog also pauses the refinement).
  printf '[General]\nGeneralSettings.ShowWelcomeDialog=false\n' > "$home/.config/ParaView/ParaView5.11.0.ini"
  Xvfb "$display" -screen 0 1280x860x24 -noreset >/dev/null 2>&1 &
  local xvfb=$!
  sleep 2
  rm -f "$work/ready"
  DISPLAY="$display" HOME="$home" XDG_CONFIG_HOME="$home/.config" MCVOL_WALK_SHOT="$name" MCVOL_WALK_READY="$work/ready" \
    MCVOL_WALK_DATA="$top/Data/figure3.vti" \
    bash "$top/scripts/paraview.sh" paraview --script="$top/scripts/paraview_walk.py" >"$work/$name.log" 2>&1 &
  local pv=$!
  for _ in $(seq 120); do
    [ -f "$work/ready" ] && break
    sleep 1
  done
  if [ ! -f "$work/ready" ]; then
    echo "mcvol screenshots: the walk did not finish ($name); log:" >&2
    cat "$work/$name.log" >&2
    kill "$pv" "$xvfb" 2>/dev/null || true
    exit 1
  fi
  # The main window fills the screen (there is no window manager to do it).
  DISPLAY="$display" xdotool search --onlyvisible --name "^ParaView [0-9]" windowmove 0 0 windowsize 1280 860 \
    >/dev/null 2>&1 || true
  sleep "$wait"
  xwd -root -display "$display" | xwdtopnm 2>/dev/null | pnmcrop -black 2>/dev/null | pnmtopng \
    > "$out/paraview-$name.png"
  echo "wrote $out/paraview-$name.png"
  kill "$pv" 2>/dev/null || true
  wait "$pv" 2>/dev/null || true
  kill "$xvfb" 2>/dev/null || true
  wait "$xvfb" 2>/dev/null || true
}

shot quick-start 40
shot edit-channel 40
