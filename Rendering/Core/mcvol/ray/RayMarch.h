// SPDX-License-Identifier: BSD-3-Clause
#pragma once

#include "mcvol/ray/Blend.h"
#include "mcvol/ray/DDA.h"
#include "mcvol/ray/Importance.h"
#include "mcvol/ray/Lighting.h"
#include "mcvol/ray/Random.h"
#include "mcvol/ray/RayGen.h"

#include <cstdint>

namespace mcvol
{
/**
 * Deterministic ray marching over the same channels, transfer functions and
 * blend modes as the Monte Carlo trackers: the reference their images are
 * measured against.
 *
 * Two compositing models (Kraus and Buerger, Sections 3.2 and 3.3):
 * - Extinction: at each sample the channels' extinctions are interpolated
 *   (post-classification, as the trackers see them) and combined by the blend
 *   mode (Blend.h); the step's opacity is exactly 1 - exp(-sigma d) (Eq. 22)
 *   and its premultiplied colour emission * alpha (Eq. 23). This is the
 *   quantity Woodcock tracking estimates: as d -> 0 both converge to the same
 *   image.
 * - Opacity: classic opacity-based sampling. Each voxel's opacity for the
 *   step d is taken from its transfer-function opacity (for the unit distance
 *   u) with the opacity correction 1 - (1 - a)^(d/u) (Eq. 16, here via the
 *   table's extinction), its opacity-weighted colour c * alpha (Eq. 17); the
 *   opacities and opacity-weighted colours are interpolated between voxels
 *   (pre-classification) and the channels combined as in Eq. 11 and 15
 *   (density: summed, opacity clamped to 1; max: the channel of largest
 *   opacity; mix: largest opacity, weighted opacity-weighted colours). It
 *   converges only as d -> 0 and shows the artifacts the paper describes.
 *   Its interpolation is trilinear or nearest: with cubic (B-spline)
 *   interpolation prepareMarch() refuses it (std::invalid_argument).
 *
 * Samples lie on the lattice t_k = (k + phase) d along each ray (phase 0.5,
 * the midpoint rule, or a per-pixel hash with jitter). Macrocells whose
 * majorants are 0 for every channel are skipped without changing the result
 * (every voxel a point there can read is transparent, in both models). The
 * march stops once the transmittance falls below a stated threshold.
 */
enum class Compositing : int
{
  Extinction = 0,
  Opacity = 1
};

struct MarchParams
{
  float step = 0.5f;                    ///< world units, > 0
  float terminateTransmittance = 1e-4f; ///< early ray termination below this
  bool skipEmpty = true;                ///< skip macrocells with all-zero majorants
  Compositing compositing = Compositing::Extinction;
};

struct MarchCounters
{
  uint64_t samples = 0;      ///< lattice points evaluated
  uint64_t skippedCells = 0; ///< macrocells skipped as empty
  uint64_t terminated = 0;   ///< rays stopped by the transmittance threshold
};

/// Opacity and premultiplied colour of one step.
struct StepOptics
{
  float alpha = 0.f;
  Vec3f colour; ///< premultiplied
};

/// Opacity-based sampling of channel n at the corners: interpolated step
/// opacity and opacity-weighted colour. A NaN voxel among the corners makes
/// the channel transparent at p (the core's NaN rule). A pre-classified
/// channel's voxel gives its own sigma and colour (alpha = 1 - exp(-sigma d)
/// per voxel, then interpolated: the paper's opacity-based baseline).
MCVOL_HOT StepOptics opacitySample(const SceneView& s, int n, const Corners& c, float step)
{
  StepOptics o;
  const ChannelView& ch = s.volume.channels[n];
  const bool classified = ch.format == ChannelFormat::Extinction;
  for (int k = 0; k < c.count; ++k)
  {
    TFSample t;
    if (classified)
    {
      float x[4];
      if (!fetchClassified(ch, c.index[k], x))
      {
        return StepOptics();
      }
      t = classifiedOptics(x);
    }
    else
    {
      const float v = fetchVoxel(ch, c.index[k]);
      if (!(v == v))
      {
        return StepOptics();
      }
      t = lookupTF(s.tables, n, v);
    }
    const float a = -expm1f(-minf(t.sigma, s.sigmaLimit) * step); // 1 - (1 - a_u)^(d/u)
    o.alpha += c.weight[k] * a;
    o.colour += t.rgb * (c.weight[k] * a);
  }
  return o;
}

/// One step's optics at p over the listed channels.
template <BlendMode Mode>
MCVOL_HOT StepOptics stepOptics(const SceneView& s, const MarchParams& mp, const int* channels, int count, Vec3f p)
{
  StepOptics out;
  if (mp.compositing == Compositing::Extinction)
  {
    const PointOptics po = blendedOptics<Mode>(s, channels, count, p);
    if (po.sigma > 0.f)
    {
      out.alpha = -expm1f(-po.sigma * mp.step);
      out.colour = po.emission * out.alpha;
    }
    return out;
  }
  const Corners c = cornersOf(s.volume, p);
  float best = -1.f;
  int bestChannel = -1;
  float mixAlpha = 0.f; // mix: sum of w_n alpha_n
  for (int i = 0; i < count; ++i)
  {
    const int n = channels[i];
    const StepOptics o = opacitySample(s, n, c, mp.step);
    if (Mode == BlendMode::Density || Mode == BlendMode::Composite)
    {
      out.alpha += o.alpha;   // Eq. 11
      out.colour += o.colour; // Eq. 15
      continue;
    }
    if (bestChannel < 0 || outranks(o.alpha, n, best, bestChannel))
    {
      best = o.alpha;
      bestChannel = n;
      if (Mode == BlendMode::Max)
      {
        out.colour = o.colour;
      }
    }
    if (Mode == BlendMode::Mix)
    {
      out.colour += o.colour * s.blend.mixWeights[n];
      mixAlpha += o.alpha * s.blend.mixWeights[n];
    }
  }
  if (Mode == BlendMode::Density || Mode == BlendMode::Composite)
  {
    if (out.alpha > 1.f)
    {
      out.colour = out.colour * (1.f / out.alpha);
      out.alpha = 1.f;
    }
    return out;
  }
  out.alpha = best > 0.f ? best : 0.f;
  if (!(out.alpha > 0.f))
  {
    out.colour = Vec3f();
  }
  else if (Mode == BlendMode::Mix && s.blend.mixAverage)
  {
    // The opacity-weighted average of the present channels' colours, at the
    // largest opacity (the opacity-model twin of mixColour).
    out.colour = mixAlpha > 0.f ? out.colour * (out.alpha / mixAlpha) : Vec3f();
  }
  return out;
}

/**
 * The visibility optimization as a march (Lerzer and Dachsbacher, Sec. 6.2,
 * after Ament et al.): the integrals of Eq. 7 become sums over the lattice,
 * K(t_k) = sum_{j<k} g_j^2 dx + g_k^2 phase dx (the sample's share of its own
 * interval), and K(z) the sum over the whole ray. `dx` is the step in
 * normalised ray units.
 */
struct MarchImportance
{
  float total = 0.f; ///< K(z)
  float K = 0.f;     ///< integral over the lattice intervals before the current one
  float dx = 0.f;
  float phase = 0.5f;
};

/// K(z) of a ray: one importance sample per lattice point over [0, tmax].
MCVOL_HOT MarchImportance marchImportanceStart(
  const SceneView& s, const MarchParams& mp, Vec3f o, Vec3f d, float tmax, float phase, MarchCounters& mc)
{
  MarchImportance mi;
  mi.dx = mp.step * s.importance.invLengthUnit;
  mi.phase = phase;
  for (int64_t k = 0;; ++k)
  {
    const float t = float((double(k) + double(phase)) * double(mp.step));
    if (!(t < tmax))
    {
      break;
    }
    const float g = importanceAt(s, o + d * t);
    mi.total += g * g * mi.dx;
    ++mc.samples;
  }
  return mi;
}

/// The factor mu'/mu at the next lattice point p (points must come in order,
/// none skipped), Eq. 7-8 with the sums above.
MCVOL_HOT float marchImportanceFactor(const SceneView& s, MarchImportance& mi, Vec3f p)
{
  const float g = importanceAt(s, p);
  const float K = mi.K + g * g * mi.phase * mi.dx;
  mi.K += g * g * mi.dx;
  return optimizedExtinctionFactor(s.importance, g, K, mi.total);
}

/// The optimized march (extinction model, unlit): every lattice point, no
/// empty-space skipping (importance may sit where the opacity is zero).
template <BlendMode Mode>
MCVOL_HOT Vec4f marchOptimized(const SceneView& s, const MarchParams& mp, const int* channels, int count, Vec3f o,
  Vec3f d, float tmax, float phase, MarchCounters& mc)
{
  Vec4f out;
  if (!(tmax > 0.f))
  {
    return out;
  }
  MarchImportance mi = marchImportanceStart(s, mp, o, d, tmax, phase, mc);
  float T = 1.f;
  Vec3f C;
  for (int64_t k = 0;; ++k)
  {
    const float t = float((double(k) + double(phase)) * double(mp.step));
    if (!(t < tmax))
    {
      break;
    }
    const Vec3f p = o + d * t;
    const float f = marchImportanceFactor(s, mi, p);
    const PointOptics po = blendedOptics<Mode>(s, channels, count, p);
    ++mc.samples;
    if (po.sigma > 0.f)
    {
      const float alpha = -expm1f(-po.sigma * f * mp.step);
      C += po.emission * (alpha * T);
      T *= 1.f - alpha;
      if (T < mp.terminateTransmittance)
      {
        ++mc.terminated;
        break;
      }
    }
  }
  return premultipliedRGBA(C, T);
}

/// Front-to-back march over [0, tmax] with the listed channels; premultiplied
/// RGB and alpha.
template <BlendMode Mode>
MCVOL_HOT Vec4f marchChannels(const SceneView& s, const MarchParams& mp, const int* channels, int count, Vec3f o,
  Vec3f d, float tmax, float phase, MarchCounters& mc)
{
  Vec4f out;
  if (count == 0 || !(tmax > 0.f))
  {
    return out;
  }
  if (s.importance.enabled)
  {
    return marchOptimized<Mode>(s, mp, channels, count, o, d, tmax, phase, mc);
  }
  float T = 1.f;
  Vec3f C;
  const int N = s.grid.numChannels;
  DDA dda;
  dda.init(s.grid, o, d, 0.f, tmax);
  // The next lattice index to evaluate, carried across cells so that every
  // sample is taken exactly once whatever the cell boundaries' rounding.
  int64_t k = 0;
  bool stop = false;
  while (!dda.done && !stop)
  {
    bool empty = mp.skipEmpty;
    if (empty)
    {
      const float* maj = s.grid.majorants + dda.cellIndex() * N;
      for (int i = 0; i < count && empty; ++i)
      {
        empty = !(minf(maj[channels[i]], s.sigmaLimit) > 0.f);
      }
    }
    if (empty)
    {
      // Jump over the cell's samples (at or before the first one past it).
      const double kEnd = floor(double(dda.t1) / double(mp.step) - double(phase));
      if (kEnd > double(k))
      {
        k = int64_t(kEnd);
      }
    }
    while (true)
    {
      // In double: float(k) + phase loses the phase once k nears 2^22.
      const float t = float((double(k) + double(phase)) * double(mp.step));
      if (!(t < dda.t1))
      {
        break;
      }
      if (!empty)
      {
        const StepOptics so = stepOptics<Mode>(s, mp, channels, count, o + d * t);
        ++mc.samples;
        C += so.colour * T;
        T *= 1.f - so.alpha;
        if (T < mp.terminateTransmittance)
        {
          ++mc.terminated;
          stop = true;
          break;
        }
      }
      ++k;
    }
    if (empty)
    {
      ++mc.skippedCells;
    }
    dda.next();
  }
  return premultipliedRGBA(C, T);
}

/// Transmittance from index point x along index direction dl (unit world
/// length per t) over [0, tmax], marched at the step with the extinction
/// model: exp(-sum sigma d), sigma the blend's combined extinction.
template <BlendMode Mode>
MCVOL_HOT float marchTransmittance(
  const SceneView& s, const int* channels, int count, Vec3f x, Vec3f dl, float tmax, float step)
{
  float tau = 0.f;
  for (float t = 0.5f * step; t < tmax; t += step)
  {
    tau += blendedOptics<Mode>(s, channels, count, x + dl * t).sigma * step;
  }
  return expf(-tau);
}

/// marchTransmittance through the optimized extinction of a light ray (paper
/// 004 Sec. 5.3 with sums for the integrals, as marchOptimized).
template <BlendMode Mode>
MCVOL_HOT float marchTransmittanceOptimized(
  const SceneView& s, const int* channels, int count, Vec3f x, Vec3f dl, float tmax, float step)
{
  MarchImportance mi;
  mi.dx = step * s.importance.invLengthUnit;
  mi.phase = 0.5f;
  for (float t = 0.5f * step; t < tmax; t += step)
  {
    const float g = importanceAt(s, x + dl * t);
    mi.total += g * g * mi.dx;
  }
  float tau = 0.f;
  for (float t = 0.5f * step; t < tmax; t += step)
  {
    const Vec3f p = x + dl * t;
    // K from the vertex (x) or, with lightRaysFromLight, from the light: the
    // rest of the ray's sum (lightRayImportanceFactor()).
    const float g = importanceAt(s, p);
    const float K = mi.K + g * g * mi.phase * mi.dx;
    mi.K += g * g * mi.dx;
    const float f =
      optimizedExtinctionFactor(s.importance, g, s.importance.lightRaysFromLight ? mi.total - K : K, mi.total);
    tau += blendedOptics<Mode>(s, channels, count, p).sigma * f * step;
  }
  return expf(-tau);
}

/// Directions of the ray marcher's ambient quadrature (marchLit).
constexpr int kAmbientDirections = 32;

/// Direction k of kAmbientDirections on the unit sphere (spherical Fibonacci
/// lattice: equal areas, no preferred axis).
MCVOL_FUNC Vec3f ambientDirection(int k)
{
  const float z = 1.f - (2.f * float(k) + 1.f) / float(kAmbientDirections);
  const float r = sqrtf(fmaxf(0.f, 1.f - z * z));
  const float phi = 2.39996322972865332f * float(k); // the golden angle
  return Vec3f(r * cosf(phi), r * sinf(phi), z);
}

/// What marchLit fixes once per ray.
struct LitRay
{
  Vec3f w;                  ///< the camera ray's world direction
  float step;               ///< lattice step (world units), also of the light rays
  bool optimized;           ///< visibility optimization on (importance.enabled)
  bool ambient;             ///< ambient radiance non-zero
  const Vec3f* ambientDirs; ///< kAmbientDirections world directions, when ambient
};

/**
 * The light at one lattice point x, gathered before the channels ask for it.
 * The arrays are marchLit's locals and the struct points to them, so that
 * its scalars stay in registers on the device (a struct that held the arrays
 * would keep x and the gradient in local memory).
 */
struct LitSample
{
  Vec3f x;            ///< the point (index space)
  Vec3f grad;         ///< extinction gradient (gradient shading)
  float gradLen;      ///< its length
  Vec3f* wl;          ///< [numLights] unit world direction towards each light
  Vec3f* arriving;    ///< [numLights] each light's radiance * transmittance * falloff at x
  float* ambientT;    ///< [kAmbientDirections] transmittance towards each quadrature direction
  bool* haveAmbientT; ///< ambientT marched (on first use: only where a channel scatters)
};

/// Transmittance of a light ray from x along index direction dl over
/// [0, tmax]: through the optimized extinction when the optimization covers
/// light rays (importance.lightRays), else the plain one.
template <BlendMode Mode>
MCVOL_HOT float marchLightRay(const SceneView& s, bool optimized, Vec3f x, Vec3f dl, float tmax, float step)
{
  return optimized && s.importance.lightRays
    ? marchTransmittanceOptimized<Mode>(s, s.active, s.numActive, x, dl, tmax, step)
    : marchTransmittance<Mode>(s, s.active, s.numActive, x, dl, tmax, step);
}

/// The marched transmittance of the part of a light ray beyond this piece
/// (outsideShadow()'s geometry: the ray leaves the piece at tPiece and
/// reaches the light at tLight), through the stand-in (SceneView::outside)
/// at the same step. 1 without a stand-in.
template <BlendMode Mode>
MCVOL_HOT float marchOutside(const SceneView& s, Vec3f x, Vec3f dl, float tPiece, float tLight, float step)
{
  if (!s.outside || !(tLight > tPiece))
  {
    return 1.f;
  }
  const SceneView& o = *s.outside;
  const Vec3f xo = toOutside(s, x);
  const Vec3f dO = toOutsideDirection(s, dl);
  const float tEnd = minf(boxExit(o.volume, xo, dO), tLight);
  if (!(tEnd > tPiece))
  {
    return 1.f;
  }
  return marchTransmittance<Mode>(o, o.active, o.numActive, xo + dO * tPiece, dO, tEnd - tPiece, step);
}

/// Direction towards each light and the light arriving at ls.x from it
/// (radiance times marched transmittance, times 1/dist^2 for a point light).
template <BlendMode Mode>
MCVOL_HOT void gatherLights(const SceneView& s, const LitRay& r, const LitSample& ls)
{
  const LightingView& L = s.lighting;
  for (int l = 0; l < L.numLights; ++l)
  {
    LightDirection way;
    const bool reached = towardsLight(L, l, ls.x, way);
    ls.wl[l] = way.wl;
    if (!reached)
    {
      ls.arriving[l] = Vec3f(); // the sample is at a point light
      continue;
    }
    const Vec3f dl = way.dl;
    const float dist = way.dist;
    const float falloff = way.falloff;
    const float tPiece = boxExit(s.volume, ls.x, dl);
    const float tl = minf(tPiece, dist);
    float Tl = 1.f;
    if (L.shadows && shadowCached(L, l))
    {
      Tl = cachedTransmittance(L, l, ls.x); // the Monte Carlo mapper's lookup
    }
    else if (L.shadows)
    {
      Tl = marchLightRay<Mode>(s, r.optimized, ls.x, dl, tl, r.step);
      if (s.outside)
      {
        Tl *= marchOutside<Mode>(s, ls.x, dl, tPiece, dist, r.step);
      }
    }
    ls.arriving[l] = L.lightRadiance[l] * (Tl * falloff);
  }
}

/// sum_k q_k T(x, w_k) for channel n: the transmittance towards the ambient
/// quadrature's directions, weighted by the channel's phase function. The
/// transmittances are marched on the first call at a sample and then reused.
template <BlendMode Mode>
MCVOL_HOT float ambientTransmittance(const SceneView& s, const LitRay& r, int n, const LitSample& ls)
{
  const LightingView& L = s.lighting;
  if (!*ls.haveAmbientT)
  {
    for (int k = 0; k < kAmbientDirections; ++k)
    {
      float Tk = 1.f;
      if (L.shadows)
      {
        const Vec3f dk = mul3(L.toIndex, r.ambientDirs[k]);
        const float tk = boxExit(s.volume, ls.x, dk);
        Tk = marchLightRay<Mode>(s, r.optimized, ls.x, dk, tk, r.step);
        if (s.outside)
        {
          Tk *= marchOutside<Mode>(s, ls.x, dk, tk, 3.4e38f, r.step);
        }
      }
      ls.ambientT[k] = Tk;
    }
    *ls.haveAmbientT = true;
  }
  float num = 0.f, den = 0.f;
  for (int k = 0; k < kAmbientDirections; ++k)
  {
    const float p = hgPhase(dot(r.w, r.ambientDirs[k]), L.anisotropy[n]);
    num += p * ls.ambientT[k];
    den += p;
  }
  return den > 0.f ? num / den : 0.f;
}

/// S_n: the light channel n scatters towards the eye at ls.x.
template <BlendMode Mode>
MCVOL_HOT Vec3f scatteredLight(const SceneView& s, const LitRay& r, int n, const LitSample& ls)
{
  const LightingView& L = s.lighting;
  Vec3f S;
  for (int l = 0; l < L.numLights; ++l)
  {
    S += ls.arriving[l] * scatterFunction(L, L.anisotropy[n], r.w, ls.wl[l], L.gradientShading, ls.grad, ls.gradLen);
  }
  if (r.ambient && L.albedo[n] > 0.f)
  {
    S += L.ambient * ambientTransmittance<Mode>(s, r, n, ls);
  }
  return S;
}

/// The combined extinction sigma at ls.x (returned) and the source term
/// sigma times the emitted and scattered colour (`source`, left 0 where
/// sigma is 0): density sums the channels; max and mix take the winning
/// channel's albedo with the blend's colour.
template <BlendMode Mode>
MCVOL_HOT float litSource(const SceneView& s, const LitRay& r, const LitSample& ls, Vec3f& source)
{
  const LightingView& L = s.lighting;
  float sigma = 0.f;
  if (Mode == BlendMode::Density)
  {
    for (int i = 0; i < s.numActive; ++i)
    {
      const int n = s.active[i];
      const TFSample tf = channelOptics(s, n, ls.x);
      if (tf.sigma > 0.f)
      {
        const float a = L.albedo[n];
        source += (tf.rgb * (1.f - a) + tf.rgb * scatteredLight<Mode>(s, r, n, ls) * a) * tf.sigma;
        sigma += tf.sigma;
      }
    }
    return sigma;
  }
  const PointOptics po = blendedOptics<Mode>(s, s.active, s.numActive, ls.x);
  int winner = -1;
  float best = -1.f;
  for (int i = 0; i < s.numActive; ++i)
  {
    const float sn = channelOptics(s, s.active[i], ls.x).sigma;
    if (winner < 0 || outranks(sn, s.active[i], best, winner))
    {
      best = sn;
      winner = s.active[i];
    }
  }
  sigma = po.sigma;
  if (sigma > 0.f)
  {
    const float a = L.albedo[winner];
    source = (po.emission * (1.f - a) + po.emission * scatteredLight<Mode>(s, r, winner, ls) * a) * sigma;
  }
  return sigma;
}

/**
 * Lit reference: single scattering with shadows, extinction model.
 * At each sample the source is sum_n sigma_n [(1 - a_n) c_n + a_n c_n S_n]
 * (density; max and mix: the winning channel with the blend's colour), S_n
 * the light each channel scatters towards the eye: sum over lights of the
 * scattering function (Henyey-Greenstein of g_n, plus the gradient term
 * when on) times the marched transmittance to the light times its radiance.
 * Ambient radiance (an environment of constant radiance L_a) adds
 * L_a sum_k q_k T(x, w_k) to S_n: a fixed quadrature over kAmbientDirections
 * spherical-Fibonacci directions w_k, weighted by the channel's phase
 * function (q_k = p(w, w_k) / sum_j p(w, w_j), so without shadows the term is
 * exactly L_a), each transmittance marched with the camera step. This is the
 * expectation of the Monte Carlo mapper's lit samples with one scattering
 * event (maxDepth 1), which estimates the same integral with one
 * phase-sampled direction per vertex, up to the quadrature's error
 * (Testing/Python/TestLitDefaults.py measures it). It costs kAmbientDirections
 * transmittance marches per visible sample: set the ambient radiance to 0 for
 * a fast lit reference.
 */
template <BlendMode Mode>
MCVOL_HOT Vec4f marchLit(
  const SceneView& s, const MarchParams& mp, Vec3f o, Vec3f d, Vec3f w, float tmax, float phase, MarchCounters& mc)
{
  const LightingView& L = s.lighting;
  Vec3f C;
  float T = 1.f;
  RayCounters rc;
  LitRay r;
  r.w = w;
  r.step = mp.step;
  // The optimization scales the camera ray's extinction (as the Monte Carlo
  // camera ray); light rays only when importance.lightRays is on.
  r.optimized = s.importance.enabled;
  MarchImportance mi;
  if (r.optimized)
  {
    mi = marchImportanceStart(s, mp, o, d, tmax, phase, mc);
  }
  // The ambient quadrature's directions (world), once per ray.
  r.ambient = L.ambient.x > 0.f || L.ambient.y > 0.f || L.ambient.z > 0.f;
  Vec3f ambientDirs[kAmbientDirections];
  if (r.ambient)
  {
    for (int k = 0; k < kAmbientDirections; ++k)
    {
      ambientDirs[k] = ambientDirection(k);
    }
  }
  r.ambientDirs = ambientDirs;
  for (int64_t k = 0;; ++k)
  {
    const float t = float((double(k) + double(phase)) * double(mp.step));
    if (!(t < tmax))
    {
      break;
    }
    LitSample ls;
    ls.x = o + d * t;
    ++mc.samples;
    const float f = r.optimized ? marchImportanceFactor(s, mi, ls.x) : 1.f;
    Vec3f wl[kMaxLights];
    Vec3f arriving[kMaxLights];
    ls.wl = wl;
    ls.arriving = arriving;
    gatherLights<Mode>(s, r, ls);
    ls.gradLen = 0.f;
    if (L.gradientShading)
    {
      ls.grad = extinctionGradient<Mode>(s, s.active, s.numActive, ls.x, rc);
      ls.gradLen = length(ls.grad);
    }
    float ambientT[kAmbientDirections];
    bool haveAmbientT = false;
    ls.ambientT = ambientT;
    ls.haveAmbientT = &haveAmbientT;
    Vec3f source;
    const float sigma = litSource<Mode>(s, r, ls, source);
    if (sigma > 0.f)
    {
      const float alpha = -expm1f(-sigma * f * mp.step);
      C += source * (T * alpha / sigma);
      T *= 1.f - alpha;
      if (T < mp.terminateTransmittance)
      {
        ++mc.terminated;
        break;
      }
    }
  }
  return premultipliedRGBA(C, T);
}

/// Phase of a pixel's sample lattice: 0.5 (midpoint rule), or with jitter a
/// hash of (pixel, seed) in [0, 1) (deterministic: same image every time).
MCVOL_FUNC float marchPhase(bool jitter, uint32_t pixel, uint32_t seed)
{
  if (!jitter)
  {
    return 0.5f;
  }
  Rng r(pixel, 0xFFFFFFFFu, seed);
  return r.next();
}

/**
 * The reference image of one pixel (ray through its centre): premultiplied
 * RGBA. Post-render composite marches each channel alone and adds the
 * results (alpha 1 - prod(1 - alpha_n)), as the Monte Carlo composite does.
 * MayBeLit false compiles marchLit out, for callers that know lighting is
 * off (the CUDA backend's unlit kernels, which then spend no registers or
 * local memory on it); the image is the same.
 */
template <BlendMode Mode, bool MayBeLit = true>
MCVOL_FUNC Vec4f marchPixel(const SceneView& s, const CameraView& cam, const MarchParams& mp, int x, int y, float depth,
  float phase, MarchCounters& mc)
{
  IndexRay ray;
  if (!generateRay(cam, s.volume, float(x) + 0.5f, float(y) + 0.5f, depth, ray))
  {
    return Vec4f();
  }
  if (MayBeLit && Mode != BlendMode::Composite && s.lighting.enabled)
  {
    return marchLit<Mode>(s, mp, ray.o, ray.d, ray.world, ray.tmax, phase, mc);
  }
  if (MayBeLit && Mode == BlendMode::Composite && s.lighting.enabled)
  {
    // Each channel lit alone, as the Monte Carlo composite does (in the
    // stand-in of the other pieces too).
    OneChannelView one(s);
    Vec4f sum;
    float clear = 1.f;
    for (int i = 0; i < s.numActive; ++i)
    {
      const Vec4f v =
        marchLit<BlendMode::Density>(one.alone(s.active[i]), mp, ray.o, ray.d, ray.world, ray.tmax, phase, mc);
      sum.r += v.r;
      sum.g += v.g;
      sum.b += v.b;
      clear *= 1.f - v.a;
    }
    sum.a = 1.f - clear;
    return sum;
  }
  if (Mode != BlendMode::Composite)
  {
    return marchChannels<Mode>(s, mp, s.active, s.numActive, ray.o, ray.d, ray.tmax, phase, mc);
  }
  Vec4f sum;
  float clear = 1.f;
  for (int i = 0; i < s.numActive; ++i)
  {
    const Vec4f v = marchChannels<BlendMode::Composite>(s, mp, s.active + i, 1, ray.o, ray.d, ray.tmax, phase, mc);
    sum.r += v.r;
    sum.g += v.g;
    sum.b += v.b;
    clear *= 1.f - v.a;
  }
  sum.a = 1.f - clear;
  return sum;
}
} // namespace mcvol
