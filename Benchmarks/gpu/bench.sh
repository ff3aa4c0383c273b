#!/usr/bin/env bash
# GPU machine, step 2: the paper's benchmarks with mcvol-bench (built by
# check.sh into the same build folder). Stages, run in the order given:
#   paper     frame rate (1024^2, 1 spp, 25 warm-up + 500 timed, both
#             trackers), GPU memory, texture vs global sampling, time to
#             converge to 35 dB: the four paper-sized datasets
#   dense     the paper stage's frame rates with opacities 8x denser
#   macrocell frame rate against macrocell size (paper Fig. 8), CUDA and CPU
#   channels  frame rate against channel count 1..16 (paper Fig. 9), CUDA and CPU
#   accuracy  the accuracy study's series with the CUDA backend (Monte Carlo,
#             new and old defaults, and the ray marches): accuracy.tgz
#   lit       lit convergence: time to 35 dB at 1024^2 with one light,
#             shadows and ambient 0.2 (converge section, --lighting ambient:
#             the expected-value and the collision estimator) on the four
#             paper-sized datasets; then the lit accuracy series
#             (mcvol-accuracy --lighting shadows|ambient|multiple: Monte Carlo
#             against the lit CUDA ray march at several steps, scored against
#             a fine-step lit march, or a Monte Carlo reference for multiple
#             scattering) on the four demo datasets at 256^2: accuracy-lit.tgz
#   rebuild   GPU majorant rebuild after one transfer-function change
#   block     render-kernel block shapes (NYX-like)
#   profile   Nsight Compute on the render kernel of the slowest paper case
#   sequences independent samples against Owen-scrambled Sobol' points, each
#             with the collision and the expected-value estimator: error
#             against spp, slopes, spp and ms to RMSE 0.01 and 35 dB (1024^2,
#             the four paper-sized datasets)
#   pyramid   levels of detail: 1-spp frame time of level 0 (4 x
#             512^3 float, scalar channels) against the pre-classified level 0
#             and box4 levels 1 and 2 (density blend), classify/build time and
#             memory; CUDA at 1024^2 (target: level 1 >= 4x faster than level
#             0), the CPU at 1024^2 and 512^2
#   estimator the automatic estimator choice: time to 35 dB
#             at 1024^2 of expected value, the unbiased march at 0.0625-2
#             strata per voxel and the automatic choice (pilots included),
#             the four paper-sized datasets; then the cost model fitted to
#             their frame times (fit_cost_model.py) and the automatic rows
#             again with the fitted weights, trying every rate so that the
#             report predicts each row measured (estimator-fit-*.md)
#   automatic the automatic choice alone at 1024^2: its time to 35 dB with the
#             default rate search (automatic-*.md), then every candidate's
#             prediction (--choice-all, automatic-all-*.md)
#   pilots    the automatic choice's pilots: time to 35 dB
#             with the pilots included (pilots-*.md, converge rows) and the
#             pilots' cost rendered all at once and one after the other
#             (section pilots), jittered and at pixel centres
#   centres   the automatic choice at pixel centres (every rate offered with
#             and without control variates, and a rate between two): its
#             time to 35 dB (centres-*.md), and the measured rows of the
#             plain strata and the control variates at 0.5-2 per voxel
#             (centres-rates-*.md)
#   big       a volume of FRACTION (default 0.6) of the device's memory
#             (figure3, 3 x float32, generated cheaply) renders: device bytes
#             and frame time
#   papertables Sahistan et al.'s Table 2 protocol (blends: every blend with
#             flat colour maps against density) and Fig. 10 (raymarch: the
#             ray marcher, mix, at 1-16x the Nyquist step against 1-DDA at
#             1-16 spp), NYX-like and Miranda-like at 1024^2
# Usage: bash Benchmarks/gpu/bench.sh [build-dir] stage...   (results under $OUT)
set -uo pipefail
b="${1:-/tmp/mcvol-gpu}"
shift
out="${RESULTS:-${OUT:-/tmp/mcvol-gpu-out}}"
mkdir -p "$out"
bench="$b/bin/mcvol-bench"
# name dataset dims channels
sets=(
  "nyx cosmology 512 512 512 4 NYX-like"
  "hurricane weather 500 500 100 4 Hurricane-like"
  "miranda cosmology 256 384 384 4 Miranda-like"
  "zebrafish microscopy 640 640 121 3 Zebrafish-like"
)
run() { # name args...
  local name="$1"
  shift
  echo "== $name: $*" >&2
  "$bench" "$@" --csv "$out/$name.csv" > "$out/$name.md" 2> "$out/$name.err"
  local rc=$?
  [ $rc -eq 0 ] || { echo "FAILED ($rc): $name" >&2; tail -5 "$out/$name.err" >&2; }
}
for stage in "$@"; do
  case "$stage" in
    paper)
      for s in "${sets[@]}"; do
        read -r key ds x y z ch label <<< "$s"
        run "paper-$key" --backend cuda --dataset "$ds" --dims "$x" "$y" "$z" --channels "$ch" --label "$label" \
          --size 1024 1024 --warmup 25 --frames 500 --reference-spp 4096 --sections paper,memory,sampling,converge
        grep -A5 "^| tracker | FPS" "$out/paper-$key.md" | sed -n 3,5p | sed "s/^/$label /"
        grep -A7 "^| estimator, tracker, sampler" "$out/paper-$key.md" | sed -n 3,7p | sed "s/^/$label /"
      done
      ;;
    sequences)
      for s in "${sets[@]}"; do
        read -r key ds x y z ch label <<< "$s"
        run "sequences-$key" --backend cuda --dataset "$ds" --dims "$x" "$y" "$z" --channels "$ch" --label "$label" \
          --size 1024 1024 --reference-spp 4096 --spp-max 128 --sections sequences \
          --estimators collision,expected-value
        grep -A5 "^| sampler |" "$out/sequences-$key.md" | sed -n 3,6p | sed "s/^/$label /"
      done
      ;;
    estimator)
      for s in "${sets[@]}"; do
        read -r key ds x y z ch label <<< "$s"
        run "estimator-$key" --backend cuda --dataset "$ds" --dims "$x" "$y" "$z" --channels "$ch" --label "$label" \
          --size 1024 1024 --reference-spp 4096 --sections converge --no-collision \
          --march-samples-per-voxel 0.0625,0.125,0.25,0.5,1,2
        grep -E "^\| (expected-value, sobol \(default\)|automatic)" "$out/estimator-$key.md" | sed "s/^/$label /"
      done
      here="$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)"
      python3 "$here/../studies/fit_cost_model.py" "$out"/estimator-*.md > "$out/cost-model-fit.md"
      tail -3 "$out/cost-model-fit.md"
      model="$(tail -1 "$out/cost-model-fit.md" | sed 's/^--cost-model //')"
      for s in "${sets[@]}"; do
        read -r key ds x y z ch label <<< "$s"
        run "estimator-fit-$key" --backend cuda --dataset "$ds" --dims "$x" "$y" "$z" --channels "$ch" \
          --label "$label" --size 1024 1024 --reference-spp 4096 --sections converge --no-collision \
          --only-automatic --choice-all --march-samples-per-voxel 0.0625,0.125,0.25,0.5,1,2 --cost-model "$model"
        grep -E "^\| automatic" "$out/estimator-fit-$key.md" | head -1 | sed "s/^/$label fitted /"
      done
      ;;
    pilots)
      # The automatic choice with its pilots all at once (the default) and
      # one after the other: time to 35 dB with the pilots included, and the
      # pilots' cost both ways.
      for s in "${sets[@]}"; do
        read -r key ds x y z ch label <<< "$s"
        run "pilots-$key" --backend cuda --dataset "$ds" --dims "$x" "$y" "$z" --channels "$ch" \
          --label "$label" --size 1024 1024 --reference-spp 4096 --sections converge,pilots --no-collision --pixel-centres \
          --only-automatic
        grep -E "^\| (expected-value, sobol|automatic)" "$out/pilots-$key.md" | head -2 | sed "s/^/$label /"
        grep -E "^\| (jittered|centres) \|" "$out/pilots-$key.md" | sed "s/^/$label /"
      done
      ;;
    automatic)
      # The automatic estimator alone: its time to 35 dB with the default
      # rate search (pilots included), then every candidate's prediction
      # (--choice-all) to set against the estimator stage's measured times.
      for s in "${sets[@]}"; do
        read -r key ds x y z ch label <<< "$s"
        run "automatic-$key" --backend cuda --dataset "$ds" --dims "$x" "$y" "$z" --channels "$ch" \
          --label "$label" --size 1024 1024 --reference-spp 4096 --sections converge --no-collision --only-automatic
        grep -E "^\| automatic" "$out/automatic-$key.md" | head -1 | sed "s/^/$label /"
        run "automatic-all-$key" --backend cuda --dataset "$ds" --dims "$x" "$y" "$z" --channels "$ch" \
          --label "$label" --size 1024 1024 --reference-spp 4096 --sections converge --no-collision --only-automatic \
          --choice-all --march-samples-per-voxel 0.0625,0.125,0.25,0.5,1,2
        grep -E "^[* ] (ExpectedValue|UnbiasedMarch)" "$out/automatic-all-$key.md" | sed "s/^/$label /"
      done
      ;;
    centres)
      for s in "${sets[@]}"; do
        read -r key ds x y z ch label <<< "$s"
        run "centres-$key" --backend cuda --dataset "$ds" --dims "$x" "$y" "$z" --channels "$ch" \
          --label "$label" --size 1024 1024 --reference-spp 4096 --sections converge --no-collision --only-automatic \
          --centres-only
        grep -E "^\| automatic" "$out/centres-$key.md" | head -1 | sed "s/^/$label centres /"
        grep -E "^[* ] (ExpectedValue|UnbiasedMarch)" "$out/centres-$key.md" | sed "s/^/$label /"
        run "centres-rates-$key" --backend cuda --dataset "$ds" --dims "$x" "$y" "$z" --channels "$ch" \
          --label "$label" --size 1024 1024 --reference-spp 4096 --sections converge --no-collision \
          --centres-only --march-samples-per-voxel 0.5,1,1.25,2
        grep -E "^\| unbiased-march" "$out/centres-rates-$key.md" | sed "s/^/$label /"
      done
      ;;
    dense)
      # The same datasets with every opacity unit distance divided by 8: more
      # collisions per ray (the synthetic transfer functions are fairly clear).
      for s in "${sets[@]}"; do
        read -r key ds x y z ch label <<< "$s"
        run "dense-$key" --backend cuda --dataset "$ds" --dims "$x" "$y" "$z" --channels "$ch" --label "$label" \
          --density 8 --size 1024 1024 --warmup 25 --frames 500 --reference-spp 4096 --sections paper,converge
        grep -A4 "^| tracker | FPS" "$out/dense-$key.md" | sed -n 3,4p | sed "s/^/$label dense /"
      done
      ;;
    macrocell)
      for s in "${sets[@]}"; do
        read -r key ds x y z ch label <<< "$s"
        run "macrocell-cuda-$key" --backend cuda --dataset "$ds" --dims "$x" "$y" "$z" --channels "$ch" \
          --label "$label" --size 1024 1024 --warmup 10 --frames 100 --macrocell-sizes 1,2,4,8,16,32 \
          --sections macrocell
        run "macrocell-cpu-$key" --backend cpu --dataset "$ds" --dims "$x" "$y" "$z" --channels "$ch" \
          --label "$label" --size 1024 1024 --warmup 1 --frames 3 --macrocell-sizes 2,4,8,16,32 --sections macrocell
      done
      ;;
    channels)
      run channels-cuda --backend cuda --dataset cosmology --dims 512 512 512 --label NYX-like --size 1024 1024 \
        --warmup 10 --frames 100 --channel-counts 1,2,3,4,5,6,7,8,9,10,11,12,13,14,15,16 --sections channels
      run channels-cpu --backend cpu --dataset cosmology --dims 512 512 512 --label NYX-like --size 1024 1024 \
        --warmup 1 --frames 3 --channel-counts 1,2,4,8,12,16 --sections channels
      ;;
    accuracy)
      # The accuracy study's series on the GPU (scores only): Monte Carlo and
      # the ray marches both on CUDA (--march-backend follows --backend; the
      # reference march interpolates in software, so it is the CPU's image to
      # float rounding): merged by accuracy_study.py --gpu.
      # The Monte Carlo configurations are the study's (accuracy_study.py
      # MC_CONFIGS): the new default (expected value, Sobol', 1-DDA),
      # collision + Sobol', the old default (collision, independent,
      # 1-DDA and N-DDA), the unbiased march (2 per voxel, Sobol') and the
      # automatic choice (its pilots timed into the series; the choice in
      # <dataset>-<mode>.meta.txt).
      # Writes accuracy/<dataset>-<mode>.csv, the layout accuracy_study.py
      # --gpu reads, and packs them with their logs into accuracy.tgz, one
      # file to bring back. ACCURACY_MODES (default: all four) and
      # ACCURACY_DATASETS (default: all four) shorten the stage.
      mkdir -p "$out/accuracy"
      configs="expected-value:sobol:1dda,collision:sobol:1dda,collision:independent:1dda,collision:independent:ndda"
      configs="$configs,unbiased-march:sobol:1dda,automatic:sobol:1dda"
      for ds in ${ACCURACY_DATASETS:-figure3 microscopy cosmology weather}; do
        for mode in ${ACCURACY_MODES:-density max mix composite}; do
          work="$(mktemp -d)"
          t0=$SECONDS
          if "$b/bin/mcvol-accuracy" --backend cuda --score-only --dataset "$ds" --blend "$mode" --size 256 256 \
            --ref-spp 2048 --spp-max 1024 --mc-configs "$configs" --out "$work" 2> "$out/accuracy/$ds-$mode.log"; then
            cp "$work/timings.csv" "$out/accuracy/$ds-$mode.csv"
            cp "$work/meta.txt" "$out/accuracy/$ds-$mode.meta.txt"
          else
            echo "accuracy $ds $mode failed"; tail -3 "$out/accuracy/$ds-$mode.log"
          fi
          echo "accuracy $ds $mode: $((SECONDS - t0)) s" >&2
          rm -rf "$work"
        done
      done
      nvidia-smi --query-gpu=name,driver_version --format=csv,noheader > "$out/accuracy/device.txt" 2>&1
      tar -czf "$out/accuracy.tgz" -C "$out" accuracy
      # The first density row of each series at 35 dB or more, per dataset.
      for f in "$out"/accuracy/*-density.csv; do
        awk -F, -v f="$(basename "$f")" 'NR == 1 { for (i = 1; i <= NF; i++) c[$i] = i; next }
          $1 != "reference" && $(c["psnr"]) >= 35 {
            k = $1 " " $2 " " $(c["estimator"]) " " $(c["sampler"]); if (!(k in seen)) { seen[k] = 1;
            printf "%s %s: %s ms (%s)\n", f, k, $(c["ms"]), $(c["param"]) } }' "$f"
      done
      ;;
    lit)
      for s in "${sets[@]}"; do
        read -r key ds x y z ch label <<< "$s"
        run "lit-converge-$key" --backend cuda --dataset "$ds" --dims "$x" "$y" "$z" --channels "$ch" --label "$label" \
          --size 1024 1024 --lighting ambient --reference-spp 2048 --steady-frames 50 --sections converge
        grep -A5 "^| estimator, tracker, sampler" "$out/lit-converge-$key.md" | sed -n 3,5p | sed "s/^/$label /"
      done
      mkdir -p "$out/accuracy-lit"
      for lighting in ${LIT_PRESETS:-shadows ambient multiple}; do
        for ds in ${ACCURACY_DATASETS:-figure3 microscopy cosmology weather}; do
          work="$(mktemp -d)"
          t0=$SECONDS
          if "$b/bin/mcvol-accuracy" --backend cuda --score-only --dataset "$ds" --size 256 256 --lighting "$lighting" \
            --ref-spp 2048 --spp-max 1024 --steps 4,2,1,0.5,0.25 \
            --mc-configs expected-value:sobol:1dda,collision:sobol:1dda,collision:independent:1dda \
            --out "$work" 2> "$out/accuracy-lit/$ds-$lighting.log"; then
            cp "$work/timings.csv" "$out/accuracy-lit/$ds-$lighting.csv"
            cp "$work/meta.txt" "$out/accuracy-lit/$ds-$lighting.meta.txt"
          else
            echo "accuracy-lit $ds $lighting failed"; tail -3 "$out/accuracy-lit/$ds-$lighting.log"
          fi
          echo "accuracy-lit $ds $lighting: $((SECONDS - t0)) s" >&2
          rm -rf "$work"
        done
      done
      nvidia-smi --query-gpu=name,driver_version --format=csv,noheader > "$out/accuracy-lit/device.txt" 2>&1
      tar -czf "$out/accuracy-lit.tgz" -C "$out" accuracy-lit
      ;;
    effects)
      # Each lighting effect's cost and effect, CUDA and CPU.
      run effects-cuda --backend cuda --dataset cosmology --dims 256 256 256 --channels 4 --label "cosmology 256^3" \
        --size 1024 1024 --warmup 10 --frames 100 --reference-spp 256 --sections effects
      run effects-cpu --backend cpu --dataset cosmology --dims 256 256 256 --channels 4 --label "cosmology 256^3" \
        --size 512 512 --warmup 1 --frames 5 --reference-spp 64 --sections effects
      grep "^| " "$out/effects-cuda.md" | head -10
      # The paper-sized sets at 1024^2: a light without shadows against the
      # unlit frame, each estimator.
      for s in "${sets[@]}"; do
        read -r key ds x y z ch label <<< "$s"
        run "effects-$key" --backend cuda --dataset "$ds" --dims "$x" "$y" "$z" --channels "$ch" --label "$label" \
          --size 1024 1024 --warmup 10 --frames 100 --reference-spp 64 --sections effects
        grep -E "^\| (emission|1 light, (no shadows|ratio-tracking))" "$out/effects-$key.md" | sed "s/^/$label /"
      done
      ;;
    ea-compare)
      # Emission-absorption frame time with the lighting code compiled in
      # (this tree) against the tree before it ($MAIN_SRC, built alike),
      # interleaved runs of the same command.
      if [ -n "${MAIN_SRC:-}" ]; then
        cmake -S "$MAIN_SRC" -B /tmp/b-main -DMCVOL_CORE_ONLY=ON -DCMAKE_BUILD_TYPE=Release -DBUILD_TESTING=OFF \
          -DCMAKE_CUDA_COMPILER="$(command -v nvcc || echo /usr/local/cuda/bin/nvcc)" > "$out/main-configure.log" 2>&1
        cmake --build /tmp/b-main -j"$(nproc)" --target mcvol-bench > "$out/main-build.log" 2>&1 || echo "main build failed"
        for rep in 1 2 3; do
          for tree in before after; do
            binary=/tmp/b-main/bin/mcvol-bench
            [ $tree = after ] && binary="$bench"
            "$binary" --backend cuda --dataset cosmology --dims 512 512 512 --channels 4 --size 1024 1024 \
              --warmup 25 --frames 500 --sections paper > "$out/ea-$tree-$rep.md" 2>/dev/null
            echo "$tree $rep: $(grep -E '^\| 1-DDA' "$out/ea-$tree-$rep.md" | head -1)"
            "$binary" --backend cpu --dataset cosmology --dims 128 128 128 --channels 4 --size 256 256 \
              --warmup 2 --frames 20 --sections trackers > "$out/ea-cpu-$tree-$rep.md" 2>/dev/null
            echo "$tree $rep cpu: $(grep -E '^\| 1-DDA' "$out/ea-cpu-$tree-$rep.md" | head -1)"
          done
        done
      fi
      ;;
    big)
      # 3 float32 channels: 12 bytes per voxel position.
      mib="$(nvidia-smi --query-gpu=memory.total --format=csv,noheader,nounits | head -1)"
      edge="$(python3 -c "print(int((${FRACTION:-0.6} * $mib * 2**20 / 12) ** (1 / 3)))")"
      run "big-$edge" --backend cuda --dataset figure3 --dims "$edge" "$edge" "$edge" --label "figure3 ${FRACTION:-0.6} of ${mib} MiB" \
        --size 1024 1024 --warmup 5 --frames 50 --sections memory,trackers
      grep -E "^GPU memory|^\| (1-DDA|N-DDA)" "$out/big-$edge.md"
      ;;
    pyramid)
      # The target: level 1 at least 4x faster than level 0 for a 4 x 512^3
      # float volume at 1024^2 on the GPU, and the CPU figures. Levels 3-6
      # too on CUDA: the coarsest level bounds what any level can gain.
      run pyramid-cuda --backend cuda --dataset cosmology --dims 512 512 512 --channels 4 --label NYX-like \
        --size 1024 1024 --warmup 25 --frames 200 --sections pyramid --pyramid-levels 6
      run pyramid-cpu-1024 --backend cpu --dataset cosmology --dims 512 512 512 --channels 4 --label NYX-like \
        --size 1024 1024 --warmup 1 --frames 5 --sections pyramid
      run pyramid-cpu-512 --backend cpu --dataset cosmology --dims 512 512 512 --channels 4 --label NYX-like \
        --size 512 512 --warmup 1 --frames 5 --sections pyramid
      for f in pyramid-cuda pyramid-cpu-1024 pyramid-cpu-512; do
        grep -E "^\| [0-9]|^Level 0" "$out/$f.md" | sed "s/^/$f /"
      done
      ;;
    rebuild)
      # One channel's transfer function changes: GPU majorant rebuild time.
      for s in "${sets[@]}"; do
        read -r key ds x y z ch label <<< "$s"
        run "rebuild-$key" --backend cuda --dataset "$ds" --dims "$x" "$y" "$z" --channels "$ch" --label "$label" \
          --sections rebuild
        echo "$label: $(grep -E '^\| 1 \|' "$out/rebuild-$key.md")"
      done
      ;;
    block)
      for bs in "8 8" "16 8" "32 4" "16 16" "32 8"; do
        run "block-${bs/ /x}" --backend cuda --dataset cosmology --dims 512 512 512 --channels 4 --label NYX-like \
          --size 1024 1024 --warmup 25 --frames 200 --block $bs --sections trackers
        echo "block $bs: $(grep -E '^\| (1-DDA|N-DDA)' "$out/block-${bs/ /x}.md" | tr '\n' ' ')"
      done
      ;;
    papertables)
      for s in "${sets[@]}"; do
        read -r key ds x y z ch label <<< "$s"
        case "$key" in nyx | miranda) ;; *) continue ;; esac
        run "papertables-$key" --backend cuda --dataset "$ds" --dims "$x" "$y" "$z" --channels "$ch" --label "$label" \
          --size 1024 1024 --warmup 5 --frames 50 --reference-spp 4096 --sections blends,raymarch
      done
      ;;
    profile)
      ncu_bin="$(command -v ncu || echo /usr/local/cuda/bin/ncu)"
      "$ncu_bin" --kernel-name regex:renderKernel --launch-skip 30 --launch-count 1 --set full \
        -o "$out/profile" -f "$bench" --backend cuda --dataset ${PROFILE_DATASET:-cosmology} \
        --dims ${PROFILE_DIMS:-512 512 512} --channels ${PROFILE_CHANNELS:-4} --size 1024 1024 --warmup 25 --frames 10 \
        --sections trackers > "$out/profile.log" 2>&1
      "$ncu_bin" --import "$out/profile.ncu-rep" --page details > "$out/profile-details.txt" 2>&1
      grep -E "Duration|Memory Throughput|Compute \(SM\) Throughput|Achieved Occupancy|Registers Per|L1/TEX Hit|L2 Hit|DRAM Throughput|Warp Cycles Per Issued|Theoretical Occupancy|Stall" \
        "$out/profile-details.txt" | head -40
      rm -f "$out/profile.ncu-rep"
      ;;
  esac
done
