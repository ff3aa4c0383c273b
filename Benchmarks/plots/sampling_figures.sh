#!/usr/bin/env bash
# Kraus and Buerger's Fig. 4 and 7 and a thin wall over pyramid levels, made
# by mcvol-sampling-figures, as the PNGs of Documentation/images/ (netpbm's
# pnmtopng converts them). Prints the Fig. 4 table of the performance page.
#
#   bash Benchmarks/plots/sampling_figures.sh [build/bin/mcvol-sampling-figures]
set -euo pipefail
top="$(cd "$(dirname "${BASH_SOURCE[0]}")/../.." && pwd)"
prog="${1:-$top/build/bin/mcvol-sampling-figures}"
work="$(mktemp -d)"
trap 'rm -rf "$work"' EXIT
"$prog" --out "$work"
for f in fig4:kraus-fig4-wall-sampling fig7:kraus-fig7-scattered-voxels levels:kraus-thin-wall-levels; do
  pnmtopng "$work/${f%%:*}.ppm" > "$top/Documentation/images/${f##*:}.png"
done
