// SPDX-License-Identifier: BSD-3-Clause
#pragma once

#include <cstdint>

namespace mcvol
{
/// Native voxel types read in place (no float copy of the data is made).
enum class ScalarType : int
{
  UInt8 = 0,
  Int16 = 1,
  UInt16 = 2,
  Float32 = 3,
  Float64 = 4
};

/**
 * How N channels combine (Sahistan et al., Sections 4.1 and 4.2).
 * - Density: Eq. 6/7, channel extinctions add; a collision picks a channel with
 *   probability proportional to its extinction (physically based; default).
 * - Max: Eq. 8/9, only the channel of largest extinction at a point exists.
 * - Mix: Eq. 8 extinction, Eq. 10 colour: sum_n w_n sigma_n c_n / max_n sigma_n
 *   with weights normalised to sum to 1.
 * - Composite: each channel rendered alone, the per-channel premultiplied
 *   images added (post-render compositing; no inter-channel occlusion).
 */
enum class BlendMode : int
{
  Density = 0,
  Max = 1,
  Mix = 2,
  Composite = 3
};

/// Sahistan et al. Section 4.4 (N-DDA, Listing 3) and 4.5 (1-DDA, Listing 4).
enum class Tracker : int
{
  OneDDA = 0,
  NDDA = 1
};

enum class Backend : int
{
  Auto = 0,
  CPU = 1,
  CUDA = 2
};

const char* toString(ScalarType t);
const char* toString(BlendMode m);
const char* toString(Tracker t);
const char* toString(Backend b);
int scalarTypeSize(ScalarType t);
} // namespace mcvol
