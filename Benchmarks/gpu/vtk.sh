#!/usr/bin/env bash
# GPU machine: runs the real VTK module, Python package and ParaView plugin
# (built here on Debian bookworm, packed by pack_root.sh) inside a bookworm
# root on the GPU machine, with the host's NVIDIA driver. See README.md.
#
#   vtk.sh recv DIR...   keep the chunks of .gpuroot/DIR (root-0.., dev-0.., build-0..;
#                        one or two per call: the machine keeps them while it
#                        stays warm)
#   vtk.sh setup         join and unpack the chunks into $MCVOL_ROOT, add the
#                        host's NVIDIA driver libraries, the device nodes,
#                        /proc and /sys, and this working tree at /work/main
#   vtk.sh build [ARGS]  configure and build the whole project in the root
#                        (after the dev chunks: pack_root.sh --dev), with
#                        this machine's nvcc; ARGS go to cmake's configure
#   vtk.sh ctest ARGS    start Xvfb in the root and run ctest ARGS in
#                        /work/main/build there, with MCVOL_BACKEND=cuda so
#                        that every Auto mapper must run on the GPU
#   vtk.sh run CMD       run CMD (bash -c) in the root, in /work/main, with
#                        the same environment
set -uo pipefail
top="$(cd "$(dirname "${BASH_SOURCE[0]}")/../.." && pwd)"
R="${MCVOL_ROOT:-/tmp/mcvol-root}"
chunks="${MCVOL_CHUNKS:-/tmp/mcvol-chunks}"
mkdir -p "$chunks"
# The host may lack zstd: bookworm's travels with the first chunk.
if ! command -v zstd > /dev/null; then
  zstd() { LD_LIBRARY_PATH="$chunks/tools" "$chunks/tools/zstd" "$@"; }
fi

in_root() {
  # The environment of a clean bookworm shell, with the display and backend.
  chroot "$R" /usr/bin/env -i PATH=/usr/local/bin:/usr/bin:/bin HOME=/root \
    LANG=C.UTF-8 DISPLAY=:99 MCVOL_BACKEND="${MCVOL_BACKEND:-cuda}" \
    MCVOL_TEST_BACKEND="${MCVOL_TEST_BACKEND:-cuda}" \
    OMPI_ALLOW_RUN_AS_ROOT=1 OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1 \
    OMPI_MCA_plm_rsh_agent=/usr/bin/false PYTHONUNBUFFERED=1 ${MCVOL_EXTRA_ENV:-} "$@"
}

start_x() {
  # A call's processes end with it, except a new session's: Xvfb runs in one
  # (setsid) and stays for the next calls while the machine is warm. A socket
  # left by an Xvfb that did end is removed first.
  if ! pgrep -f "Xvfb :99" > /dev/null; then
    rm -f "$R/tmp/.X11-unix/X99" "$R/tmp/.X99-lock"
    setsid chroot "$R" /usr/bin/env -i PATH=/usr/bin:/bin /usr/bin/Xvfb :99 -screen 0 1920x1200x24 \
      -nolisten tcp -noreset > /tmp/mcvol-xvfb.log 2>&1 < /dev/null &
    for _ in $(seq 50); do
      [ -e "$R/tmp/.X11-unix/X99" ] && return 0
      sleep 0.2
    done
    echo "Xvfb did not start:"; tail -20 /tmp/mcvol-xvfb.log; return 1
  fi
}

