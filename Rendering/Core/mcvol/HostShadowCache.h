// SPDX-License-Identifier: BSD-3-Clause
#pragma once

#include "mcvol/Scene.h"
#include "mcvol/ray/ShadowCache.h"

#include <array>
#include <cstdint>
#include <vector>

namespace mcvol
{
/**
 * Whether view `s` (its lighting frame and stand-in set for this render)
 * caches light l's shadow (LightingDesc::cacheShadows): a directional light
 * of a lit view with shadows, in density, max or mix blending, with no
 * stand-in of other pieces and no visibility optimization of light rays.
 */
bool cachesShadow(const SceneView& s, int l);

/// The inputs a light's cached grid depends on: the Scene and its versions,
/// the blend, the active channels, the sampling, the box, the node spacing
/// and the light's index-space direction. Equal keys: the grid still holds.
struct ShadowCacheKey
{
  std::array<double, 17 + kMaxChannels> values{};
  bool operator==(const ShadowCacheKey& o) const { return this->values == o.values; }
  bool operator!=(const ShadowCacheKey& o) const { return !(*this == o); }
};
ShadowCacheKey shadowCacheKey(const Scene& scene, const SceneView& s, int l);

/// Light l's index-space direction towards it, per unit of world length.
Vec3f shadowCacheDirection(const LightingView& L, int l);

/// The world length of a unit of index length along index direction dl.
float shadowCacheWorldPerIndex(Vec3f dl);

/// Sets whether every light's shadow is cached (LightingView::cachedOnly)
/// from L.shadowCache.
void linkShadowCaches(LightingView& L);

/**
 * The host's cached shadows (the CPU backend and the CPU ray marcher):
 * prepare() fills the grids a render needs, when their key changed, and
 * points the view's lighting at them; a grid a render does not need is
 * freed.
 */
class HostShadowCache
{
public:
  /// `threads` as the backends' (0: OpenMP's default).
  void prepare(const Scene& scene, SceneView& s, int threads);
  /// Grids filled by the last prepare() (0 when all were current).
  int lastRebuilt() const { return this->LastRebuilt; }
  double lastBuildSeconds() const { return this->LastSeconds; }
  size_t bytes() const;

private:
  std::array<std::vector<float>, kMaxLights> Grids;
  std::array<ShadowCacheFrame, kMaxLights> Frames{};
  std::array<ShadowCacheKey, kMaxLights> Keys{};
  std::array<bool, kMaxLights> Valid{};
  int LastRebuilt = 0;
  double LastSeconds = 0.0;
};
} // namespace mcvol
