#!/usr/bin/env bash
# GPU machine: frame rates of this tree against another source tree (a
# change that must not cost time, such as a restructuring), measured in turns
# so drift of the machine hits both alike. Builds the other tree's
# mcvol-bench (core only) into /tmp/mcvol-other; this tree's must already be
# built by check.sh into the build folder given.
# Usage: bash Benchmarks/gpu/compare.sh OTHER_SRC [build-dir] [rounds]
# Prints one Markdown row per dataset, tracker and round; tables under $OUT.
set -uo pipefail
other="$1"
b="${2:-/tmp/mcvol-gpu}"
rounds="${3:-3}"
out="${RESULTS:-${OUT:-/tmp/mcvol-gpu-out}}"
mkdir -p "$out"
ob=/tmp/mcvol-other
arch="$(grep -E '^CMAKE_CUDA_ARCHITECTURES:' "$b/CMakeCache.txt" | cut -d= -f2)"
cmake -S "$other" -B "$ob" -DMCVOL_CORE_ONLY=ON -DCMAKE_BUILD_TYPE=Release \
  -DCMAKE_CUDA_COMPILER="$(command -v nvcc || echo /usr/local/cuda/bin/nvcc)" \
  ${arch:+-DCMAKE_CUDA_ARCHITECTURES="$arch"} > "$out/other-configure.log" 2>&1 || { tail -20 "$out/other-configure.log"; exit 1; }
cmake --build "$ob" -j"$(nproc)" --target mcvol-bench > "$out/other-build.log" 2>&1 || { tail -20 "$out/other-build.log"; exit 1; }
sets=(
  "nyx cosmology 512 512 512 4"
  "zebrafish microscopy 640 640 121 3"
)
echo "| dataset | round | tree | 1-DDA FPS | N-DDA FPS |"
echo "|---|---|---|---|---|"
for s in "${sets[@]}"; do
  read -r key ds x y z ch <<< "$s"
  for r in $(seq 1 "$rounds"); do
    for tree in other this; do
      bin="$b/bin/mcvol-bench"
      [ "$tree" = other ] && bin="$ob/bin/mcvol-bench"
      "$bin" --backend cuda --dataset "$ds" --dims "$x" "$y" "$z" --channels "$ch" --size 1024 1024 \
        --warmup 25 --frames 500 --sections paper > "$out/compare-$key-$tree-$r.md" 2>&1
      fps="$(grep -A4 '^| tracker | FPS' "$out/compare-$key-$tree-$r.md" | sed -n 3,4p | awk -F'|' '{print $3}' | tr -d ' ' | paste -sd'|')"
      echo "| $key | $r | $tree | ${fps/|/ | } |"
    done
  done
done
