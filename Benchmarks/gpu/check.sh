#!/usr/bin/env bash
# GPU machine, step 1: build the VTK-free core, the CUDA backend, their tests
# and the benchmark from the working tree (GoogleTest from third_party/), run
# every test, then compute-sanitizer memcheck over the GPU tests.
# Usage: bash Benchmarks/gpu/check.sh [build-dir]   (logs under $OUT if set)
set -uo pipefail
top="$(cd "$(dirname "${BASH_SOURCE[0]}")/../.." && pwd)"
b="${1:-/tmp/mcvol-gpu}"
out="${RESULTS:-${OUT:-/tmp/mcvol-gpu-out}}"
mkdir -p "$out"
nvcc_path="$(command -v nvcc || echo /usr/local/cuda/bin/nvcc)"
nvidia-smi --query-gpu=name,driver_version,memory.total --format=csv > "$out/gpu.txt" 2>&1
cat "$out/gpu.txt"
cmake -S "$top" -B "$b" -DMCVOL_CORE_ONLY=ON -DCMAKE_BUILD_TYPE=Release \
  -DCMAKE_CUDA_COMPILER="$nvcc_path" > "$out/configure.log" 2>&1 || { tail -30 "$out/configure.log"; exit 1; }
cmake --build "$b" -j"$(nproc)" > "$out/build.log" 2>&1 || { grep -E "error" -A5 "$out/build.log" | head -60; exit 1; }
echo "build ok"
(cd "$b" && ctest -j8 --output-on-failure > "$out/ctest.log" 2>&1); rc=$?
(cd "$b" && ctest -L cuda -V > "$out/ctest-cuda-verbose.log" 2>&1)
tail -15 "$out/ctest.log"
grep -E "same seed|Failure|Expected|Which is|differ" "$out/ctest.log" | head -40
if [ "${SANITIZE:-1}" = 1 ]; then
  sanitizer="$(command -v compute-sanitizer || echo /usr/local/cuda/bin/compute-sanitizer)"
  for t in mcvol_cuda_test mcvol_hardcases_test; do
    MCVOL_TEST_BACKEND=cuda timeout 400 "$sanitizer" --tool memcheck --leak-check full --error-exitcode 7 \
      "$b/bin/$t" ${SANITIZE_FILTER:+--gtest_filter=$SANITIZE_FILTER} > "$out/memcheck-$t.log" 2>&1
    echo "memcheck $t: rc=$? $(grep -E 'ERROR SUMMARY|LEAK SUMMARY' "$out/memcheck-$t.log" | tr '\n' ' ')"
  done
fi
exit $rc
