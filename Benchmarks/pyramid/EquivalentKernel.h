// SPDX-License-Identifier: BSD-3-Clause
//
// mcvol-pyramid: the equivalent convolution of a pyramid level, the paper's
// criterion for a level's image (Kraus and Buerger, "Interpolating and
// Downsampling RGBA Volume Data", Sec. 4.2).

#pragma once

#include "mcvol/Pyramid.h"

#include <vector>

namespace mcvolbench
{
/**
 * The equivalent convolution of downsampling to level l and reconstructing
 * there (the paper's criterion, Sec. 4.2, after Kraus' quasi-convolution
 * pyramid blurring): the shift-invariant filter that the pyramid
 * approximates, per axis (the 3-D filter is its tensor product).
 *
 * Derivation, in fine voxels along one axis, s = 2^l. Coarse voxel c of
 * level l is centred at p_c = s c + (s - 1) / 2 (cell-centred levels,
 * Pyramid.h). Level m reads level m-1 voxels 2c + first + k with weights
 * w_k, i.e. at offsets (first + k - 1/2) 2^(m-1) fine voxels from its centre;
 * so level l's voxel is sum_o W(o) f(p_c + o), W the taps of level 1, the
 * taps of level 2 dilated by 2, ..., of level l dilated by 2^(l-1), all
 * convolved (offsets are half-integers for l >= 1). Trilinear
 * reconstruction at level l is the tent T_s(t) = max(0, 1 - |t| / s) over
 * the coarse centres. A fine voxel at y therefore reaches x with weight
 * sum_c T_s(x - p_c) W(y - p_c). This depends on the phase of y against the
 * coarse grid; averaged over the s phases (y = 0..s-1 with x - y = t fixed),
 * y - p_c runs over every offset of the lattice once, so
 *
 *     K_l(t) = (1/s) sum_o W(o) T_s(t + o),      t integer,
 *
 * which sums to 1 (the tent's partition of unity). Rendering the level
 * approximates rendering the full-resolution volume convolved with K_l (in
 * extinction and extinction-weighted colour); how far the image is from
 * that is the criterion's error. The full-resolution render of the blurred
 * volume adds level 0's own trilinear reconstruction (a tent of width 1,
 * variance 1/6 voxel^2 against K_1's 1.9 for box4), as every full-resolution
 * render does. checkKernel() compares K_l with the library's own 1-D
 * pyramid averaged over the phases.
 *
 * Returns K_l(t) for t = -R..R (index t + R).
 */
std::vector<double> equivalentKernel(mcvol::DownsampleFilter f, int level);

/**
 * K_l measured on the library itself: a 1-D volume (N x 1 x 1) with one
 * voxel of sigma 1 at y, its extinction pyramid, level l reconstructed by
 * linear interpolation at every fine voxel x (its spacing and origin), the
 * response at x = y + t averaged over the s phases of y. Returns the largest
 * difference from equivalentKernel().
 */
double checkKernel(mcvol::DownsampleFilter f, int level);

/// Separable convolution of a packed float4 volume with a symmetric kernel
/// (index t + R), clamped at the edges as the pyramid's filters are.
std::vector<float> blur(const std::vector<float>& in, const int d[3], const std::vector<double>& K);
} // namespace mcvolbench
