// SPDX-License-Identifier: BSD-3-Clause
#pragma once

#include "mcvol/ray/Random.h"
#include "mcvol/ray/Sampling.h"
#include "mcvol/ray/SceneView.h"

#include <cmath>
#include <cstdint>

/**
 * View-dependent visibility optimization (Lerzer and Dachsbacher, EG 2025):
 * the extinction at a point y of a camera ray becomes
 *
 *   mu'(y) = p mu(y) / (p + (1 - g(y))^(2 lambda) h(y))                (Eq. 8)
 *   h(y)   = (r - q) K(y) + q K(z),   K(y) = int_x^y k(s)^2 ds         (Eq. 7)
 *
 * where g is the post-interpolative importance (Sec. 4.2) and k its step
 * function along the ray. Every ray keeps a sorted list of segments of
 * constant importance (Sec. 5.1), refined by stratified samples across
 * progressive passes (Sec. 5.2), from which K is a binary search plus the
 * in-segment term. Since the factor p / (p + ...) never exceeds 1, mu' <= mu
 * and the majorant grids stay valid.
 *
 * Distances inside a segment list are in normalised ray units: world length
 * divided by ImportanceView::lengthUnit (half the volume's largest world
 * extent, so the volume spans 2 units as in the paper's [-1, 1]^3 scaling and
 * the paper's default weights mean the same thing here).
 */
