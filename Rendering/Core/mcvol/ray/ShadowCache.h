// SPDX-License-Identifier: BSD-3-Clause
#pragma once

#include "mcvol/ray/Blend.h"
#include "mcvol/ray/DDA.h"

#include <cmath>

namespace mcvol
{
/**
 * Cached shadows: the transmittance towards a directional light, stored on
 * a grid of nodes aligned with the light and interpolated trilinearly,
 * instead of a shadow ray tracked through the volume. A biased option
 * (LightingDesc::cacheShadows): shadow edges finer than the node spacing
 * blur. Its error is measured against tracked shadows
 * (Documentation/performance.md). Per-ray code, shared by the backends.
 *
 * The grid's third axis points to the light, and its nodes along that axis
 * lie on rays towards the light. The grid is filled in two passes: each
 * segment between neighbouring nodes of a ray gets its optical depth (the
 * extinction integrated by the midpoint rule at kShadowCacheSamplesPerVoxel
 * points per voxel; outside the volume's box nothing absorbs), all
 * segments in parallel; then each ray sums its segments from the light's
 * side, the transmittance at a node being exp(-sum) of the segments
 * between it and the light. A value is therefore exact up to that rule
 * along each ray, and a lookup interpolates once across rays: no error
 * accumulates from node to node, as it would in a grid aligned with the
 * volume filled slice by slice. Both passes are the same code on both
 * backends.
 */

/// Points per voxel of length at which a ray of the grid samples the extinction.
constexpr float kShadowCacheSamplesPerVoxel = 2.f;
/// The node spacing's range, voxels (LightingDesc::cacheSpacing).
constexpr float kShadowCacheMinSpacing = 0.5f;
constexpr float kShadowCacheMaxSpacing = 64.f;
/**
 * A light's grid: node (i, j, k) at index point origin + i step[0] axis[0]
 * + j step[1] axis[1] + k step[2] axis[2], axis[2] the unit index-space
 * direction towards the light, axis[0] and axis[1] orthonormal to it; the
 * nodes cover the volume's box, at least 2 per axis. Node (i, j, k) is
 * stored at i + dims[0] (j + dims[1] k) after the header.
 */
struct ShadowCacheFrame
{
  Vec3f origin;
  Vec3f axis[3];
  float step[3] = { 1.f, 1.f, 1.f };
  int dims[3] = { 2, 2, 2 };

