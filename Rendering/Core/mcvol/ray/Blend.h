// SPDX-License-Identifier: BSD-3-Clause
#pragma once

#include "mcvol/ray/Sampling.h"

namespace mcvol
{
/**
 * The blend modes' optical model at one point, shared by the Monte Carlo
 * trackers (Tracking.h) and the ray marcher (RayMarch.h), so that each Monte
 * Carlo mode converges to the matching ray-marched image.
 *
 * Per channel n the transfer function gives extinction sigma_n and colour c_n.
 * - Density (Eq. 6/7): sigma = sum_n sigma_n, emission sum_n sigma_n c_n / sigma.
 * - Max (Eq. 8/9): only the channel of largest extinction exists: sigma =
 *   max_n sigma_n, emission its colour.
 * - Mix (Eq. 8/10): sigma = max_n sigma_n, emission sum_n w_n sigma_n c_n / sigma.
 * - Composite: each channel alone (the caller renders them separately).
 */

/// True if channel k (extinction sk) takes precedence over channel n
/// (extinction sn) in max and mix blending: larger extinction wins, ties go
/// to the lower channel index (so equal channels never both vanish).
MCVOL_HOT bool outranks(float sk, int k, float sn, int n)
{
  return sk > sn || (sk == sn && k < n);
}

/// Mix colour from sum_n w_n sigma_n c_n (weighted), sum_n w_n sigma_n
/// (weightedSigma) and max_n sigma_n (maxSigma > 0): the weighted average of
/// the present channels' colours (mixAverage), or Eq. 10. Present channels
/// that all weigh 0 give black either way.
MCVOL_HOT Vec3f mixColour(const BlendView& b, Vec3f weighted, float weightedSigma, float maxSigma)
{
  if (b.mixAverage)
  {
    return weightedSigma > 0.f ? weighted * (1.f / weightedSigma) : Vec3f();
  }
  return weighted * (1.f / maxSigma);
}

/// The optics of channel n at p on the paths most scenes never take, out of
/// line: a pre-classified channel (sampleClassified, any interpolation) or a
/// scalar channel with cubic B-spline interpolation (sampleChannelCubic,
/// then its transfer function).
MCVOL_COLD TFSample coldChannelOptics(const SceneView& s, int n, Vec3f p)
{
  if (s.volume.channels[n].format == ChannelFormat::Extinction)
  {
    return sampleClassified(s.volume, n, p);
  }
  return lookupTF(s.tables, n, sampleChannelCubic(s.volume, n, p));
}

/// One channel's optics at p (extinction clamped to the render's limit, as
/// the trackers clamp it): a scalar channel's interpolated value through its
/// transfer function, or a pre-classified channel's interpolated extinction
/// and extinction-weighted colour (sampleClassified). Every tracker, blend
/// mode, the lighting (extinction gradient) and the extinction-model march
/// read channels through here. Pre-classified channels and cubic
/// interpolation share one out-of-line call (coldChannelOptics), so the
/// render kernels hold as many call sites as without cubic sampling.
MCVOL_HOT TFSample channelOptics(const SceneView& s, int n, Vec3f p)
{
#if defined(__CUDA_ARCH__) && defined(MCVOL_DEVICE_PLAIN_CHANNELS)
  // Device kernels for plain scenes only (Rendering/CUDA/CUDALaunchPlain.cu:
  // scalar channels, linear or nearest interpolation; the launcher checks).
  TFSample t = lookupTF(s.tables, n, sampleChannel(s.volume, n, p));
#else
  TFSample t = s.volume.channels[n].format == ChannelFormat::Extinction || s.volume.cubic
    ? coldChannelOptics(s, n, p)
    : lookupTF(s.tables, n, sampleChannel(s.volume, n, p));
#endif
  t.sigma = minf(t.sigma, s.sigmaLimit);
  return t;
}

/// Extinction and emitted colour (not premultiplied) of the blend at p over
/// the listed channels.
struct PointOptics
{
  float sigma = 0.f;
  Vec3f emission;
};

/// The colours of blendedOptics() as the transfer functions give them.
struct TableColour
{
  MCVOL_FUNC Vec3f operator()(int, Vec3f rgb) const { return rgb; }
};

/// `present`: bit n set for each listed channel n to evaluate; the others
/// are taken as sigma 0 (the unlit estimators pass the channels present in
/// the macrocell, blendMajorant()). `colour(n, c)`: the radiance a unit of
/// channel n's extinction of colour c sends, for density of each channel,
/// for max and mix of the blend's colour with its channel (the lit closed
/// form, UnshadowedOptics in Lighting.h; unlit: c).
template <BlendMode Mode, typename Colour = TableColour>
MCVOL_HOT PointOptics blendedOptics(const SceneView& s, const int* channels, int count, Vec3f p, uint32_t present = ~0u,
  const Colour& colour = Colour())
{
  PointOptics out;
  Vec3f weighted;           // sum of (weight) sigma_n c_n
  float weightedSigma = 0.f; // mix: sum of w_n sigma_n
  float best = -1.f;
  int bestChannel = -1;
  Vec3f bestColour;
  for (int i = 0; i < count; ++i)
  {
    const int n = channels[i];
    if (((present >> n) & 1u) == 0u)
    {
      continue;
    }
    const TFSample t = channelOptics(s, n, p);
    if (Mode == BlendMode::Density || Mode == BlendMode::Composite)
    {
      out.sigma += t.sigma;
      weighted += colour(n, t.rgb) * t.sigma;
      continue;
    }
    if (bestChannel < 0 || outranks(t.sigma, n, best, bestChannel))
    {
      best = t.sigma;
      bestChannel = n;
      bestColour = t.rgb;
    }
    if (Mode == BlendMode::Mix)
    {
      weighted += t.rgb * (t.sigma * s.blend.mixWeights[n]);
      weightedSigma += t.sigma * s.blend.mixWeights[n];
    }
  }
  if (Mode == BlendMode::Density || Mode == BlendMode::Composite)
  {
    out.emission = out.sigma > 0.f ? weighted * (1.f / out.sigma) : Vec3f();
    return out;
  }
  out.sigma = best > 0.f ? best : 0.f;
  if (out.sigma > 0.f)
  {
    out.emission =
      colour(bestChannel, Mode == BlendMode::Max ? bestColour : mixColour(s.blend, weighted, weightedSigma, out.sigma));
  }
  return out;
}
} // namespace mcvol
