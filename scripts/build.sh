#!/usr/bin/env bash
# Installs what is missing, configures and builds mcvol in build/ (Release,
# against ParaView 5.11's VTK).
#
#   bash scripts/build.sh                 everything: module, plugin, tools, tests
#   bash scripts/build.sh TARGET...       only these targets (and what they need)
#
# The CUDA backend is built for the GPUs that nvidia-smi lists, or, with none,
# for one architecture so that the kernels are still compiled and checked.
# MCVOL_CMAKE_ARGS adds configure options (e.g. -DMCVOL_ENABLE_CUDA=OFF).
set -euo pipefail
top="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
bash "$top/scripts/deps.sh"
# shellcheck disable=SC2086 # MCVOL_CMAKE_ARGS is a list of options
cmake -S "$top" -B "$top/build" -DCMAKE_BUILD_TYPE=Release ${MCVOL_CMAKE_ARGS:-}
targets=()
for t in "$@"; do targets+=(--target "$t"); done
cmake --build "$top/build" -j"$(nproc)" "${targets[@]}"
