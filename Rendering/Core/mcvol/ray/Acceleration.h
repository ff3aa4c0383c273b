// SPDX-License-Identifier: BSD-3-Clause
#pragma once

#include "mcvol/ray/Sampling.h"

#include <cstdint>

namespace mcvol
{
/**
 * Pieces of the macrocell and majorant builds that the host build
 * (SceneMacrocells.cxx, SceneMajorants.cxx) and the GPU build (Rendering/CUDA)
 * share, so both produce the same grids.
 */

/// Voxels beyond a macrocell's own that its ranges cover, per side
/// (cellVoxelBounds): the reconstruction filter's reach past the cell plus
/// one voxel for the rounding of the DDA's cell boundaries. Trilinear (and
/// nearest) points read voxels floor(x) .. floor(x) + 1, the cubic B-spline
/// floor(x) - 1 .. floor(x) + 2: one voxel more per side.
MCVOL_FUNC int footprintApron(bool cubic)
{
  return cubic ? 2 : 1;
}

/// Voxels whose values a point of macrocell `cell` can read: the cell's
/// voxels widened by `apron` voxels per side (footprintApron(): 1 for
/// trilinear, the 27-neighbourhood; 2 for the cubic B-spline), so a range
/// stays conservative under interpolation and under rounding of the DDA's
/// cell boundaries. Inclusive bounds.
MCVOL_FUNC void cellVoxelBounds(const int dims[3], int macrocell, const int cell[3], int apron, int lo[3], int hi[3])
{
  for (int a = 0; a < 3; ++a)
  {
    if (dims[a] == 1)
    {
      lo[a] = hi[a] = 0;
      continue;
    }
    const int l = cell[a] * macrocell - apron;
    const int h = (cell[a] + 1) * macrocell + apron;
    lo[a] = l > 0 ? l : 0;
    hi[a] = h < dims[a] - 1 ? h : dims[a] - 1;
  }
}

/// Levels of a max sparse table over a channel's K texels (level L holds the
/// maximum of 2^L texels starting at each index; stored [L * K + i]).
MCVOL_FUNC int sparseLevels(int K)
{
  int levels = 1;
  while ((2 << (levels - 1)) <= K)
  {
    ++levels;
  }
  return levels;
}

/// Majorants are inflated by a relative 2^-16 so that float rounding in the
/// interpolation can never push a sampled extinction above them.
constexpr float kMajorantInflation = 1.f + 0x1p-16f;

/**
 * Majorant of channel n over a macrocell whose scalar range is [mn, mx]: the
 * largest extinction of the texels the range covers, both ends included
 * (the table is interpolated linearly), in O(1) through the sparse table.
 * An empty range (mn > mx: every voxel NaN) gives 0.
 */
MCVOL_FUNC float cellMajorant(const TableView& tv, int n, float mn, float mx, const float* sparse)
{
  if (!(mn <= mx))
  {
    return 0.f;
  }
  const int K = tv.size;
  const float c0 = floorf(texelCoord(tv, n, mn));
  const float c1 = ceilf(texelCoord(tv, n, mx));
  const int i0 = c0 > 0.f ? int(c0) : 0;
  int i1 = int(c1) < K - 1 ? int(c1) : K - 1;
  i1 = i1 > i0 ? i1 : i0;
  int L = 0;
  while ((2 << L) <= i1 - i0 + 1)
  {
    ++L;
  }
  const float a = sparse[int64_t(L) * K + i0];
  const float b = sparse[int64_t(L) * K + i1 - (1 << L) + 1];
  return (a > b ? a : b) * kMajorantInflation;
}

/**
 * Majorant of a pre-classified (Extinction) channel over a macrocell: its
 * "scalar" range is the range of the sanitised sigma over the cell's
 * footprint (classifiedVoxel), so the identity rule applies: the largest
 * sigma, inflated as cellMajorant() inflates. Interpolation (convex weights)
 * never exceeds it. An empty range (every voxel NaN) gives 0.
 */
MCVOL_FUNC float classifiedCellMajorant(float mn, float mx)
{
  if (!(mn <= mx) || !(mx > 0.f))
  {
    return 0.f;
  }
  return mx * kMajorantInflation;
}

/// Fills `sparse` (sparseLevels(K) * K floats) from channel n's texels
/// (r, g, b, extinction).
MCVOL_FUNC void buildSparseTable(const float* texels, int K, float* sparse)
{
  for (int i = 0; i < K; ++i)
  {
    sparse[i] = texels[4 * i + 3];
  }
  const int levels = sparseLevels(K);
  for (int L = 1; L < levels; ++L)
  {
    const float* prev = sparse + int64_t(L - 1) * K;
    float* cur = sparse + int64_t(L) * K;
    const int half = 1 << (L - 1);
    for (int i = 0; i + (1 << L) <= K; ++i)
    {
      const float a = prev[i];
      const float b = prev[i + half];
      cur[i] = a > b ? a : b;
    }
  }
}
} // namespace mcvol
