#!/usr/bin/env bash
# README command 2: installs what is missing, builds, and runs the whole test
# suite under a virtual X server. GPU-only tests report "skipped" (ctest
# return code 125) on machines without a CUDA device.
set -euo pipefail
top="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
bash "$top/scripts/build.sh"
cd "$top/build"
xvfb-run -a -s "-screen 0 1280x1024x24" ctest --output-on-failure -j"$(nproc)"
