#!/usr/bin/env bash
# GPU machine: compute-sanitizer's memcheck, racecheck and initcheck over
# every CUDA test program of a core build made by Benchmarks/gpu/check.sh:
# the CUDA-only programs, and the core test programs whose GPU runs ctest
# makes with MCVOL_TEST_BACKEND=cuda (the same gtest filters). Each run has a
# time limit (PER_RUN seconds, default 18: 8 programs x 3 tools take at most
# about 8 minutes); a run cut by it keeps the reports printed so far, and the summary
# says it was cut. Logs and summary.txt under $OUT (or RESULTS, or
# /tmp/mcvol-gpu-out/sanitize).
#
#   bash Benchmarks/gpu/check.sh /tmp/mcvol-gpu      # builds and tests first
#   bash Benchmarks/gpu/sanitize.sh /tmp/mcvol-gpu
set -uo pipefail
b="${1:-/tmp/mcvol-gpu}"
out="${RESULTS:-${OUT:-/tmp/mcvol-gpu-out}}/sanitize"
per_run="${PER_RUN:-18}"
mkdir -p "$out"
sanitizer="$(command -v compute-sanitizer || echo /usr/local/cuda/bin/compute-sanitizer)"
if [ ! -x "$sanitizer" ]; then
  echo "compute-sanitizer not found" >&2
  exit 1
fi
# program|gtest filter ("" = all)|environment
runs=(
  "mcvol_cuda_test||"
  "mcvol_cuda_pyramid_test||"
  "mcvol_cuda_march_test||"
  "mcvol_hardcases_test||MCVOL_TEST_BACKEND=cuda"
  "mcvol_lighting_test|Lighting.*|MCVOL_TEST_BACKEND=cuda"
  "mcvol_importance_test|Visibility.*|MCVOL_TEST_BACKEND=cuda"
  "mcvol_estimate_test|ErrorEstimate.*:EstimatorChoice.*|MCVOL_TEST_BACKEND=cuda"
  "mcvol_render_test||MCVOL_TEST_BACKEND=cuda"
)
summary="$out/summary.txt"
: > "$summary"
status=0
for tool in memcheck racecheck initcheck; do
  for r in "${runs[@]}"; do
    IFS='|' read -r prog filter env <<< "$r"
    if [ ! -x "$b/bin/$prog" ]; then
      echo "$tool $prog: not built" | tee -a "$summary"
      continue
    fi
    log="$out/$tool-$prog.log"
    extra=()
    [ "$tool" = memcheck ] && extra=(--leak-check full)
    start=$(date +%s)
    # shellcheck disable=SC2086 # env is one VAR=value or empty
    env $env timeout -s INT -k 5 "$per_run" "$sanitizer" --tool "$tool" "${extra[@]}" --error-exitcode 7 \
      --print-limit 50 "$b/bin/$prog" ${filter:+--gtest_filter=$filter} > "$log" 2>&1
    rc=$?
    secs=$(( $(date +%s) - start ))
    errors="$(grep -E 'ERROR SUMMARY|LEAK SUMMARY|RACECHECK SUMMARY' "$log" | tr '\n' ' ')"
    case $rc in
      0) verdict="clean" ;;
      7) verdict="ERRORS"; status=1 ;;
      124|130|137) verdict="cut at ${per_run} s (reports so far: $(grep -c '^=========  *\(Invalid\|Uninitialized\|Race\|Error\)' "$log"))" ;;
      *) verdict="exit $rc" ;;
    esac
    echo "$tool $prog${filter:+ ($filter)}: $verdict, ${secs} s. $errors" | tee -a "$summary"
  done
done
exit $status
