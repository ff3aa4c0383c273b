// SPDX-License-Identifier: BSD-3-Clause
#pragma once

#include "mcvol/ray/SceneView.h"

#include <algorithm>
#include <cstdint>
#include <cstring>
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

/**
 * Host code: pre-classified voxel v of `data` (float32, or float16 times
 * `scale`; `stride` in elements) as classifiedVoxel() reads it. The one
 * reader of both layouts: the per-ray sampling, the macrocell ranges and the
 * CUDA backend's upload (which widens float16 to float32, the same values).
 * Multiplying by a power-of-two scale (PyramidLevel::toHalfPrecision) is
 * exact.
 */
inline bool classifiedVoxelAt(const void* data, ScalarType type, double scale, int64_t stride, int64_t v, float out[4])
{
  if (type == ScalarType::Float16)
  {
    const uint16_t* h = static_cast<const uint16_t*>(data) + v * stride;
    const float s = float(scale);
    const uint16_t top = std::max(std::max(h[0], h[1]), std::max(h[2], h[3]));
    float x[4];
    if (top < 0x7c00u)
    {
      // The common case, every value finite and not negative (all a
      // pyramid level holds but NaN): the bits shifted into a float's are
      // the value times 2^-112, exactly (subnormals included), so the
      // decode is a shift and two exact multiplications, without
      // halfToFloat's branches (which made the CPU's level-1 frames markedly
      // slower).
      for (int e = 0; e < 4; ++e)
      {
        const uint32_t bits = uint32_t(h[e]) << 13;
        float f;
        std::memcpy(&f, &bits, sizeof f);
        x[e] = f * 0x1p112f * s;
      }
    }
    else
    {
      // A sign bit, an infinity or NaN: the exact decode, sanitised below.
      for (int e = 0; e < 4; ++e)
      {
        x[e] = halfToFloat(h[e]) * s;
      }
    }
    return classifiedVoxel(x, out);
  }
  return classifiedVoxel(static_cast<const float*>(data) + v * stride, out);
}

#if defined(__CUDACC__)
/// Texel (i, j, k) of a float4 texture of pre-classified voxels (sanitised
/// and NaN-free on upload) through its point object, as classifiedVoxel()
/// reads it (declared in both of nvcc's passes: the CUDA backend's range
/// kernels call it from device code of their own).
__device__ inline bool classifiedTexel(cudaTextureObject_t tex, int i, int j, int k, float out[4])
{
  const float4 t = tex3D<float4>(tex, float(i) + 0.5f, float(j) + 0.5f, float(k) + 0.5f);
  const float x[4] = { t.x, t.y, t.z, t.w };
  return classifiedVoxel(x, out);
}
#endif

#if defined(__CUDA_ARCH__)

/// Voxel (i, j, k) of a texture-held pre-classified channel. Out of line,
/// as fetchTextureVoxel(): the march kernels inline fetchClassified() for
/// scalar scenes too, and the float4 read inlined there costs them
/// registers.
__device__ __noinline__ inline bool fetchClassifiedTexelAt(const ChannelView& c, int i, int j, int k, float out[4])
{
  return classifiedTexel(c.voxelTexture, i, j, k, out);
}

/// The same by flat voxel index v (divided back into i, j, k).
__device__ __noinline__ inline bool fetchClassifiedTexel(const ChannelView& c, int64_t v, float out[4])
{
  const int64_t nx = c.voxelTextureDims[0];
  const int64_t nxy = nx * c.voxelTextureDims[1];
  const int64_t k = v / nxy;
  const int64_t r = v - k * nxy;
  const int64_t j = r / nx;
  return classifiedTexel(c.voxelTexture, int(r - j * nx), int(j), int(k), out);
}
#endif

/// A pre-classified channel's voxel v (index, not element) as classifiedVoxel() reads it.
MCVOL_HOT bool fetchClassified(const ChannelView& c, int64_t v, float out[4])
{
#if defined(__CUDA_ARCH__)
  if (c.data == nullptr)
  {
    return fetchClassifiedTexel(c, v, out);
  }
  return classifiedVoxel(static_cast<const float*>(c.data) + v * c.stride, out);
#else
  return classifiedVoxelAt(c.data, c.type, c.offset, c.stride, v, out);
#endif
}

