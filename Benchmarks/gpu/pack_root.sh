#!/usr/bin/env bash
# Here (Debian bookworm, the CI image): packs what the real VTK module, the
# Python package and the ParaView plugin need at run time into chunks that
# the `device` tool can carry to the GPU machine (Ubuntu 24.04, no VTK, no
# apt, no network). The GPU machine unpacks them into a bookworm root and
# runs the tests there with chroot (Benchmarks/gpu/vtk.sh).
#
# Two archives, each split into chunks of $CHUNK_MB MiB:
#   .gpuroot/root.tar.zst.*   bookworm files: every Debian package that owns
#                             a library the product loads (ldd closure of
#                             pvpython, pvbatch, Python's VTK/ParaView
#                             modules, our module, plugin and test
#                             programs, Xvfb and Mesa), plus Python 3.11,
#                             numpy, tifffile, Xvfb, xkb data, ctest, MPI and
#                             the test data packages; docs, man pages,
#                             locales, headers and static libraries left out.
#   .gpuroot/build.tar.zst.*  the build tree's run-time files (programs,
#                             libraries, Python package, plugin, CTest files);
#                             object files and the VTK-free core's test
#                             programs (check.sh builds those there) left out,
#                             unless MCVOL_PACK_TESTS=cuda.
# The working tree itself travels with every call.
#
# Usage: bash Benchmarks/gpu/pack_root.sh [--build-only | --dev] [build-dir]
#   (default build-dir: build). --build-only re-packs the build tree alone
#   (after a rebuild), keeping the bookworm root's chunks. --dev packs what
#   building there needs (.gpuroot/dev-N: compilers, headers, CMake
#   packages), for `vtk.sh build`; it needs the root's chunks.
# Then carry the .gpuroot/root-N and build-N folders in back-to-back calls
# (see README.md).
set -euo pipefail
build_only=0
dev_only=0
if [ "${1:-}" = "--build-only" ]; then build_only=1; shift; fi
if [ "${1:-}" = "--dev" ]; then dev_only=1; build_only=1; shift; fi
top="$(cd "$(dirname "${BASH_SOURCE[0]}")/../.." && pwd)"
b="$(cd "${1:-$top/build}" && pwd)"
out="$top/.gpuroot"
# A call carries 64 MiB, the working tree included.
chunk_mb="${CHUNK_MB:-24}"
work="$(mktemp -d)"
trap 'rm -rf "$work"' EXIT
grep -qxF '/.gpuroot/' "$top/.git/info/exclude" 2>/dev/null || {
  mkdir -p "$top/.git/info"; echo '/.gpuroot/' >> "$top/.git/info/exclude"; }

# Package file lists to the files to pack: existing files and links (no
# plain folders), each folder part resolved (bookworm merges /usr), without
# the leading slash, each once.
real_files() {
  python3 -c '
import os, sys
seen = set()
for line in sys.stdin:
    f = line.rstrip("\n")
    if not (os.path.lexists(f)) or (os.path.isdir(f) and not os.path.islink(f)):
        continue
    path = os.path.join(os.path.realpath(os.path.dirname(f)), os.path.basename(f))[1:]
    if path not in seen:
        seen.add(path)
        print(path)
'
}

mkdir -p "$out"
if [ "$build_only" = 0 ]; then
# --- 1. the programs and modules whose libraries we need --------------------
roots=(/usr/bin/pvpython /usr/bin/pvbatch /usr/bin/Xvfb /usr/bin/xkbcomp
  /usr/bin/xauth /usr/bin/ctest /usr/bin/python3.11 /usr/bin/bash
  /usr/bin/mpiexec /usr/bin/orted /usr/lib/x86_64-linux-gnu/dri/swrast_dri.so
  /usr/lib/x86_64-linux-gnu/libGLX_mesa.so.0 /usr/lib/x86_64-linux-gnu/libEGL_mesa.so.0)
# Open MPI loads its components (and they PMIx, libfabric, UCX...) with
# dlopen: their libraries too, or MPI_Init fails in pvpython and pvbatch.
mapfile -t mpiso < <(find /usr/lib/x86_64-linux-gnu/openmpi/lib /usr/lib/x86_64-linux-gnu/pmix2 \
  -name '*.so' 2>/dev/null)
