// SPDX-License-Identifier: BSD-3-Clause
#pragma once

#include "mcvol/ray/Macros.h"

#include <cstdint>
#include <cstring>

namespace mcvol
{
/// Native voxel types read in place (no float copy of the data is made).
enum class ScalarType : int
{
  UInt8 = 0,
  Int16 = 1,
  UInt16 = 2,
  Float32 = 3,
  Float64 = 4,
  /// IEEE binary16, for pre-classified (Extinction) channels only: the
  /// pyramid levels' half-precision layout (8 bytes a voxel instead of
  /// 16). Scene::setVolume rejects it for scalar channels.
  Float16 = 5
};

/**
 * What a channel's voxels hold (Kraus and Buerger, Sec. 3.3).
 * - Scalar: one value per voxel, classified after interpolation through the
 *   channel's transfer-function table (post-classification).
 * - Extinction: pre-classified voxels of 4 float32 values (sigma, sigma r,
 *   sigma g, sigma b), or 4 binary16 values times a per-channel scale
 *   (ScalarType::Float16, ChannelSource::scale): extinction per world unit (as the transfer-function
 *   tables hold it) and extinction-weighted linear RGB. Extinction and
 *   extinction-weighted colour are interpolated; the colour at a point is
 *   their ratio (Eq. 18-21). No transfer function is read.
 */
enum class ChannelFormat : int
{
  Scalar = 0,
  Extinction = 1
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

/**
 * Where a pixel's samples draw their random numbers (Sequence.h).
 * - Independent: every number from the PCG stream of (pixel, sample, seed).
 * - Sobol: the leading decisions (sub-pixel position, the camera ray's
 *   first free flight per channel and its first tentative collisions; lit,
 *   the scatter test and ambient direction of its collision) from
 *   Owen-scrambled Sobol' points with per-pixel index shuffling (Burley
 *   2020; SequenceGroup), the rest from the PCG stream. Unbiased as well;
 *   lower error at a given sample count.
 */
enum class Sampler : int
{
  Independent = 0,
  Sobol = 1
};

/**
 * What a camera ray scores. All three are unbiased
 * estimates of the same emission-absorption integral.
 * - Collision: Woodcock tracking to the first real collision, which scores
 *   its colour with alpha 1 (the papers' estimator; the trackers choose
 *   1-DDA or N-DDA).
 * - ExpectedValue: every tentative collision of the summed (density) or
 *   largest (max, mix) majorant scores T * (sigma / majorant) * emission of
 *   the blend there and multiplies the running transmittance T by
 *   1 - sigma / majorant (ratio tracking of the emission term), until T
 *   falls below kRouletteThreshold and Russian roulette ends it; alpha is
 *   1 - T. More work per sample (every active channel is sampled at every
 *   tentative collision, and the ray goes on past the first real one), much
 *   less noise per sample.
 * - UnbiasedMarch: a jittered ray march (RenderSettings::
 *   marchSamplesPerVoxel strata per voxel in non-empty macrocells) scores
 *   the emission, with an unbiased transmittance from a random-order power
 *   series over independent marches (Kettunen et al. 2021;
 *   trackUnbiasedMarch() in Tracking.h). Unbiased; about 2x a ray march's
 *   samples per frame, far less noise per frame where structures are thin
 *   and dense (microscopy), more work where the majorants are sparse.
 * Lit camera rays take ExpectedValue too (traceLitExpected() in
 * Lighting.h: the emission with the expected-value weights, the scattered
 * light at one tentative collision picked by weight) or Collision; UnbiasedMarch
 * lights nothing and runs Collision there. Post-render compositing and the
 * visibility optimization keep the collision estimator whatever is asked
 * (their own estimators apply).
 */
enum class Estimator : int
{
  Collision = 0,
  ExpectedValue = 1,
  UnbiasedMarch = 2
};

/**
 * How a channel is reconstructed between voxels (vtkVolumeProperty's
 * interpolation types, with cubic as VTK_CUBIC_INTERPOLATION).
 * - Nearest: the nearest voxel.
 * - Linear: trilinear interpolation of the 8 surrounding voxels.
 * - Cubic: the uniform cubic B-spline over the 64 surrounding voxels
 *   (Sigg and Hadwiger, GPU Gems 2 ch. 20; not Kraus and Buerger's B-spline
 *   sampling, which is quadratic). It approximates rather than interpolates
 *   (a sample at a voxel centre is
 *   (v_-1 + 4 v_0 + v_+1) / 6 per axis) and is C2 smooth. Its weights are
 *   non-negative and sum to 1, so a sample stays within the range of the
 *   voxels it reads, which keeps the macrocell majorants valid (the
 *   footprint is one voxel wider than trilinear's, and the macrocell ranges
 *   widen with it).
 */
enum class Interpolation : int
{
  Nearest = 0,
  Linear = 1,
  Cubic = 2
};

enum class Backend : int
{
  Auto = 0,
  CPU = 1,
  CUDA = 2
};

/// A type carried as a value, so that a generic lambda can learn it:
/// `[&](auto tag) { using T = typename decltype(tag)::type; ... }`.
template <class T>
struct TypeTag
{
  using type = T;
};

/**
 * The one switch over ScalarType: calls `f(TypeTag<T>{})` with the C++ type
 * that stores a voxel of type `t` (uint8_t, int16_t, uint16_t, float,
 * double) and returns what `f` returns. Every per-type loop (range builds on
 * the host and the device, voxel fetches, uploads) goes through here, so a
 * new scalar type is added in one place. Usable in per-ray code. A value
 * outside the enum visits float; Scene::setVolume rejects such channels, so
 * none reaches the per-ray code.
 */
template <class F>
MCVOL_HOT decltype(auto) visitScalarType(ScalarType t, F&& f)
{
  switch (t)
  {
    case ScalarType::UInt8:
      return f(TypeTag<uint8_t>{});
    case ScalarType::Int16:
      return f(TypeTag<int16_t>{});
    case ScalarType::UInt16:
      return f(TypeTag<uint16_t>{});
    case ScalarType::Float16:
      // Never a scalar channel (setVolume rejects it): pre-classified voxels
      // are read by fetchClassified(). The 2-byte storage type, so that the
      // switch stays complete.
      return f(TypeTag<uint16_t>{});
    case ScalarType::Float32:
      return f(TypeTag<float>{});
    case ScalarType::Float64:
      return f(TypeTag<double>{});
  }
  // Not an enumerator (Scene::setVolume rejects those); a case of its own
  // above keeps the switch a jump table in per-ray code.
  return f(TypeTag<float>{});
}

const char* toString(ScalarType t);
const char* toString(ChannelFormat f);
const char* toString(BlendMode m);
const char* toString(Tracker t);
const char* toString(Sampler s);
const char* toString(Estimator e);
const char* toString(Interpolation i);
const char* toString(Backend b);
int scalarTypeSize(ScalarType t);

/**
 * IEEE binary16 bits to float, exactly: normals, subnormals, signed zeros,
 * infinities and NaN (quiet, its payload kept in the high mantissa bits).
 * Host code (the CPU's reads of half-precision pre-classified voxels; the
 * CUDA backend widens them to float32 on upload). The exponent is rebiased
 * by a multiplication: bits << 13 read as a float is the value times
 * 2^-112, subnormals included.
 */
inline float halfToFloat(uint16_t h)
{
  const uint32_t sign = uint32_t(h & 0x8000u) << 16;
  const uint32_t magnitude = uint32_t(h & 0x7fffu);
  uint32_t bits = magnitude << 13;
  if (magnitude >= 0x7c00u)
  {
    bits |= 0x7f800000u; // Inf or NaN: the float's exponent all ones
  }
  else
  {
    float f;
    std::memcpy(&f, &bits, sizeof f);
    f *= 0x1p112f;
    std::memcpy(&bits, &f, sizeof f);
  }
  bits |= sign;
  float out;
  std::memcpy(&out, &bits, sizeof out);
  return out;
}

/// float to IEEE binary16, rounded to nearest (ties to even); magnitudes of
/// 65520 and above become infinity, NaN stays NaN. halfToFloat(floatToHalf(x))
/// is the binary16 value nearest x (relative error at most 2^-11 for normals,
/// |x| from 2^-14 to 65504).
uint16_t floatToHalf(float x);
} // namespace mcvol
