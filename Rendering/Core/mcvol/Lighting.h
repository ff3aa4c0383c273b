// SPDX-License-Identifier: BSD-3-Clause
#pragma once

#include "mcvol/Blend.h"
#include "mcvol/DDA.h"
#include "mcvol/Random.h"
#include "mcvol/Tracking.h"

#include <cmath>

namespace mcvol
{
/**
 * Building blocks of lighting (issue 6): the Henyey-Greenstein phase
 * function and transmittance estimators for shadow rays. Per-ray code, shared
 * by the backends like the trackers.
 */

constexpr float kPi = 3.14159265358979323846f;

/**
 * Henyey-Greenstein phase function, normalised over the sphere, of the angle
 * between the propagation direction before scattering and the direction
 * after it (mu = cos theta; g > 0 scatters forward, g = 0 is isotropic).
 */
MCVOL_FUNC float hgPhase(float mu, float g)
{
  const float denom = 1.f + g * g - 2.f * g * mu;
  return (1.f - g * g) / (4.f * kPi * denom * sqrtf(denom));
}

/// Samples mu = cos theta from Henyey-Greenstein by inverting its CDF, for u
/// in [0, 1); mean mu is g.
MCVOL_FUNC float sampleHGCosine(float g, float u)
{
  if (fabsf(g) < 1e-3f)
  {
    return 1.f - 2.f * u;
  }
  const float s = (1.f - g * g) / (1.f - g + 2.f * g * u);
  const float mu = (1.f + g * g - s * s) / (2.f * g);
  return clampf(mu, -1.f, 1.f);
}

/// A unit vector at angle acos(mu) from the unit vector d, azimuth 2 pi v.
MCVOL_FUNC Vec3f directionAround(Vec3f d, float mu, float v)
{
  // Orthonormal basis around d (Duff et al. 2017, branchless).
  const float sign = d.z >= 0.f ? 1.f : -1.f;
  const float a = -1.f / (sign + d.z);
  const float b = d.x * d.y * a;
  const Vec3f t1(1.f + sign * d.x * d.x * a, sign * b, -sign * d.x);
  const Vec3f t2(b, sign + d.y * d.y * a, -d.y);
  const float sinTheta = sqrtf(fmaxf(0.f, 1.f - mu * mu));
  const float phi = 2.f * kPi * v;
  return t1 * (sinTheta * cosf(phi)) + t2 * (sinTheta * sinf(phi)) + d * mu;
}

/// How a shadow ray estimates transmittance.
enum class ShadowEstimator : int
{
  Ratio = 0, ///< ratio tracking: a smooth estimate in [0, 1]
  Delta = 1  ///< delta tracking: 0 or 1 (the paper's viewer)
};

/// Shadow-ray work (tests and the benchmark read it).
struct ShadowCounters
{
  uint32_t rays = 0;
  uint32_t tentative = 0; ///< tentative collisions along shadow rays
};

/**
 * Transmittance along o + t d, t in [0, tmax] (index space, t in world
 * units, as the trackers' rays), through the listed channels combined by the
 * blend mode (Blend.h: density sums the extinctions, max and mix take the
 * largest). The macrocell majorants bound the combined extinction per cell
 * (their sum, or their largest); cells with majorant 0 cost nothing.
 * Ratio tracking multiplies 1 - sigma / majorant at each tentative
 * collision, with Russian roulette below 0.1 so that the loop ends; delta
 * tracking stops at the first real collision. Both are unbiased.
 */
template <BlendMode Mode>
MCVOL_HOT float shadowTransmittance(const SceneView& s, const int* channels, int count, Vec3f o, Vec3f d, float tmax,
  ShadowEstimator estimator, Rng& rng, ShadowCounters& c)
{
  ++c.rays;
  if (count == 0 || !(tmax > 0.f))
  {
    return 1.f;
  }
  float T = 1.f;
  DDA dda;
  dda.init(s.grid, o, d, 0.f, tmax);
  const int N = s.grid.numChannels;
  float tau = sampleOpticalDepth(rng);
  while (!dda.done)
  {
    const float* maj = s.grid.majorants + dda.cellIndex() * N;
    float m = 0.f;
    for (int i = 0; i < count; ++i)
    {
      const float mi = minf(maj[channels[i]], s.sigmaLimit);
      if (Mode == BlendMode::Density || Mode == BlendMode::Composite)
      {
        m += mi;
      }
      else
      {
        m = mi > m ? mi : m;
      }
    }
    if (m > 0.f)
    {
      float t = dda.t0;
      while (true)
      {
        const float room = (dda.t1 - t) * m;
        if (!(tau < room))
        {
          tau -= room > 0.f ? room : 0.f;
          break;
        }
        t = advance(t, tau / m);
        tau = sampleOpticalDepth(rng);
        ++c.tentative;
        const float sigma = blendedOptics<Mode>(s, channels, count, o + d * t).sigma;
        if (estimator == ShadowEstimator::Delta)
        {
          if (rng.next() * m < sigma)
          {
            return 0.f;
          }
          continue;
        }
        T *= 1.f - minf(sigma / m, 1.f);
        if (T < 0.1f)
        {
          if (rng.next() < 0.5f)
          {
            return 0.f;
          }
          T *= 2.f;
        }
      }
    }
    dda.next();
  }
  return T;
}
} // namespace mcvol
