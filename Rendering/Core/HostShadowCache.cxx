// SPDX-License-Identifier: BSD-3-Clause
// Cached shadows on the host: which lights, their keys, the fill.
#include "mcvol/HostShadowCache.h"

#include "mcvol/ray/Lighting.h"

#include <chrono>
#include <cmath>

#ifdef _OPENMP
#include <omp.h>
#endif

namespace mcvol
{
bool cachesShadow(const SceneView& s, int l)
{
  const LightingView& L = s.lighting;
  return L.enabled && L.shadows && L.cacheShadows && l < L.numLights && L.lightType[l] == 0 && !s.outside &&
    s.blend.mode != BlendMode::Composite && !(s.importance.enabled && s.importance.lightRays);
}

Vec3f shadowCacheDirection(const LightingView& L, int l)
{
  return mul3(L.toIndex, L.lightVector[l]);
}

ShadowCacheKey shadowCacheKey(const Scene& scene, const SceneView& s, int l)
{
  ShadowCacheKey k;
  size_t i = 0;
  auto put = [&](double v) { k.values[i++] = v; };
  put(double(scene.id()));
  put(double(scene.dataVersion()));
  put(double(scene.tableVersion()));
  put(double(int(s.blend.mode)));
  put(s.volume.nearest ? 1 : 0);
  put(s.volume.cubic ? 1 : 0);
  put(s.lighting.cacheSpacing);
  const Vec3f d = shadowCacheDirection(s.lighting, l);
  for (int a = 0; a < 3; ++a)
  {
    put(d[a]);
    put(s.volume.boxLo[a]);
    put(s.volume.boxHi[a]);
  }
  put(s.numActive);
  for (int n = 0; n < kMaxChannels; ++n)
  {
    put(n < s.numActive ? s.active[n] : -1);
  }
  return k;
}

void linkShadowCaches(LightingView& L)
{
  bool all = L.numLights > 0;
  for (int l = 0; l < L.numLights; ++l)
  {
    all = all && L.shadowCache[l] != nullptr;
  }
  L.cachedOnly = all && !(L.ambient.x > 0.f || L.ambient.y > 0.f || L.ambient.z > 0.f);
}

float shadowCacheWorldPerIndex(Vec3f dl)
{
  return 1.f / std::sqrt(dot(dl, dl));
}

namespace
{
template <BlendMode Mode>
void fill(const SceneView& s, const ShadowCacheFrame& f, float worldPerIndex, float* nodes, int threads)
{
  const int rays = f.dims[0] * f.dims[1];
  const int64_t segments = int64_t(rays) * int64_t(f.dims[2] - 1);
  const int nt = threads > 0 ? threads : omp_get_max_threads();
#pragma omp parallel num_threads(nt)
  {
#pragma omp for schedule(static)
    for (int64_t q = 0; q < segments; ++q)
    {
      const int r = int(q % rays);
      const int k = int(q / rays);
      nodes[size_t(q)] = shadowCacheSegment<Mode>(s, f, worldPerIndex, r % f.dims[0], r / f.dims[0], k);
    }
#pragma omp for schedule(static)
    for (int r = 0; r < rays; ++r)
    {
      shadowCacheSum(f, nodes, r % f.dims[0], r / f.dims[0]);
    }
  }
}
} // namespace

void HostShadowCache::prepare(const Scene& scene, SceneView& s, int threads)
{
  LightingView& L = s.lighting;
  this->LastRebuilt = 0;
  this->LastSeconds = 0.0;
  const auto start = std::chrono::steady_clock::now();
  for (int l = 0; l < kMaxLights; ++l)
  {
    L.shadowCache[l] = nullptr;
    std::vector<float>& grid = this->Grids[size_t(l)];
    if (!cachesShadow(s, l))
    {
      // Off costs nothing: a grid no longer asked for is freed.
      std::vector<float>().swap(grid);
      this->Valid[size_t(l)] = false;
      continue;
    }
    const ShadowCacheKey key = shadowCacheKey(scene, s, l);
    ShadowCacheFrame& f = this->Frames[size_t(l)];
    if (!this->Valid[size_t(l)] || this->Keys[size_t(l)] != key)
    {
      const Vec3f dl = shadowCacheDirection(L, l);
      f = ShadowCacheFrame::of(s.volume, dl, L.cacheSpacing);
      grid.assign(f.nodes(), 1.f);
      const float worldPerIndex = shadowCacheWorldPerIndex(dl);
      switch (s.blend.mode)
      {
        case BlendMode::Max:
          fill<BlendMode::Max>(s, f, worldPerIndex, grid.data(), threads);
          break;
        case BlendMode::Mix:
          fill<BlendMode::Mix>(s, f, worldPerIndex, grid.data(), threads);
          break;
        default:
          fill<BlendMode::Density>(s, f, worldPerIndex, grid.data(), threads);
          break;
      }
      this->Keys[size_t(l)] = key;
      this->Valid[size_t(l)] = true;
      ++this->LastRebuilt;
    }
    L.shadowCache[l] = grid.data();
    f.write(L, l);
  }
  this->LastSeconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  linkShadowCaches(L);
}

size_t HostShadowCache::bytes() const
{
  size_t b = 0;
  for (size_t l = 0; l < this->Grids.size(); ++l)
  {
    b += this->Valid[l] ? this->Grids[l].size() * sizeof(float) : 0;
  }
  return b;
}
} // namespace mcvol
