// SPDX-License-Identifier: BSD-3-Clause
#pragma once

#include "mcvol/HostShadowCache.h"
#include "mcvol/MarchSetup.h"
#include "mcvol/ray/RayMarch.h"
#include "mcvol/Renderer.h"

namespace mcvol
{
/**
 * The deterministic OpenMP ray marcher (RayMarch.h): one ray through each
 * pixel centre. render() replaces the Accumulator's image (its sample count
 * becomes 1). The image does not depend on the thread count. It needs the
 * Scene's host macrocells and majorants; CPURenderer::march() runs it, and
 * CUDARenderer::march() runs the same per-ray code on the GPU.
 */
class RayMarcher
{
public:
  void render(const Scene& scene, const Camera& camera, const MarchSettings& settings, const float* depth,
    Accumulator& out, MarchCounters* counters = nullptr);
  /// 0 = OpenMP's default.
  void setThreads(int n) { this->Threads = n; }
  /// Half the smallest voxel spacing (world units) of the camera's volume
  /// (marchNyquistStep()).
  static double nyquistStep(const Camera& camera);
  /// The step a render with these settings uses (marchEffectiveStep()).
  static double effectiveStep(const Camera& camera, const MarchSettings& settings);

  /// Cached shadows (LightingDesc::cacheShadows) kept elsewhere (the
  /// CPURenderer's, shared with its renders); null: this marcher's own.
  void setShadowCache(HostShadowCache* cache) { this->SharedCache = cache; }

private:
  int Threads = 0;
  HostShadowCache Cache;
  HostShadowCache* SharedCache = nullptr;
};
} // namespace mcvol
