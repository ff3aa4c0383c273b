// SPDX-License-Identifier: BSD-3-Clause
#pragma once

#include "mcvol/ray/Macros.h"
#include "mcvol/ray/Sequence.h"

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
  /// The stream of state 0 (increment 1); DeferredShadows holds one until
  /// a path's stream is copied in.
  MCVOL_FUNC Rng()
    : State(0)
    , Inc(1)
  {
  }

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
   * Sampler::Sobol: the decisions listed in SequenceGroup take this
   * sample's points of the pixel's Owen-scrambled Sobol' sets (Sequence.h)
   * until endSequence(); keyed like the constructor, so they too depend on
   * nothing but pixel, sample index and seed. Every coordinate serves one
   * decision at most, so a sample's numbers stay independent uniforms.
   * Without a sequence sequence() and collision() are next(), in the order
   * the code drew before, and the independent sampler's images are unchanged.
   */
  MCVOL_FUNC void startSequence(uint32_t pixel, uint32_t sample, uint32_t seed)
  {
    this->QKey = hashCombine(seed ^ 0x2545F491u, pixel);
    this->QSample = sample;
    this->QCollisions = 0;
    this->QOn = true;
  }

  /// The rest of the path (after the camera ray) draws from the PCG stream.
  MCVOL_FUNC void endSequence() { this->QOn = false; }

  /// Coordinate `coord` (0 or 1) of padded set `group`, or the next PCG
  /// number when no sequence is on.
  MCVOL_FUNC float sequence(uint32_t group, int coord = 0)
  {
    if (!this->QOn)
    {
      return this->next();
    }
    return sequencePoint(this->QSample, this->QKey, group, coord);
  }

  /// Both coordinates of padded set `group` (one index shuffle), or the next
  /// two PCG numbers.
  MCVOL_FUNC void sequence2(uint32_t group, float& u0, float& u1)
  {
    if (!this->QOn)
    {
      u0 = this->next();
      u1 = this->next();
      return;
    }
    sequencePoint2(this->QSample, this->QKey, group, u0, u1);
  }

  /// The numbers of a tentative collision: the free flight after it, then
  /// its accept test (this order without a sequence, as before). The first
  /// kSequenceCollisions of the camera ray take set kGroupCollision + k.
  MCVOL_FUNC void collision(float& flight, float& accept)
  {
    if (!this->QOn || this->QCollisions >= kSequenceCollisions)
    {
      flight = this->next();
      accept = this->next();
      return;
    }
    sequencePoint2(this->QSample, this->QKey, kGroupCollision + this->QCollisions++, accept, flight);
  }

private:
  uint64_t State;
  uint64_t Inc;
  uint32_t QSample = 0;     ///< the sample index (each set shuffles it)
  uint32_t QKey = 0;        ///< the pixel's scramble key
  uint32_t QCollisions = 0; ///< tentative collisions that took sets so far
  bool QOn = false;
};
} // namespace mcvol
