// SPDX-License-Identifier: BSD-3-Clause
#include "mcvol/CPURenderer.h"

#include "mcvol/RenderSetup.h"

#include <stdexcept>

#ifdef _OPENMP
#include <omp.h>
#endif

namespace mcvol
{
namespace
{
/// The visibility optimization's per-pixel lists for one render (null pool:
/// the optimization is off and no pixel touches any of it).
struct ImportanceFrame
{
  Accumulator::ImportancePool* pool = nullptr;
  bool refine = false; ///< this render refines the lists (the first passes)
  uint32_t seed = 0;
};

/// The Accumulator's buffers a render writes: the mean and the sums (and the
/// error estimate's even half of each, null when it is off).
struct PixelSums
{
  float* mean = nullptr;
  double* sums = nullptr;
  float* even = nullptr;
  double* evenSums = nullptr;
};

/// Optimized is a compile-time choice, as Lit: the unoptimized rows contain
/// none of the optimization's code (its off state costs nothing).
template <BlendMode Mode, bool Lit, bool Optimized>
void renderRows(const SceneView& s, const CameraView& cam, const FrameParams& fp, const float* depth,
  const PixelSums& out, uint32_t previous, int threads, const ImportanceFrame& imp, RenderCounters* counters)
{
  uint64_t dda = 0, tentative = 0, real = 0, samples = 0, scattering = 0, shadowRays = 0, gradients = 0;
  uint64_t importance = 0, overflows = 0;
  const int W = cam.width;
  const int H = cam.height;
  Accumulator::ImportancePool* pool = Optimized ? imp.pool : nullptr;
  const int pass = pool ? pool->passes : 0;
  const int unlit =
    unlitEstimator(fp.estimator, Mode, Lit, Optimized, s.marchControlVariates, localKernels(s, Mode, fp.estimator));
  const uint32_t total = previous + uint32_t(fp.samplesPerPixel);
  // The even half is neither read nor written by a render that adds no
  // sample of even index (as on the device).
  const bool addsEven = out.even && addedEvenSamples(previous, fp.samplesPerPixel) > 0u;
  const SceneView& light = lightView(s);
#pragma omp parallel num_threads(threads > 0 ? threads : omp_get_max_threads()) \
  reduction(+ : dda, tentative, real, samples, scattering, shadowRays, gradients, importance, overflows)
  {
#pragma omp for schedule(dynamic, 1)
    for (int y = 0; y < H; ++y)
    {
      RayCounters c; // per row, folded into 64-bit sums (no overflow at 4096 spp)
      for (int x = 0; x < W; ++x)
      {
        const size_t p = size_t(y) * size_t(W) + size_t(x);
        const float z = depth ? depth[p] : 1.f;
        Vec4d sum = loadSum(out.sums + 4 * p, previous);
        Vec4d evenSum = addsEven ? loadSum(out.evenSums + 4 * p, evenSampleCount(previous)) : Vec4d();
        Vec4d* evenOut = addsEven ? &evenSum : nullptr;
        if (Optimized)
        {
          ImportanceSegment* seg = pool->segments.data() + p * size_t(kImportanceCapacity);
          int count = pool->counts[p];
          if (imp.refine)
          {
            bool overflow = false;
            count = refineImportance(s, cam, x, y, z, pass, imp.seed, seg, count, pool->totals[p], overflow, c);
            pool->counts[p] = uint8_t(count);
            overflows += overflow ? 1u : 0u;
          }
          RayImportance ri;
          ri.segments = seg;
          ri.count = count;
          ri.total = pool->totals[p];
          renderPixel<Mode, Lit, true>(s, light, cam, fp, x, y, z, c, sum, &ri, evenOut);
        }
        else
        {
          switch (unlit)
          {
            case kLocalLight:
              if constexpr (Lit)
              {
                renderPixel<Mode, Lit, false, kLocalLight>(s, light, cam, fp, x, y, z, c, sum, nullptr, evenOut);
              }
              break;
            case 1 + kLocalLight:
              if constexpr (Lit)
              {
                renderPixel<Mode, Lit, false, 1 + kLocalLight>(s, light, cam, fp, x, y, z, c, sum, nullptr, evenOut);
              }
              break;
            case 1:
              renderPixel<Mode, Lit, false, 1>(s, light, cam, fp, x, y, z, c, sum, nullptr, evenOut);
              break;
            case 2:
              renderPixel<Mode, Lit, false, 2>(s, light, cam, fp, x, y, z, c, sum, nullptr, evenOut);
              break;
            case 3:
              renderPixel<Mode, Lit, false, 3>(s, light, cam, fp, x, y, z, c, sum, nullptr, evenOut);
              break;
            default:
              renderPixel<Mode, Lit>(s, light, cam, fp, x, y, z, c, sum, nullptr, evenOut);
              break;
          }
        }
        storeSum(out.mean + 4 * p, out.sums + 4 * p, sum, total);
        if (addsEven)
        {
          storeSum(out.even + 4 * p, out.evenSums + 4 * p, evenSum, evenSampleCount(total));
        }
      }
      dda += c.ddaSteps;
      tentative += c.tentative;
      real += c.real;
      samples += c.samples;
      scattering += c.scattering;
      shadowRays += c.shadowRays;
      gradients += c.gradients;
      if (Optimized)
      {
        importance += c.importance;
        overflows += c.importanceOverflows;
      }
    }
  }
  if (pool)
  {
    pool->overflows += overflows;
    pool->passes += imp.refine ? 1 : 0;
  }
  if (counters)
  {
    counters->rays += uint64_t(W) * uint64_t(H) * uint64_t(fp.samplesPerPixel);
    counters->ddaSteps += dda;
    counters->tentativeCollisions += tentative;
    counters->realCollisions += real;
    counters->channelSamples += samples;
    counters->scatteringEvents += scattering;
    counters->shadowRays += shadowRays;
    counters->gradientEvaluations += gradients;
    counters->importanceSamples += importance;
  }
}
/// The unlit kernel unless the scene asks for lighting (compile-time choice:
/// the unlit kernel contains none of the lighting code).
template <BlendMode Mode>
void rows(bool lit, const SceneView& s, const CameraView& cam, const FrameParams& fp, const float* depth,
  const PixelSums& out, uint32_t previous, int threads, const ImportanceFrame& imp, RenderCounters* counters)
{
  const bool optimized = imp.pool != nullptr;
  if (lit)
  {
    optimized ? renderRows<Mode, true, true>(s, cam, fp, depth, out, previous, threads, imp, counters)
              : renderRows<Mode, true, false>(s, cam, fp, depth, out, previous, threads, imp, counters);
  }
  else
  {
    optimized ? renderRows<Mode, false, true>(s, cam, fp, depth, out, previous, threads, imp, counters)
              : renderRows<Mode, false, false>(s, cam, fp, depth, out, previous, threads, imp, counters);
  }
}
} // namespace

void CPURenderer::render(const Scene& scene, const Camera& camera, const RenderSettings& settings, const float* depth,
  Accumulator& accum, RenderCounters* counters)
{
  checkRenderArguments(camera, settings, accum);
  // A copy: the extinction limit belongs to this render's camera.
  SceneView s = scene.view();
  if (s.volume.numChannels == 0 || s.tables.size < 2)
  {
    throw std::logic_error("mcvol: Scene::update() must succeed before rendering");
  }
  if (!s.grid.majorants)
  {
    throw std::logic_error("mcvol: the CPU backend needs the Scene's host macrocells and majorants, but "
                           "Scene::setHostAcceleration(false) turned them off");
  }
  const CameraView cam = toView(camera);
  s.sigmaLimit = extinctionLimit(cam);
  s.minRate = settings.minSamplesPerVoxel > 0.f ? settings.minSamplesPerVoxel * voxelRate(cam) : 0.f;
  s.marchRate = settings.marchSamplesPerVoxel * voxelRate(cam);
  s.marchControlVariates = marchControlVariates(settings, camera);
  const FrameParams fp = frameParams(settings, accum.samples());
  const bool lit = s.lighting.enabled;
  // Lit, one piece of a split volume: the stand-in of the other pieces.
  SceneView outside;
  if (lit)
  {
    setLightingFrame(s, camera);
    if (prepareOutside(scene, camera, s, outside))
    {
      s.outside = &outside;
    }
    this->Cache.prepare(scene, s, this->Threads);
  }
  ImportanceFrame imp;
  if (s.importance.enabled)
  {
    setImportanceFrame(s, camera);
    imp.pool = &accum.importancePool();
    imp.refine = imp.pool->passes < s.importance.refinePasses;
    imp.seed = settings.seed;
  }
  PixelSums out;
  out.sums = accum.sums();
  out.mean = accum.rgba();
  out.even = accum.evenRGBA(); // null: no error estimate wanted
  out.evenSums = out.even ? accum.evenSums() : nullptr;
  const uint32_t previous = accum.samples();
  switch (s.blend.mode)
  {
    case BlendMode::Max:
      rows<BlendMode::Max>(lit, s, cam, fp, depth, out, previous, this->Threads, imp, counters);
      break;
    case BlendMode::Mix:
      rows<BlendMode::Mix>(lit, s, cam, fp, depth, out, previous, this->Threads, imp, counters);
      break;
    case BlendMode::Composite:
      rows<BlendMode::Composite>(lit, s, cam, fp, depth, out, previous, this->Threads, imp, counters);
      break;
    case BlendMode::Density:
    default:
      rows<BlendMode::Density>(lit, s, cam, fp, depth, out, previous, this->Threads, imp, counters);
      break;
  }
  accum.addSamples(uint32_t(settings.samplesPerPixel), true);
}
} // namespace mcvol
