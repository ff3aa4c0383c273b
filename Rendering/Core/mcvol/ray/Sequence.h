// SPDX-License-Identifier: BSD-3-Clause
#pragma once

#include "mcvol/ray/Macros.h"

#include <cstdint>

namespace mcvol
{
/**
 * Owen-scrambled Sobol' points for the leading dimensions of a pixel's
 * samples (RenderSettings::sampler = Sampler::Sobol), after B. Burley,
 * "Practical Hash-based Owen Scrambling", JCGT 9(4), 2020:
 *
 * - Sobol' (1967) points from the generator matrices of the first five
 *   dimensions (dimension 0 the van der Corput sequence; the others from the
 *   primitive polynomials and initial direction numbers m_k of Joe and Kuo,
 *   "Constructing Sobol sequences with better two-dimensional projections",
 *   SIAM J. Sci. Comput. 30, 2008), computed on the fly bit by bit: no
 *   table, nothing to upload, and the loop ends with the index's highest bit.
 * - Nested uniform (Owen) scrambling of each coordinate with the
 *   Laine-Karras style hash of Burley Sec. 3 (reverse the bits, an addition
 *   and four xor-multiplies by even constants, where output bit k depends
 *   only on input bits <= k, reverse back): every bit is flipped by a hash
 *   of the bits above it, so the scrambled points keep the net's
 *   stratification and each point is uniform on [0,1) (Owen 1995).
 * - Index shuffling (Burley Sec. 4): the sample index itself goes through
 *   a nested uniform scramble, seeded per pixel. The first 2^m indices then
 *   map to one aligned block of 2^m Sobol' indices, itself a (t, m, s)-net,
 *   so every power-of-two prefix of a pixel's samples is stratified while
 *   different pixels use decorrelated points.
 * - Padding (Burley Sec. 4): each decision of a sample takes its own 2D
 *   point set (Sobol' dimensions 0 and 1, a (0, m, 2)-net) with its own
 *   index shuffle and scrambles, so the sets of different decisions are
 *   decorrelated by random permutations (like Latin hypercube sampling
 *   across the sets) while each set keeps its 2D stratification. One
 *   coordinate scrambled twice would not do: its two scrambles share every
 *   digit's structure, a (t = m)-net on the diagonal.
 *
 * Each pixel's points are a randomized QMC set (scramble and shuffle seeded
 * from pixel and seed), so every sample is uniformly distributed and the
 * per-pixel estimate stays unbiased; the points depend on (pixel, sample
 * index, seed) only, so images stay independent of batching and threads.
 */

/// Sobol' dimensions sobolCoordinate() knows (the renderer pads with 2D
/// sets of dimensions 0-1; 2-4 serve wider sets).
constexpr int kSequenceDimensions = 5;

/**
 * The decisions of a sample that take sequence points (Rng::sequence), each
 * a 2D set of its own; the rest of a path uses the PCG stream. Chosen for
 * what decides most of an image's per-pixel variance at low sample counts:
 * where in the pixel the ray goes, how far each channel's first flight
 * reaches, the first tentative collisions' accept tests and the flights
 * after them (in tenuous media a real collision comes after several null
 * ones: Woodcock tracking's majorant exceeds the extinction), and, lit, the
 * camera ray's scatter-or-absorb test and ambient direction. The renderer
 * has no light choice to stratify: every light is sampled at every vertex.
 */
enum SequenceGroup : uint32_t
{
  kGroupPixel = 0,      ///< (x, y) sub-pixel jitter (the pixel's box filter)
  kGroupScatter = 1,    ///< lit: (scatter or absorb, unused) at the camera ray's collision
  kGroupAmbient = 2,    ///< lit: the camera ray's ambient direction (cos theta, azimuth)
  kGroupFlight = 16,    ///< + active slot: (first free flight, unused) of the camera ray
  kGroupCollision = 64, ///< + k: (accept test, next flight) of the ray's k-th tentative collision
};

/// Tentative collisions of the camera ray (counted over its channels) that
/// take sequence points; later ones draw from the PCG stream. More of them
/// lower the error further at a small cost per point (RMSE at 64 spp against
/// independent samples: 0 gives -4% on microscopy and -12% on figure3, 8
/// gives -7% and -16%). Overridable at build time
/// (-DMCVOL_SEQUENCE_COLLISIONS=n) to tune on other devices.
#ifndef MCVOL_SEQUENCE_COLLISIONS
#define MCVOL_SEQUENCE_COLLISIONS 8
#endif
constexpr uint32_t kSequenceCollisions = MCVOL_SEQUENCE_COLLISIONS;

/// Bits reversed (bit 0 becomes bit 31).
MCVOL_FUNC uint32_t reverseBits32(uint32_t x)
{
#if defined(__CUDA_ARCH__)
  return __brev(x);
#else
  x = (x << 16) | (x >> 16);
  x = ((x & 0x00ff00ffu) << 8) | ((x & 0xff00ff00u) >> 8);
  x = ((x & 0x0f0f0f0fu) << 4) | ((x & 0xf0f0f0f0u) >> 4);
  x = ((x & 0x33333333u) << 2) | ((x & 0xccccccccu) >> 2);
  x = ((x & 0x55555555u) << 1) | ((x & 0xaaaaaaaau) >> 1);
  return x;
#endif
}

/**
 * Dimension 1's generator matrix (the Pascal matrix mod 2) times i, digits
 * in bit order (digit j, weight 2^-(j+1), at bit j). By Lucas' theorem the
 * binomial C(k, j) is odd exactly when j's bits are a subset of k's, so
 * digit j is the xor of the index bits k that contain j: a superset sum
 * over 5-bit positions, five shift-mask-xor steps instead of one step per
 * index bit (a shuffled index has all 32 bits in use).
 */
MCVOL_FUNC uint32_t pascalDigits(uint32_t i)
{
  i ^= (i >> 1) & 0x55555555u;
  i ^= (i >> 2) & 0x33333333u;
  i ^= (i >> 4) & 0x0f0f0f0fu;
  i ^= (i >> 8) & 0x00ff00ffu;
  i ^= (i >> 16) & 0x0000ffffu;
  return i;
}

/**
 * Coordinate `dim` (0 to kSequenceDimensions - 1) of Sobol' point `i`, as a
 * 32-bit binary fraction: the xor of the direction numbers v_j of the set
 * bits j of i. v_j = m_j 2^(31-j) for j < s (degree s of the dimension's
 * primitive polynomial x^s + a_1 x^(s-1) + ... + a_(s-1) x + 1), then
 * Bratley and Fox's recurrence
 *   v_j = a_1 v_(j-1) ^ ... ^ a_(s-1) v_(j-s+1) ^ v_(j-s) ^ (v_(j-s) >> s).
 * Joe-Kuo parameters (s, a, m): dim 1 (1, 0, {1}); dim 2 (2, 1, {1, 3});
 * dim 3 (3, 1, {1, 3, 1}); dim 4 (3, 2, {1, 1, 1}).
 */
MCVOL_FUNC uint32_t sobolCoordinate(uint32_t i, int dim)
{
  if (dim == 0)
  {
    return reverseBits32(i); // van der Corput: v_j = 2^(31-j)
  }
  if (dim == 1)
  {
    return reverseBits32(pascalDigits(i));
  }
  int s = 1;
  uint32_t a = 0;
  uint32_t m0 = 1, m1 = 1, m2 = 1;
  switch (dim)
  {
    case 2:
      s = 2;
      a = 1;
      m1 = 3;
      break;
    case 3:
      s = 3;
      a = 1;
      m1 = 3;
      break;
    case 4:
      s = 3;
      a = 2;
      break;
    default:
      break;
  }
  // Window of the last three direction numbers: w1 = v_(j-1), w2 = v_(j-2),
  // w3 = v_(j-3).
  uint32_t w1 = 0, w2 = 0, w3 = 0;
  uint32_t x = 0;
  for (int j = 0; i != 0 && j < 32; ++j, i >>= 1)
  {
    uint32_t v;
    if (j < s)
    {
      v = (j == 0 ? m0 : j == 1 ? m1 : m2) << (31 - j);
    }
    else
    {
      const uint32_t back = s == 1 ? w1 : s == 2 ? w2 : w3; // v_(j-s)
      v = back ^ (back >> s);
      // a_k is bit (s-1-k) of a, the coefficient of v_(j-k), 1 <= k < s.
      if (s >= 2 && ((a >> (s - 2)) & 1u))
      {
        v ^= w1;
      }
      if (s >= 3 && (a & 1u))
      {
        v ^= w2;
      }
    }
    w3 = w2;
    w2 = w1;
    w1 = v;
    if (i & 1u)
    {
      x ^= v;
    }
  }
  return x;
}

/// Burley Sec. 3: a hash-based nested uniform scramble of the bit-reversed
/// value. Output bit k (from the least significant) is input bit k xor a
/// hash of bits 0..k-1 and the seed: adding the seed and xoring with products
/// by even constants carry information only upwards.
MCVOL_FUNC uint32_t laineKarrasPermutation(uint32_t x, uint32_t seed)
{
  x += seed;
  x ^= x * 0x6c50b47cu;
  x ^= x * 0xb82f1e52u;
  x ^= x * 0xc7afe638u;
  x ^= x * 0x8d22f6e6u;
  return x;
}

/// Nested uniform scramble of a 32-bit fraction (bit 31 the most significant
/// digit): each digit is flipped by a hash of the digits above it.
MCVOL_FUNC uint32_t nestedUniformScramble(uint32_t x, uint32_t seed)
{
  return reverseBits32(laineKarrasPermutation(reverseBits32(x), seed));
}

/// 32-bit hash of two words (the SplitMix64 finaliser's mixing, folded).
MCVOL_FUNC uint32_t hashCombine(uint32_t a, uint32_t b)
{
  uint64_t x = (uint64_t(a) << 32) | b;
  x += 0x9E3779B97F4A7C15ull;
  x = (x ^ (x >> 30)) * 0xBF58476D1CE4E5B9ull;
  x = (x ^ (x >> 27)) * 0x94D049BB133111EBull;
  x ^= x >> 31;
  return uint32_t(x ^ (x >> 32));
}

/// The Sobol' index used for sample `sample` of the pixel keyed `key`
/// (Burley Sec. 4: shuffled by a nested uniform scramble of the index), per
/// padded set `group`.
MCVOL_FUNC uint32_t shuffledSobolIndex(uint32_t sample, uint32_t key, uint32_t group = 0)
{
  return nestedUniformScramble(sample, hashCombine(key, 0x68bc21ebu + group * 0x2C1B3C6Du));
}

/**
 * Coordinate `dim` of the scrambled Sobol' point with (already shuffled)
 * index `index`, for the pixel keyed `key`, as 32 bits; `salt` (the padded
 * set) gives independent scrambles.
 */
MCVOL_FUNC uint32_t owenSobolBits(uint32_t index, int dim, uint32_t key, uint32_t salt = 0)
{
  const uint32_t seed = hashCombine(key, uint32_t(dim) * 0x9E3779B9u + salt * 0x85EBCA6Bu + 1u);
  // Dimensions 0 and 1 come out of their generators bit-reversed, which is
  // the order the scramble works in: the reversals cancel.
  if (dim == 0)
  {
    return reverseBits32(laineKarrasPermutation(index, seed));
  }
  if (dim == 1)
  {
    return reverseBits32(laineKarrasPermutation(pascalDigits(index), seed));
  }
  return nestedUniformScramble(sobolCoordinate(index, dim), seed);
}

/// The same as a float in [0, 1 - 2^-24] (24 leading bits: never 1).
MCVOL_FUNC float bitsToUnitFloat(uint32_t x)
{
  return float(x >> 8) * 0x1p-24f;
}

/// Coordinate `coord` (0 or 1) of padded set `group`'s point for sample
/// `sample` of the pixel keyed `key`, in [0, 1).
MCVOL_FUNC float sequencePoint(uint32_t sample, uint32_t key, uint32_t group, int coord)
{
  return bitsToUnitFloat(owenSobolBits(shuffledSobolIndex(sample, key, group), coord, key, group));
}

/// Both coordinates of that point (one index shuffle).
MCVOL_FUNC void sequencePoint2(uint32_t sample, uint32_t key, uint32_t group, float& u0, float& u1)
{
  const uint32_t index = shuffledSobolIndex(sample, key, group);
  u0 = bitsToUnitFloat(owenSobolBits(index, 0, key, group));
  u1 = bitsToUnitFloat(owenSobolBits(index, 1, key, group));
}
} // namespace mcvol
