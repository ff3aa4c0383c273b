#!/usr/bin/env bash
# AddressSanitizer and UndefinedBehaviorSanitizer over the VTK-free core:
#
#   bash scripts/sanitize.sh core   the core, its CPU backend and every core
#                                   test built at -O1 with -fsanitize=address,
#                                   undefined (build-sanitize/), and run (ctest)
#   bash scripts/sanitize.sh fuzz   the core's entry-point harness
#                                   (Testing/Core/fuzz/) under libFuzzer with
#                                   clang, for FUZZ_SECONDS (default 120)
#                                   from the corpus in Testing/Data/fuzz-corpus
#   bash scripts/sanitize.sh        both
#
# The CPU renderer's sanitized build is long (its translation unit holds every
# estimator): expect tens of minutes on 2 cores. The test suite's own part,
# mcvol.sanitized.EntryFuzz, compiles only the Scene's sources and runs in
# seconds. Any sanitizer report fails the run (-fno-sanitize-recover). The VTK
# module is not built sanitized: ParaView's libraries are not, and mixing them
# reports their leaks. GPU code: Benchmarks/gpu/sanitize.sh.
set -euo pipefail
top="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
what="${1:-all}"
flags="-fsanitize=address,undefined,float-cast-overflow -fno-sanitize-recover=all -fno-omit-frame-pointer"
export ASAN_OPTIONS="detect_leaks=1:abort_on_error=1:${ASAN_OPTIONS:-}"
export UBSAN_OPTIONS="print_stacktrace=1:${UBSAN_OPTIONS:-}"
bash "$top/scripts/deps.sh"

if [ "$what" = core ] || [ "$what" = all ]; then
  b="$top/build-sanitize"
  cmake -S "$top" -B "$b" -DMCVOL_CORE_ONLY=ON -DMCVOL_ENABLE_CUDA=OFF -DCMAKE_BUILD_TYPE=Debug \
    -DCMAKE_CXX_FLAGS_DEBUG="-O1 -g" -DCMAKE_CXX_FLAGS="$flags" \
    -DCMAKE_EXE_LINKER_FLAGS="$flags" -DCMAKE_SHARED_LINKER_FLAGS="$flags" ${MCVOL_CMAKE_ARGS:-}
  cmake --build "$b" -j"$(nproc)"
  # The CUDA tests skip without a device; OpenMP threads as on CI.
  (cd "$b" && OMP_NUM_THREADS=2 ctest --output-on-failure -j"$(nproc)" -LE cuda)
fi

if [ "$what" = fuzz ] || [ "$what" = all ]; then
  cxx="$(command -v clang++ || true)"
  if [ -z "$cxx" ]; then
    echo "scripts/sanitize.sh fuzz needs clang++ (Debian: clang) for libFuzzer" >&2
    exit 1
  fi
  f="$top/build-sanitize/fuzz"
  mkdir -p "$f/corpus"
  core="$top/Rendering/Core"
  sources=()
  for s in Scene SceneVolume SceneTransferFunction SceneMacrocells SceneMajorants SceneLighting SceneImportance \
           ObjectId Types; do
    sources+=("$core/$s.cxx")
  done
  "$cxx" -std=c++17 -O1 -g -fopenmp $flags -fsanitize=fuzzer -I"$core" -I"$top/Testing/Core/fuzz" \
    "${sources[@]}" "$top/Testing/Core/fuzz/EntryFuzz.cxx" "$top/Testing/Core/fuzz/libfuzzer_main.cxx" \
    -o "$f/entry_fuzzer"
  # New inputs go to a scratch corpus; the repository's stays as it is.
  "$f/entry_fuzzer" -max_total_time="${FUZZ_SECONDS:-120}" -timeout=10 -rss_limit_mb=2048 -print_final_stats=1 \
    "$f/corpus" "$top/Testing/Data/fuzz-corpus/entry"
fi
