// SPDX-License-Identifier: BSD-3-Clause
#pragma once

#include "mcvol/SceneView.h"

#include <cstdint>
#include <type_traits>

namespace mcvol
{
/// Transfer-function sample: linear RGB and extinction (world units^-1).
struct TFSample
{
  Vec3f rgb;
  float sigma = 0.f;
};

/// Largest extinction a pre-classified voxel keeps (larger values, +Inf
/// included, are clamped to it): finite, so that a zero interpolation weight
/// times it stays 0, and far above any render's extinction limit.
constexpr float kMaxClassifiedSigma = 1e30f;

/**
 * One pre-classified voxel (ChannelFormat::Extinction) at x[0..3] = (sigma,
 * sigma r, sigma g, sigma b), sanitised as ChannelSource documents: negative
 * sigma -> 0 (and its colour 0), sigma clamped to kMaxClassifiedSigma, each
 * sigma*c to [0, sigma]. Returns false if any of the four is NaN (the voxel
 * makes the channel transparent where it is read). Shared by the per-ray
 * sampling and the macrocell range builds (host and device), so the ranges
 * bound exactly the values the sampling interpolates.
 */
MCVOL_FUNC bool classifiedVoxel(const float* x, float out[4])
{
  const float s = x[0], r = x[1], g = x[2], b = x[3];
  if (!(s == s) || !(r == r) || !(g == g) || !(b == b))
  {
    return false;
  }
  if (!(s > 0.f))
  {
    out[0] = out[1] = out[2] = out[3] = 0.f;
    return true;
  }
  const float sc = s < kMaxClassifiedSigma ? s : kMaxClassifiedSigma;
  out[0] = sc;
  out[1] = clampf(r, 0.f, sc);
  out[2] = clampf(g, 0.f, sc);
  out[3] = clampf(b, 0.f, sc);
  return true;
}

/// A pre-classified channel's voxel v (index, not element) as classifiedVoxel() reads it.
MCVOL_HOT bool fetchClassified(const ChannelView& c, int64_t v, float out[4])
{
  return classifiedVoxel(static_cast<const float*>(c.data) + v * c.stride, out);
}

/// Optics of a sanitised classified value (sigma, sigma r, sigma g, sigma b):
/// the colour is the ratio (Eq. 23's C~(tau) / tau), black where sigma is 0.
MCVOL_HOT TFSample classifiedOptics(const float v[4])
{
  TFSample t;
  t.sigma = v[0];
  if (v[0] > 0.f)
  {
    const float inv = 1.f / v[0];
    t.rgb = Vec3f(minf(v[1] * inv, 1.f), minf(v[2] * inv, 1.f), minf(v[3] * inv, 1.f));
  }
  return t;
}

/// One voxel of an array-held channel (c.data not null), converted to float.
MCVOL_HOT float fetchArrayVoxel(const ChannelView& c, int64_t v)
{
  const int64_t i = v * c.stride;
  return visitScalarType(c.type,
    [&](auto tag) -> float
    {
      using T = typename decltype(tag)::type;
      const T x = static_cast<const T*>(c.data)[i];
      if constexpr (std::is_same_v<T, double>)
      {
        // In double, before the rounding to float, so data far from zero
        // keeps its resolution (ChannelSource::offset).
        return float(x - c.offset);
      }
      else
      {
        return float(x);
      }
    });
}

#if defined(__CUDA_ARCH__)
/// One voxel of a texture-held channel (ChannelView::voxelTexture, c.data
/// null): the point-sampled texel at the voxel's centre. Only the reference
/// march reads such voxels one by one (its exact corner reads); out of line,
/// so that the division of the flat index stays out of the kernels that
/// inline fetchVoxel().
__device__ __noinline__ inline float fetchTextureVoxel(const ChannelView& c, int64_t v)
{
  const int64_t nx = c.voxelTextureDims[0];
  const int64_t nxy = nx * c.voxelTextureDims[1];
  const int64_t k = v / nxy;
  const int64_t r = v - k * nxy;
  const int64_t j = r / nx;
  const int64_t i = r - j * nx;
  return c.textureScale * tex3D<float>(c.voxelTexture, float(i) + 0.5f, float(j) + 0.5f, float(k) + 0.5f);
}
#endif

/// One voxel of a channel, converted to float, wherever the channel is held.
MCVOL_HOT float fetchVoxel(const ChannelView& c, int64_t v)
{
#if defined(__CUDA_ARCH__)
  if (c.data == nullptr)
  {
    return fetchTextureVoxel(c, v);
  }
#endif
  return fetchArrayVoxel(c, v);
}

/// Index of the voxel nearest to p, clamped to the grid.
MCVOL_HOT int64_t nearestVoxel(const VolumeView& vol, Vec3f p)
{
  int64_t v = 0;
  int64_t stride = 1;
  for (int a = 0; a < 3; ++a)
  {
    const int i = int(clampf(p[a], 0.f, float(vol.dims[a] - 1)) + 0.5f);
    v += stride * int64_t(i < vol.dims[a] ? i : vol.dims[a] - 1);
    stride *= vol.dims[a];
  }
  return v;
}

/// The trilinear footprint of p, clamped to the grid: lower and upper voxel
/// and the weight of the upper one per axis (an axis with one voxel uses it
/// for both, weight 0).
MCVOL_HOT void trilinearFootprint(const VolumeView& vol, Vec3f p, int i0[3], int i1[3], float f[3])
{
  for (int a = 0; a < 3; ++a)
  {
    const float x = clampf(p[a], 0.f, float(vol.dims[a] - 1));
    int i = int(x);
    if (i > vol.dims[a] - 2)
    {
      i = vol.dims[a] - 2 < 0 ? 0 : vol.dims[a] - 2;
    }
    i0[a] = i;
    i1[a] = vol.dims[a] > 1 ? i + 1 : i;
    f[a] = vol.dims[a] > 1 ? x - float(i) : 0.f;
  }
}

/**
 * One voxel (i, j, k) of channel c, converted to float, wherever the channel
 * is held: the point-sampled texel of a texture-held channel (only the
 * reference march reads those in software; the Monte Carlo kernels sample
 * them through the filtered texture) or the array element. Per-axis indices,
 * so the texel read needs no division of a flat index (which, inlined into 8
 * fetches, cost the render kernels registers).
 */
MCVOL_HOT float fetchVoxelAt(const VolumeView& vol, const ChannelView& c, int i, int j, int k)
{
#if defined(__CUDA_ARCH__)
  if (c.data == nullptr)
  {
    return c.textureScale * tex3D<float>(c.voxelTexture, float(i) + 0.5f, float(j) + 0.5f, float(k) + 0.5f);
  }
#endif
  return fetchArrayVoxel(c, int64_t(i) + int64_t(vol.dims[0]) * (int64_t(j) + int64_t(vol.dims[1]) * k));
}

/**
 * Trilinear interpolation (or the nearest voxel, if vol.nearest) of channel n
 * at continuous index p, clamped to the grid (axes with one voxel are
 * constant). Both stay within the macrocell ranges, which cover every voxel
 * a cell's points can read. A NaN voxel among the 8 corners
 * gives NaN, which the transfer-function lookup maps to zero extinction.
 */
MCVOL_HOT float sampleChannel(const VolumeView& vol, int n, Vec3f p)
{
  const ChannelView& c = vol.channels[n];
#if defined(__CUDA_ARCH__)
  if (c.texture != 0)
  {
    // Hardware filtering (linear or point, chosen when the texture object was
    // made to match vol.nearest): texel centres sit at i + 0.5 and the clamp
    // address mode reproduces the clamping below. The weights have 8
    // fractional bits, so values differ from the software path by a fraction
    // of a voxel's step, but stay a convex combination of the same voxels.
    return c.textureScale * tex3D<float>(c.texture, p.x + 0.5f, p.y + 0.5f, p.z + 0.5f);
  }
#endif
  if (vol.nearest)
  {
    int i[3];
    for (int a = 0; a < 3; ++a)
    {
      i[a] = int(clampf(p[a], 0.f, float(vol.dims[a] - 1)) + 0.5f);
      i[a] = i[a] < vol.dims[a] ? i[a] : vol.dims[a] - 1;
    }
    return fetchVoxelAt(vol, c, i[0], i[1], i[2]);
  }
  int i0[3];
  int i1[3];
  float f[3];
  trilinearFootprint(vol, p, i0, i1, f);
  const float v000 = fetchVoxelAt(vol, c, i0[0], i0[1], i0[2]);
  const float v100 = fetchVoxelAt(vol, c, i1[0], i0[1], i0[2]);
  const float v010 = fetchVoxelAt(vol, c, i0[0], i1[1], i0[2]);
  const float v110 = fetchVoxelAt(vol, c, i1[0], i1[1], i0[2]);
  const float v001 = fetchVoxelAt(vol, c, i0[0], i0[1], i1[2]);
  const float v101 = fetchVoxelAt(vol, c, i1[0], i0[1], i1[2]);
  const float v011 = fetchVoxelAt(vol, c, i0[0], i1[1], i1[2]);
  const float v111 = fetchVoxelAt(vol, c, i1[0], i1[1], i1[2]);
  const float x00 = v000 + f[0] * (v100 - v000);
  const float x10 = v010 + f[0] * (v110 - v010);
  const float x01 = v001 + f[0] * (v101 - v001);
  const float x11 = v011 + f[0] * (v111 - v011);
  const float y0 = x00 + f[1] * (x10 - x00);
  const float y1 = x01 + f[1] * (x11 - x01);
  return y0 + f[2] * (y1 - y0);
}

/// The 8 trilinear corners of p (or the nearest voxel, weight 1): voxel
/// indices and weights, clamped to the grid exactly as sampleChannel() does.
struct Corners
{
  int64_t index[8];
  float weight[8];
  int count = 0;
};

MCVOL_HOT Corners cornersOf(const VolumeView& vol, Vec3f p)
{
  Corners c;
  if (vol.nearest)
  {
    c.index[0] = nearestVoxel(vol, p);
    c.weight[0] = 1.f;
    c.count = 1;
    return c;
  }
  int i0[3];
  int i1[3];
  float f[3];
  trilinearFootprint(vol, p, i0, i1, f);
  const int64_t sy = vol.dims[0];
  const int64_t sz = int64_t(vol.dims[0]) * vol.dims[1];
  for (int k = 0; k < 8; ++k)
  {
    const int bx = k & 1, by = (k >> 1) & 1, bz = (k >> 2) & 1;
    c.index[k] = (bx ? i1[0] : i0[0]) + (by ? i1[1] : i0[1]) * sy + (bz ? i1[2] : i0[2]) * sz;
    c.weight[k] = (bx ? f[0] : 1.f - f[0]) * (by ? f[1] : 1.f - f[1]) * (bz ? f[2] : 1.f - f[2]);
  }
  c.count = 8;
  return c;
}

/**
 * Extinction-based sampling of a pre-classified channel n at continuous index
 * p (Kraus and Buerger Sec. 3.3): sigma and sigma*colour interpolated
 * trilinearly (or the nearest voxel, if vol.nearest) with the footprint and
 * clamping of sampleChannel(), colour their ratio. A NaN among the voxels
 * read gives sigma 0 (transparent). Always software sampling (no texture).
 * It walks the corners itself rather than through cornersOf(): built on
 * cornersOf()'s arrays, it made the expected-value render kernel 17% slower
 * on scalar-only scenes, which never call it (H100, NYX-like, 1.06 -> 1.24
 * ms per frame).
 */
MCVOL_COLD TFSample sampleClassified(const VolumeView& vol, int n, Vec3f p)
{
  const ChannelView& c = vol.channels[n];
  float acc[4] = { 0.f, 0.f, 0.f, 0.f };
  if (vol.nearest)
  {
    if (!fetchClassified(c, nearestVoxel(vol, p), acc))
    {
      return TFSample();
    }
    return classifiedOptics(acc);
  }
  int i0[3];
  int i1[3];
  float f[3];
  trilinearFootprint(vol, p, i0, i1, f);
  const int64_t sy = vol.dims[0];
  const int64_t sz = int64_t(vol.dims[0]) * vol.dims[1];
  for (int k = 0; k < 8; ++k)
  {
    const int bx = k & 1, by = (k >> 1) & 1, bz = (k >> 2) & 1;
    const int64_t v = (bx ? i1[0] : i0[0]) + (by ? i1[1] : i0[1]) * sy + (bz ? i1[2] : i0[2]) * sz;
    const float w = (bx ? f[0] : 1.f - f[0]) * (by ? f[1] : 1.f - f[1]) * (bz ? f[2] : 1.f - f[2]);
    float x[4];
    if (!fetchClassified(c, v, x))
    {
      return TFSample();
    }
    acc[0] += w * x[0];
    acc[1] += w * x[1];
    acc[2] += w * x[2];
    acc[3] += w * x[3];
  }
  return classifiedOptics(acc);
}

/// Continuous texel coordinate of scalar s in channel n's table, in [0, K-1];
/// NaN maps to -1 (no texel).
MCVOL_HOT float texelCoord(const TableView& t, int n, float s)
{
  const float x = (s - t.scalarMin[n]) * t.scale[n];
  if (!(x == x))
  {
    return -1.f;
  }
  return clampf(x, 0.f, float(t.size - 1));
}

/// Linear interpolation between texels of (r, g, b, extinction). Extinction,
/// not opacity, is interpolated, so a majorant taken over the covered texels
/// bounds every interpolated value.
MCVOL_HOT TFSample lookupTF(const TableView& t, int n, float s)
{
  TFSample out;
  const float x = texelCoord(t, n, s);
  if (x < 0.f)
  {
    return out; // NaN scalar: transparent
  }
  int i = int(x);
  if (i > t.size - 2)
  {
    i = t.size - 2;
  }
  const float f = x - float(i);
  const float* a = t.texels + (int64_t(n) * t.size + i) * 4;
  const float* b = a + 4;
  out.rgb = Vec3f(a[0] + f * (b[0] - a[0]), a[1] + f * (b[1] - a[1]), a[2] + f * (b[2] - a[2]));
  out.sigma = a[3] + f * (b[3] - a[3]);
  return out;
}

} // namespace mcvol