roots+=("${mpiso[@]}")
mapfile -t pyso < <(find /usr/lib/python3/dist-packages/paraview \
  /usr/lib/python3/dist-packages/vtkmodules /usr/lib/python3/dist-packages/numpy \
  -name '*.so' 2>/dev/null)
mapfile -t ours < <(find "$b/lib" "$b/bin" -maxdepth 4 -type f \
  \( -name '*.so' -o -name '*.so.*' -o -perm -u+x \) ! -name '*.a' 2>/dev/null)
for f in "${roots[@]}" "${pyso[@]}" "${ours[@]}"; do
  ldd "$f" 2>/dev/null | awk '/=> \//{print $3}' || true
done | sort -u > "$work/libs"

# --- 2. the Debian packages that own them, and the ones needed as a whole ---
explicit=(libc6 libc-bin dash bash coreutils sed grep findutils procps
  util-linux python3 python3.11 python3.11-minimal libpython3.11-minimal
  libpython3.11-stdlib python3-minimal python3-numpy python3-tifffile
  python3-paraview paraview cmake cmake-data xvfb xserver-common xauth xkb-data x11-xkb-utils
  libgl1-mesa-dri libglx-mesa0 libegl-mesa0 openmpi-bin openmpi-common
  libopenmpi3 mricron-data)
{
  printf '%s\n' "${explicit[@]}"
  # dpkg knows a file by the path its package installed (/lib/... or
  # /usr/lib/...): ask for the normalised path, its /usr-less twin and the
  # symbolic link's target, all in one call.
  while read -r f; do
    n="$(realpath -s "$f")"; echo "$n"; echo "${n#/usr}"; readlink -f "$f"
  done < "$work/libs" | sort -u | xargs dpkg -S 2>/dev/null |
    cut -d: -f1 | tr ',' '\n' | sed 's/ //g' || true
} | sort -u > "$work/pkgs"

# --- 3. their files, with /bin, /lib... resolved (bookworm merges /usr) -----
while read -r p; do dpkg -L "$p" 2>/dev/null || true; done < "$work/pkgs" |
  grep -vE '^/usr/share/(doc|man|info|locale|lintian|bug|doc-base)/|^/usr/include/|\.a$|/__pycache__/|^/\.$' |
  real_files > "$work/files"
# Links that update-alternatives made (libblas.so.3, mpiexec, ...): no package
# owns them, so add every one in the program and library folders, and the
# /etc/alternatives links they go through.
find /usr/bin /usr/sbin /usr/lib/x86_64-linux-gnu -maxdepth 1 -type l \
  -lname '/etc/alternatives/*' | sed 's#^/##' >> "$work/files"
# The /usr merge links, a minimal /etc and the loader's, MPI's and Python's
# configuration.
for e in etc/passwd etc/group etc/hosts etc/nsswitch.conf etc/ld.so.conf etc/debian_version etc/os-release usr/lib/os-release; do
  [ -e "/$e" ] && echo "$e"
done >> "$work/files"
find /etc/alternatives /etc/ld.so.conf.d /etc/openmpi /etc/python3.11 \( -type f -o -type l \) 2>/dev/null |
  sed 's#^/##' >> "$work/files"
printf '%s\n' bin lib lib64 sbin >> "$work/files"

rm -rf "$out"/root.tar.zst "$out"/root-*
sort -u "$work/files" | tar -C / --no-recursion -cf - -T - |
  zstd -q -T0 -"${ZSTD_LEVEL:-12}" -o "$out/root.tar.zst"
echo "root: $(wc -l < "$work/pkgs") packages, $(wc -l < "$work/files") files," \
  "$(du -m "$out/root.tar.zst" | cut -f1) MiB compressed"

fi

