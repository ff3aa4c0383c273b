// SPDX-License-Identifier: BSD-3-Clause
#pragma once

#include "mcvol/ray/Blend.h"
#include "mcvol/ray/DDA.h"
#include "mcvol/ray/Importance.h"
#include "mcvol/ray/Random.h"
#include "mcvol/ray/Sampling.h"

#include <cfloat>
#include <cstdint>

namespace mcvol
{
/// Work counters of the rays of one image row at most (32 bits suffice there);
/// backends fold them into 64-bit totals row by row.
struct RayCounters
{
  uint32_t ddaSteps = 0;
  uint32_t tentative = 0;
  uint32_t real = 0;
  uint32_t samples = 0;
  // Lighting (zero whenever lighting is off: the unlit kernels never touch them).
  uint32_t scattering = 0; ///< real collisions that scattered
  uint32_t shadowRays = 0;
  uint32_t gradients = 0; ///< extinction gradients evaluated
  // Visibility optimization (zero whenever it is off).
  uint32_t importance = 0;          ///< importance evaluations
  uint32_t importanceOverflows = 0; ///< light-ray segment lists that did not fit
};

/// Result of tracking one ray: the accepted collision, if any.
struct Hit
{
  float t = FLT_MAX;
  Vec3f rgb;
  int channel = -1;
  MCVOL_FUNC bool found() const { return this->channel >= 0; }
};

/**
 * Null-collision test of channel n at p under the blend mode (Eq. 7 for
 * density; Eq. 8-10 for max and mix, which redefine sigma_a and L_e).
 * `xiMaj` is xi * majorant: a collision is real when it is below the
 * channel's effective extinction. On a real collision `rgb` gets L_e.
 */
/// The visibility optimization's test at a collision that passed without it:
/// still real under mu' = f mu (Lerzer and Dachsbacher, Eq. 8)? The factor f <= 1 scales
/// the blend's extinction and so every channel's alike (colours keep their
/// proportions); `sigma` is the extinction the unoptimized test used.
MCVOL_OUTLINE bool optimizedCollision(
  const SceneView& s, const RayImportance& imp, float t, Vec3f p, float xiMaj, float sigma, RayCounters& c)
{
  ++c.importance;
  return xiMaj < sigma * importanceFactor(s.importance, imp, t, importanceAt(s, p));
}

MCVOL_HOT bool realUnderImportance(
  const SceneView& s, const RayImportance* imp, float t, Vec3f p, float xiMaj, float sigma, RayCounters& c)
{
  return !imp || optimizedCollision(s, *imp, t, p, xiMaj, sigma, c);
}

template <BlendMode Mode>
MCVOL_HOT bool realCollision(const SceneView& s, int n, Vec3f p, float xiMaj, Vec3f& rgb, RayCounters& c,
  const RayImportance* imp = nullptr, float t = 0.f)
{
  const TFSample own = channelOptics(s, n, p);
  ++c.samples;
  // Cheap rejection first: the effective extinction never exceeds sigma_n.
  if (!(xiMaj < own.sigma))
  {
    return false;
  }
  if (Mode == BlendMode::Density || Mode == BlendMode::Composite)
  {
    if (!realUnderImportance(s, imp, t, p, xiMaj, own.sigma, c))
    {
      return false;
    }
    rgb = own.rgb;
    return true;
  }
  // Max and mix: channel n exists at p only if its extinction is the largest
  // (ties go to the lowest channel index, so equal channels do not vanish).
  Vec3f mix = own.rgb * (own.sigma * s.blend.mixWeights[n]);
  float mixSigma = own.sigma * s.blend.mixWeights[n];
  for (int i = 0; i < s.numActive; ++i)
  {
    const int k = s.active[i];
    if (k == n)
    {
      continue;
    }
    const TFSample other = channelOptics(s, k, p);
    ++c.samples;
    if (outranks(other.sigma, k, own.sigma, n))
    {
      return false;
    }
    if (Mode == BlendMode::Mix)
    {
      mix += other.rgb * (other.sigma * s.blend.mixWeights[k]);
      mixSigma += other.sigma * s.blend.mixWeights[k];
    }
  }
  if (!realUnderImportance(s, imp, t, p, xiMaj, own.sigma, c))
  {
    return false;
  }
  // Mix: sum_k w_k sigma_k c_k over sum_k w_k sigma_k, or over max_k sigma_k
  // (Eq. 10; sigma_n is the max).
  rgb = Mode == BlendMode::Max ? own.rgb : mixColour(s.blend, mix, mixSigma, own.sigma);
  return true;
}

/// t + dt, but at least one float step further: a free flight shorter than
/// t's rounding step would otherwise leave t where it was.
MCVOL_HOT float advance(float t, float dt)
{
  const float next = t + dt;
  return next > t ? next : nextafterf(t, 3.4e38f);
}

/// An exponential optical depth -ln(1 - u): the free flight of Eq. 3 (Listing
/// 1) in units of majorant times distance; divided by the majorant it is the
/// distance. Rng::next() never returns 1, so the logarithm is finite.
MCVOL_HOT float sampleOpticalDepth(Rng& rng)
{
  return -logf(1.f - rng.next());
}

/// The same from a given uniform number u in [0, 1).
MCVOL_HOT float opticalDepthOf(float u)
{
  return -logf(1.f - u);
}

/**
 * Woodcock steps of channel n over the segment [t0, tStop] of one macrocell
 * with majorant m (Eq. 3 free flights, Eq. 7 / Listing 2 null-collision
 * test). `tau` is the channel's remaining optical depth: it is consumed by
 * the segment and carried to the next one, so a new free flight is drawn
 * only after a tentative collision. Returns true, with `hit` filled, on a
 * real collision.
 */
template <BlendMode Mode>
MCVOL_HOT bool woodcockSegment(const SceneView& s, int n, Vec3f o, Vec3f d, float t0, float tStop, float m, float& tau,
  Rng& rng, RayCounters& c, Hit& hit, const RayImportance* imp = nullptr)
{
  float t = t0;
  while (true)
  {
    const float room = (tStop - t) * m; // optical depth left in the segment
    if (!(tau < room))
    {
      tau -= room > 0.f ? room : 0.f;
      return false;
    }
    t = advance(t, tau / m);
    float uFlight, uAccept;
    rng.collision(uFlight, uAccept);
    tau = opticalDepthOf(uFlight);
    ++c.tentative;
    Vec3f rgb;
    if (realCollision<Mode>(s, n, o + d * t, uAccept * m, rgb, c, imp, t))
    {
      hit.t = t;
      hit.rgb = rgb;
      hit.channel = n;
      return true;
    }
  }
}

/**
 * Method #2 (Section 4.5, Listing 4): one DDA over the macrocells; in each
 * cell every active channel takes Woodcock steps with its own majorant until
 * it leaves the cell, passes the closest hit so far, or collides. The
 * traversal stops after the first cell with a collision.
 *
 * Each channel carries its sampled optical depth across cells instead of
 * drawing a new free flight at every cell entry (Listing 4 restarts at
 * dda.cellEntryT()). Both are exact because the exponential is memoryless;
 * carrying it costs one logarithm per tentative collision rather than one per
 * channel per cell, which is most of the work in sparse regions.
 */
template <BlendMode Mode>
MCVOL_HOT Hit track1DDA(const SceneView& s, Vec3f o, Vec3f d, float tmin, float tmax, Rng& rng, RayCounters& c,
  const RayImportance* imp = nullptr)
{
  Hit hit;
  hit.t = tmax;
  if (s.numActive == 0)
  {
    return hit; // nothing visible: no traversal (as N-DDA)
  }
  float tau[kMaxChannels];
  for (int i = 0; i < s.numActive; ++i)
  {
    // The first free flight: a set per active channel under Sampler::Sobol
    // (next() otherwise, in the same order as before). Keyed by the place in
    // the active list, not the channel's index, so that a transparent
    // channel (never active) changes no image, with either sampler.
    tau[i] = opticalDepthOf(rng.sequence(kGroupFlight + uint32_t(i)));
  }
  DDA dda;
  dda.init(s.grid, o, d, tmin, tmax);
  const int N = s.grid.numChannels;
  while (!dda.done)
  {
    ++c.ddaSteps;
    const float* maj = s.grid.majorants + dda.cellIndex() * N;
    for (int i = 0; i < s.numActive; ++i)
    {
      const int n = s.active[i];
      const float m = minf(maj[n], s.sigmaLimit);
      if (m <= 0.f)
      {
        continue; // empty for this channel: no sampling at all
      }
      woodcockSegment<Mode>(s, n, o, d, dda.t0, minf(dda.t1, hit.t), m, tau[i], rng, c, hit, imp);
    }
    if (hit.found())
    {
      ++c.real;
      break;
    }
    dda.next();
  }
  return hit;
}

/// Woodcock tracking of active channel `slot` (s.active[slot]) alone over
/// [tmin, tmax] (used by N-DDA for each channel and by post-render
/// compositing); the optical depth is carried across cells as in track1DDA.
template <BlendMode Mode>
MCVOL_HOT bool trackChannel(const SceneView& s, int slot, Vec3f o, Vec3f d, float tmin, float tmax, Rng& rng,
  RayCounters& c, Hit& hit, const RayImportance* imp = nullptr)
{
  const int n = s.active[slot];
  DDA dda;
  dda.init(s.grid, o, d, tmin, tmax);
  const int N = s.grid.numChannels;
  float tau = opticalDepthOf(rng.sequence(kGroupFlight + uint32_t(slot)));
  while (!dda.done)
  {
    ++c.ddaSteps;
    const float m = minf(s.grid.majorants[dda.cellIndex() * N + n], s.sigmaLimit);
    if (m > 0.f && woodcockSegment<Mode>(s, n, o, d, dda.t0, dda.t1, m, tau, rng, c, hit, imp))
    {
      return true;
    }
    dda.next();
  }
  return false;
}

/**
 * Method #1 (Section 4.4, Listing 3): a separate DDA traversal per channel,
 * each ending at the closest collision found so far; the closest wins.
 */
template <BlendMode Mode>
MCVOL_HOT Hit trackNDDA(const SceneView& s, Vec3f o, Vec3f d, float tmin, float tmax, Rng& rng, RayCounters& c,
  const RayImportance* imp = nullptr)
{
  Hit hit;
  hit.t = tmax;
  for (int i = 0; i < s.numActive; ++i)
  {
    trackChannel<Mode>(s, i, o, d, tmin, hit.t, rng, c, hit, imp);
  }
  if (hit.found())
  {
    ++c.real;
  }
  return hit;
}

/**
 * Post-render compositing: every channel rendered on its own, the
 * premultiplied results added (alpha combines as 1 - prod(1 - alpha_n), which
 * "any channel collided" estimates without bias since channels draw
 * independent random numbers).
 */
MCVOL_HOT Vec4f trackComposite(const SceneView& s, Vec3f o, Vec3f d, float tmin, float tmax, Rng& rng, RayCounters& c,
  const RayImportance* imp = nullptr)
{
  Vec4f out;
  for (int i = 0; i < s.numActive; ++i)
  {
    Hit hit;
    if (trackChannel<BlendMode::Composite>(s, i, o, d, tmin, tmax, rng, c, hit, imp))
    {
      ++c.real;
      out.r += hit.rgb.x;
      out.g += hit.rgb.y;
      out.b += hit.rgb.z;
      out.a = 1.f;
    }
  }
  return out;
}

/// The active channels present in a macrocell: bit n of `mask` for channel n
/// (kMaxChannels is 32), and how many.
struct CellChannels
{
  uint32_t mask = 0;
  int count = 0;
};

/// The blend's majorant in macrocell `cell`: the sum of the active channels'
/// majorants (density) or their maximum (max and mix, whose extinction is the
/// largest channel's), each at most sigmaLimit. In `present`: the active
/// channels whose majorant in the cell is not 0. The others have sigma 0 at
/// every point the cell's samples read (the majorants cover the cell's
/// voxels and an apron, cellVoxelBounds()), so the unlit estimators, which
/// evaluate every active channel at a point, skip them there
/// (blendedOptics()'s mask): the same optics, without the work for channels
/// absent from the cell.
template <BlendMode Mode>
MCVOL_HOT float blendMajorant(const SceneView& s, int64_t cell, CellChannels& present)
{
  const float* maj = s.grid.majorants + cell * s.grid.numChannels;
  float M = 0.f;
  present = CellChannels();
  for (int i = 0; i < s.numActive; ++i)
  {
    const int n = s.active[i];
    const float m = minf(maj[n], s.sigmaLimit);
    M = Mode == BlendMode::Density ? M + m : maxf(M, m);
    if (m > 0.f)
    {
      present.mask |= 1u << n;
      ++present.count;
    }
  }
  return M;
}

/// Transmittance below which the expected-value estimator plays Russian
/// roulette: it goes on with probability T / kRouletteThreshold (T raised to
/// the threshold) or stops (T = 0), which keeps it unbiased.
constexpr float kRouletteThreshold = 0.05f;

/**
 * The expected-value estimator's traversal of one camera ray over [tmin,
 * tmax], with `optics(p, present)` the blend's extinction sigma(p) and the
 * radiance c(p) a unit of it sends to the camera (a PointOptics: sigma and
 * emission): premultiplied RGB and alpha = 1 - T. One DDA over the
 * macrocells; in each cell the tentative collisions follow the sum of the
 * active channels' majorants M (density) or their maximum (max and mix,
 * whose extinction is the largest channel's), with the optical depth
 * carried across cells. At a collision at p with running transmittance T:
 * w = sigma / M, L += T w c, T *= 1 - w (ratio tracking). Given the
 * collisions so far, E[T w c] is T c sigma / M and E[1 - w] is
 * 1 - sigma / M, so L estimates the integral of T sigma c without bias, and
 * the roulette keeps it so.
 */
template <BlendMode Mode, typename Optics>
MCVOL_HOT Vec4f trackExpectedOf(
  const SceneView& s, Vec3f o, Vec3f d, float tmin, float tmax, Rng& rng, RayCounters& c, const Optics& optics)
{
  Vec4f out;
  if (s.numActive == 0)
  {
    return out;
  }
  Vec3f L;
  float T = 1.f;
  float tau = opticalDepthOf(rng.sequence(kGroupFlight));
  DDA dda;
  dda.init(s.grid, o, d, tmin, tmax);
  while (!dda.done && T > 0.f)
  {
    ++c.ddaSteps;
    CellChannels present;
    float M = blendMajorant<Mode>(s, dda.cellIndex(), present);
    if (M > 0.f)
    {
      M = maxf(M, s.minRate); // a denser tentative process stays unbiased
    }
    float t = dda.t0;
    while (M > 0.f)
    {
      const float room = (dda.t1 - t) * M; // optical depth left in the cell
      if (!(tau < room))
      {
        tau -= room > 0.f ? room : 0.f;
        break;
      }
      t = advance(t, tau / M);
      float uFlight, uUnused;
      rng.collision(uFlight, uUnused);
      tau = opticalDepthOf(uFlight);
      ++c.tentative;
      // Every channel present in the cell is sampled: the blend's extinction
      // and emission at p (choosing one channel per collision with
      // probability m_n / M instead cost 2-3x more time to the same error on
      // the CPU).
      const PointOptics po = optics(o + d * t, present.mask);
      c.samples += uint32_t(present.count);
      const float w = minf(po.sigma / M, 1.f);
      L += po.emission * (T * w);
      T *= 1.f - w;
      if (T < kRouletteThreshold)
      {
        if (rng.next() * kRouletteThreshold >= T)
        {
          T = 0.f;
          break;
        }
        T = kRouletteThreshold;
      }
    }
    dda.next();
  }
  return premultipliedRGBA(L, T);
}

/// The blend's emission-absorption optics at a point (blendedOptics()), as
/// trackExpectedOf() takes them.
template <BlendMode Mode>
struct EmissionOptics
{
  const SceneView& s;
  MCVOL_HOT PointOptics operator()(Vec3f p, uint32_t present) const
  {
    return blendedOptics<Mode>(s, s.active, s.numActive, p, present);
  }
};

/**
 * The expected-value estimator (Estimator::ExpectedValue) of one camera ray
 * over [tmin, tmax], unlit: trackExpectedOf() with the blend's emission
 * (blendedOptics(), the ray marcher's model), so that L estimates the
 * emission integral.
 */
template <BlendMode Mode>
MCVOL_HOT Vec4f trackExpected(const SceneView& s, Vec3f o, Vec3f d, float tmin, float tmax, Rng& rng, RayCounters& c)
{
  return trackExpectedOf<Mode>(s, o, d, tmin, tmax, rng, c, EmissionOptics<Mode>{ s });
}

/// Highest order of the unbiased march's power series (Estimator::UnbiasedMarch).
constexpr int kMarchMaxOrder = 16;
/// Probability that the unbiased march's series goes on from order k >= 1 to
/// k + 1. Order 1 is always taken (marchOrderProbability()).
constexpr float kMarchOrderContinue = 0.25f;
/// P(K > k | K >= k) of the unbiased march's series order K: 1 for the first
/// order, kMarchOrderContinue after. To first order in the marches' errors, the
/// series replaces the pivot march's error by the first correction march's,
/// and a first order taken with probability q adds (2 / q - 2) times that
/// variance: with q = 0.5 for every order the transmittance's variance is
/// about 3x that of one march; with q = 1 it is about 1x, for 1.33
/// correction marches per ray on average instead of 1 (with
/// kMarchOrderContinue 0.25). The higher orders are second order in the
/// errors, so a low kMarchOrderContinue costs little variance (0.1, 0.25
/// and 0.5 give the same error on the microscopy scene).
MCVOL_HOST_DEVICE inline float marchOrderProbability(int k)
{
  return k == 0 ? 1.f : kMarchOrderContinue;
}
/// Strata of the unbiased march per unit of majorant optical depth, at least:
/// keeps h sigma small where the extinction is high.
constexpr float kMarchMajorantStrata = 0.25f;

/// Strata of the unbiased march in a non-empty macrocell of length `len` and
/// blend majorant M at `rate` strata per unit length (SceneView::marchRate):
/// ceil(len max(rate, kMarchMajorantStrata M)), at least 1, at most 65536.
MCVOL_HOST_DEVICE inline int marchStrata(float len, float M, float rate)
{
  const float want = len * maxf(rate, M * kMarchMajorantStrata);
  return want < 1.f ? 1 : (want < 65536.f ? int(ceilf(want)) : 65536);
}

/// One order l of the unbiased march's power series at a point: the term
/// times (pivot - X_l(t)) / ((l + 1) P(K > l | K >= l)), where X_l(t) is
/// march l's sum `Xl` plus its point in this stratum `dl` if that point lies
/// before t (`before`); then the point joins the sum. Returns the new term
/// (the caller adds it to the series).
MCVOL_HOST_DEVICE inline float marchSeriesStep(float term, float pivot, float& Xl, float dl, bool before, int l)
{
  term *= (pivot - (before ? Xl + dl : Xl)) / (float(l + 1) * marchOrderProbability(l));
  Xl += dl;
  return term;
}

/// The unbiased march's power series at the ray's end: sum over k <= K of
/// prod_{l<=k} (pivot - X[l]) / ((l + 1) P(K > l | K >= l)).
MCVOL_HOST_DEVICE inline float marchSeriesEnd(const float* X, float pivot, int K)
{
  float series = 1.f;
  float term = 1.f;
  for (int l = 0; l < K; ++l)
  {
    term *= (pivot - X[l]) / (float(l + 1) * marchOrderProbability(l));
    series += term;
  }
  return series;
}

/// The unbiased march's Russian roulette (as trackExpected()'s) on the
/// estimate exp(logW - tau): below `threshold` the ray goes on with
/// probability estimate / threshold, its weight raised to the threshold, or
/// stops (returns true).
MCVOL_HOT bool marchRoulette(float& logW, float tau, Rng& rng, float threshold)
{
  const float est = expf(logW - tau);
  if (est < threshold)
  {
    if (rng.next() * threshold >= est)
    {
      return true;
    }
    logW = logf(threshold) + tau;
  }
  return false;
}

/// Roulette threshold of the unbiased march with control variates, lower
/// than kRouletteThreshold: once the control variates have taken out the
/// strata's noise, the roulette's is what is left. A ray that survives it
/// carries its weight raised to the threshold, so its variance is up to
/// about threshold times the emission still ahead. On the microscopy scene
/// (pixel centres, one sample, 1 stratum per voxel) 0.005 instead of 0.05
/// lowers one sample's MSE by about a third, for about 6% more strata per
/// ray.
constexpr float kControlRouletteThreshold = 0.005f;

/// Walks the unbiased march's macrocells along the ray (one DDA): for every
/// non-empty one [a, b] (blend majorant M > 0; empty cells have sigma = 0
/// and no strata), `cell(a, b, n, h, present)` with its n strata of length h
/// (marchStrata()) and the channels present in it (blendMajorant()). Stops
/// where `cell` returns true.
template <BlendMode Mode, typename Cell>
MCVOL_HOT void forEachMarchCell(const SceneView& s, Vec3f o, Vec3f d, float tmin, float tmax, RayCounters& c, Cell&& cell)
{
  DDA dda;
  dda.init(s.grid, o, d, tmin, tmax);
  while (!dda.done)
  {
    ++c.ddaSteps;
    CellChannels present;
    const float M = blendMajorant<Mode>(s, dda.cellIndex(), present);
    if (M > 0.f)
    {
      const int n = marchStrata(dda.t1 - dda.t0, M, s.marchRate);
      if (cell(dda.t0, dda.t1, n, (dda.t1 - dda.t0) / float(n), present))
      {
        return;
      }
    }
    dda.next();
  }
}

/**
 * The unbiased march with control variates (Estimator::UnbiasedMarch where
 * SceneView::marchControlVariates): the strata of trackUnbiasedMarch(), and
 * in each stratum [s0, s1] of length h the point optics at both ends (the
 * end shared with the next stratum), which define
 * - sigma~(t): sigma interpolated linearly between the ends, tau~ its exact
 *   integral (a trapezoid per stratum, quadratic inside one) and
 *   T~ = exp(-tau~);
 * - the control variate g(t) = cbar sigma~(t) T~(t), cbar the ends' mean
 *   colour, whose integral over the stratum is cbar (T~(s0) - T~(s1)): the
 *   ray marcher's compositing of a stratum, added deterministically.
 * What is left to chance is the residual. The emission adds
 * h (sigma(t) c(t) T^(t) - g(t)) at the jittered point t = s0 + u0 h, and
 * T^(t) is trackUnbiasedMarch()'s power series with the pivot tau~(t) and
 * the correction marches replaced by tau~(t) + R_l(t), R_l the sum of
 * h (sigma - sigma~) at march l's points before t (each an unbiased
 * estimate of tau(t) - tau~(t)): T^ = T~(t) sum_k prod_{l<=k} (-R_l(t)) /
 * (l P(K >= l)). Every term is an unbiased estimate (the end points are not
 * random; u0 and the v_l are independent), so the sum is; where sigma and
 * the colour are close to linear across a stratum the residuals, and with
 * them the noise, are small. It costs one more lookup per stratum (the
 * end), about 3.3 instead of 2.3. Russian roulette on T~.
 */
template <BlendMode Mode>
MCVOL_HOT Vec4f trackControlMarch(const SceneView& s, Vec3f o, Vec3f d, float tmin, float tmax, float u0,
  const float* v, int K, Rng& rng, RayCounters& c)
{
  float R[kMarchMaxOrder];
  for (int l = 0; l < K; ++l)
  {
    R[l] = 0.f;
  }
  float tau = 0.f;  // tau~ at the last stratum's end
  float logW = 0.f; // roulette weight, as a logarithm
  bool stopped = false;
  Vec3f L;
  float tEnd = -1.f; // where the last non-empty cell ended, and its optics there
  PointOptics pEnd;
  forEachMarchCell<Mode>(s, o, d, tmin, tmax, c, [&](float a, float b, int n, float h, const CellChannels& present) {
    const uint32_t mask = present.mask;
    const uint32_t count = uint32_t(present.count);
    PointOptics e0 = pEnd;
    if (tEnd != a)
    {
      e0 = blendedOptics<Mode>(s, s.active, s.numActive, o + d * a, mask);
      c.samples += count;
    }
    for (int j = 0; j < n; ++j)
    {
      const float s0 = a + float(j) * h;
      ++c.tentative;
      const PointOptics e1 = blendedOptics<Mode>(s, s.active, s.numActive, o + d * (j + 1 == n ? b : s0 + h), mask);
      const PointOptics po = blendedOptics<Mode>(s, s.active, s.numActive, o + d * (s0 + u0 * h), mask);
      c.samples += 2u * count;
      const float sA = minf(e0.sigma, s.sigmaLimit);
      const float dS = minf(e1.sigma, s.sigmaLimit) - sA;
      float series = 1.f;
      float term = 1.f;
      for (int l = 0; l < K; ++l)
      {
        const PointOptics pl = blendedOptics<Mode>(s, s.active, s.numActive, o + d * (s0 + v[l] * h), mask);
        c.samples += count;
        // The residual against the linear sigma~: the series of
        // (tau~ - (tau~ + R_l)) = -R_l, i.e. pivot 0 over the sums R.
        const float r = h * (minf(pl.sigma, s.sigmaLimit) - (sA + dS * v[l]));
        term = marchSeriesStep(term, 0.f, R[l], r, v[l] < u0, l);
        series += term;
      }
      const float tauEnd = tau + h * (sA + 0.5f * dS);
      const Vec3f cbar = (e0.emission + e1.emission) * 0.5f;
      const float Tt = expf(logW - (tau + h * u0 * (sA + 0.5f * dS * u0)));
      L += cbar * (expf(logW - tau) - expf(logW - tauEnd));
      L += po.emission * (h * minf(po.sigma, s.sigmaLimit) * Tt * series) - cbar * (h * (sA + dS * u0) * Tt);
      tau = tauEnd;
      e0 = e1;
      if (marchRoulette(logW, tau, rng, kControlRouletteThreshold))
      {
        stopped = true;
        return true;
      }
    }
    pEnd = e0;
    tEnd = b;
    return false;
  });
  return premultipliedRGBA(L, stopped ? 0.f : expf(logW - tau) * marchSeriesEnd(R, 0.f, K));
}

/**
 * The unbiased-march estimator (Estimator::UnbiasedMarch) of one camera ray
 * over [tmin, tmax], unlit: premultiplied RGB and alpha = 1 - T, like
 * trackExpected(), but with stratified (jittered) samples instead of the
 * majorant's Poisson process, and an unbiased transmittance after Kettunen
 * et al. 2021 ("An unbiased ray-marching transmittance estimator").
 * - Strata: every non-empty macrocell [a, b] of the DDA (blend majorant M, as
 *   trackExpected) is cut into n equal strata of length h, n = ceil((b - a)
 *   max(marchRate, kMarchMajorantStrata M)) (marchRate: RenderSettings::
 *   marchSamplesPerVoxel per voxel length); empty cells (M = 0, so sigma =
 *   0) have none.
 * - March 0 puts one point at offset u0 in every stratum (one jitter per
 *   ray): it scores the emission h sigma(t) c(t) T^(t) there and sums
 *   X0 = sum h sigma, which E_u0 makes an unbiased quadrature of the
 *   emission integral given unbiased T^(t).
 * - T^(t): with the pivot P = X0 before t + u0 h sigma(t) (any value
 *   independent of the other marches will do), exp(-tau) =
 *   exp(-P) sum_k (P - tau)^k / k!, and (P - tau)^k is estimated without
 *   bias by prod_{l<=k} (P - X_l(t)), X_l(t) the optical depth of march l (its
 *   own offset v_l, one point per stratum, a point scored only where it lies
 *   before t) up to t, an unbiased estimate of tau(t). The order K is random,
 *   at least 1, P(K >= k) = kMarchOrderContinue^(k - 1) (see
 *   marchOrderProbability()), each term divided by that, up to
 *   kMarchMaxOrder (16: the terms left out, |P - tau|^17 / 17! and smaller,
 *   are below 4e-7 for |P - tau| <= 3, and K reaches 16 once in 4^15 rays).
 * Unbiased, but not bounded: a sample's T^ may be negative or above 1
 * where the marches disagree (sharp features thinner than a stratum); the
 * mean converges to the emission-absorption integral. Russian roulette on
 * exp(-X0) (kept as a log weight) ends the ray as in trackExpected().
 * Control (a compile-time choice: the kernels that run the plain strata
 * contain none of its code; unlitEstimator() code 3, from
 * kMarchControlVariateRate strata per voxel at pixel centres) hands the ray,
 * with its random numbers drawn, to trackControlMarch().
 */
template <BlendMode Mode, bool Control = false>
MCVOL_HOT Vec4f trackUnbiasedMarch(
  const SceneView& s, Vec3f o, Vec3f d, float tmin, float tmax, Rng& rng, RayCounters& c)
{
  if (s.numActive == 0)
  {
    return Vec4f();
  }
  const float u0 = rng.sequence(kGroupFlight);
  int K = 0;
  float v[kMarchMaxOrder];
  while (K < kMarchMaxOrder && rng.next() < marchOrderProbability(K))
  {
    v[K++] = rng.next();
  }
  if constexpr (Control)
  {
    return trackControlMarch<Mode>(s, o, d, tmin, tmax, u0, v, K, rng, c);
  }
  float X[kMarchMaxOrder];
  for (int l = 0; l < K; ++l)
  {
    X[l] = 0.f;
  }
  float X0 = 0.f;
  float logW = 0.f; // roulette weight, as a logarithm
  bool stopped = false;
  Vec3f L;
  forEachMarchCell<Mode>(s, o, d, tmin, tmax, c, [&](float a, float, int n, float h, const CellChannels& present) {
    const uint32_t mask = present.mask;
    const uint32_t count = uint32_t(present.count);
    for (int j = 0; j < n; ++j)
    {
      const float s0 = a + float(j) * h;
      ++c.tentative;
      const PointOptics po = blendedOptics<Mode>(s, s.active, s.numActive, o + d * (s0 + u0 * h), mask);
      const float sig0 = minf(po.sigma, s.sigmaLimit);
      c.samples += count;
      const float pivot = X0 + u0 * h * sig0;
      float series = 1.f;
      float term = 1.f;
      for (int l = 0; l < K; ++l)
      {
        const PointOptics pl = blendedOptics<Mode>(s, s.active, s.numActive, o + d * (s0 + v[l] * h), mask);
        c.samples += count;
        term = marchSeriesStep(term, pivot, X[l], h * minf(pl.sigma, s.sigmaLimit), v[l] < u0, l);
        series += term;
      }
      L += po.emission * (h * sig0 * expf(logW - pivot) * series);
      X0 += h * sig0;
      if (marchRoulette(logW, X0, rng, kRouletteThreshold))
      {
        stopped = true;
        return true;
      }
    }
    return false;
  });
  return premultipliedRGBA(L, stopped ? 0.f : expf(logW - X0) * marchSeriesEnd(X, X0, K));
}

/// One Monte Carlo sample of a ray: premultiplied RGB and alpha (1 if the
/// path collided, else 0).
template <BlendMode Mode>
MCVOL_HOT Vec4f traceSample(const SceneView& s, Tracker tracker, Vec3f o, Vec3f d, float tmin, float tmax, Rng& rng,
  RayCounters& c, const RayImportance* imp = nullptr)
{
  if (Mode == BlendMode::Composite)
  {
    return trackComposite(s, o, d, tmin, tmax, rng, c, imp);
  }
  const Hit hit = tracker == Tracker::OneDDA ? track1DDA<Mode>(s, o, d, tmin, tmax, rng, c, imp)
                                             : trackNDDA<Mode>(s, o, d, tmin, tmax, rng, c, imp);
  Vec4f out;
  if (hit.found())
  {
    out.r = hit.rgb.x;
    out.g = hit.rgb.y;
    out.b = hit.rgb.z;
    out.a = 1.f;
  }
  return out;
}

MCVOL_HOT Vec4f traceSample(
  const SceneView& s, Tracker tracker, Vec3f o, Vec3f d, float tmin, float tmax, Rng& rng, RayCounters& c)
{
  switch (s.blend.mode)
  {
    case BlendMode::Max:
      return traceSample<BlendMode::Max>(s, tracker, o, d, tmin, tmax, rng, c);
    case BlendMode::Mix:
      return traceSample<BlendMode::Mix>(s, tracker, o, d, tmin, tmax, rng, c);
    case BlendMode::Composite:
      return traceSample<BlendMode::Composite>(s, tracker, o, d, tmin, tmax, rng, c);
    case BlendMode::Density:
    default:
      return traceSample<BlendMode::Density>(s, tracker, o, d, tmin, tmax, rng, c);
  }
}
} // namespace mcvol
