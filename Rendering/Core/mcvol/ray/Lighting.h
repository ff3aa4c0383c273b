// SPDX-License-Identifier: BSD-3-Clause
#pragma once

#include "mcvol/ray/Blend.h"
#include "mcvol/ray/DDA.h"
#include "mcvol/ray/Importance.h"
#include "mcvol/ray/Random.h"
#include "mcvol/ray/ShadowCache.h"
#include "mcvol/ray/Tracking.h"

#include <cmath>

namespace mcvol
{
/**
 * Building blocks of lighting: the Henyey-Greenstein phase
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
  Delta = 1  ///< delta tracking: 0 or 1 (Sahistan et al.'s viewer)
};

/// Shadow-ray work (tests and the benchmark read it).
struct ShadowCounters
{
  uint32_t rays = 0;
  uint32_t tentative = 0;           ///< tentative collisions along shadow rays
  uint32_t importance = 0;          ///< importance evaluations of optimized shadow rays
  uint32_t importanceOverflows = 0; ///< light-ray lists that did not fit (ray left unoptimized)
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
  ShadowEstimator estimator, Rng& rng, ShadowCounters& c, const RayImportance* imp = nullptr)
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
        float sigma = blendedOptics<Mode>(s, channels, count, o + d * t).sigma;
        if (imp && sigma > 0.f)
        {
          // Ratio or delta tracking through mu' (Lerzer and Dachsbacher, Sec. 5.3).
          ++c.importance;
          sigma *= lightRayImportanceFactor(s.importance, *imp, t, importanceAt(s, o + d * t));
        }
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

/**
 * The transmittance of a ray to a light: optimized through a fresh segment
 * list when the visibility optimization covers light rays (Lerzer and
 * Dachsbacher, Sec. 5.3; every connection to a light, at every scattering vertex: Sec. 5.4,
 * option 2), else the plain estimate. A list that would overflow leaves that
 * ray unoptimized, counted (the mapper reports it with the camera rays'
 * overflows).
 */
template <BlendMode Mode, bool Optimized = true>
MCVOL_HOT float optimizedShadow(
  const SceneView& s, Vec3f x, Vec3f d, float tmax, ShadowEstimator est, Rng& rng, ShadowCounters& sc)
{
  // Optimized false: a kernel that renders without the optimization (its
  // light rays never have one) and so carries none of its code.
  if (Optimized && s.importance.enabled && s.importance.lightRays && tmax > 0.f)
  {
    ImportanceSegment seg[kImportanceCapacity];
    RayImportance ri;
    if (buildLightRayImportance(s, x, d, tmax, rng, seg, ri, sc.importance))
    {
      return shadowTransmittance<Mode>(s, s.active, s.numActive, x, d, tmax, est, rng, sc, &ri);
    }
    ++sc.importanceOverflows;
  }
  return shadowTransmittance<Mode>(s, s.active, s.numActive, x, d, tmax, est, rng, sc);
}

/// 3x3 row-major matrix times vector.
MCVOL_FUNC Vec3f mul3(const float* m, Vec3f v)
{
  return Vec3f(
    m[0] * v.x + m[1] * v.y + m[2] * v.z, m[3] * v.x + m[4] * v.y + m[5] * v.z, m[6] * v.x + m[7] * v.y + m[8] * v.z);
}

/// Transposed 3x3 row-major matrix times vector.
MCVOL_FUNC Vec3f mul3T(const float* m, Vec3f v)
{
  return Vec3f(
    m[0] * v.x + m[3] * v.y + m[6] * v.z, m[1] * v.x + m[4] * v.y + m[7] * v.z, m[2] * v.x + m[5] * v.y + m[8] * v.z);
}

/// Distance (world units) from index point x to the volume box along the
/// index direction d (the image of a unit world direction); 0 if outside.
MCVOL_FUNC float boxExit(const VolumeView& vol, Vec3f x, Vec3f d)
{
  float t0 = 0.f, t1 = 3.4e38f;
  return intersectBox(vol.boxLo, vol.boxHi, x, d, t0, t1) ? t1 : 0.f;
}

/**
 * Whether this compilation carries the lighting across a piece's boundary
 * (a light path that leaves the piece for its stand-in,
 * SceneView::outside). The plain kernels' device code does not
 * (CUDARenderKernels.h): a second shadow march and a second tracking take
 * the lit kernels from about 150 to 225 registers per thread (ptxas
 * --resource-usage, sm_90) and spill the max and mix ones. They still
 * render an exact stand-in (SceneView::outsideExact), whose paths move
 * into it at their first vertex and never cross a boundary; the launcher
 * sends a scene with a coarse stand-in to the general kernels.
 */
#if defined(__CUDA_ARCH__) && defined(MCVOL_DEVICE_PLAIN_CHANNELS)
constexpr bool kStandInCode = false;
#else
constexpr bool kStandInCode = true;
#endif

/**
 * The transmittance of the part of a light ray beyond this piece
 * (SceneView::outside): the ray from index point x along d leaves the
 * piece's box at tPiece (boxExit) and reaches the light at tLight (world
 * units; 3.4e38 for a directional light or the environment); the stand-in
 * covers [tPiece, tLight] up to its own box. The piece's box is convex, so
 * the ray never comes back into the piece. 1 without a stand-in (one
 * process: nothing is read, no random number is drawn).
 */
template <BlendMode Mode>
MCVOL_HOT float outsideShadow(const SceneView& s, Vec3f x, Vec3f d, float tPiece, float tLight,
  ShadowEstimator estimator, Rng& rng, ShadowCounters& c)
{
  if (!kStandInCode || !s.outside || !(tLight > tPiece))
  {
    return 1.f;
  }
  const SceneView& o = *s.outside;
  const Vec3f xo = toOutside(s, x);
  const Vec3f dO = toOutsideDirection(s, d);
  const float tEnd = minf(boxExit(o.volume, xo, dO), tLight);
  if (!(tEnd > tPiece))
  {
    return 1.f;
  }
  return shadowTransmittance<Mode>(o, o.active, o.numActive, xo + dO * tPiece, dO, tEnd - tPiece, estimator, rng, c);
}

/**
 * Gradient of the blend's extinction at index point p, in world units
 * (central differences one voxel apart, mapped by the transpose of the
 * world-to-index matrix).
 */
template <BlendMode Mode>
MCVOL_HOT Vec3f extinctionGradient(const SceneView& s, const int* channels, int count, Vec3f p, RayCounters& c)
{
  ++c.gradients;
  Vec3f g;
  for (int a = 0; a < 3; ++a)
  {
    Vec3f lo = p, hi = p;
    lo[a] -= 1.f;
    hi[a] += 1.f;
    g[a] =
      0.5f * (blendedOptics<Mode>(s, channels, count, hi).sigma - blendedOptics<Mode>(s, channels, count, lo).sigma);
  }
  return mul3T(s.lighting.toIndex, g);
}

/**
 * Scattering function at a scattering vertex: Henyey-Greenstein plus, with
 * gradient shading, the Blinn-Phong term of Lerzer and Dachsbacher,
 * Section 3, scaled by the gradient magnitude: |grad| (H . N)^n (N . wl)_+,
 * with N = -grad / |grad| (pointing out of denser material) and H the half vector of the light
 * direction wl and the direction back to the viewer -w.
 */
MCVOL_HOT float scatterFunction(
  const LightingView& L, float g, Vec3f w, Vec3f wl, bool gradient, Vec3f grad, float gradLen)
{
  float f = hgPhase(dot(w, wl), g);
  if (gradient && gradLen > 0.f)
  {
    const Vec3f n = grad * (-1.f / gradLen);
    Vec3f h = wl - w;
    const float hl = length(h);
    const float nl = dot(n, wl);
    if (hl > 0.f && nl > 0.f)
    {
      h = h * (1.f / hl);
      const float nh = fmaxf(0.f, dot(n, h));
      f += gradLen * powf(nh, L.shininess) * nl;
    }
  }
  return f;
}

/// The way from index point x to a light (towardsLight()).
struct LightDirection
{
  Vec3f wl;              ///< unit world direction towards the light
  Vec3f dl;              ///< its index-space image, per unit of world length
  float dist = 3.4e38f;  ///< world distance to a point light (3.4e38 for a directional one)
  float falloff = 1.f;   ///< 1 / dist^2 for a point light
};

/// The way from index point x to light l of L. False where x is at a point
/// light (no direction: the light adds nothing there).
MCVOL_HOT bool towardsLight(const LightingView& L, int l, Vec3f x, LightDirection& out)
{
  if (L.lightType[l] == 0)
  {
    out.wl = L.lightVector[l];
    out.dl = mul3(L.toIndex, out.wl);
    return true;
  }
  const Vec3f toLight = mul3(L.toIndex, L.lightVector[l]) + L.indexOffset - x; // index space
  const Vec3f worldVec = mul3(L.toWorld, toLight);
  out.dist = length(worldVec);
  if (!(out.dist > 0.f))
  {
    return false;
  }
  out.wl = worldVec * (1.f / out.dist);
  out.dl = toLight * (1.f / out.dist);
  out.falloff = 1.f / (out.dist * out.dist);
  return true;
}

/**
 * Whether every light path of `L` ends at the camera ray's collision: no
 * shadow rays (none asked for, or every shadow cached: LightingView::
 * cachedOnly) and one scattering vertex. Its radiance is then a function
 * of that point alone, so the lit kernels that leave the other rays' code
 * out (litPathFrom()'s Local) render it, with the same random numbers and
 * the same image as the full path.
 */
MCVOL_FUNC bool localLighting(const LightingView& L)
{
  return L.enabled && (!L.shadows || L.cachedOnly) && L.maxDepth <= 1;
}

/// Most shadow rays one deferred scattering vertex holds (DeferredShadows):
/// a light's and the ambient light's.
constexpr int kDeferredRays = 2;

/**
 * The shadow rays of a lit sample's scattering vertex, recorded instead of
 * traced (litPathFrom()'s Defer), and what the sample needs to be finished
 * by finishDeferredSample(). The rays draw from the path's stream as it
 * stands at the first of them, in the order the traced path draws, and
 * their terms are added in its order too: the finished sample is the traced
 * one bit for bit. On the GPU the few pixels whose camera ray scatters then
 * trace their shadow rays in full warps of their own, and the camera rays'
 * kernel carries no shadow-ray code (CUDARenderKernels.h).
 */
struct DeferredShadows
{
  Rng rng;            ///< the path's stream at its first shadow ray
  Vec4f sample;       ///< the sample without the rays' terms
  Vec3f x;            ///< the vertex, index space
  int count = 0;      ///< rays recorded
  uint32_t pixel = 0; ///< the pixel the sample belongs to (row-major)
  Vec3f dir[kDeferredRays];
  float tmax[kDeferredRays];
  Vec3f scale[kDeferredRays]; ///< the path's throughput times the light's radiance
  float f[kDeferredRays];     ///< the scatter function towards the light
  float falloff[kDeferredRays];
  float weight[kDeferredRays]; ///< the light's selection weight
};

/**
 * Whether the lit paths of view `s` can defer their shadow rays
 * (DeferredShadows): shadows on, one scattering vertex, no stand-in of
 * other pieces, no visibility optimization of light rays, at most
 * kDeferredRays rays per vertex, and with ambient light the Sobol' sampler,
 * which draws the ambient direction from its own set: the independent
 * sampler would draw it from the stream the light's shadow ray draws from
 * before it.
 */
MCVOL_FUNC bool deferrableShadows(const SceneView& s, Sampler sampler)
{
  const LightingView& L = s.lighting;
  if (!L.enabled || !L.shadows || L.cachedOnly || L.maxDepth > 1 || s.outside ||
    (s.importance.enabled && s.importance.lightRays))
  {
    return false;
  }
  const bool ambient = L.ambient.x > 0.f || L.ambient.y > 0.f || L.ambient.z > 0.f;
  if (ambient && sampler != Sampler::Sobol)
  {
    return false;
  }
  return (L.sampleOneLight ? 1 : L.numLights) + (ambient ? 1 : 0) <= kDeferredRays;
}

/**
 * A light's term of the radiance at a scattering vertex: `scale` (the path's
 * throughput times the light's radiance) times the scatter function f, the
 * transmittance T, the falloff and the light's selection weight, in this
 * order wherever it is computed, so that a deferred shadow ray adds what a
 * traced one adds.
 */
MCVOL_FUNC Vec3f shadowedLight(Vec3f scale, float f, float T, float falloff, float weight)
{
  return scale * (f * T * falloff * weight);
}

/// Records a shadow ray of the vertex x into `d` (litPathFrom()'s Defer).
/// deferrableShadows() keeps the count within kDeferredRays.
MCVOL_FUNC void recordShadowRay(
  DeferredShadows& d, const Rng& rng, Vec3f x, Vec3f dir, float tmax, Vec3f scale, float f, float falloff, float weight)
{
  if (d.count >= kDeferredRays)
  {
    return;
  }
  if (d.count == 0)
  {
    d.rng = rng;
    d.x = x;
  }
  const int i = d.count++;
  d.dir[i] = dir;
  d.tmax[i] = tmax;
  d.scale[i] = scale;
  d.f[i] = f;
  d.falloff[i] = falloff;
  d.weight[i] = weight;
}

/**
 * The lit path from a real collision `hit` of the ray o + t d (index space;
 * `w` its unit world direction): the collision scatters with probability
 * albedo_n of its channel n and otherwise absorbs, emitting the blend's
 * colour when `emitFirst` (the expected-value estimator has scored that
 * emission already). At a scattering vertex the path's throughput takes
 * the blend's colour, each light is sampled (next-event estimation with a
 * shadow ray) and the ambient environment through one phase-sampled
 * direction (its phase value over its pdf is 1); the path then continues in
 * a phase-sampled direction, tracked with the collision estimator, up to
 * maxDepth scattering events, with Russian roulette from the third. Returns
 * the radiance. Optimized: the render runs the visibility optimization
 * (only then can a light ray have one, optimizedShadow()). `light` is
 * lightView(s), the view the path runs in. Local (a compile-time choice,
 * for scenes where localLighting() holds): the same path without the code
 * of the rays it never casts there, the tracking of scattered rays and the
 * shadow rays, which would otherwise hold registers in every lit kernel.
 * Defer (for scenes where deferrableShadows() holds): the same path with its
 * shadow rays recorded into `defer` instead of traced, and their terms left
 * out of the radiance (finishDeferredShadows() adds them). scatterWeight > 0:
 * the first collision scatters (no albedo test) with that throughput, the
 * expected-value estimator's vertex (traceLitExpected()).
 */
template <BlendMode Mode, bool Optimized, bool Local = false, bool Defer = false>
MCVOL_HOT Vec3f litPathFrom(const SceneView& s, const SceneView& light, Tracker tracker, Vec3f o, Vec3f d, Vec3f w,
  Hit hit, bool emitFirst, Rng& rng, RayCounters& c, ShadowCounters& sc, DeferredShadows* defer = nullptr,
  float scatterWeight = 0.f)
{
  const ShadowEstimator est =
    s.lighting.shadowEstimator == 1 ? ShadowEstimator::Delta : ShadowEstimator::Ratio;
  Vec3f radiance;
  const float first = scatterWeight > 0.f ? scatterWeight : 1.f;
  Vec3f throughput(first, first, first);
  // The view the path is in: this piece, or, once a scattered ray has left
  // the piece and collided beyond it, the stand-in of the whole volume
  // (SceneView::outside), whose own outside is null; with an exact
  // stand-in, the stand-in from the start.
  const SceneView* v = &light;
  if (s.outside && s.outsideExact)
  {
    // `light` is the exact stand-in, which holds this piece as it is: the
    // whole path runs in it, one march per ray, the same expectation (the
    // stand-in's hit point is the piece's, t in world units along either
    // direction).
    o = toOutside(s, o);
    d = toOutsideDirection(s, d);
  }
  for (int depth = 0;; ++depth)
  {
    if (!Local && !Defer && depth > 0)
    {
      // The visibility optimization acts on the camera ray only (its segment
      // list belongs to the pixel).
      const float tmax = boxExit(v->volume, o, d);
      hit = tracker == Tracker::OneDDA ? track1DDA<Mode>(*v, o, d, 0.f, tmax, rng, c)
                                       : trackNDDA<Mode>(*v, o, d, 0.f, tmax, rng, c);
      if (kStandInCode && !hit.found() && v->outside)
      {
        // A scattered ray that leaves the piece goes on through the stand-in
        // (camera rays stay in the piece: the pieces' images are composited).
        const SceneView& os = *v->outside;
        const Vec3f oo = toOutside(*v, o);
        const Vec3f od = toOutsideDirection(*v, d);
        const float tEnd = boxExit(os.volume, oo, od);
        if (tEnd > tmax)
        {
          hit = tracker == Tracker::OneDDA ? track1DDA<Mode>(os, oo, od, tmax, tEnd, rng, c)
                                           : trackNDDA<Mode>(os, oo, od, tmax, tEnd, rng, c);
          if (hit.found())
          {
            v = &os;
            o = oo;
            d = od;
          }
        }
      }
      if (!hit.found())
      {
        break; // escaped: the environment was counted at the vertices
      }
    }
    const LightingView& L = v->lighting;
    const Vec3f x = o + d * hit.t;
    // Scatter or absorb: a set of its own at the camera ray's collision
    // under Sampler::Sobol (next() otherwise, as before).
    if ((depth > 0 || !(scatterWeight > 0.f)) && !(rng.sequence(kGroupScatter) < L.albedo[hit.channel]))
    {
      if (depth > 0 || emitFirst)
      {
        radiance += throughput * hit.rgb; // absorbed: emits
      }
      break;
    }
    ++c.scattering;
    throughput = throughput * hit.rgb;
    const float g = L.anisotropy[hit.channel];
    Vec3f grad;
    float gradLen = 0.f;
    if (L.gradientShading)
    {
      grad = extinctionGradient<Mode>(*v, v->active, v->numActive, x, c);
      gradLen = length(grad);
    }
    // Every light, or one chosen by its share of the radiance and weighted
    // by the inverse of that share (the same expectation, one shadow ray).
    int lightBegin = 0;
    int lightEnd = L.numLights;
    float lightWeight = 1.f;
    if (L.sampleOneLight)
    {
      const float u = rng.next();
      int pick = 0;
      while (pick + 1 < L.numLights && !(u < L.lightCdf[pick]))
      {
        ++pick;
      }
      lightBegin = pick;
      lightEnd = L.lightPdf[pick] > 0.f ? pick + 1 : pick;
      lightWeight = L.lightPdf[pick] > 0.f ? 1.f / L.lightPdf[pick] : 0.f;
    }
    for (int l = lightBegin; l < lightEnd; ++l)
    {
      LightDirection ld;
      if (!towardsLight(L, l, x, ld))
      {
        continue;
      }
      const Vec3f dl = ld.dl;
      const float dist = ld.dist;
      const float falloff = ld.falloff;
      const float f = scatterFunction(L, g, w, ld.wl, L.gradientShading, grad, gradLen);
      if (!(f > 0.f))
      {
        continue;
      }
      float T = 1.f;
      if (L.shadows && shadowCached(L, l))
      {
        // Looked up, no ray: the cache belongs to the view the path started
        // in, which is the only view that has one (no stand-in).
        T = cachedTransmittance(L, l, x);
      }
      else if (Defer && L.shadows)
      {
        ++c.shadowRays;
        recordShadowRay(*defer, rng, x, dl, minf(boxExit(v->volume, x, dl), dist), throughput * L.lightRadiance[l], f,
          falloff, lightWeight);
        continue;
      }
      else if (!Local && L.shadows)
      {
        ++c.shadowRays;
        const float tPiece = boxExit(v->volume, x, dl);
        T = optimizedShadow<Mode, Optimized>(*v, x, dl, minf(tPiece, dist), est, rng, sc);
        if (T > 0.f)
        {
          T *= outsideShadow<Mode>(*v, x, dl, tPiece, dist, est, rng, sc);
        }
      }
      radiance += shadowedLight(throughput * L.lightRadiance[l], f, T, falloff, lightWeight);
    }
    if (L.ambient.x > 0.f || L.ambient.y > 0.f || L.ambient.z > 0.f)
    {
      // The camera ray's vertex: a 2D set (next() otherwise, as before).
      float u0, u1;
      rng.sequence2(kGroupAmbient, u0, u1);
      const Vec3f wa = directionAround(w, sampleHGCosine(g, u0), u1);
      if (Defer && L.shadows)
      {
        // Its term is the scale times T (shadowedLight() with f, falloff
        // and weight 1), as below.
        ++c.shadowRays;
        const Vec3f da = mul3(L.toIndex, wa);
        recordShadowRay(*defer, rng, x, da, boxExit(v->volume, x, da), throughput * L.ambient, 1.f, 1.f, 1.f);
      }
      else
      {
        float T = 1.f;
        if (!Local && L.shadows)
        {
          ++c.shadowRays;
          const Vec3f da = mul3(L.toIndex, wa);
          const float tPiece = boxExit(v->volume, x, da);
          T = optimizedShadow<Mode, Optimized>(*v, x, da, tPiece, est, rng, sc);
          if (T > 0.f)
          {
            T *= outsideShadow<Mode>(*v, x, da, tPiece, 3.4e38f, est, rng, sc);
          }
        }
        radiance += throughput * L.ambient * T;
      }
    }
    // From here on the path draws from the PCG stream.
    rng.endSequence();
    if (Local || Defer || depth + 1 >= L.maxDepth)
    {
      break;
    }
    if (depth >= 2)
    {
      const float q = clampf(fmaxf(throughput.x, fmaxf(throughput.y, throughput.z)), 0.05f, 1.f);
      if (!(rng.next() < q))
      {
        break;
      }
      throughput = throughput * (1.f / q);
    }
    w = directionAround(w, sampleHGCosine(g, rng.next()), rng.next());
    d = mul3(L.toIndex, w);
    o = x;
  }
  return radiance;
}

/**
 * The radiance a deferred vertex's shadow rays add (DeferredShadows), in
 * view `s` (no stand-in: deferrableShadows()): each ray's transmittance
 * from d.rng, in the order recorded, times its term.
 */
template <BlendMode Mode>
MCVOL_HOT Vec3f finishDeferredShadows(const SceneView& s, DeferredShadows& d, ShadowCounters& sc)
{
  const ShadowEstimator est = s.lighting.shadowEstimator == 1 ? ShadowEstimator::Delta : ShadowEstimator::Ratio;
  Vec3f radiance;
  for (int i = 0; i < d.count; ++i)
  {
    const float T = shadowTransmittance<Mode>(s, s.active, s.numActive, d.x, d.dir[i], d.tmax[i], est, d.rng, sc);
    radiance += shadowedLight(d.scale[i], d.f[i], T, d.falloff[i], d.weight[i]);
  }
  return radiance;
}

/// The sample of a deferred vertex with its shadow rays' radiance added: the
/// sample the path would have returned with the rays traced.
template <BlendMode Mode>
MCVOL_HOT Vec4f finishDeferredSample(const SceneView& s, DeferredShadows& d)
{
  ShadowCounters sc;
  const Vec3f radiance = finishDeferredShadows<Mode>(s, d, sc);
  Vec4f v = d.sample;
  v.r += radiance.x;
  v.g += radiance.y;
  v.b += radiance.z;
  return v;
}

/// Moves the shadow rays' importance counts into the ray counters.
MCVOL_FUNC void foldShadowCounters(RayCounters& c, ShadowCounters& sc)
{
  c.importance += sc.importance;
  c.importanceOverflows += sc.importanceOverflows;
  sc.importance = 0;
  sc.importanceOverflows = 0;
}

/**
 * One lit Monte Carlo sample with the collision estimator (Lerzer and
 * Dachsbacher Eq. 1-2 with the paper's multi-density tracking): the camera
 * path is tracked as in the unlit case to its first real collision, from
 * which litPathFrom() scatters or absorbs. `w` is the ray's unit world
 * direction, `d` its index-space image.
 */
template <BlendMode Mode, bool Optimized = false, bool Local = false, bool Defer = false>
MCVOL_HOT Vec4f traceLitSample(const SceneView& s, const SceneView& light, Tracker tracker, Vec3f o, Vec3f d, Vec3f w,
  float tmax, Rng& rng, RayCounters& c, ShadowCounters& sc, const RayImportance* imp = nullptr,
  DeferredShadows* defer = nullptr);

/**
 * Lighting under post-render compositing: each active channel lit as if it
 * were alone (its own emission, scattering and shadows), the premultiplied
 * results added. Alpha estimates 1 - prod(1 - alpha_n) as "some channel's
 * camera ray collided", which holds only when the channels' samples are
 * independent: they draw from the PCG stream, not from one shared Sobol'
 * point (whose sets are keyed by the place in the active list, the same
 * place 0 for every channel alone).
 */
template <bool Optimized>
MCVOL_HOT Vec4f traceLitComposite(const SceneView& s, Tracker tracker, Vec3f o, Vec3f d, Vec3f w, float tmax, Rng& rng,
  RayCounters& c, ShadowCounters& sc, const RayImportance* imp)
{
  rng.endSequence();
  OneChannelView one(s);
  Vec4f out;
  for (int i = 0; i < s.numActive; ++i)
  {
    const SceneView& alone = one.alone(s.active[i]);
    const Vec4f v =
      traceLitSample<BlendMode::Density, Optimized>(alone, lightView(alone), tracker, o, d, w, tmax, rng, c, sc, imp);
    out.r += v.r;
    out.g += v.g;
    out.b += v.b;
    out.a = fmaxf(out.a, v.a);
  }
  return out;
}

template <BlendMode Mode, bool Optimized, bool Local, bool Defer>
MCVOL_HOT Vec4f traceLitSample(const SceneView& s, const SceneView& light, Tracker tracker, Vec3f o, Vec3f d, Vec3f w,
  float tmax, Rng& rng, RayCounters& c, ShadowCounters& sc, const RayImportance* imp, DeferredShadows* defer)
{
  if (Mode == BlendMode::Composite)
  {
    return traceLitComposite<Optimized>(s, tracker, o, d, w, tmax, rng, c, sc, imp);
  }
  Vec4f out;
  const Hit hit = tracker == Tracker::OneDDA ? track1DDA<Mode>(s, o, d, 0.f, tmax, rng, c, imp)
                                             : trackNDDA<Mode>(s, o, d, 0.f, tmax, rng, c, imp);
  if (hit.found())
  {
    const Vec3f radiance =
      litPathFrom<Mode, Optimized, Local, Defer>(s, light, tracker, o, d, w, hit, true, rng, c, sc, defer);
    out = Vec4f{ radiance.x, radiance.y, radiance.z, 1.f };
  }
  foldShadowCounters(c, sc);
  return out;
}

/// A lit point's optics for the expected-value estimator: the blend's
/// extinction, its scattering coefficient, the colour its absorbed share
/// emits, and (max and mix) the channel and colour of its real collision.
struct LitPointOptics
{
  float sigma = 0.f;
  float scatter = 0.f; ///< sum_n sigma_n albedo_n (density); albedo times sigma of the blend's channel (max, mix)
  Vec3f absorbed;      ///< sum_n sigma_n (1 - albedo_n) c_n / sigma (density); (1 - albedo) c of the blend (max, mix)
  int channel = -1;    ///< max, mix: the channel of largest extinction where sigma > 0 (realCollision())
  Vec3f rgb;           ///< max, mix: the blend's colour there
};

/**
 * litPointOptics: the blend at p as blendedOptics() (Blend.h) sees it, with
 * each channel's albedo, over the channels in `present`.
 */
template <BlendMode Mode>
MCVOL_HOT LitPointOptics litPointOptics(const SceneView& s, Vec3f p, uint32_t present)
{
  const LightingView& L = s.lighting;
  LitPointOptics out;
  Vec3f weighted;
  Vec3f absorbed;
  float weightedSigma = 0.f;
  float best = -1.f;
  int bestChannel = -1;
  Vec3f bestColour;
  for (int i = 0; i < s.numActive; ++i)
  {
    const int n = s.active[i];
    if (((present >> n) & 1u) == 0u)
    {
      continue;
    }
    const TFSample t = channelOptics(s, n, p);
    if (Mode == BlendMode::Density || Mode == BlendMode::Composite)
    {
      out.sigma += t.sigma;
      out.scatter += t.sigma * L.albedo[n];
      absorbed += t.rgb * (t.sigma * (1.f - L.albedo[n]));
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
    out.absorbed = out.sigma > 0.f ? absorbed * (1.f / out.sigma) : Vec3f();
    return out;
  }
  out.sigma = best > 0.f ? best : 0.f;
  if (out.sigma > 0.f)
  {
    const Vec3f colour = Mode == BlendMode::Max ? bestColour : mixColour(s.blend, weighted, weightedSigma, out.sigma);
    out.absorbed = colour * (1.f - L.albedo[bestChannel]);
    out.scatter = out.sigma * L.albedo[bestChannel];
    out.channel = bestChannel;
    out.rgb = colour;
  }
  return out;
}

/**
 * The channel that scatters at p, chosen with uniform u: for density, channel
 * n with probability sigma_n albedo_n / sum_m sigma_m albedo_m, one pass over
 * the channels (u rescaled to the part of [0, 1) left after each decision);
 * for max and mix the blend's real-collision channel. Channel -1 where
 * nothing scatters.
 */
template <BlendMode Mode>
MCVOL_HOT Hit scatteringChannelAt(const SceneView& s, Vec3f p, float u)
{
  Hit h;
  if (Mode == BlendMode::Density || Mode == BlendMode::Composite)
  {
    float sum = 0.f;
    for (int i = 0; i < s.numActive; ++i)
    {
      const int n = s.active[i];
      const TFSample t = channelOptics(s, n, p);
      const float wn = t.sigma * s.lighting.albedo[n];
      if (!(wn > 0.f))
      {
        continue;
      }
      sum += wn;
      const float share = wn / sum;
      if (u < share)
      {
        h.channel = n;
        h.rgb = t.rgb;
        u = u / share;
      }
      else
      {
        u = (u - share) / (1.f - share);
      }
    }
    return h;
  }
  const LitPointOptics po = litPointOptics<Mode>(s, p, ~0u);
  h.channel = po.channel;
  h.rgb = po.rgb;
  return h;
}

/**
 * The light arriving at index point x and scattered towards the camera
 * (world direction w: -w towards the eye) by a Henyey-Greenstein phase of
 * anisotropy g, without shadow rays: every light's radiance times its phase
 * value, falloff and, with cached shadows (LightingView::cachedOnly), its
 * cached transmittance, plus the ambient light (its phase integral is 1).
 * The expected value over litPathFrom()'s choice of one light
 * (LightingDesc::sampleOneLight) is this sum.
 */
MCVOL_HOT Vec3f unshadowedRadiance(const LightingView& L, float g, Vec3f w, Vec3f x)
{
  Vec3f r = L.ambient;
  for (int l = 0; l < L.numLights; ++l)
  {
    LightDirection ld;
    if (towardsLight(L, l, x, ld))
    {
      const float T = L.shadows ? cachedTransmittance(L, l, x) : 1.f;
      r += L.lightRadiance[l] * (hgPhase(dot(w, ld.wl), g) * ld.falloff * T);
    }
  }
  return r;
}

/**
 * Where the expected-value estimator of lit camera rays scores the light a
 * point scatters in closed form (traceLitExpected()): under localLighting()
 * (no shadows, one scattering vertex), without gradient shading (whose
 * gradient would cost six lookups of every channel a collision), and for
 * density blending with one anisotropy over the active channels (the
 * scattered light is then sum_n sigma_n albedo_n c_n times one radiance).
 * Sets `g` to that anisotropy (density) and `uniform` to whether every
 * active channel has it.
 */
MCVOL_HOT bool closedFormScattering(const SceneView& s, BlendMode mode, float& g, bool& uniform)
{
  const LightingView& L = s.lighting;
  if (!localLighting(L) || L.gradientShading || s.numActive == 0)
  {
    return false;
  }
  g = L.anisotropy[s.active[0]];
  uniform = true;
  for (int i = 1; i < s.numActive; ++i)
  {
    uniform = uniform && L.anisotropy[s.active[i]] == g;
  }
  return uniform || (mode != BlendMode::Density && mode != BlendMode::Composite);
}

/// closedFormScattering() without its anisotropy.
MCVOL_HOT bool closedFormScattering(const SceneView& s, BlendMode mode)
{
  float g = 0.f;
  bool uniform = false;
  return closedFormScattering(s, mode, g, uniform);
}

/**
 * Whether the lit kernels compiled for localLighting() (kLocalLight,
 * litPathFrom()'s and traceLitExpected()'s Local) render view `s` with
 * estimator `e`: the collision estimator's always, the expected-value
 * estimator's where it scores the scattered light in closed form
 * (closedFormScattering()), the only code its Local kernels carry, so that
 * they hold the registers of the unlit traversal. A local scene the closed
 * form does not cover (gradient shading, density with per-channel
 * anisotropy) runs the full lit kernels with the expected-value estimator.
 */
MCVOL_HOT bool localKernels(const SceneView& s, BlendMode mode, Estimator e)
{
  return localLighting(s.lighting) && (e != Estimator::ExpectedValue || closedFormScattering(s, mode));
}

/**
 * The radiance a unit of extinction of channel n and colour c sends to the
 * camera without shadows (blendedOptics()'s colour): the absorbed share's
 * emission plus the scattered share's light, c ((1 - albedo_n) +
 * albedo_n L_in), L_in = unshadowedRadiance(): `in`, or where `perChannel`
 * (max and mix with point lights or per-channel anisotropy: one call a
 * point) that of channel n's anisotropy at p.
 */
struct UnshadowedColour
{
  const LightingView& L;
  Vec3f in;
  Vec3f w;
  Vec3f p;
  bool perChannel;
  MCVOL_HOT Vec3f operator()(int n, Vec3f c) const
  {
    const Vec3f lin = perChannel ? unshadowedRadiance(L, L.anisotropy[n], w, p) : in;
    const float a = L.albedo[n];
    return c * (lin * a + Vec3f(1.f - a, 1.f - a, 1.f - a));
  }
};

/**
 * The optics of a lit point under closedFormScattering(), as
 * trackExpectedOf() takes them: the blend's extinction and, as emission,
 * each colour's absorbed share plus its scattered share times the light it
 * scatters towards the camera (UnshadowedColour). With directional lights
 * only and one anisotropy that light is the same along the ray
 * (`perRay`); with point lights it is a function of the point (`perPoint`),
 * for density computed once a point with the one anisotropy `g`.
 */
template <BlendMode Mode>
struct UnshadowedOptics
{
  const SceneView& s;
  Vec3f w;
  float g;
  bool perPoint;
  Vec3f perRay;
  MCVOL_HOT PointOptics operator()(Vec3f p, uint32_t present) const
  {
    constexpr bool density = Mode == BlendMode::Density || Mode == BlendMode::Composite;
    UnshadowedColour colour{ s.lighting, perRay, w, p, !density && perPoint };
    if (density && perPoint)
    {
      colour.in = unshadowedRadiance(s.lighting, g, w, p);
    }
    return blendedOptics<Mode>(s, s.active, s.numActive, p, present, colour);
  }
};

/**
 * One lit sample with the expected-value estimator (Estimator::
 * ExpectedValue with lighting): next-event estimation on the camera ray of
 * trackExpected(). The camera ray's tentative collisions follow the blend's
 * majorant M, as trackExpected()'s; at each, with running transmittance T
 * (ratio tracking, Russian roulette below kRouletteThreshold), the
 * absorbed share of the emission is scored with the expected-value weight
 * w = sigma / M: L += T w c_abs, c_abs = sum_n sigma_n (1 - albedo_n) c_n /
 * sigma, so the emission needs no random absorb-or-scatter decision.
 *
 * The scattered share, sum_i T_i sigma_s(x_i) / M L_in(x_i) over the
 * tentative collisions, needs shadow rays for its L_in; it is scored at
 * one of them. Weighted reservoir sampling over the traversal (one
 * candidate, the collision's own uniform number) picks collision i with
 * probability w_i / W, w_i = T_i sigma_s(x_i) / M, W = sum_i w_i (the
 * expected-value estimate of the light the ray scatters, at most 1), and
 * the path scatters there with throughput W, in channel n with probability
 * sigma_n albedo_n / sigma_s: W L_in(x_I) has the sum's expectation, with
 * neither the collision estimator's decision whether the ray collides nor
 * the albedo's whether it scatters. Where W is below
 * LightingView::scatterRoulette (theta), Russian roulette keeps the vertex
 * with probability W / theta at throughput theta, so that a thin ray does
 * not cost a whole vertex's shadow rays: theta 1 spends about the collision
 * estimator's vertices (W is about the probability that it scatters).
 * Only the position of the pick is carried through the traversal, so the
 * camera ray's loop carries no lighting code; the vertex is handled after
 * it (litPathFrom()). Where closedFormScattering() holds (no shadows, one
 * vertex, no gradient shading), L_in needs no ray and the scattered share
 * is scored at every tentative collision as the absorbed share is
 * (UnshadowedOptics through trackExpectedOf(), the unlit traversal): no
 * vertex at all. Local: the kernels localKernels() picks for such scenes,
 * which carry that closed form alone.
 */
template <BlendMode Mode, bool Local = false, bool Defer = false>
MCVOL_HOT Vec4f traceLitExpected(const SceneView& s, const SceneView& light, Tracker tracker, Vec3f o, Vec3f d, Vec3f w,
  float tmax, Rng& rng, RayCounters& c, ShadowCounters& sc, DeferredShadows* defer = nullptr)
{
  if (s.numActive == 0)
  {
    return Vec4f();
  }
  float g = 0.f;
  bool uniform = false;
  // Local: localKernels() runs these kernels only where the closed form
  // holds, and they carry nothing else.
  if (closedFormScattering(s, Mode, g, uniform) || Local)
  {
    const LightingView& lv = s.lighting;
    bool pointLights = false;
    for (int l = 0; l < lv.numLights; ++l)
    {
      pointLights = pointLights || lv.lightType[l] != 0;
    }
    // Cached shadows vary along the ray: the light is looked up per point.
    const bool perPoint = pointLights || !uniform || lv.shadows;
    const Vec3f perRay = perPoint ? Vec3f() : unshadowedRadiance(lv, g, w, o);
    return trackExpectedOf<Mode>(s, o, d, 0.f, tmax, rng, c, UnshadowedOptics<Mode>{ s, w, g, perPoint, perRay });
  }
  Vec3f L;
  float T = 1.f;
  float W = 0.f;     // sum of the scattering weights w_i
  float tPick = 0.f; // the reservoir's collision
  float tau = opticalDepthOf(rng.sequence(kGroupFlight));
  DDA dda;
  dda.init(s.grid, o, d, 0.f, tmax);
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
      float uFlight, uPick;
      rng.collision(uFlight, uPick);
      tau = opticalDepthOf(uFlight);
      ++c.tentative;
      const LitPointOptics po = litPointOptics<Mode>(s, o + d * t, present.mask);
      c.samples += uint32_t(present.count);
      const float ws = T * minf(po.scatter / M, 1.f);
      if (ws > 0.f)
      {
        W += ws;
        if (uPick * W < ws)
        {
          tPick = t;
        }
      }
      const float wt = minf(po.sigma / M, 1.f);
      L += po.absorbed * (T * wt);
      T *= 1.f - wt;
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
  if (W > 0.f)
  {
    // The roulette's number: the set the collision estimator's scatter test takes.
    const float theta = s.lighting.scatterRoulette;
    const float q = W < theta ? W / theta : 1.f;
    if (rng.sequence(kGroupScatter) < q)
    {
      Hit hit = scatteringChannelAt<Mode>(s, o + d * tPick, rng.next());
      if (hit.found())
      {
        hit.t = tPick;
        ++c.real;
        L += litPathFrom<Mode, false, Local, Defer>(s, light, tracker, o, d, w, hit, false, rng, c, sc, defer, W / q);
      }
    }
  }
  foldShadowCounters(c, sc);
  return premultipliedRGBA(L, T);
}
} // namespace mcvol
