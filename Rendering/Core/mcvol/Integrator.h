// SPDX-License-Identifier: BSD-3-Clause
#pragma once

#include "mcvol/Lighting.h"
#include "mcvol/RayGen.h"
#include "mcvol/Tracking.h"

#include <cstdint>

namespace mcvol
{
/// What one render asks of every pixel.
struct FrameParams
{
  int samplesPerPixel = 1;
  uint32_t firstSample = 0; ///< samples already accumulated
  uint32_t seed = 0;
  Tracker tracker = Tracker::OneDDA;
  bool jitter = true;
};

/**
 * Sum of `samplesPerPixel` Monte Carlo samples of pixel (x, y), premultiplied
 * RGBA. Sample k of a pixel draws from Rng(pixel, firstSample + k, seed), so
 * the result depends on nothing but the pixel, the sample indices and the seed.
 */
template <BlendMode Mode, bool Lit = false>
MCVOL_FUNC Vec4f renderPixel(
  const SceneView& s, const CameraView& cam, const FrameParams& fp, int x, int y, float depth, RayCounters& c)
{
  ShadowCounters sc;
  Vec4f sum;
  const uint32_t pixel = uint32_t(y) * uint32_t(cam.width) + uint32_t(x);
  for (int k = 0; k < fp.samplesPerPixel; ++k)
  {
    Rng rng(pixel, fp.firstSample + uint32_t(k), fp.seed);
    const float jx = fp.jitter ? rng.next() : 0.5f;
    const float jy = fp.jitter ? rng.next() : 0.5f;
    IndexRay ray;
    if (!generateRay(cam, s.volume, float(x) + jx, float(y) + jy, depth, ray))
    {
      continue;
    }
    const Vec4f v = Lit ? traceLitSample<Mode>(s, fp.tracker, ray.o, ray.d, ray.world, ray.tmax, rng, c, sc)
                        : traceSample<Mode>(s, fp.tracker, ray.o, ray.d, 0.f, ray.tmax, rng, c);
    sum.r += v.r;
    sum.g += v.g;
    sum.b += v.b;
    sum.a += v.a;
  }
  return sum;
}

/// Folds a render's per-pixel sum into the running mean of `previous` samples.
MCVOL_FUNC void accumulate(float* rgba, const Vec4f& sum, uint32_t previous, int added)
{
  const float inv = 1.f / float(previous + uint32_t(added));
  const float keep = float(previous) * inv;
  rgba[0] = rgba[0] * keep + sum.r * inv;
  rgba[1] = rgba[1] * keep + sum.g * inv;
  rgba[2] = rgba[2] * keep + sum.b * inv;
  rgba[3] = rgba[3] * keep + sum.a * inv;
}
} // namespace mcvol
