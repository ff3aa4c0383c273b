// SPDX-License-Identifier: BSD-3-Clause
#pragma once

#include "mcvol/ray/Lighting.h"
#include "mcvol/ray/RayGen.h"
#include "mcvol/ray/Tracking.h"

#include <cstdint>

namespace mcvol
{
/// Added to a lit estimator code (0 or 1) where localKernels() holds: the
/// kernels then compile litPathFrom()'s Local path.
constexpr int kLocalLight = 4;
/// Added to a lit estimator code (0 or 1) where the shadow rays are
/// deferred (deferrableShadows()): renderSample() then records them into its
/// DeferredShadows instead of tracing them.
constexpr int kDeferredShadows = 8;

/// The estimator a render's camera rays use, as the kernels' compile-time
/// code: 0 collision, 1 expected value (lit: traceLitExpected()), 2
/// unbiased march with plain strata, 3 unbiased march with control variates
/// (`controlVariates`: SceneView::marchControlVariates,
/// marchControlVariates()). The last three only when asked for, not
/// optimized and not post-render compositing, and the marches only unlit
/// (the others keep the collision estimator, Estimator's documentation says
/// why). Lit with `local` (localKernels()), not optimized and not
/// post-render compositing: the lit code plus kLocalLight.
MCVOL_FUNC int unlitEstimator(
  Estimator e, BlendMode mode, bool lit, bool optimized, bool controlVariates = false, bool local = false)
{
  if (optimized || mode == BlendMode::Composite)
  {
    return 0;
  }
  if (lit)
  {
    return (e == Estimator::ExpectedValue ? 1 : 0) + (local ? kLocalLight : 0);
  }
  if (e == Estimator::UnbiasedMarch)
  {
    return controlVariates ? 3 : 2;
  }
  return e == Estimator::ExpectedValue ? 1 : 0;
}

/// What one render asks of every pixel.
struct FrameParams
{
  int samplesPerPixel = 1;
  uint32_t firstSample = 0; ///< samples already accumulated
  uint32_t seed = 0;
  Tracker tracker = Tracker::OneDDA;
  bool jitter = true;
  Sampler sampler = Sampler::Sobol;
  Estimator estimator = Estimator::ExpectedValue;
  /// A batch of one-sample pilot images in one CUDA launch
  /// (CUDARenderer::renderPilots), 0 elsewhere: with batchSamples > 0,
  /// blockIdx.z = r x batchSamples + k renders sample k of replicate r
  /// (seed `seed` for r = 0, batchSeed for r = 1) into image z, and
  /// replicate 1 adds its work counters batchCounterOffset further on.
  /// Only the kernels that count work read these (the pilots count).
  int batchSamples = 0;
  uint32_t batchSeed = 0;
  int batchCounterOffset = 0;
};

/**
 * Sample `index` of pixel (x, y), premultiplied RGBA, into `v`; false when
 * the pixel's ray misses the volume's box (the sample is then transparent
 * and `v` is not written). The sample draws from Rng(pixel, index, seed)
 * (and, with Sampler::Sobol, the pixel's scrambled Sobol' point of that
 * sample index), so it depends on nothing but the pixel, the sample index
 * and the seed. Optimized (a compile-time choice, as Lit) tracks through the
 * visibility optimization with the pixel's list `ri`; without it the
 * tracking code is exactly the unoptimized one (the null list folds away).
 * `light` is lightView(s), the view lit paths run in (unlit renders never
 * read it). Unlit (a compile-time choice too, so that each kernel carries
 * only its estimator's code and registers; unlitEstimator() decides it): 1
 * scores unlit camera rays with trackExpected() and lit ones with
 * traceLitExpected(), 2 with trackUnbiasedMarch(), 3 with
 * trackUnbiasedMarch()'s control variates, 0 with the collision estimator;
 * lit, kLocalLight added compiles the light path's Local code, and
 * kDeferredShadows added its Defer code, which records the shadow rays into
 * `defer` (its count 0 on entry) and leaves their terms out of `v`.
 */
template <BlendMode Mode, bool Lit, bool Optimized, int Unlit>
MCVOL_FUNC bool renderSample(const SceneView& s, const SceneView& light, const CameraView& cam, const FrameParams& fp,
  int x, int y, float depth, uint32_t index, RayCounters& c, ShadowCounters& sc, const RayImportance* ri, Vec4f& v,
  DeferredShadows* defer = nullptr)
{
  constexpr bool Local = Lit && (Unlit & kLocalLight) != 0;
  constexpr bool Defer = Lit && (Unlit & kDeferredShadows) != 0;
  constexpr int Code = Unlit & ~(kLocalLight | kDeferredShadows);
  const uint32_t pixel = uint32_t(y) * uint32_t(cam.width) + uint32_t(x);
  Rng rng(pixel, index, fp.seed);
  if (fp.sampler == Sampler::Sobol)
  {
    rng.startSequence(pixel, index, fp.seed);
  }
  float jx = 0.5f, jy = 0.5f;
  if (fp.jitter)
  {
    rng.sequence2(kGroupPixel, jx, jy);
    if (cam.jitterScale != 1.f)
    {
      jx = 0.5f + (jx - 0.5f) * cam.jitterScale;
      jy = 0.5f + (jy - 0.5f) * cam.jitterScale;
    }
  }
  IndexRay ray;
  if (!generateRay(cam, s.volume, float(x) + jx, float(y) + jy, depth, ray))
  {
    return false;
  }
  if (Lit && Code == 1 && !Optimized && Mode != BlendMode::Composite)
  {
    v = traceLitExpected<Mode, Local, Defer>(s, light, fp.tracker, ray.o, ray.d, ray.world, ray.tmax, rng, c, sc, defer);
  }
  else if (Lit)
  {
    v = traceLitSample<Mode, Optimized, Local, Defer>(
      s, light, fp.tracker, ray.o, ray.d, ray.world, ray.tmax, rng, c, sc, ri, defer);
  }
  else if (Code == 1 && !Optimized && Mode != BlendMode::Composite)
  {
    v = trackExpected<Mode>(s, ray.o, ray.d, 0.f, ray.tmax, rng, c);
  }
  else if ((Code == 2 || Code == 3) && !Optimized && Mode != BlendMode::Composite)
  {
    v = trackUnbiasedMarch<Mode, Code == 3>(s, ray.o, ray.d, 0.f, ray.tmax, rng, c);
  }
  else
  {
    v = traceSample<Mode>(s, fp.tracker, ray.o, ray.d, 0.f, ray.tmax, rng, c, ri);
  }
  return true;
}

/**
 * Adds `samplesPerPixel` Monte Carlo samples of pixel (x, y) (renderSample(),
 * sample indices firstSample, firstSample + 1, ...) to the pixel's running
 * sum `sum` one at a time, in double precision (addSample()); since each is
 * added to the sum of all the pixel's earlier samples, the sum does not
 * depend on how the samples were batched into renders. `even` (optional)
 * is the running sum of the samples of even index, the half the error
 * estimate keeps (Accumulator::estimatedMSE). The other parameters are
 * renderSample()'s; Unlit does not take kDeferredShadows here.
 */
template <BlendMode Mode, bool Lit = false, bool Optimized = false, int Unlit = 0>
MCVOL_FUNC void renderPixel(const SceneView& s, const SceneView& light, const CameraView& cam, const FrameParams& fp,
  int x, int y, float depth, RayCounters& c, Vec4d& sum, const RayImportance* imp = nullptr, Vec4d* even = nullptr)
{
  static_assert((Unlit & kDeferredShadows) == 0, "deferred shadow rays are finished by finishDeferredSample()");
  const RayImportance* ri = Optimized ? imp : nullptr;
  ShadowCounters sc;
  for (int k = 0; k < fp.samplesPerPixel; ++k)
  {
    const uint32_t index = fp.firstSample + uint32_t(k);
    Vec4f v;
    if (!renderSample<Mode, Lit, Optimized, Unlit>(s, light, cam, fp, x, y, depth, index, c, sc, ri, v))
    {
      continue;
    }
    addSample(sum, v);
    if (even && (index & 1u) == 0u)
    {
      addSample(*even, v);
    }
  }
}

/**
 * One refinement pass of pixel (x, y)'s importance segments (Lerzer and Dachsbacher,
 * Sec. 5.1-5.2): stratified importance samples along the pixel's centre ray
 * (pass 0 uniform, later passes adaptive) merged into its list by Algorithm
 * 1. Samples draw from their own random stream (sample index `pass` of a
 * seed distinct from the tracking's), so a fixed seed gives the same list
 * whatever the thread count. Returns the new count; when the merged list
 * would not fit, the list is left as it was and `overflow` is set.
 */
MCVOL_FUNC int refineImportance(const SceneView& s, const CameraView& cam, int x, int y, float depth, int pass,
  uint32_t seed, ImportanceSegment* seg, int count, float& total, bool& overflow, RayCounters& c)
{
  const ImportanceView& iv = s.importance;
  overflow = false;
  IndexRay ray;
  if (!generateRay(cam, s.volume, float(x) + 0.5f, float(y) + 0.5f, depth, ray))
  {
    return count;
  }
  const float T = ray.tmax * iv.invLengthUnit;
  const uint32_t pixel = uint32_t(y) * uint32_t(cam.width) + uint32_t(x);
  Rng rng(pixel, uint32_t(pass), seed ^ 0x5bd1e995u);
  const int N = iv.samplesPerPass < kMaxImportanceSamples ? iv.samplesPerPass : kMaxImportanceSamples;
  float pos[kMaxImportanceSamples];
  const int n = importanceSamplePositions(seg, count, T, N, pass, rng, pos);
  ImportanceSegment samples[kMaxImportanceSamples];
  const float toWorld = 1.f / iv.invLengthUnit;
  for (int k = 0; k < n; ++k)
  {
    samples[k].t = pos[k];
    samples[k].length = 0.f;
    samples[k].k = importanceAt(s, ray.o + ray.d * (pos[k] * toWorld));
    samples[k].K = 0.f;
  }
  c.importance += uint32_t(n);
  // Two strata by default: consecutive samples of one importance then always
  // join into one segment.
  const float strata = float(N >= 3 ? N - 2 : N);
  const float d = iv.mergeDistance > 0.f ? iv.mergeDistance : 2.f * T / strata;
  float newTotal = total;
  const int merged = importanceMerge(seg, count, kImportanceCapacity, samples, n, d, T, newTotal);
  if (merged < 0)
  {
    overflow = true;
    return count;
  }
  total = newTotal;
  return merged;
}

/// Samples of even index a render adds to a pixel that had `previous`.
MCVOL_FUNC uint32_t addedEvenSamples(uint32_t previous, int added)
{
  return (previous + uint32_t(added) + 1u) / 2u - (previous + 1u) / 2u;
}

/// Samples of even index among a pixel's first n: 0, 2, 4, ... < n.
MCVOL_FUNC uint32_t evenSampleCount(uint32_t n)
{
  return (n + 1u) / 2u;
}

/// A pixel's running sum before a render: the stored sum of its `previous`
/// samples (4 doubles, RGBA), or zero for a new image (previous 0: the
/// buffer is not read, so a reset needs no clearing) or no buffer (null).
MCVOL_FUNC Vec4d loadSum(const double* stored, uint32_t previous)
{
  Vec4d sum;
  if (stored && previous > 0u)
  {
    sum.r = stored[0];
    sum.g = stored[1];
    sum.b = stored[2];
    sum.a = stored[3];
  }
  return sum;
}

/**
 * Stores a pixel's running sum of `samples` samples (into `stored`, unless
 * null) and its mean, rounded once to float, into `mean`. The image is the
 * sum in double over the sample count: each sample is added to the sum of
 * all that came before it (renderPixel()), so the image keeps converging
 * past 2^24 samples per pixel, where a float sum or a float running mean
 * stops taking small samples (Documentation/user-guide/numerical-limits.md),
 * and it is the same however the samples were batched.
 */
MCVOL_FUNC void storeSum(float* mean, double* stored, const Vec4d& sum, uint32_t samples)
{
  if (stored)
  {
    stored[0] = sum.r;
    stored[1] = sum.g;
    stored[2] = sum.b;
    stored[3] = sum.a;
  }
  const double n = double(samples);
  mean[0] = float(sum.r / n);
  mean[1] = float(sum.g / n);
  mean[2] = float(sum.b / n);
  mean[3] = float(sum.a / n);
}
} // namespace mcvol