case "${1:-}" in
  recv)
    shift
    for d in "$@"; do
      src="$top/.gpuroot/$d"
      [ -d "$src" ] || { echo "no $src (carry .gpuroot/$d)"; exit 1; }
      cp -r "$src"/* "$chunks"/
    done
    echo "have: $(ls "$chunks" | tr '\n' ' ')"
    ;;
  setup)
    # Each archive is joined, checked and unpacked once it is complete; a
    # new build (build-N chunks after pack_root.sh --build-only) replaces
    # the old one.
    for name in root dev build; do
      ls "$chunks/$name".[0-9][0-9] > /dev/null 2>&1 || continue
      (cd "$chunks" && cat "$name".[0-9][0-9] > "$name.tar.zst" &&
        sha256sum -c "$name.sha256") || { echo "$name: chunks missing or corrupt"; ls -la "$chunks"; exit 1; }
      mkdir -p "$R"
      [ "$name" = build ] && rm -rf "$R/work/main/build"
      zstd -dc "$chunks/$name.tar.zst" | tar -x -C "$R" || exit 1
      rm -f "$chunks/$name".[0-9][0-9] "$chunks/$name.tar.zst"
      echo "$name unpacked"
    done
    [ -x "$R/usr/bin/python3.11" ] || { echo "root not unpacked yet"; exit 1; }
    [ -d "$R/work/main/build" ] || [ -x "$R/usr/bin/g++" ] || { echo "neither a build nor the dev chunks unpacked"; exit 1; }
    # The host's NVIDIA user-space driver (it must match the kernel module).
    for lib in $(ldconfig -p | awk '/lib(cuda|nvidia-ptxjitcompiler|nvidia-ml|nvidia-nvvm|nvidia-gpucomp)\.so/{print $NF}'); do
      cp -L "$lib" "$R/usr/lib/x86_64-linux-gnu/$(basename "$lib")"
    done
    cp -L "$(command -v nvidia-smi)" "$R/usr/bin/" 2>/dev/null || true
    chroot "$R" /usr/sbin/ldconfig
    for d in dev proc sys; do
      mkdir -p "$R/$d"
      mountpoint -q "$R/$d" || mount --rbind "/$d" "$R/$d" || { echo "cannot mount /$d"; exit 1; }
    done
    # The host's CUDA toolkit, for compute-sanitizer over the real programs.
    if [ -d /usr/local/cuda ]; then
      mkdir -p "$R/usr/local/cuda"
      mountpoint -q "$R/usr/local/cuda" || mount --bind /usr/local/cuda "$R/usr/local/cuda"
    fi
    # CMake's GNUInstallDirs recognises Debian by this file (lib, not lib64):
    # roots packed before it travelled get bookworm's.
    [ -e "$R/etc/debian_version" ] || echo 12.11 > "$R/etc/debian_version"
    mkdir -p "$R/tmp" "$R/root" "$R/work/main" && chmod 1777 "$R/tmp"
    # This working tree (sources, tests, data) beside the unpacked build.
    tar -C "$top" --exclude=./.gpuroot --exclude=./build --exclude=./third_party -cf - . |
      tar -x -C "$R/work/main"
    in_root /usr/bin/nvidia-smi -L 2>/dev/null || true
    in_root /usr/bin/python3 -c "import sys; print('python', sys.version.split()[0])"
    echo "root ready: $(du -sm "$R" | cut -f1) MiB"
    ;;
  build)
    # Configure and build the whole project in the root (needs the dev
    # chunks): the module, Python wrapping, plugin, tests and benchmarks,
    # CUDA with this machine's nvcc. ARGS go to the configure step.
    shift
    in_root /usr/bin/bash -c "cd /work/main && rm -rf build &&
      cmake -S . -B build -DCMAKE_BUILD_TYPE=Release -DCMAKE_CUDA_ARCHITECTURES=${MCVOL_CUDA_ARCH:-native} \
        -DCMAKE_CUDA_COMPILER=/usr/local/cuda/bin/nvcc $(printf '%q ' "$@") &&
      cmake --build build -j\$(nproc)"
    ;;
  ctest)
    shift
    start_x || exit 1
    in_root /usr/bin/bash -c "cd /work/main/build && ctest $(printf '%q ' "$@")"
    ;;
  run)
    shift
    start_x || exit 1
    in_root /usr/bin/bash -c "cd /work/main && $*"
    ;;
  *)
    sed -n 2,20p "$0"; exit 2
    ;;
esac
