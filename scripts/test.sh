#!/usr/bin/env bash
# README command 2: installs what is missing, builds everything (the CUDA
# backend included wherever nvcc is, so that its kernels are compiled and
# checked) and runs the whole test suite under a virtual X server. GPU-only
# tests report "skipped" (ctest return code 125) on machines without a CUDA
# device.
set -euo pipefail
top="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
export MCVOL_CMAKE_ARGS="-DMCVOL_ENABLE_CUDA=ON ${MCVOL_CMAKE_ARGS:-}"
bash "$top/scripts/build.sh"
cd "$top/build"
# -noreset: Xvfb otherwise resets whenever its last client disconnects, and
# a program connecting during the reset (pvserver or an MPI rank started
# right after another test's program exits) fails with "bad X server
# connection".
xvfb-run -a -s "-noreset -screen 0 1280x1024x24" ctest --output-on-failure -j"$(nproc)"
