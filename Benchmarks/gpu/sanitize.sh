#!/usr/bin/env bash
# GPU machine: compute-sanitizer's memcheck, racecheck and initcheck over
# every CUDA test program of a core build made by Benchmarks/gpu/check.sh:
# the CUDA-only programs, and the core test programs whose GPU runs ctest
# makes with MCVOL_TEST_BACKEND=cuda (the same gtest filters). Under the
# sanitizers the tests run tens of times slower, so each program is split
# into gtest shards (GTEST_TOTAL_SHARDS), and all the runs of one tool go at
# once; each run has a time limit (PER_RUN seconds, default 540), and a run
# cut by it keeps the reports printed so far (the summary says it was cut
# and how many of its tests passed). One tool's runs fit one remote call of
# 10 minutes: pass the tools one call at a time (TOOLS, default all three).
# Logs and summary-TOOL.txt under $OUT (or RESULTS, or
# /tmp/mcvol-gpu-out/sanitize).
#
#   bash Benchmarks/gpu/check.sh /tmp/mcvol-gpu      # builds and tests first
#   TOOLS=memcheck bash Benchmarks/gpu/sanitize.sh /tmp/mcvol-gpu
#   TOOLS=racecheck bash Benchmarks/gpu/sanitize.sh /tmp/mcvol-gpu
#   TOOLS=initcheck bash Benchmarks/gpu/sanitize.sh /tmp/mcvol-gpu
set -uo pipefail
b="${1:-/tmp/mcvol-gpu}"
out="${RESULTS:-${OUT:-/tmp/mcvol-gpu-out}}/sanitize"
per_run="${PER_RUN:-540}"
mkdir -p "$out"
sanitizer="$(command -v compute-sanitizer || echo /usr/local/cuda/bin/compute-sanitizer)"
if [ ! -x "$sanitizer" ]; then
  echo "compute-sanitizer not found" >&2
  exit 1
fi
# program|gtest filter ("" = all)|environment|shards
runs=(
  "mcvol_cuda_test|||4"
  "mcvol_cuda_pyramid_test|||1"
  "mcvol_cuda_march_test|||3"
  "mcvol_hardcases_test||MCVOL_TEST_BACKEND=cuda|1"
  "mcvol_lighting_test|Lighting.*|MCVOL_TEST_BACKEND=cuda|3"
  "mcvol_importance_test|Visibility.*|MCVOL_TEST_BACKEND=cuda|3"
  "mcvol_estimate_test|ErrorEstimate.*:EstimatorChoice.*|MCVOL_TEST_BACKEND=cuda|2"
  "mcvol_render_test||MCVOL_TEST_BACKEND=cuda|1"
)
status=0
for tool in ${TOOLS:-memcheck racecheck initcheck}; do
  summary="$out/summary-$tool.txt"
  : > "$summary"
  pids=()
  for r in "${runs[@]}"; do
    IFS='|' read -r prog filter env shards <<< "$r"
    if [ ! -x "$b/bin/$prog" ]; then
      echo "$tool $prog: not built" | tee -a "$summary"
      continue
    fi
    for ((shard = 0; shard < shards; shard++)); do
      (
        log="$out/$tool-$prog-$shard.log"
        extra=()
        [ "$tool" = memcheck ] && extra=(--leak-check full)
        start=$(date +%s)
        # shellcheck disable=SC2086 # env is one VAR=value or empty
        env $env GTEST_TOTAL_SHARDS="$shards" GTEST_SHARD_INDEX="$shard" timeout -s INT -k 5 "$per_run" \
          "$sanitizer" --tool "$tool" "${extra[@]}" --error-exitcode 7 --print-limit 50 \
          "$b/bin/$prog" ${filter:+--gtest_filter=$filter} > "$log" 2>&1
        rc=$?
        secs=$(( $(date +%s) - start ))
        tests="$(grep -c '^\[       OK \]' "$log") of $(grep -c '^\[ RUN' "$log") tests passed"
        errors="$(grep -E 'ERROR SUMMARY|LEAK SUMMARY|RACECHECK SUMMARY' "$log" | tr '\n' ' ')"
        case $rc in
          0) verdict="clean" ;;
          7) verdict="ERRORS" ;;
          124|130|137) verdict="cut at ${per_run} s (reports so far: $(grep -cE '^=========  *(Invalid|Uninitialized|Race|Error|Leaked)' "$log"))" ;;
          *) verdict="exit $rc" ;;
        esac
        echo "$tool $prog${filter:+ ($filter)} shard $((shard + 1))/$shards: $verdict, $tests, ${secs} s. $errors" |
          tee -a "$summary"
        [ $rc = 7 ] && exit 1
        exit 0
      ) &
      pids+=($!)
    done
  done
  for p in "${pids[@]}"; do
    wait "$p" || status=1
  done
done
exit $status
