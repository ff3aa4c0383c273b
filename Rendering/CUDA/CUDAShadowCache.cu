// SPDX-License-Identifier: BSD-3-Clause
//
// Cached shadows on the device (LightingDesc::cacheShadows): each light's
// grid is marched ray by ray (mcvol/ray/ShadowCache.h), one thread per ray
// of the grid, from the same per-ray code as the host's.
#include "CUDAInternal.h"

#include "mcvol/ray/ShadowCache.h"

namespace mcvol
{
namespace
{
constexpr int kShadowCacheBlock = 128;

template <BlendMode Mode>
__global__ void shadowCacheKernel(
  const __grid_constant__ SceneView s, ShadowCacheFrame f, float worldPerIndex, float* __restrict__ nodes)
{
  const int ray = int(blockIdx.x * blockDim.x + threadIdx.x);
  if (ray >= f.dims[0] * f.dims[1])
  {
    return;
  }
  shadowCacheRay<Mode>(s, f, worldPerIndex, nodes, ray % f.dims[0], ray / f.dims[0]);
}
} // namespace

void CUDARenderer::Internal::linkShadowCaches(const Scene& scene, SceneView& s)
{
  LightingView& L = s.lighting;
  for (int l = 0; l < kMaxLights; ++l)
  {
    L.shadowCache[l] = nullptr;
    if (!cachesShadow(s, l))
    {
      continue;
    }
    const ShadowCacheKey key = shadowCacheKey(scene, s, l);
    DeviceBuffer<float>& grid = this->ShadowGrids[l];
    if (!this->ShadowValid[l] || this->ShadowKeys[l] != key)
    {
      // Invalid until the rays are queued: a failed launch leaves no
      // half-filled grid that a later render would take as current.
      this->ShadowValid[l] = false;
      const Vec3f dl = shadowCacheDirection(L, l);
      const ShadowCacheFrame f = ShadowCacheFrame::of(s.volume, dl, L.cacheSpacing);
      grid.resize(size_t(kShadowCacheHeader) + f.nodes());
      float header[kShadowCacheHeader];
      f.write(header);
      MCVOL_CUDA(cudaMemcpy(grid.ptr, header, sizeof(header), cudaMemcpyHostToDevice));
      const int rays = f.dims[0] * f.dims[1];
      const unsigned blocks = unsigned((rays + kShadowCacheBlock - 1) / kShadowCacheBlock);
      const float worldPerIndex = shadowCacheWorldPerIndex(dl);
      withBlendMode(s.blend.mode, [&](auto mode) {
        shadowCacheKernel<decltype(mode)::value>
          <<<blocks, kShadowCacheBlock>>>(s, f, worldPerIndex, grid.ptr + kShadowCacheHeader);
      });
      MCVOL_CUDA(cudaGetLastError());
      this->ShadowKeys[l] = key;
      this->ShadowValid[l] = true;
      ++this->Updates.shadowCaches;
    }
    L.shadowCache[l] = grid.ptr;
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