  /// The frame of a light in index direction dl (per unit world length, not
  /// zero) over volume v, at `spacing` index units.
  MCVOL_FUNC static ShadowCacheFrame of(const VolumeView& v, Vec3f dl, float spacing)
  {
    ShadowCacheFrame f;
    const Vec3f w = dl * (1.f / sqrtf(dot(dl, dl)));
    // An orthonormal basis around w (Duff et al. 2017, as directionAround()).
    const float sign = w.z >= 0.f ? 1.f : -1.f;
    const float a = -1.f / (sign + w.z);
    const float b = w.x * w.y * a;
    f.axis[0] = Vec3f(1.f + sign * w.x * w.x * a, sign * b, -sign * w.x);
    f.axis[1] = Vec3f(b, sign + w.y * w.y * a, -w.y);
    f.axis[2] = w;
    float lo[3] = { 3.4e38f, 3.4e38f, 3.4e38f };
    float hi[3] = { -3.4e38f, -3.4e38f, -3.4e38f };
    for (int corner = 0; corner < 8; ++corner)
    {
      const Vec3f c((corner & 1) ? v.boxHi.x : v.boxLo.x, (corner & 2) ? v.boxHi.y : v.boxLo.y,
        (corner & 4) ? v.boxHi.z : v.boxLo.z);
      for (int e = 0; e < 3; ++e)
      {
        const float x = dot(c, f.axis[e]);
        lo[e] = x < lo[e] ? x : lo[e];
        hi[e] = x > hi[e] ? x : hi[e];
      }
    }
    for (int e = 0; e < 3; ++e)
    {
      const float extent = hi[e] - lo[e];
      const int cells = extent > 0.f ? int(ceilf(extent / spacing - 1e-3f)) : 1;
      f.dims[e] = (cells < 1 ? 1 : cells) + 1;
      f.step[e] = extent > 0.f ? extent / float(f.dims[e] - 1) : 1.f;
    }
    f.origin = f.axis[0] * lo[0] + f.axis[1] * lo[1] + f.axis[2] * lo[2];
    return f;
  }
  MCVOL_FUNC size_t nodes() const { return size_t(dims[0]) * size_t(dims[1]) * size_t(dims[2]); }
  MCVOL_FUNC size_t index(int i, int j, int k) const
  {
    return size_t(i) + size_t(dims[0]) * (size_t(j) + size_t(dims[1]) * size_t(k));
  }
  /// Light l's frame in L, as cachedTransmittance() reads it: the origin,
  /// each axis divided by its step (a point's node coordinates are then
  /// dot products), the dims.
  MCVOL_FUNC void write(LightingView& L, int l) const
  {
    float* h = L.cacheFrame[l];
    h[0] = origin.x;
    h[1] = origin.y;
    h[2] = origin.z;
    for (int e = 0; e < 3; ++e)
    {
      const Vec3f a = axis[e] * (1.f / step[e]);
      h[3 + 3 * e] = a.x;
      h[4 + 3 * e] = a.y;
      h[5 + 3 * e] = a.z;
      L.cacheDims[l][e] = dims[e];
    }
  }
};

/// Whether index point p lies in the volume's box.
MCVOL_FUNC bool insideBox(const VolumeView& v, Vec3f p)
{
  return p.x >= v.boxLo.x && p.x <= v.boxHi.x && p.y >= v.boxLo.y && p.y <= v.boxHi.y && p.z >= v.boxLo.z &&
    p.z <= v.boxHi.z;
}

/**
 * The first pass: the optical depth of the segment from node (i, j, k) to
 * node (i, j, k + 1), k below the last node. worldPerIndex is the world
 * length of a unit of index length along the light (1 / |dl|). Extinction
 * that is NaN or negative counts as 0; the result is >= 0 (infinite where
 * the extinction is).
 */
template <BlendMode Mode>
MCVOL_HOT float shadowCacheSegment(
  const SceneView& s, const ShadowCacheFrame& f, float worldPerIndex, int i, int j, int k)
{
  const Vec3f base = f.origin + f.axis[0] * (float(i) * f.step[0]) + f.axis[1] * (float(j) * f.step[1]) +
    f.axis[2] * (float(k) * f.step[2]);
  int n = int(ceilf(f.step[2] * kShadowCacheSamplesPerVoxel));
  n = n < 1 ? 1 : n;
  const float dt = f.step[2] / float(n); // index length
  float tau = 0.f;
  for (int m = 0; m < n; ++m)
  {
    const Vec3f p = base + f.axis[2] * ((float(m) + 0.5f) * dt);
    if (insideBox(s.volume, p))
    {
      const float sigma = blendedOptics<Mode>(s, s.active, s.numActive, p).sigma;
      if (sigma > 0.f)
      {
        tau += sigma;
      }
    }
  }
  return tau * (dt * worldPerIndex);
}

/**
 * The second pass over ray (i, j): `nodes` holds each segment's optical
 * depth at its lower node (the last node holds nothing); afterwards each
 * node holds its transmittance towards the light, in [0, 1].
 */
MCVOL_FUNC void shadowCacheSum(const ShadowCacheFrame& f, float* nodes, int i, int j)
{
  const int last = f.dims[2] - 1;
  float tau = 0.f;
  nodes[f.index(i, j, last)] = 1.f;
  for (int k = last - 1; k >= 0; --k)
  {
    float& v = nodes[f.index(i, j, k)];
    tau += v;
    v = tau > 0.f ? expf(-tau) : 1.f;
  }
}

/// Light l's cached transmittance at index point x: trilinear between the
/// grid's nodes (LightingView::shadowCache[l] must be set); points beyond
/// the grid read its border.
MCVOL_HOT float cachedTransmittance(const LightingView& L, int l, Vec3f x)
{
  const float* h = L.cacheFrame[l];
  const int* dims = L.cacheDims[l];
  const Vec3f r = x - Vec3f(h[0], h[1], h[2]);
  int lo[3];
  float f[3];
  for (int a = 0; a < 3; ++a)
  {
    float u = dot(r, Vec3f(h[3 + 3 * a], h[4 + 3 * a], h[5 + 3 * a]));
    const float top = float(dims[a] - 1);
    u = u > 0.f ? (u < top ? u : top) : 0.f; // also NaN to 0
    int i = int(u);
    i = i > dims[a] - 2 ? dims[a] - 2 : i;
    lo[a] = i;
    f[a] = u - float(i);
  }
  const size_t sy = size_t(dims[0]);
  const size_t sz = sy * size_t(dims[1]);
  const float* c = L.shadowCache[l] + size_t(lo[0]) + sy * size_t(lo[1]) + sz * size_t(lo[2]);
  const float x00 = c[0] + f[0] * (c[1] - c[0]);
  const float x10 = c[sy] + f[0] * (c[sy + 1] - c[sy]);
  const float x01 = c[sz] + f[0] * (c[sz + 1] - c[sz]);
  const float x11 = c[sz + sy] + f[0] * (c[sz + sy + 1] - c[sz + sy]);
  const float y0 = x00 + f[1] * (x10 - x00);
  const float y1 = x01 + f[1] * (x11 - x01);
  return y0 + f[2] * (y1 - y0);
}

/// Whether light l of L has a cached shadow.
MCVOL_FUNC bool shadowCached(const LightingView& L, int l)
{
  return L.shadowCache[l] != nullptr;
}
} // namespace mcvol
