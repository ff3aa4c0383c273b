#!/usr/bin/env bash
# One device call: check.sh (build, tests, memcheck unless SANITIZE=0), then
# the bench.sh stages given as arguments; every log and table is packed into
# $OUT/results.tgz (the device tool brings back a limited number of files).
top="$(cd "$(dirname "${BASH_SOURCE[0]}")/../.." && pwd)"
export RESULTS=/tmp/mcvol-results
rm -rf "$RESULTS" && mkdir -p "$RESULTS"
if [ "${CHECK:-1}" = 1 ]; then
  bash "$top/Benchmarks/gpu/check.sh" /tmp/b || [ -x /tmp/b/bin/mcvol-bench ] || { echo "build failed"; exit 1; }
else
  [ -f /tmp/b/CMakeCache.txt ] || cmake -S "$top" -B /tmp/b -DMCVOL_CORE_ONLY=ON -DCMAKE_BUILD_TYPE=Release \
    -DCMAKE_CUDA_COMPILER="$(command -v nvcc || echo /usr/local/cuda/bin/nvcc)" > "$RESULTS/configure.log" 2>&1
  cmake --build /tmp/b -j"$(nproc)" > "$RESULTS/build.log" 2>&1 || { echo "build failed"; tail -20 "$RESULTS/build.log"; exit 1; }
fi
[ $# -gt 0 ] && bash "$top/Benchmarks/gpu/bench.sh" /tmp/b "$@"
tar czf "${OUT:-/tmp}/results.tgz" -C "$RESULTS" .
