#!/usr/bin/env bash
# Installs the Debian packages mcvol needs, only those missing. Run by
# scripts/build.sh (and so by demo.sh and test.sh); safe to run again.
set -euo pipefail

MCVOL_PACKAGES=(
  cmake make g++ pkg-config
  # ParaView 5.11 and its own VTK 9.2 (we build against it: Documentation/design.md)
  paraview paraview-dev python3-paraview
  # find_package(ParaView) needs these Qt development packages
  qtbase5-dev qttools5-dev libqt5svg5-dev libqt5x11extras5-dev libqt5opengl5-dev
  # tests: an X server for OpenGL, GoogleTest sources, numpy/matplotlib/scikit-image
  xvfb xauth googletest python3-numpy python3-matplotlib python3-skimage python3-tifffile
  # OME-Zarr input (mcvol.omezarr decodes with numcodecs; the tests write with zarr)
  python3-zarr
  # the scene parser's and readers' fuzz test (Testing/Python/TestFuzzScenes.py)
  python3-hypothesis
  # real data for the gallery test (TestGallery, TestReaders): brain templates and atlases (16 MB)
  mricron-data
  # ParaView's VTK links VTK::glew and VTK::tiff through these -dev packages' targets
  libglew-dev libtiff-dev
  # The ParaView plugin: find_package(ParaView COMPONENTS RemotingViews) looks up
  # these third-party packages of ParaView's VTK; openmpi-bin runs the
  # `mpiexec -n 2 pvbatch` test; xmlpatterns is called by paraview_add_plugin.
  libopenmpi-dev openmpi-bin libhdf5-dev libnetcdf-dev libboost-dev
  libdouble-conversion-dev liblz4-dev libutfcpp-dev libexpat1-dev liblzma-dev
  libxml2-dev libfreetype-dev libjpeg-dev libpng-dev libeigen3-dev
  qtxmlpatterns5-dev-tools
  # Benchmarks/plots/sampling_figures.sh turns the figure program's PPMs into PNGs
  netpbm
)

mcvol_missing=()
for p in "${MCVOL_PACKAGES[@]}"; do
  if ! dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed"; then
    mcvol_missing+=("$p")
  fi
done
if [ ${#mcvol_missing[@]} -gt 0 ]; then
  echo "mcvol: installing missing packages: ${mcvol_missing[*]}"
  SUDO=""
  if [ "$(id -u)" -ne 0 ]; then SUDO="sudo"; fi
  export DEBIAN_FRONTEND=noninteractive
  $SUDO apt-get update -q
  $SUDO apt-get install -y -q --no-install-recommends "${mcvol_missing[@]}"
fi
