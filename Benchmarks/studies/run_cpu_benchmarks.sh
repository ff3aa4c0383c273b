#!/usr/bin/env bash
# Re-runs the CPU frame-time benchmarks (mcvol-bench on three datasets, and
# VTK's own mappers beside ours) in one go, from a built tree (bash
# scripts/build.sh first). Writes Markdown and CSV to Benchmarks/results/cpu-core/
# and Benchmarks/results/vtk-peers/ and redraws the plots.
set -euo pipefail
top="$(cd "$(dirname "${BASH_SOURCE[0]}")/../.." && pwd)"
bench="$top/build/bin/mcvol-bench"
out="$top/Benchmarks/results/cpu-core"
peers="$top/Benchmarks/results/vtk-peers"
mkdir -p "$out" "$peers"
"$bench" --dataset cosmology --dims 256 256 256 --size 512 512 --warmup 3 --frames 10 \
  --csv "$out/cpu-cosmology256.csv" > "$out/cpu-cosmology256.md"
"$bench" --dataset microscopy --dims 320 320 60 --size 512 512 --warmup 2 --frames 8 \
  --sections macrocell,memory,trackers --csv "$out/cpu-microscopy320.csv" > "$out/cpu-microscopy320.md"
"$bench" --dataset weather --dims 250 250 50 --size 512 512 --warmup 2 --frames 8 \
  --sections macrocell,memory,trackers,channels --channel-counts 1,2,4,8,12 \
  --csv "$out/cpu-weather250.csv" > "$out/cpu-weather250.md"
PYTHONPATH="$top/build/lib/python3.11/site-packages" xvfb-run -a -s "-screen 0 1280x1024x24" \
  /usr/bin/python3 "$top/Benchmarks/studies/bench_vtk.py" --dims 256 256 256 --size 512 --warmup 2 --frames 5 \
  --images "$peers/images" > "$peers/cpu-mappers-cosmology256.md"
/usr/bin/python3 "$top/Benchmarks/plots/montage_peers.py" "$peers/images" "$peers/vtk-peers.png"
rm -rf "$peers/images"
/usr/bin/python3 "$top/Benchmarks/plots/plot_results.py" "$out"/cpu-cosmology256.csv "$out"/cpu-microscopy320.csv \
  "$out"/cpu-weather250.csv --out "$out"
echo "mcvol: results in $out and $peers"
