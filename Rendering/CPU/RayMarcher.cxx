// SPDX-License-Identifier: BSD-3-Clause
#include "mcvol/RayMarcher.h"
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
  // World length of one index step along axis a: the norm of column a of the
  // inverse of worldToIndex's linear part.
  const double* w = camera.worldToIndex;
  const double a = w[0], b = w[1], c = w[2], d = w[4], e = w[5], f = w[6], g = w[8], h = w[9], i = w[10];
  const double det = a * (e * i - f * h) - b * (d * i - f * g) + c * (d * h - e * g);
  if (!(std::fabs(det) > 0.0) || !std::isfinite(det))
  {
    throw std::invalid_argument("mcvol: the volume's world-to-index map is singular");
  }
  const double inv[9] = { (e * i - f * h) / det, (c * h - b * i) / det, (b * f - c * e) / det, (f * g - d * i) / det,
    (a * i - c * g) / det, (c * d - a * f) / det, (d * h - e * g) / det, (b * g - a * h) / det, (a * e - b * d) / det };
  double smallest = HUGE_VAL;
  for (int col = 0; col < 3; ++col)
  {
    const double len = std::sqrt(inv[col] * inv[col] + inv[3 + col] * inv[3 + col] + inv[6 + col] * inv[6 + col]);
    smallest = std::min(smallest, len);
  }
  return 0.5 * smallest;
}

double RayMarcher::effectiveStep(const Camera& camera, const MarchSettings& settings)
{
  return settings.step > 0.0 ? settings.step : nyquistStep(camera);
}

void RayMarcher::render(const Scene& scene, const Camera& camera, const MarchSettings& settings, const float* depth,
  Accumulator& out, MarchCounters* counters)
{
  if (camera.width <= 0 || camera.height <= 0)
  {
    throw std::invalid_argument("mcvol: the image size must be positive");
  }
  if (!(settings.step >= 0.0) || !std::isfinite(settings.step))
  {
    throw std::invalid_argument("mcvol: the ray-marching step must be a finite number >= 0 (0 = Nyquist)");
  }
  if (!(settings.terminateTransmittance >= 0.f && settings.terminateTransmittance < 1.f))
  {
    throw std::invalid_argument("mcvol: the termination transmittance must be in [0, 1)");
  }
  SceneView s = scene.view();
  if (s.volume.numChannels == 0 || s.tables.size < 2)
  {
    throw std::logic_error("mcvol: Scene::update() must succeed before rendering");
  }
  if (!s.grid.majorants)
  {
    throw std::logic_error("mcvol: the ray marcher needs the Scene's host macrocells and majorants, but "
                           "Scene::setHostAcceleration(false) turned them off");
  }
  const double step = effectiveStep(camera, settings);
  // Work guard: a step far below the voxel size over a long ray would run
  // for hours, and past about 2^22 samples per ray the float sample
  // positions stop being distinct. The longest ray through the box is at
  // most the sum of its edges, each edge's world length its index extent
  // times that axis's spacing (the column norms of the index-to-world map).
  {
    const double* w = camera.worldToIndex;
    const double a = w[0], b = w[1], c = w[2], d = w[4], e = w[5], f = w[6], g = w[8], h = w[9], i = w[10];
    const double det = a * (e * i - f * h) - b * (d * i - f * g) + c * (d * h - e * g);
    const double inv[9] = { (e * i - f * h) / det, (c * h - b * i) / det, (b * f - c * e) / det, (f * g - d * i) / det,
      (a * i - c * g) / det, (c * d - a * f) / det, (d * h - e * g) / det, (b * g - a * h) / det,
      (a * e - b * d) / det };
    double longest = 0.0;
    for (int col = 0; col < 3; ++col)
    {
      const double spacing = std::sqrt(inv[col] * inv[col] + inv[3 + col] * inv[3 + col] + inv[6 + col] * inv[6 + col]);
      longest += (double(s.volume.boxHi[col] - s.volume.boxLo[col]) + 1.0) * spacing;
    }
    const double samples = longest / step;
    if (!(samples <= double(1 << 22)))
    {
      throw std::invalid_argument("mcvol: the ray-marching step " + std::to_string(step) + " would take up to " +
        std::to_string(samples) + " samples per ray (at most 2^22 are allowed); use a larger step");
    }
  }
  const CameraView cam = toView(camera);
  s.sigmaLimit = extinctionLimit(cam);
  if (s.lighting.enabled)
  {
    if (s.blend.mode == BlendMode::Composite || settings.compositing != Compositing::Extinction)
    {
      throw std::invalid_argument("mcvol: the lit reference supports the extinction model and density, max and "
                                  "mix blending");
    }
    if (s.lighting.maxDepth > 1)
    {
      throw std::invalid_argument("mcvol: the lit reference is single scattering: it does not render a maximum "
                                  "scattering depth of " +
        std::to_string(s.lighting.maxDepth) + " (set it to 1 to compare)");
    }
    setLightingFrame(s, camera);
  }
  if (s.importance.enabled)
  {
    if (settings.compositing != Compositing::Extinction)
    {
      throw std::invalid_argument("mcvol: the visibility optimization scales extinctions; it needs the extinction "
                                  "compositing model");
    }
    setImportanceFrame(s, camera);
  }
  MarchParams mp;
  mp.step = float(step);
  mp.terminateTransmittance = settings.terminateTransmittance;
  mp.skipEmpty = settings.skipEmpty;
  mp.compositing = settings.compositing;
  if (!(mp.step > 0.f))
  {
    throw std::invalid_argument("mcvol: the ray-marching step is too small for float precision");
  }
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
} // namespace mcvol
