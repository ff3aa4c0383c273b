#!/usr/bin/env bash
# Re-runs every CPU benchmark recorded in Benchmarks/RESULTS.md, in one go,
# from a built tree (bash scripts/build.sh first). Writes Markdown and CSV to
# Benchmarks/results/ and redraws the plots. Takes about 6 minutes on 2 cores.
set -euo pipefail
top="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
bench="$top/build/bin/mcvol-bench"
out="$top/Benchmarks/results"
mkdir -p "$out"
"$bench" --dataset cosmology --dims 256 256 256 --size 512 512 --warmup 3 --frames 10 \
  --csv "$out/cpu-cosmology256.csv" > "$out/cpu-cosmology256.md"
"$bench" --dataset microscopy --dims 320 320 60 --size 512 512 --warmup 2 --frames 8 \
  --sections macrocell,memory,trackers --csv "$out/cpu-microscopy320.csv" > "$out/cpu-microscopy320.md"
"$bench" --dataset weather --dims 250 250 50 --size 512 512 --warmup 2 --frames 8 \
  --sections macrocell,memory,trackers,channels --channel-counts 1,2,4,8,12 \
  --csv "$out/cpu-weather250.csv" > "$out/cpu-weather250.md"
PYTHONPATH="$top/build/lib/python3.11/site-packages" xvfb-run -a -s "-screen 0 1280x1024x24" \
  /usr/bin/python3 "$top/Benchmarks/bench_vtk.py" --dims 256 256 256 --size 512 --warmup 2 --frames 5 \
  --images "$out/vtk-peers" > "$out/cpu-vtk-peers-cosmology256.md"
/usr/bin/python3 "$top/Benchmarks/montage_peers.py" "$out/vtk-peers" "$out/vtk-peers.png"
rm -rf "$out/vtk-peers"
/usr/bin/python3 "$top/Benchmarks/plot_results.py" "$out"/cpu-cosmology256.csv "$out"/cpu-microscopy320.csv \
  "$out"/cpu-weather250.csv --out "$out"
echo "mcvol: results in $out"
