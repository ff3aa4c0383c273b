#!/usr/bin/env bash
# GPU machine with several GPUs, after `vtk.sh setup` (the bookworm root with
# ParaView and this build): ParaView's MPI engine, one GPU per rank, measured
# with mpi_gpus.py under `mpiexec -n N pvbatch --symmetric`.
#
#   scaling.sh strong [RANKS...]  NYX-like (cosmology, 4 x 512^3 float32) at
#                                 1024^2, unlit and lit, on each rank count
#                                 (default 1 2 4): frame times, samples per
#                                 second, time to 35 dB
#   scaling.sh weak [RANKS...]    4 x 2048^3 float32 (128 GiB, generated piece
#                                 by piece on the ranks) on each rank count
#                                 (default 4 2), unlit; device memory per rank
#   scaling.sh tests              the parallel ParaView tests on CUDA: every
#                                 rank on its own GPU
#
# RESULTS (default $OUT, else ./scaling-results) receives one log per run
# and results.jsonl, the RESULT lines of every run.
set -uo pipefail
top="$(cd "$(dirname "${BASH_SOURCE[0]}")/../.." && pwd)"
vtk="$top/Benchmarks/gpu/vtk.sh"
res="${RESULTS:-${OUT:-$top/scaling-results}}"
mkdir -p "$res"
cores="$(nproc)"
env_root="PYTHONPATH=/work/main/build/lib/python3.11/site-packages PV_PLUGIN_PATH=/work/main/build/lib/paraview-5.11/plugins/mcvolPlugin"

run_ranks() { # name ranks args...
  local name="$1" n="$2"
  shift 2
  # The ranks share the cores for generating their pieces.
  local threads=$((cores / n))
  echo "== $name: $n rank(s), $threads threads each"
  MCVOL_BACKEND=cuda bash "$vtk" run "$env_root OMP_NUM_THREADS=$threads mpiexec --bind-to none -n $n \
    -x PYTHONPATH -x PV_PLUGIN_PATH -x OMP_NUM_THREADS -x MCVOL_BACKEND \
    pvbatch --symmetric Benchmarks/gpu/mpi_gpus.py $*" 2>&1 | tee "$res/$name.log" |
    grep -E "^(RESULT|rank|progress|Traceback|.*Error)" | cut -c1-400
  grep -h "^RESULT " "$res/$name.log" | sed 's/^RESULT //' >> "$res/results.jsonl"
}

case "${1:-}" in
  strong)
    shift
    for n in "${@:-1 2 4}"; do
      for k in $n; do
        run_ranks "strong-nyx-${k}gpu" "$k" --dataset cosmology --dims 512 512 512 --channels 4 --size 1024 1024 \
          --lighting none shadows --ref-spp 1024 --label NYX-like --save /tmp/mcvol-scaling-images
      done
    done
    # The reference images, from inside the root.
    cp -r "${MCVOL_ROOT:-/tmp/mcvol-root}/tmp/mcvol-scaling-images" "$res/images" 2>/dev/null || true
    ;;
  weak)
    shift
    for n in "${@:-4 2}"; do
      for k in $n; do
        run_ranks "weak-2048-${k}gpu" "$k" --dataset cosmology --dims 2048 2048 2048 --channels 4 --size 1024 1024 \
          --lighting none --ref-spp 256 --frames 10 --spp 1 2 4 8 16 32 64 --label cosmology-4x2048^3
      done
    done
    ;;
  tests)
    bash "$vtk" ctest -R "ParaView.TestParaViewParallel|ParaView.TestParallelLitRayMarch" --output-on-failure 2>&1 |
      tee "$res/parallel-tests.log" | tail -40
    ;;
  *)
    sed -n 2,18p "$0"; exit 2
    ;;
esac
