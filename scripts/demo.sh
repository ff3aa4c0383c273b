#!/usr/bin/env bash
# README command 1: installs what is missing, builds, and renders the default
# demo scene (density blending, converged) to demo.png (or the path given).
set -euo pipefail
top="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
out="${1:-$PWD/demo.png}"
bash "$top/scripts/build.sh"
xvfb-run -a -s "-screen 0 1280x1024x24" "$top/build/bin/mcvol-render" "$top/Data/scenes/default.json" -o "$out"
echo "mcvol: wrote $out"