namespace mcvol
{
/// One piece of k~(t): importance `k` on [t, t + length]; `K` is the
/// integral of k~^2 from the ray's start to `t` (gaps included).
struct ImportanceSegment
{
  float t = 0.f;
  float length = 0.f;
  float k = 0.f;
  float K = 0.f;
  MCVOL_FUNC float right() const { return this->t + this->length; }
};

/// Most segments one pixel keeps (16 bytes each). A pass whose merged list
/// would not fit leaves the pixel's list as it was and is counted as an
/// overflow (ImportanceStats), never written past the end.
constexpr int kImportanceCapacity = 16;
/// Most samples one refinement pass may draw per ray.
constexpr int kMaxImportanceSamples = 64;

/// Importance of the blend at p: the maximum over the channels that carry an
/// importance function, each looked up (nearest texel: the table is a step
/// function) at the channel's interpolated value. NaN values give 0. The
/// value is trilinear (or nearest) even with cubic interpolation: a cubic
/// sample here would add a call to every optimized kernel, and the
/// importance only weighs extinction, identically for Monte Carlo and the
/// march, so both still agree.
MCVOL_HOT float importanceAt(const SceneView& s, Vec3f p)
{
  const ImportanceView& iv = s.importance;
  float g = 0.f;
  for (int i = 0; i < iv.numChannels; ++i)
  {
    const int n = iv.channels[i];
    const float x = texelCoord(s.tables, n, sampleChannel(s.volume, n, p));
    if (x < 0.f)
    {
      continue;
    }
    const float v = iv.table[int64_t(n) * s.tables.size + int(x + 0.5f)];
    g = v > g ? v : g;
  }
  return g;
}

/// The integral K(t) = int_0^t k~(s)^2 ds of a segment list (Sec. 5.1): in a
/// segment its value plus k^2 times the way in; in a gap between segments
/// the linear interpolation of the integrals at its ends (the gap's
/// importance is the mean of its neighbours'; before the first and after the
/// last segment the border importance is 0).
MCVOL_FUNC float importanceIntegral(const ImportanceSegment* seg, int count, float t)
{
  if (count <= 0)
  {
    return 0.f;
  }
  if (t < seg[0].t)
  {
    const float k = 0.5f * seg[0].k;
    return k * k * (t > 0.f ? t : 0.f);
  }
  // Binary search: the last segment starting at or before t.
  int lo = 0, hi = count - 1;
  while (lo < hi)
  {
    const int mid = (lo + hi + 1) / 2;
    if (seg[mid].t <= t)
    {
      lo = mid;
    }
    else
    {
      hi = mid - 1;
    }
  }
  const ImportanceSegment& a = seg[lo];
  const float end = a.right();
  if (t <= end)
  {
    return a.K + a.k * a.k * (t - a.t);
  }
  const float atEnd = a.K + a.k * a.k * a.length;
  if (lo + 1 < count)
  {
    const ImportanceSegment& b = seg[lo + 1];
    const float w = (t - end) / (b.t - end);
    return atEnd + w * (b.K - atEnd);
  }
  const float k = 0.5f * a.k;
  return atEnd + k * k * (t - end);
}

/// Fills in K of every segment and returns the integral over [0, T].
MCVOL_FUNC float importanceIntegrals(ImportanceSegment* seg, int count, float T)
{
  float K = 0.f;
  float prevEnd = 0.f;
  float prevK = 0.f; // border importance before the first segment
  for (int i = 0; i < count; ++i)
  {
    const float gapK = 0.5f * (prevK + seg[i].k);
    const float gap = seg[i].t - prevEnd;
    K += gapK * gapK * (gap > 0.f ? gap : 0.f);
    seg[i].K = K;
    K += seg[i].k * seg[i].k * seg[i].length;
    prevEnd = seg[i].right();
    prevK = seg[i].k;
  }
  const float gapK = 0.5f * prevK;
  const float gap = T - prevEnd;
  return K + gapK * gapK * (gap > 0.f ? gap : 0.f);
}

/**
 * Algorithm 1 (Sec. 5.1) for one candidate against the end of `list`
 * (`n` entries, room for `cap`). Candidates arrive sorted by t. Returns the
 * new count, or -1 when the list is full. A split hands back, in `later`,
 * the right end of the split segment as a zero-length sample of its
 * importance, to be processed in its turn (`hasLater` set).
 *
 * Two readings of the listing: a merge never shortens the current segment
 * (line 9 takes the larger right end, so a candidate inside it, line 11,
 * changes nothing), and a split keeps the current segment's left end as a
 * sample (line 18).
 */
MCVOL_FUNC int importanceInsert(ImportanceSegment* list, int n, int cap, const ImportanceSegment& cand, float d,
  ImportanceSegment& later, bool& hasLater)
{
  hasLater = false;
  if (n > 0)
  {
    ImportanceSegment& curr = list[n - 1];
    const bool inside = cand.t > curr.t && cand.t < curr.right();
    if (curr.k == cand.k)
    {
      if (cand.t - curr.right() < d)
      {
        // Merge (lines 7-10) or discard (lines 11-13).
        const float r = cand.right() > curr.right() ? cand.right() : curr.right();
        curr.length = r - curr.t;
        return n;
      }
    }
    else if (inside)
    {
      // Split (lines 15-20): [t, right] becomes the sample at t, the
      // candidate, and later the sample at the old right end.
      if (n + 1 > cap)
      {
        return -1;
      }
      later.t = curr.right();
      later.length = 0.f;
      later.k = curr.k;
      later.K = 0.f;
      hasLater = true;
      curr.length = 0.f;
      list[n] = cand;
      return n + 1;
    }
  }
  if (n + 1 > cap)
  {
    return -1;
  }
  list[n] = cand; // insert (lines 1-4, 21-23)
  return n + 1;
}

/**
 * Merges the sorted new samples into the sorted segment list `seg` (`count`
 * entries), Algorithm 1 applied to the combined stream in order of t, and
 * recomputes the integrals over [0, T]. Returns the new count, or -1 (and
 * `seg` unchanged) when the result would exceed `cap`.
 */
MCVOL_FUNC int importanceMerge(ImportanceSegment* seg, int count, int cap, const ImportanceSegment* samples,
  int numSamples, float d, float T, float& total)
{
  ImportanceSegment out[kImportanceCapacity + 1];
  ImportanceSegment pending[kImportanceCapacity];
  int numPending = 0; // sorted by t, smallest first
  int n = 0;
  int i = 0, j = 0;
  const int room = cap < kImportanceCapacity ? cap : kImportanceCapacity;
  while (i < count || j < numSamples || numPending > 0)
  {
    // The next element of the stream: the smallest t of the three sources
    // (old segments first on ties, so an old segment is met before a new
    // sample at its start).
    int src = -1;
    float best = 3.4e38f;
    if (i < count)
    {
      src = 0;
      best = seg[i].t;
    }
    if (j < numSamples && samples[j].t < best)
    {
      src = 1;
      best = samples[j].t;
    }
    if (numPending > 0 && pending[0].t < best)
    {
      src = 2;
    }
    ImportanceSegment cand;
    if (src == 0)
    {
      cand = seg[i++];
    }
    else if (src == 1)
    {
      cand = samples[j++];
    }
    else
    {
      cand = pending[0];
      for (int k = 1; k < numPending; ++k)
      {
        pending[k - 1] = pending[k];
      }
      --numPending;
    }
    ImportanceSegment later;
    bool hasLater = false;
    n = importanceInsert(out, n, room, cand, d, later, hasLater);
    if (n < 0)
    {
      return -1;
    }
    if (hasLater)
    {
      if (numPending >= kImportanceCapacity)
      {
        return -1;
      }
      int k = numPending++;
      while (k > 0 && pending[k - 1].t > later.t)
      {
        pending[k] = pending[k - 1];
        --k;
      }
      pending[k] = later;
    }
  }
  for (int k = 0; k < n; ++k)
  {
    seg[k] = out[k];
  }
  total = importanceIntegrals(seg, n, T);
  return n;
}

/**
 * Sorted sample positions in [0, T] for refinement pass `pass` (Sec. 5.2):
 * pass 0 takes the two ends and one sample in each of N - 2 equal strata; later passes place
 * the strata adaptively over what the list does not pin down yet: half over
 * the gaps between segments (the ray's ends included) and half over the
 * interiors of segments (where a change of importance may hide), each in
 * proportion to length.
 * Returns the number of positions written (at most N).
 */
MCVOL_FUNC int importanceSamplePositions(
  const ImportanceSegment* seg, int count, float T, int N, int pass, Rng& rng, float* pos)
{
  if (!(T > 0.f) || N <= 0)
  {
    return 0;
  }
  if (pass == 0 || count == 0)
  {
    // The ray's two ends, then one sample in each of the N - 2 strata
    // between: with the ends sampled, no border gap is left to guess at (the
    // paper assumes importance 0 beyond the first and last samples).
    if (N < 3)
    {
      const float w = T / float(N);
      for (int k = 0; k < N; ++k)
      {
        pos[k] = (float(k) + rng.next()) * w;
      }
      return N;
    }
    const float w = T / float(N - 2);
    pos[0] = 0.f;
    for (int k = 0; k < N - 2; ++k)
    {
      pos[k + 1] = (float(k) + rng.next()) * w;
    }
    pos[N - 1] = T;
    return N;
  }
  // Intervals in order: gap before segment 0, segment 0, gap, ..., gap to T.
  // Half the samples go to the gaps and half to the segments' interiors,
  // each half in proportion to length: the gaps are where the list knows
  // least, so they shrink geometrically, while long segments are still
  // searched for changes they may hide.
  float gaps = 0.f, inner = 0.f;
  for (int k = 0; k <= count; ++k)
  {
    const float a = k == 0 ? 0.f : seg[k - 1].right();
    const float b = k == count ? T : seg[k].t;
    gaps += b > a ? b - a : 0.f;
    if (k < count)
    {
      inner += seg[k].length;
    }
  }
  if (!(gaps > 0.f) && !(inner > 0.f))
  {
    return 0; // the list covers the ray with points only: nothing left
  }
  const float gapScale = gaps > 0.f ? (inner > 0.f ? 0.5f / gaps : 1.f / gaps) : 0.f;
  const float innerScale = inner > 0.f ? (gaps > 0.f ? 0.5f / inner : 1.f / inner) : 0.f;
  // Stratify the concatenated weighted intervals (total weight 1): stratum m
  // covers [m, m + 1) / N of it, mapped back to t.
  const float w = 1.f / float(N);
  int written = 0;
  float acc = 0.f; // weight before the current interval
  int m = 0;
  float u = (float(m) + rng.next()) * w;
  for (int k = 0; k <= count && m < N; ++k)
  {
    for (int part = 0; part < 2 && m < N; ++part)
    {
      float a, b, scale;
      if (part == 0)
      {
        a = k == 0 ? 0.f : seg[k - 1].right();
        b = k == count ? T : seg[k].t;
        scale = gapScale;
      }
      else
      {
        if (k == count)
        {
          break;
        }
        a = seg[k].t;
        b = seg[k].right();
        scale = innerScale;
      }
      const float len = (b > a ? b - a : 0.f) * scale;
      while (m < N && u < acc + len)
      {
        const float x = a + (u - acc) / scale;
        pos[written++] = x < b ? x : b;
        ++m;
        u = (float(m) + rng.next()) * w;
      }
      acc += len;
    }
  }
  return written;
}

/// Per-ray state of the optimization while tracking: the pixel's list and
/// the integral over the whole ray, K(z).
struct RayImportance
{
  const ImportanceSegment* segments = nullptr;
  int count = 0;
  float total = 0.f;
};

/**
 * A light ray's list (Sec. 5.3): built afresh for every ray to a light (the
 * scatter vertices move, so nothing carries over between passes) from N
 * stratified samples over [0, tmax] (world units), the ray's two ends
 * included. Samples arrive in order, so Algorithm 1 only merges and
 * inserts. Returns false when the list would exceed kImportanceCapacity
 * (the caller then tracks the ray unoptimized and counts it).
 */
MCVOL_HOT bool buildLightRayImportance(const SceneView& s, Vec3f o, Vec3f d, float tmax, Rng& rng,
  ImportanceSegment* seg, RayImportance& out, uint32_t& samples)
{
  const ImportanceView& iv = s.importance;
  const int N = iv.lightRaySamples;
  const float T = tmax * iv.invLengthUnit;
  const float toWorld = 1.f / iv.invLengthUnit;
  const float w = T / float(N - 2 > 0 ? N - 2 : 1);
  const float dist = iv.mergeDistance > 0.f ? iv.mergeDistance : 2.f * w;
  int n = 0;
  ImportanceSegment later;
  bool hasLater = false;
  for (int k = 0; k < N; ++k)
  {
    const float t = k == 0 ? 0.f : (k == N - 1 ? T : (float(k - 1) + rng.next()) * w);
    ImportanceSegment cand;
    cand.t = t;
    cand.k = importanceAt(s, o + d * (t * toWorld));
    n = importanceInsert(seg, n, kImportanceCapacity, cand, dist, later, hasLater);
    if (n < 0)
    {
      samples += uint32_t(k + 1);
      return false;
    }
  }
  samples += uint32_t(N);
  out.segments = seg;
  out.count = n;
  out.total = importanceIntegrals(seg, n, T);
  return true;
}

/// Eq. 8's factor mu'/mu = p / (p + (1 - g)^(2 lambda) h) with Eq. 7's
/// h = (r - q) K + q Kz, for importance g, the integral K before the point and
/// Kz over the whole ray (both backends' tracking and the ray march use it).
MCVOL_HOT float optimizedExtinctionFactor(const ImportanceView& iv, float g, float K, float Kz)
{
  const float h = (iv.r - iv.q) * K + iv.q * Kz;
  const float oneMinusG = 1.f - g;
  const float w = iv.twoLambda == 0.f ? 1.f : (oneMinusG > 0.f ? powf(oneMinusG, iv.twoLambda) : 0.f);
  const float denom = iv.p + w * (h > 0.f ? h : 0.f);
  return denom > 0.f ? iv.p / denom : 1.f;
}

/// The factor mu'/mu at world distance t along the ray, where the importance
/// is g (Eq. 7-8), K from the ray's segment list.
MCVOL_HOT float importanceFactor(const ImportanceView& iv, const RayImportance& ray, float t, float g)
{
  return optimizedExtinctionFactor(iv, g, importanceIntegral(ray.segments, ray.count, t * iv.invLengthUnit), ray.total);
}

/**
 * importanceFactor() on a light ray, whose list runs from the scattering
 * vertex (t = 0) to the light. Eq. 7's x is the vertex by default; with
 * iv.lightRaysFromLight it is the light, and the integral before the point
 * is the rest of the ray's, K(z) - K(t) (the list's integral is the same
 * read from either end: its gaps are interpolated linearly, its ends have
 * importance 0).
 */
MCVOL_HOT float lightRayImportanceFactor(const ImportanceView& iv, const RayImportance& ray, float t, float g)
{
  const float K = importanceIntegral(ray.segments, ray.count, t * iv.invLengthUnit);
  return optimizedExtinctionFactor(iv, g, iv.lightRaysFromLight ? ray.total - K : K, ray.total);
}
} // namespace mcvol
