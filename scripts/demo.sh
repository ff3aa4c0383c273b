#!/usr/bin/env bash
# README command 1: installs what is missing, builds what the command-line
# renderer needs, and renders the default demo scene (the microscopy phantom,
# density blending, converged) to demo.png (or the path given).
#
# On a machine without an NVIDIA GPU the first build leaves the CUDA backend
# out, since nothing here could run it; `bash scripts/test.sh` adds it (the
# suite checks that the kernels compile). With a GPU it is built for that GPU.
set -euo pipefail
top="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
out="${1:-$PWD/demo.png}"
if [ ! -f "$top/build/CMakeCache.txt" ] && ! nvidia-smi -L >/dev/null 2>&1; then
  export MCVOL_CMAKE_ARGS="-DMCVOL_ENABLE_CUDA=OFF ${MCVOL_CMAKE_ARGS:-}"
fi
bash "$top/scripts/build.sh" mcvolRenderingMonteCarloPython mcvol_python_package
xvfb-run -a -s "-screen 0 1280x1024x24" "$top/build/bin/mcvol-render" "$top/Data/scenes/default.json" -o "$out"
echo "mcvol: wrote $out"