/// fetchClassified() of voxel (i, j, k) of a grid dims[0] x dims[1] wide:
/// per-axis indices, so that a texture-held channel's texel is read without
/// dividing a flat index (the exact march reads 8 of them per sample).
MCVOL_HOT bool fetchClassifiedAt(const ChannelView& c, const int dims[3], int i, int j, int k, float out[4])
{
#if defined(__CUDA_ARCH__)
  if (c.data == nullptr)
  {
    return fetchClassifiedTexelAt(c, i, j, k, out);
  }
#endif
  const int64_t v = int64_t(i) + int64_t(dims[0]) * (int64_t(j) + int64_t(dims[1]) * int64_t(k));
#if defined(__CUDA_ARCH__)
  return classifiedVoxel(static_cast<const float*>(c.data) + v * c.stride, out);
#else
  return classifiedVoxelAt(c.data, c.type, c.offset, c.stride, v, out);
#endif
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
 * Uniform cubic B-spline weight of tap k (0..3: voxel floor(x) - 1 + k) at
 * fraction t in [0, 1) past voxel floor(x) (the cubic B-spline of Sigg and
 * Hadwiger, GPU Gems 2 ch. 20): B(d) at the tap's distance d = |t - k + 1|.
 * The four are >= 0 and sum to 1, so a sample is a convex combination of
 * the voxels it reads.
 */
MCVOL_FUNC float bsplineWeight(float t, int k)
{
  const float d = fabsf(t - float(k - 1));
  if (d < 1.f)
  {
    return (4.f + d * d * (3.f * d - 6.f)) * (1.f / 6.f);
  }
  const float e = d < 2.f ? 2.f - d : 0.f;
  return e * e * e * (1.f / 6.f);
}

/// The four weights bsplineWeight(t, 0..3).
MCVOL_FUNC void bsplineWeights(float t, float w[4])
{
  for (int k = 0; k < 4; ++k)
  {
    w[k] = bsplineWeight(t, k);
  }
}

/// One axis of a cubic B-spline footprint: voxel i = floor(x) of the point
/// clamped to [0, last] and the fraction t past it (cubicTap() gives the taps).
struct CubicAxis
{
  int i = 0;
  int last = 0;
  float t = 0.f;
};

MCVOL_FUNC CubicAxis cubicAxis(float p, int dim)
{
  CubicAxis a;
  a.last = dim - 1;
  const float x = clampf(p, 0.f, float(a.last));
  const float fl = floorf(x);
  a.i = int(fl);
  a.t = x - fl;
  return a;
}

/// Tap k (0..3) of axis a: voxel i - 1 + k clamped to the grid as the
/// trilinear path clamps (edge voxels repeat; an axis with one voxel reads
/// it four times, so it is constant).
MCVOL_FUNC int cubicTap(const CubicAxis& a, int k)
{
  const int v = a.i - 1 + k;
  return v < 0 ? 0 : (v > a.last ? a.last : v);
}

/**
 * Cubic B-spline sample of scalar channel n at continuous index p
 * (Interpolation::Cubic), clamped to the grid as sampleChannel() clamps. A
 * NaN voxel among the 64 read gives NaN (the transfer function maps it to
 * zero extinction), as among trilinear's 8. The weights are convex, so the
 * sample stays within the range of the voxels read, which the macrocell
 * ranges cover (footprintApron(true)).
 *
 * Out of line (MCVOL_COLD), and register-light: on the device a call's
 * callee clobbers the caller's registers, so a callee that holds many
 * values (its loops unrolled, 24 weights and indices) made the lit and
 * optimized render kernels spill around the call (ptxas -warn-spills,
 * sm_90). The loops stay rolled and weights are computed per tap.
 *
 * On the device, a channel with a (linear-filtered) texture combines 8
 * hardware trilinear fetches (Sigg and Hadwiger, GPU Gems 2 ch. 20): per
 * axis, the taps (w0, w1) are one linear fetch at i - 1 + w1 / (w0 + w1)
 * weighted w0 + w1, and (w2, w3) one at i + 1 + w3 / (w2 + w3) weighted
 * w2 + w3 (both sums >= 1/6); the clamp address mode repeats the edge
 * texels as cubicTap() does. The hardware's 8-bit fractional weights make
 * it differ from the 64-tap sum by a fraction of the voxels' local
 * differences. Elsewhere (CPU, arrays, texture-held voxels read exactly
 * through the point object) it sums the 64 voxels.
 */
MCVOL_COLD float sampleChannelCubic(const VolumeView& vol, int n, Vec3f p)
{
  const ChannelView& c = vol.channels[n];
  const CubicAxis ax = cubicAxis(p.x, vol.dims[0]);
  const CubicAxis ay = cubicAxis(p.y, vol.dims[1]);
  const CubicAxis az = cubicAxis(p.z, vol.dims[2]);
#if defined(__CUDA_ARCH__)
  if (c.texture != 0)
  {
    float g0[3];
    float h0[3];
    float h1[3];
    const CubicAxis* axes[3] = { &ax, &ay, &az };
#pragma unroll
    for (int a = 0; a < 3; ++a)
    {
      const float t = axes[a]->t;
      const float w0 = bsplineWeight(t, 0), w1 = bsplineWeight(t, 1);
      const float w2 = bsplineWeight(t, 2), w3 = bsplineWeight(t, 3);
      g0[a] = w0 + w1;
      // Texel coordinates: index + 0.5 (texel centres).
      h0[a] = float(axes[a]->i) - 0.5f + w1 / g0[a];
      h1[a] = float(axes[a]->i) + 1.5f + w3 / (w2 + w3);
    }
    const cudaTextureObject_t tex = c.texture;
    // g1 = 1 - g0 (the four weights sum to 1).
    const float y0 = g0[1] *
        (g0[0] * tex3D<float>(tex, h0[0], h0[1], h0[2]) + (1.f - g0[0]) * tex3D<float>(tex, h1[0], h0[1], h0[2])) +
      (1.f - g0[1]) *
        (g0[0] * tex3D<float>(tex, h0[0], h1[1], h0[2]) + (1.f - g0[0]) * tex3D<float>(tex, h1[0], h1[1], h0[2]));
    const float y1 = g0[1] *
        (g0[0] * tex3D<float>(tex, h0[0], h0[1], h1[2]) + (1.f - g0[0]) * tex3D<float>(tex, h1[0], h0[1], h1[2])) +
      (1.f - g0[1]) *
        (g0[0] * tex3D<float>(tex, h0[0], h1[1], h1[2]) + (1.f - g0[0]) * tex3D<float>(tex, h1[0], h1[1], h1[2]));
    return c.textureScale * (g0[2] * y0 + (1.f - g0[2]) * y1);
  }
#endif
  float sum = 0.f;
  MCVOL_NO_UNROLL
  for (int k = 0; k < 4; ++k)
  {
    const int z = cubicTap(az, k);
    float plane = 0.f;
    MCVOL_NO_UNROLL
    for (int j = 0; j < 4; ++j)
    {
      const int y = cubicTap(ay, j);
      float row = 0.f;
      MCVOL_NO_UNROLL
      for (int i = 0; i < 4; ++i)
      {
        row += bsplineWeight(ax.t, i) * fetchVoxelAt(vol, c, cubicTap(ax, i), y, z);
      }
      plane += bsplineWeight(ay.t, j) * row;
    }
    sum += bsplineWeight(az.t, k) * plane;
  }
  return sum;
}

/**
 * Trilinear interpolation (or the nearest voxel, if vol.nearest) of channel n
 * at continuous index p, clamped to the grid (axes with one voxel are
 * constant). Both stay within the macrocell ranges, which cover every voxel
 * a cell's points can read. A NaN voxel among the 8 corners
 * gives NaN, which the transfer-function lookup maps to zero extinction.
 * It ignores vol.cubic: channelOptics() sends cubic sampling to
 * sampleChannelCubic() on its out-of-line path, so that this inlined code
 * (and the render kernels around it) stays as it is. A check and call here
 * made the render kernels spill registers (ptxas -warn-spills: the max and
 * mix kernels).
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

#if !defined(__CUDA_ARCH__)
/**
 * CPU only: starts loading the four (y, z) rows of an array-held
 * pre-classified channel's trilinear footprint i0..i1 (an x pair of float4
 * voxels shares a cache line but for one in 4; of float16 voxels, but for
 * one in 8). On large levels every corner
 * misses the caches; issuing the rows' loads together, before the corners
 * are read and checked one by one, overlaps their latency (faster frames on
 * large levels). Not compiled into device code.
 */
inline void prefetchClassifiedRows(const ChannelView& c, const int dims[3], const int i0[3], const int i1[3])
{
  if (c.data == nullptr)
  {
    return;
  }
  const char* base = static_cast<const char*>(c.data);
  const int64_t bytes = c.stride * (c.type == ScalarType::Float16 ? 2 : 4); // per voxel
  for (int k = 0; k < 4; ++k)
  {
    const int j = (k & 1) ? i1[1] : i0[1];
    const int z = (k & 2) ? i1[2] : i0[2];
    const int64_t v = int64_t(i0[0]) + int64_t(dims[0]) * (int64_t(j) + int64_t(dims[1]) * int64_t(z));
    __builtin_prefetch(base + v * bytes);
  }
}
#endif

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
 * Cubic B-spline variant of sampleClassified() (vol.cubic): sigma and
 * sigma*colour each filtered over the 64 voxels of the footprint
 * (cubicTap()), colour their ratio (Kraus and Buerger's extinction-based
 * sampling, Sec. 3.3, with Sigg and Hadwiger's cubic B-spline in place of
 * trilinear interpolation; the paper's own B-spline is quadratic). Convex weights keep sigma within the voxels'
 * sigma range (the macrocell majorants) and sigma*colour within [0, sigma].
 * A NaN among the voxels read gives sigma 0 (transparent), as in the
 * trilinear variant. Register-light, as sampleChannelCubic() explains.
 */
MCVOL_COLD TFSample sampleClassifiedCubic(const VolumeView& vol, int n, Vec3f p)
{
  const ChannelView& c = vol.channels[n];
  const CubicAxis ax = cubicAxis(p.x, vol.dims[0]);
  const CubicAxis ay = cubicAxis(p.y, vol.dims[1]);
  const CubicAxis az = cubicAxis(p.z, vol.dims[2]);
  float acc[4] = { 0.f, 0.f, 0.f, 0.f };
  MCVOL_NO_UNROLL
  for (int k = 0; k < 4; ++k)
  {
    MCVOL_NO_UNROLL
    for (int j = 0; j < 4; ++j)
    {
      const float wjk = bsplineWeight(ay.t, j) * bsplineWeight(az.t, k);
      const int y = cubicTap(ay, j);
      const int z = cubicTap(az, k);
      MCVOL_NO_UNROLL
      for (int i = 0; i < 4; ++i)
      {
        float x[4];
        if (!fetchClassifiedAt(c, vol.dims, cubicTap(ax, i), y, z, x))
        {
          return TFSample();
        }
        const float w = bsplineWeight(ax.t, i) * wjk;
        acc[0] += w * x[0];
        acc[1] += w * x[1];
        acc[2] += w * x[2];
        acc[3] += w * x[3];
      }
    }
  }
  return classifiedOptics(acc);
}

/**
 * Extinction-based sampling of a pre-classified channel n at continuous index
 * p (Kraus and Buerger Sec. 3.3): sigma and sigma*colour interpolated
 * trilinearly (or the nearest voxel, if vol.nearest; the cubic B-spline, if
 * vol.cubic: sampleClassifiedCubic) with the footprint and
 * clamping of sampleChannel(), colour their ratio. A NaN among the voxels
 * read gives sigma 0 (transparent). Software sampling, or on the device the
 * hardware's trilinear (or point) filter of a float4 texture of the
 * sanitised voxels where the CUDA backend holds one (a NaN-free channel
 * under texture sampling). It walks the corners itself rather than through
 * cornersOf(): built on cornersOf()'s arrays, it made the expected-value
 * render kernel markedly slower on scalar-only scenes, which never call it.
 */
MCVOL_COLD TFSample sampleClassified(const VolumeView& vol, int n, Vec3f p)
{
  if (vol.cubic)
  {
    // Dispatched here rather than in channelOptics(), which is inlined into
    // every render kernel: this function is already out of line.
    return sampleClassifiedCubic(vol, n, p);
  }
  const ChannelView& c = vol.channels[n];
#if defined(__CUDA_ARCH__)
  if (c.texture != 0)
  {
    // The hardware filters sigma and sigma*colour together: the
    // extinction-based interpolation itself (8-bit fractional weights, as
    // for scalar channels; a convex combination, so the majorants still
    // bound it).
    const float4 t = tex3D<float4>(c.texture, p.x + 0.5f, p.y + 0.5f, p.z + 0.5f);
    const float v[4] = { t.x, t.y, t.z, t.w };
    return classifiedOptics(v);
  }
#endif
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
#if !defined(__CUDA_ARCH__)
  prefetchClassifiedRows(c, vol.dims, i0, i1);
#endif
  for (int k = 0; k < 8; ++k)
  {
    const int bx = k & 1, by = (k >> 1) & 1, bz = (k >> 2) & 1;
    const float w = (bx ? f[0] : 1.f - f[0]) * (by ? f[1] : 1.f - f[1]) * (bz ? f[2] : 1.f - f[2]);
    float x[4];
    if (!fetchClassifiedAt(c, vol.dims, bx ? i1[0] : i0[0], by ? i1[1] : i0[1], bz ? i1[2] : i0[2], x))
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
