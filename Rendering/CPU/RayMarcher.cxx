// SPDX-License-Identifier: BSD-3-Clause
#include "mcvol/RayMarcher.h"
#include "mcvol/CPURenderer.h"
#include "mcvol/RenderSetup.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>

#ifdef _OPENMP
#include <omp.h>
#endif

namespace mcvol
{
namespace
{
template <BlendMode Mode>
void marchRows(const SceneView& s, const CameraView& cam, const MarchParams& mp, bool jitter, uint32_t seed,
  const float* depth, float* rgba, int threads, MarchCounters* counters)
{
  uint64_t samples = 0, skipped = 0, terminated = 0;
  const int W = cam.width;
  const int H = cam.height;
#pragma omp parallel num_threads(threads > 0 ? threads : omp_get_max_threads()) \
  reduction(+ : samples, skipped, terminated)
  {
#pragma omp for schedule(dynamic, 1)
    for (int y = 0; y < H; ++y)
    {
      MarchCounters c;
      for (int x = 0; x < W; ++x)
      {
        const size_t p = size_t(y) * size_t(W) + size_t(x);
        const float phase = marchPhase(jitter, uint32_t(p), seed);
        const Vec4f v = marchPixel<Mode>(s, cam, mp, x, y, depth ? depth[p] : 1.f, phase, c);
        rgba[4 * p + 0] = v.r;
        rgba[4 * p + 1] = v.g;
        rgba[4 * p + 2] = v.b;
        rgba[4 * p + 3] = v.a;
      }
      samples += c.samples;
      skipped += c.skippedCells;
      terminated += c.terminated;
    }
  }
  if (counters)
  {
    counters->samples += samples;
    counters->skippedCells += skipped;
    counters->terminated += terminated;
  }
}

} // namespace

double RayMarcher::nyquistStep(const Camera& camera)
{
  return marchNyquistStep(camera);
}

double RayMarcher::effectiveStep(const Camera& camera, const MarchSettings& settings)
{
  return marchEffectiveStep(camera, settings);
}

void RayMarcher::render(const Scene& scene, const Camera& camera, const MarchSettings& settings, const float* depth,
  Accumulator& out, MarchCounters* counters)
{
  SceneView s = scene.view();
  if (s.volume.numChannels > 0 && !s.grid.majorants)
  {
    throw std::logic_error("mcvol: the ray marcher needs the Scene's host macrocells and majorants, but "
                           "Scene::setHostAcceleration(false) turned them off");
  }
  // The checks, refusals and per-render set-up every backend shares.
  const MarchParams mp = prepareMarch(camera, settings, s);
  // Lit, one piece of a split volume: the stand-in of the other pieces.
  SceneView outside;
  if (prepareOutside(scene, camera, s, outside))
  {
    s.outside = &outside;
  }
  if (s.lighting.enabled)
  {
    (this->SharedCache ? *this->SharedCache : this->Cache).prepare(scene, s, this->Threads);
  }
  const CameraView cam = toView(camera);
  out.resize(camera.width, camera.height);
  out.reset();
  float* rgba = out.rgba();
  switch (s.blend.mode)
  {
    case BlendMode::Max:
      marchRows<BlendMode::Max>(s, cam, mp, settings.jitter, settings.seed, depth, rgba, this->Threads, counters);
      break;
    case BlendMode::Mix:
      marchRows<BlendMode::Mix>(s, cam, mp, settings.jitter, settings.seed, depth, rgba, this->Threads, counters);
      break;
    case BlendMode::Composite:
      marchRows<BlendMode::Composite>(s, cam, mp, settings.jitter, settings.seed, depth, rgba, this->Threads, counters);
      break;
    case BlendMode::Density:
    default:
      marchRows<BlendMode::Density>(s, cam, mp, settings.jitter, settings.seed, depth, rgba, this->Threads, counters);
      break;
  }
  out.addSamples(1);
}

void CPURenderer::march(const Scene& scene, const Camera& camera, const MarchSettings& settings, const float* depth,
  Accumulator& accum, MarchCounters* counters)
{
  RayMarcher marcher;
  marcher.setThreads(this->Threads);
  marcher.setShadowCache(&this->Cache);
  marcher.render(scene, camera, settings, depth, accum, counters);
}
} // namespace mcvol
