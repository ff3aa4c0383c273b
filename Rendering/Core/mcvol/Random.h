// SPDX-License-Identifier: BSD-3-Clause
#pragma once

#include "mcvol/Macros.h"
#include "mcvol/Sequence.h"

#include <cstdint>

namespace mcvol
{
/// SplitMix64 finaliser: a bijective 64-bit hash with full avalanche.
MCVOL_FUNC uint64_t splitmix64(uint64_t x)
{
  x += 0x9E3779B97F4A7C15ull;
  x = (x ^ (x >> 30)) * 0xBF58476D1CE4E5B9ull;
  x = (x ^ (x >> 27)) * 0x94D049BB133111EBull;
  return x ^ (x >> 31);
}

/**
 * PCG32 stream keyed by (pixel, sample, seed).
 *
 * Why keyed this way: a pixel's random numbers depend only on which pixel,
 * which sample and which seed, never on the thread, tile or launch order, so
 * an image is bit-reproducible whatever the thread count. (MDWTracker seeds
 * from the thread index, which correlates pixels across blocks.)
 */
class Rng
{
public:
  MCVOL_FUNC Rng(uint32_t pixel, uint32_t sample, uint32_t seed)
  {
    const uint64_t key = splitmix64((uint64_t(seed) << 32) ^ pixel);
    const uint64_t key2 = splitmix64(key ^ (uint64_t(sample) * 0xD1B54A32D192ED03ull));
    this->Inc = (splitmix64(key2 + 1) << 1) | 1u;
    this->State = 0;
    this->nextU32();
    this->State += key2;
    this->nextU32();
  }

  MCVOL_FUNC uint32_t nextU32()
  {
    const uint64_t old = this->State;
    this->State = old * 6364136223846793005ull + this->Inc;
    const uint32_t xorshifted = uint32_t(((old >> 18u) ^ old) >> 27u);
    const uint32_t rot = uint32_t(old >> 59u);
    return (xorshifted >> rot) | (xorshifted << ((~rot + 1u) & 31u));
  }

  /// Uniform in [0, 1 - 2^-24]: never 1, so -log(1 - u) stays finite.
  MCVOL_FUNC float next() { return float(this->nextU32() >> 8) * 0x1p-24f; }

  /**
   * Sampler::Sobol: the leading dimensions (SequenceDimension) of this
   * sample come from the pixel's Owen-scrambled Sobol' points (Sequence.h)
   * until endSequence(); same key as the constructor, so they too depend on
   * nothing but pixel, sample index and seed. Without it leading() and
   * firstAccept() are next(), and the independent sampler's images are
   * unchanged.
   */
  MCVOL_FUNC void startSequence(uint32_t pixel, uint32_t sample, uint32_t seed)
  {
    this->QKey = hashCombine(seed ^ 0x2545F491u, pixel);
    this->QIndex = shuffledSobolIndex(sample, this->QKey);
    this->QAccepted = 0;
    this->QOn = true;
  }

  /// The rest of the path (after the camera ray) draws from the PCG stream.
  MCVOL_FUNC void endSequence() { this->QOn = false; }

  /// Coordinate `dim` of the sample's point (scrambled independently per
  /// `salt`), or the next PCG number when no sequence is on.
  MCVOL_FUNC float leading(int dim, uint32_t salt = 0)
  {
    if (!this->QOn)
    {
      return this->next();
    }
    return bitsToUnitFloat(owenSobolBits(this->QIndex, dim, this->QKey, salt));
  }

  /// The accept test's number of a tentative collision of `channel`: its
  /// first one on the camera ray takes kDimAccept, later ones the PCG stream.
  MCVOL_FUNC float acceptTest(int channel)
  {
    const uint32_t bit = 1u << (uint32_t(channel) & 31u);
    if (!this->QOn || (this->QAccepted & bit))
    {
      return this->next();
    }
    this->QAccepted |= bit;
    return bitsToUnitFloat(owenSobolBits(this->QIndex, kDimAccept, this->QKey, uint32_t(channel)));
  }

private:
  uint64_t State;
  uint64_t Inc;
  uint32_t QIndex = 0;    ///< the pixel's shuffled Sobol' index of this sample
  uint32_t QKey = 0;      ///< the pixel's scramble key
  uint32_t QAccepted = 0; ///< channels whose first accept test was drawn
  bool QOn = false;
};
} // namespace mcvol
