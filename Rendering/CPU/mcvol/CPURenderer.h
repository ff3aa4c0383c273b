// SPDX-License-Identifier: BSD-3-Clause
#pragma once

#include "mcvol/HostShadowCache.h"
#include "mcvol/Renderer.h"

namespace mcvol
{
/**
 * OpenMP backend: runs the core's per-pixel code over rows of the image.
 * Threads never share random numbers, so the image does not depend on the
 * thread count (OMP_NUM_THREADS or setThreads()). It renders on the host:
 * every frame is finished when render() returns, it reads the Scene's host
 * macrocells and majorants and the channels in place, and it has no
 * GPU-level interface (device() is nullptr).
 */
class CPURenderer final : public Renderer
{
public:
  void render(const Scene& scene, const Camera& camera, const RenderSettings& settings, const float* depth,
    Accumulator& accum, RenderCounters* counters = nullptr) override;
  /// The OpenMP ray marcher (RayMarcher) with this renderer's thread count.
  void march(const Scene& scene, const Camera& camera, const MarchSettings& settings, const float* depth,
    Accumulator& accum, MarchCounters* counters = nullptr) override;
  const char* name() const override { return "cpu"; }
  /// 0 = OpenMP's default.
  void setThreads(int n) { this->Threads = n; }

  /// The cached shadows (LightingDesc::cacheShadows) its renders and
  /// marches share.
  const HostShadowCache& shadowCache() const { return this->Cache; }

private:
  int Threads = 0;
  HostShadowCache Cache;
};
} // namespace mcvol