# --- 3b. --dev: what building the project there needs ------------------------
# The compilers, headers, CMake packages and static libraries of every package
# scripts/deps.sh installs and of their installed dependencies, less the files
# the root's chunks already hold: with it, `vtk.sh build` configures and
# builds the whole project (module, Python wrapping, plugin, tests) inside
# the root on the GPU machine, with that machine's nvcc (/usr/local/cuda,
# bound into the root).
if [ "$dev_only" = 1 ]; then
  ls "$out"/root-*/root.[0-9][0-9] > /dev/null 2>&1 || { echo "pack the root first (no .gpuroot/root-N)"; exit 1; }
  mapfile -t want < <(bash -c "$(sed -n '/^MCVOL_PACKAGES=(/,/^)/p' "$top/scripts/deps.sh")"'
    printf "%s\n" "${MCVOL_PACKAGES[@]}"')
  apt-cache depends --recurse --no-recommends --no-suggests --no-conflicts --no-breaks \
    --no-replaces --no-enhances "${want[@]}" 2>/dev/null | grep -v '^[ <]' | sort -u > "$work/deps"
  dpkg-query -W -f='${Package}\n' | sort -u > "$work/installed"
  comm -12 "$work/deps" "$work/installed" > "$work/devpkgs"
  cat $(ls "$out"/root-*/root.[0-9][0-9] | sort) | zstd -dc | tar -t | sed 's#/$##' | sort -u > "$work/inroot"
  while read -r p; do dpkg -L "$p" 2>/dev/null || true; done < "$work/devpkgs" |
    grep -vE '^/usr/share/(doc|man|info|locale|lintian|bug|doc-base)/|/__pycache__/|^/\.$' |
    real_files | sort -u > "$work/devall"
  # update-alternatives links (cc, c++, ...) and their /etc/alternatives hops
  find /usr/bin -maxdepth 1 -type l -lname '/etc/alternatives/*' | sed 's#^/##' >> "$work/devall"
  find /etc/alternatives -type l | sed 's#^/##' >> "$work/devall"
  sort -u "$work/devall" | comm -23 - "$work/inroot" > "$work/devfiles"
  rm -rf "$out"/dev.tar.zst "$out"/dev-*
  tar -C / --no-recursion -cf - -T "$work/devfiles" | zstd -q -T0 -"${ZSTD_LEVEL:-12}" -o "$out/dev.tar.zst"
  echo "dev: $(wc -l < "$work/devpkgs") packages, $(wc -l < "$work/devfiles") files," \
    "$(du -m "$out/dev.tar.zst" | cut -f1) MiB compressed"
fi

# --- 4. the build tree's run-time part ---------------------------------------
if [ "$dev_only" = 0 ]; then
rm -rf "$out"/build.tar.zst "$out"/build-*
# The core's test programs (~9 MiB each compressed, mostly CUDA kernels) are
# left out, unless MCVOL_PACK_TESTS=cuda: then the programs of the `cuda`
# ctest label come along, and `vtk.sh ctest -L cuda` runs the core's CUDA
# tests in the root without building them on the GPU machine.
keep_tests=""
if [ "${MCVOL_PACK_TESTS:-}" = cuda ]; then
  keep_tests="$(cd "$b" && ctest -N -V -L cuda | sed -n 's/.*Test command: \([^ ]*mcvol_[a-z_]*_test\).*/\1/p' | sort -u)"
fi
{
  (cd / && find "${b#/}" \( -name CMakeFiles -o -name '_deps' \) -prune -o -type f \
    ! -name '*.o' ! -name '*.a' ! -name '*.d' ! -name 'mcvol_*_test' -print)
  for t in $keep_tests; do echo "${t#/}"; done
} |
  tar -C / -cf - -T - | zstd -q -T0 -"${ZSTD_LEVEL:-12}" -o "$out/build.tar.zst"
echo "build: $(du -m "$out/build.tar.zst" | cut -f1) MiB compressed"
fi

# --- 5. chunks: one folder per call, NAME-N/NAME.NN plus its checksum --------
for name in root dev build; do
  [ -f "$out/$name.tar.zst" ] || continue
  (cd "$out" && split -b "${chunk_mb}M" -d -a 2 "$name.tar.zst" "$name." &&
    sha256sum "$name.tar.zst" > "$name.sha256")
  n=0
  for c in "$out/$name".[0-9][0-9]; do
    mkdir -p "$out/$name-$n"; mv "$c" "$out/$name-$n/"; n=$((n + 1))
  done
  mv "$out/$name.sha256" "$out/$name-0/"
  if [ "$name" = root ]; then
    # zstd for a GPU machine without one (vtk.sh setup uses it), in the
    # last, smallest folder
    mkdir -p "$out/root-$((n - 1))/tools"
    cp /usr/bin/zstd "$out/root-$((n - 1))/tools/"
    cp -L /usr/lib/x86_64-linux-gnu/libzstd.so.1 "$out/root-$((n - 1))/tools/"
  fi
  rm -f "$out/$name.tar.zst"
  echo "$name: $n chunks of at most $chunk_mb MiB in $out/$name-0 .. $name-$((n - 1))"
done
