// SPDX-License-Identifier: BSD-3-Clause
//
// Cached shadows on the device (LightingDesc::cacheShadows): each light's
// grid is filled in the two passes of mcvol/ray/ShadowCache.h, one thread
// per segment and then one per ray, from the same code as the host's.
#include "CUDAInternal.h"

#include "mcvol/ray/ShadowCache.h"

namespace mcvol
{
namespace
{
constexpr int kShadowCacheBlock = 128;

/// The first pass: one thread per segment.
template <BlendMode Mode>
__global__ void shadowCacheSegmentKernel(
  const __grid_constant__ SceneView s, ShadowCacheFrame f, float worldPerIndex, float* __restrict__ nodes)
{
  const int rays = f.dims[0] * f.dims[1];
  const int64_t q = int64_t(blockIdx.x) * blockDim.x + threadIdx.x;
  if (q >= int64_t(rays) * (f.dims[2] - 1))
  {
    return;
  }
  const int r = int(q % rays);
  nodes[q] = shadowCacheSegment<Mode>(s, f, worldPerIndex, r % f.dims[0], r / f.dims[0], int(q / rays));
}

/// The second pass: one thread per ray.
__global__ void shadowCacheSumKernel(ShadowCacheFrame f, float* __restrict__ nodes)
{
  const int r = int(blockIdx.x * blockDim.x + threadIdx.x);
  if (r >= f.dims[0] * f.dims[1])
  {
    return;
  }
  shadowCacheSum(f, nodes, r % f.dims[0], r / f.dims[0]);
}
} // namespace

void CUDARenderer::Internal::linkShadowCaches(const Scene& scene, SceneView& s)
{
  LightingView& L = s.lighting;
  for (int l = 0; l < kMaxLights; ++l)
  {
    L.shadowCache[l] = nullptr;
    DeviceBuffer<float>& grid = this->ShadowGrids[l];
    if (!cachesShadow(s, l))
    {
      // Off costs nothing: a grid no longer asked for is freed.
      grid.release();
      this->ShadowValid[l] = false;
      continue;
    }
    const ShadowCacheKey key = shadowCacheKey(scene, s, l);
    if (!this->ShadowValid[l] || this->ShadowKeys[l] != key)
    {
      // Invalid until the rays are queued: a failed launch leaves no
      // half-filled grid that a later render would take as current.
      this->ShadowValid[l] = false;
      const Vec3f dl = shadowCacheDirection(L, l);
      const ShadowCacheFrame f = ShadowCacheFrame::of(s.volume, dl, L.cacheSpacing);
      this->ShadowFrames[l] = f;
      grid.resize(f.nodes());
      const int64_t rays = int64_t(f.dims[0]) * f.dims[1];
      const int64_t segments = rays * (f.dims[2] - 1);
      const float worldPerIndex = shadowCacheWorldPerIndex(dl);
      withBlendMode(s.blend.mode, [&](auto mode) {
        shadowCacheSegmentKernel<decltype(mode)::value>
          <<<unsigned((segments + kShadowCacheBlock - 1) / kShadowCacheBlock), kShadowCacheBlock>>>(
            s, f, worldPerIndex, grid.ptr);
      });
      shadowCacheSumKernel<<<unsigned((rays + kShadowCacheBlock - 1) / kShadowCacheBlock), kShadowCacheBlock>>>(
        f, grid.ptr);
      MCVOL_CUDA(cudaGetLastError());
      this->ShadowKeys[l] = key;
      this->ShadowValid[l] = true;
      ++this->Updates.shadowCaches;
    }
    L.shadowCache[l] = grid.ptr;
    this->ShadowFrames[l].write(L, l);
  }
  mcvol::linkShadowCaches(L);
}

size_t CUDARenderer::Internal::shadowCacheBytes() const
{
  size_t b = 0;
  for (int l = 0; l < kMaxLights; ++l)
  {
    b += this->ShadowValid[l] ? this->ShadowGrids[l].bytes() : 0;
  }
  return b;
}
} // namespace mcvol
