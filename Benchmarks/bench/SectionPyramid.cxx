// SPDX-License-Identifier: BSD-3-Clause
//
// mcvol-bench section "pyramid": what levels of detail buy a frame. Frame
// time at 1 spp of level 0 rendered the normal way (the scalar channels
// through their transfer functions) against the pre-classified levels: the
// channels classified by classifyScalars into one float4 extinction channel
// (with accumulate = true: their density blend, so the blend mode is
// density), level 0 of that, and levels 1..--pyramid-levels of its box4
// extinction pyramid, each with its own spacing and origin (the same view).
// Also the classify and build times and the memory of each level, and the
// ratio of level 0's frame time to level 1's against a 4x target (the GPU
// figure comes from Benchmarks/gpu/bench.sh pyramid; the CPU figure is the
// same section with --backend cpu). Image quality per level is mcvol-pyramid's.
// Last, the rebuild of levels 1 and 2 after a transfer-function edit on the
// host and by the renderer's classifyLevel (on the GPU for CUDA).

#include "BenchCommon.h"
#include "Sections.h"

#include "mcvol/DeviceRenderer.h"
#include "mcvol/MarchSetup.h"
#include "mcvol/Pyramid.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <memory>
#include <string>
#include <vector>

namespace mcvolbench
{
namespace
{
/// Median ms of --frames 1-spp frames after --warmup, the image left on the
/// device (as timeFrames, with a camera of the caller's).
double medianFrameMs(const Options& o, mcvol::Renderer& r, const mcvol::Scene& scene, const mcvol::Camera& cam,
  mcvol::Estimator estimator, float marchSamplesPerVoxel = 2.f)
{
  mcvol::Accumulator acc;
  mcvol::RenderSettings st;
  st.samplesPerPixel = 1;
  st.tracker = mcvol::Tracker::OneDDA;
  st.estimator = estimator;
  st.marchSamplesPerVoxel = marchSamplesPerVoxel;
  st.readBack = false;
  for (int i = 0; i < o.warmup; ++i)
  {
    r.render(scene, cam, st, nullptr, acc);
  }
  r.finish();
  acc.reset();
  std::vector<double> ms;
  for (int i = 0; i < std::max(1, o.frames); ++i)
  {
    const auto t0 = Clock::now();
    r.render(scene, cam, st, nullptr, acc);
    r.finish();
    ms.push_back(1e3 * seconds(t0));
  }
  r.readBack(acc);
  return median(ms);
}

/// Median ms of a deterministic ray march (the level's Nyquist step, early
/// termination 1e-4: MarchSettings' defaults, as the ray-march mapper draws an
/// interactive frame), over min(--frames, 5) marches after one untimed one.
double medianMarchMs(const Options& o, mcvol::Renderer& r, const mcvol::Scene& scene, const mcvol::Camera& cam)
{
  mcvol::Accumulator acc;
  const mcvol::MarchSettings ms;
  r.march(scene, cam, ms, nullptr, acc);
  std::vector<double> t;
  for (int i = 0; i < std::max(1, std::min(o.frames, 5)); ++i)
  {
    const auto t0 = Clock::now();
    r.march(scene, cam, ms, nullptr, acc);
    t.push_back(1e3 * seconds(t0));
  }
  return median(t);
}

/// Largest |a - b| / max(|b|, 1e-6 max|b|) over two levels of equal size
/// (-1 when the sizes differ).
double maxRelativeDiff(const mcvol::PyramidLevel& a, const mcvol::PyramidLevel& b)
{
  if (a.voxels.size() != b.voxels.size())
  {
    return -1.0;
  }
  double top = 0.0;
  for (float x : b.voxels)
  {
    top = std::max(top, double(std::fabs(x)));
  }
  double worst = 0.0;
  for (size_t i = 0; i < b.voxels.size(); ++i)
  {
    const double d = std::fabs(double(a.voxels[i]) - double(b.voxels[i]));
    worst = std::max(worst, d / std::max(double(std::fabs(b.voxels[i])), 1e-6 * top + 1e-30));
  }
  return worst;
}

/**
 * Rebuilding a level after a transfer-function edit:
 * levels 1 and 2 (box4) of the loaded scalar channels, their density blend
 * (all channels summed into one level) and per channel (one level each,
 * times added), by the host build (classifyExtinctionLevel, once: seconds
 * at 512^3) and by the renderer's classifyLevel: on a device backend the
 * first build (the channels copied to the device) and then the median of
 * --frames builds, each after an edit of every table, with the channels
 * kept on the device (ClassifyInput::dataVersion), which is what an edit
 * costs. Bytes: the host build's working memory and the device build's
 * peak device memory (inputs kept included), besides the level itself.
 */
void runLevelRebuild(Bench& bench)
{
  const Options& o = bench.o;
  Setup& s = bench.s;
  mcvol::Renderer& r = bench.r;
  const std::string ds = describe(o, s);
  const int* d = s.volume.dims;
  const int channels = s.volume.numChannels();
  const double MiB = 1024.0 * 1024.0;
  // classifyLevel() builds on the device with the CUDA backend.
  const bool device = std::string(r.name()) == "cuda";
  std::vector<mcvol::TransferFunctionDesc> tfs;
  for (int k = 0; k < channels; ++k)
  {
    tfs.push_back(demoTransferFunction(s.volume, k, s.ranges[size_t(k)], o.tableSize, o.density));
  }
  const std::vector<mcvol::TransferFunctionDesc> original = tfs;
  std::vector<mcvol::ClassifyInput> inputs(static_cast<size_t>(channels));
  for (int k = 0; k < channels; ++k)
  {
    inputs[size_t(k)].source = s.volume.source(k);
    inputs[size_t(k)].tf = &tfs[size_t(k)];
    inputs[size_t(k)].dataVersion = uint64_t(k) + 1; // the data never change here
  }
  const double origin[3] = { 0, 0, 0 };
  const mcvol::DownsampleFilter f = mcvol::DownsampleFilter::Box4;
  // An edit: every table's opacities scaled by a factor that alternates.
  auto edit = [&](int i)
  {
    const float scale = i % 2 ? 0.9f : 1.f / 0.9f;
    for (auto& tf : tfs)
    {
      for (float& a : tf.opacity)
      {
        a = std::min(1.f, a * scale);
      }
    }
  };

  struct RebuildRow
  {
    std::string what;
    int level = 0;
    int dims[3] = { 0, 0, 0 };
    double levelMiB = 0;
    double hostMs = 0, hostWorkMiB = 0;
    double firstMs = -1, editMs = -1, deviceMiB = 0, relDiff = -1;
  };
  std::vector<RebuildRow> rows;
  const int levels = std::min(2, mcvol::maxPyramidLevels(d));
  for (int level = 1; level <= levels; ++level)
  {
    for (bool summed : { true, false })
    {
      RebuildRow row;
      row.what = summed ? "density blend (" + std::to_string(channels) + " channels summed)"
                        : "per channel (" + std::to_string(channels) + " levels)";
      row.level = level;
      const int groups = summed ? 1 : channels;
      const int per = summed ? channels : 1;
      std::vector<mcvol::PyramidLevel> host;
      for (int g = 0; g < groups; ++g)
      {
        size_t work = 0;
        const auto t0 = Clock::now();
        host.push_back(
          mcvol::classifyExtinctionLevel(inputs.data() + g * per, per, d, s.volume.spacing, origin, level, f, &work));
        row.hostMs += 1e3 * seconds(t0);
        row.hostWorkMiB = std::max(row.hostWorkMiB, double(work) / MiB);
        row.levelMiB += double(host.back().bytes()) / MiB;
      }
      std::copy(host[0].dims, host[0].dims + 3, row.dims);
      if (device)
      {
        // The first build copies the channels (a kept copy of the previous
        // row's may be reused: release them to time the copy).
#ifdef MCVOL_WITH_CUDA
        if (mcvol::CUDARenderer* cuda = asCuda(r))
        {
          cuda->releaseLevelInputs();
        }
#endif
        std::vector<double> ms;
        for (int i = 0; i <= std::max(1, o.frames); ++i)
        {
          if (i > 0)
          {
            edit(i);
          }
          double total = 0.0;
          for (int g = 0; g < groups; ++g)
          {
            size_t peak = 0;
            const auto t0 = Clock::now();
            const mcvol::PyramidLevel lv =
              r.device()->classifyLevel(inputs.data() + g * per, per, d, s.volume.spacing, origin, level, f, &peak);
            total += 1e3 * seconds(t0);
            row.deviceMiB = std::max(row.deviceMiB, double(peak) / MiB);
            if (i == 0)
            {
              row.relDiff = std::max(row.relDiff, maxRelativeDiff(lv, host[size_t(g)]));
            }
          }
          if (i == 0)
          {
            row.firstMs = total;
          }
          else
          {
            ms.push_back(total);
          }
        }
        row.editMs = median(ms);
        for (size_t k = 0; k < tfs.size(); ++k)
        {
          tfs[k] = original[k]; // the tables as the host build had them
        }
      }
      rows.push_back(row);
    }
  }

  std::printf("## Level rebuild after a transfer-function edit (%s, %d channels, box4; host: classifyExtinctionLevel, "
              "%s: DeviceRenderer::classifyLevel)\n\n",
    ds.c_str(), channels, r.name());
  std::printf(
    "| level | grid | channels | level MiB | host ms | host work MiB | %s first build ms (copies the data) | %s "
    "ms after an edit (median of %d) | speed-up (edit) | %s device peak MiB | max rel. diff |\n"
    "|---|---|---|---|---|---|---|---|---|---|---|\n",
    r.name(), r.name(), std::max(1, o.frames), r.name());
  for (const RebuildRow& row : rows)
  {
    if (row.firstMs >= 0)
    {
      std::printf("| %d | %dx%dx%d | %s | %.1f | %.1f | %.1f | %.2f | %.2f | %.1fx | %.1f | %.2g |\n", row.level,
        row.dims[0], row.dims[1], row.dims[2], row.what.c_str(), row.levelMiB, row.hostMs, row.hostWorkMiB, row.firstMs,
        row.editMs, row.hostMs / row.editMs, row.deviceMiB, row.relDiff);
    }
    else
    {
      std::printf("| %d | %dx%dx%d | %s | %.1f | %.1f | %.1f | - | - | - | - | - |\n", row.level, row.dims[0],
        row.dims[1], row.dims[2], row.what.c_str(), row.levelMiB, row.hostMs, row.hostWorkMiB);
    }
    const std::string extra = "level " + std::to_string(row.level) + (row.what[0] == 'd' ? " summed" : " per channel");
    bench.row("pyramid", ds, channels, o.macrocell, "host-build", row.hostMs, "rebuild_ms", extra);
    bench.row("pyramid", ds, channels, o.macrocell, "host-build", row.hostWorkMiB, "work_MiB", extra);
    if (row.firstMs >= 0)
    {
      bench.row("pyramid", ds, channels, o.macrocell, "device-build", row.firstMs, "first_build_ms", extra);
      bench.row("pyramid", ds, channels, o.macrocell, "device-build", row.editMs, "rebuild_ms", extra);
      bench.row("pyramid", ds, channels, o.macrocell, "device-build", row.deviceMiB, "device_peak_MiB", extra);
      bench.row("pyramid", ds, channels, o.macrocell, "device-build", row.relDiff, "max_rel_diff", extra);
    }
  }
  if (!device)
  {
    std::printf("\n(%s builds levels on the host: classifyExtinctionLevel.)\n", r.name());
  }
#ifdef MCVOL_WITH_CUDA
  if (mcvol::CUDARenderer* cuda = asCuda(r))
  {
    cuda->releaseLevelInputs();
  }
#endif
  std::printf("\n");
  std::fflush(stdout);
}

constexpr float kPyramidMarchRate = 1.f / 16.f;

struct LevelRow
{
  std::string name;
  int dims[3] = { 0, 0, 0 };
  double hostMiB = 0;
  double buildMs = -1; ///< classify (classified level 0) or its downsampling step; -1: none
  double evMs = 0;     ///< expected-value estimator (the renderer's default)
  double colMs = 0;    ///< collision estimator (the paper's protocol)
  /// The unbiased march at kPyramidMarchRate strata per voxel of the level
  /// (the automatic choice on the NYX-like set at full resolution): its
  /// strata follow the level's voxels, so a coarser level takes fewer.
  double mcMarchMs = 0;
  double marchMs = 0;         ///< ray march (includes copying the image back on a device)
  double tentativePerRay = 0; ///< collision estimator, one counted frame
  double ddaPerRay = 0;       ///< macrocells visited per ray, same frame
  double deviceMiB = 0;
  double halfRmse = -1; ///< half-precision rows: ray-march image RMSE against the float32 level's; -1: none
  double halfMaxDiff = -1;
};
} // namespace

void runPyramid(Bench& bench)
{
  const Options& o = bench.o;
  Setup& s = bench.s;
  mcvol::Renderer& r = bench.r;
  s.load(o, o.channels, o.macrocell, bench.hostAccel);
  s.scene.setBlendMode(mcvol::BlendMode::Density);
  s.scene.update();
  const std::string ds = describe(o, s);
  const int* d = s.volume.dims;
  const size_t n = size_t(d[0]) * size_t(d[1]) * size_t(d[2]);
  const double MiB = 1024.0 * 1024.0;
  const mcvol::Camera cam0 = benchCamera(o, s.scene);
  std::vector<LevelRow> rows;

  auto timeScene = [&](LevelRow& row, const mcvol::Scene& scene, const mcvol::Camera& cam)
  {
    row.evMs = medianFrameMs(o, r, scene, cam, mcvol::Estimator::ExpectedValue);
    row.colMs = medianFrameMs(o, r, scene, cam, mcvol::Estimator::Collision);
    row.mcMarchMs = medianFrameMs(o, r, scene, cam, mcvol::Estimator::UnbiasedMarch, kPyramidMarchRate);
    row.marchMs = medianMarchMs(o, r, scene, cam);
    // Where Monte Carlo's time goes: a level keeps each ray's optical depth,
    // so the tentative collisions (majorant x path) stay, and only the
    // macrocells crossed and the lookups get cheaper. One counted frame
    // (counting adds atomics; not timed).
    mcvol::RenderSettings st;
    st.estimator = mcvol::Estimator::Collision;
    mcvol::Accumulator acc;
    mcvol::RenderCounters c;
    r.render(scene, cam, st, nullptr, acc, &c);
    row.tentativePerRay = double(c.tentativeCollisions) / double(std::max<uint64_t>(1, c.rays));
    row.ddaPerRay = double(c.ddaSteps) / double(std::max<uint64_t>(1, c.rays));
    row.deviceMiB = r.device() ? double(r.device()->deviceBytes()) / MiB : 0.0;
  };

  // Level 0, the normal path.
  {
    LevelRow row;
    row.name = "0 (" + std::to_string(s.volume.numChannels()) + " scalar channels)";
    std::copy(d, d + 3, row.dims);
    for (const auto& c : s.volume.channels)
    {
      row.hostMiB += double(c.size()) / MiB;
    }
    timeScene(row, s.scene, cam0);
    rows.push_back(row);
  }

  // Pre-classification: the same tables as Setup::configure, summed.
  std::vector<float> level0;
  LevelRow classifiedRow;
  {
    const auto t0 = Clock::now();
    level0.assign(4 * n, 0.f);
    for (int k = 0; k < s.volume.numChannels(); ++k)
    {
      const mcvol::TransferFunctionDesc tf =
        demoTransferFunction(s.volume, k, s.ranges[size_t(k)], o.tableSize, o.density);
      mcvol::classifyScalars(s.volume.source(k), d, tf, level0.data(), 4, true);
    }
    classifiedRow.buildMs = 1e3 * seconds(t0);
  }
  mcvol::ClassifiedVolumeView v0;
  v0.voxels = level0.data();
  std::copy(d, d + 3, v0.dims);
  std::copy(s.volume.spacing, s.volume.spacing + 3, v0.spacing);
  // --pyramid-levels N times levels past 2 down to the coarsest: the
  // frame time no level can go below (the per-ray work, and the tentative
  // collisions, which an extinction pyramid keeps since it keeps each ray's
  // optical depth).
  const int levels = std::min(o.pyramidLevels, mcvol::maxPyramidLevels(d));
  std::vector<mcvol::PyramidLevel> pyr;
  std::vector<double> buildMs;
  for (int l = 1; l <= levels; ++l)
  {
    const auto t0 = Clock::now();
    pyr.push_back(mcvol::downsampleExtinction(l == 1 ? v0 : pyr.back().view(), mcvol::DownsampleFilter::Box4));
    buildMs.push_back(1e3 * seconds(t0));
    pyr.back().level = l;
  }

  auto sourceScene = [&](const mcvol::ChannelSource& src, const int dims[3])
  {
    auto scene = std::make_unique<mcvol::Scene>();
    scene->setHostAcceleration(bench.hostAccel);
    scene->setVolume(dims, 1, &src);
    scene->setMacrocellSize(o.macrocell);
    scene->setBlendMode(mcvol::BlendMode::Density);
    scene->update();
    return scene;
  };
  // The ray march's image (premultiplied RGBA), for the half-precision rows.
  auto marchImage = [&](const mcvol::Scene& scene, const mcvol::Camera& cam)
  {
    mcvol::Accumulator acc;
    mcvol::MarchSettings ms;
    ms.terminateTransmittance = 0.f; // no termination decided on a rounding
    r.march(scene, cam, ms, nullptr, acc);
    return std::vector<float>(acc.rgba(), acc.rgba() + size_t(cam.width) * size_t(cam.height) * 4);
  };
  auto gridScene = [&](const mcvol::ClassifiedVolumeView& v)
  { return classifiedScene(v, o.macrocell, bench.hostAccel); };

  // Level 0 pre-classified: what pre-classification alone changes.
  {
    classifiedRow.name = "0 (classified)";
    std::copy(d, d + 3, classifiedRow.dims);
    classifiedRow.hostMiB = double(level0.size() * sizeof(float)) / MiB;
    auto scene = gridScene(v0);
    timeScene(classifiedRow, *scene, forGrid(cam0, v0.spacing, v0.origin));
    rows.push_back(classifiedRow);
  }
  for (int l = 1; l <= levels; ++l)
  {
    const mcvol::PyramidLevel& L = pyr[size_t(l - 1)];
    LevelRow row;
    row.name = std::to_string(l);
    std::copy(L.dims, L.dims + 3, row.dims);
    row.hostMiB = double(L.bytes()) / MiB;
    row.buildMs = buildMs[size_t(l - 1)];
    const mcvol::Camera cam = forGrid(cam0, L.spacing, L.origin);
    auto scene = gridScene(L.view());
    timeScene(row, *scene, cam);
    rows.push_back(row);
    if (l > 2)
    {
      continue; // the deeper levels for their frame time alone
    }
    // The same level in half precision (the mapper's default for levels,
    // PyramidLevel::toHalfPrecision): its memory, conversion time, frames
    // and how far its ray-march image is from the float32 level's.
    mcvol::PyramidLevel H = L;
    LevelRow half;
    half.name = std::to_string(l) + " (half precision)";
    std::copy(L.dims, L.dims + 3, half.dims);
    const auto t0 = Clock::now();
    H.toHalfPrecision();
    half.buildMs = 1e3 * seconds(t0);
    half.hostMiB = double(H.bytes()) / MiB;
    auto halfScene = sourceScene(H.source(), H.dims);
    timeScene(half, *halfScene, cam);
    const std::vector<float> a = marchImage(*scene, cam), b = marchImage(*halfScene, cam);
    double sq = 0.0, worst = 0.0;
    for (size_t i = 0; i < a.size(); ++i)
    {
      const double e = double(a[i]) - double(b[i]);
      sq += e * e;
      worst = std::max(worst, std::fabs(e));
    }
    half.halfRmse = std::sqrt(sq / double(std::max<size_t>(1, a.size())));
    half.halfMaxDiff = worst;
    rows.push_back(half);
  }

  std::printf("## Levels of detail (%s, %d channels, density blend, macrocell %d, %dx%d, 1 spp, 1-DDA, %d warm-up + "
              "%d timed frames, median; box4 pyramid)\n\n",
    ds.c_str(), s.volume.numChannels(), o.macrocell, o.width, o.height, o.warmup, o.frames);
  std::printf(
    "| level | grid | host MiB | classify / build ms (host) | MC ms expected-value | MC ms collision | MC ms "
    "unbiased march (1/16 per voxel) | ray march ms | tentative/ray | DDA steps/ray | renderer device MiB | half vs "
    "float32 march: RMSE / max |\n"
    "|---|---|---|---|---|---|---|---|---|---|---|---|\n");
  for (const LevelRow& row : rows)
  {
    char build[32] = "-";
    if (row.buildMs >= 0)
    {
      std::snprintf(build, sizeof(build), "%.1f", row.buildMs);
    }
    char half[64] = "-";
    if (row.halfRmse >= 0)
    {
      std::snprintf(half, sizeof(half), "%.2g / %.2g", row.halfRmse, row.halfMaxDiff);
      bench.row("pyramid", ds, s.volume.numChannels(), o.macrocell, "raymarch", row.halfRmse, "half_rmse", row.name);
      bench.row(
        "pyramid", ds, s.volume.numChannels(), o.macrocell, "raymarch", row.halfMaxDiff, "half_max_diff", row.name);
    }
    std::printf("| %s | %dx%dx%d | %.1f | %s | %.3f | %.3f | %.3f | %.3f | %.2f | %.2f | %.1f | %s |\n",
      row.name.c_str(), row.dims[0], row.dims[1], row.dims[2], row.hostMiB, build, row.evMs, row.colMs, row.mcMarchMs,
      row.marchMs, row.tentativePerRay, row.ddaPerRay, row.deviceMiB, half);
    bench.row("pyramid", ds, s.volume.numChannels(), o.macrocell, "unbiased-march-1/16", row.mcMarchMs, "ms", row.name);
    bench.row("pyramid", ds, s.volume.numChannels(), o.macrocell, "expected-value", row.evMs, "ms", row.name);
    bench.row("pyramid", ds, s.volume.numChannels(), o.macrocell, "collision", row.colMs, "ms", row.name);
    bench.row("pyramid", ds, s.volume.numChannels(), o.macrocell, "raymarch", row.marchMs, "ms", row.name);
    bench.row("pyramid", ds, s.volume.numChannels(), o.macrocell, "collision", row.tentativePerRay, "tentative_per_ray",
      row.name);
    bench.row(
      "pyramid", ds, s.volume.numChannels(), o.macrocell, "collision", row.ddaPerRay, "dda_steps_per_ray", row.name);
    bench.row("pyramid", ds, s.volume.numChannels(), o.macrocell, "-", row.hostMiB, "host_MiB", row.name);
    if (row.buildMs >= 0)
    {
      bench.row("pyramid", ds, s.volume.numChannels(), o.macrocell, "-", row.buildMs, "build_ms", row.name);
    }
  }
  if (rows.size() > 2)
  {
    const double ev = rows[0].evMs / rows[2].evMs, col = rows[0].colMs / rows[2].colMs;
    const double rm = rows[0].marchMs / rows[2].marchMs;
    const double um = rows[0].mcMarchMs / rows[2].mcMarchMs;
    const int met = int(ev >= 4.0) + int(col >= 4.0) + int(um >= 4.0);
    std::printf("\nLevel 0 (scalar) / level 1 frame time: Monte Carlo %.2fx expected-value, %.2fx collision, %.2fx "
                "unbiased march at 1/16 per voxel (target >= 4x: %s); ray march %.2fx\n",
      ev, col, um,
      met == 3 ? "met"
               : (met > 0 ? "met with " + std::to_string(met) + " of 3 estimators" : std::string("not met")).c_str(),
      rm);
    bench.row("pyramid", ds, s.volume.numChannels(), o.macrocell, "unbiased-march-1/16", um, "ratio", "level0/level1");
    bench.row("pyramid", ds, s.volume.numChannels(), o.macrocell, "raymarch", rm, "ratio", "level0/level1");
    bench.row("pyramid", ds, s.volume.numChannels(), o.macrocell, "expected-value", ev, "ratio", "level0/level1");
    bench.row("pyramid", ds, s.volume.numChannels(), o.macrocell, "collision", col, "ratio", "level0/level1");
    if (rows.size() > 3 && rows[3].halfRmse >= 0)
    {
      const double evh = rows[0].evMs / rows[3].evMs, colh = rows[0].colMs / rows[3].colMs;
      const double rmh = rows[0].marchMs / rows[3].marchMs;
      std::printf("Level 0 (scalar) / level 1 in half precision: Monte Carlo %.2fx expected-value, %.2fx collision; "
                  "ray march %.2fx\n",
        evh, colh, rmh);
      bench.row(
        "pyramid", ds, s.volume.numChannels(), o.macrocell, "expected-value", evh, "ratio", "level0/level1-half");
      bench.row("pyramid", ds, s.volume.numChannels(), o.macrocell, "collision", colh, "ratio", "level0/level1-half");
      bench.row("pyramid", ds, s.volume.numChannels(), o.macrocell, "raymarch", rmh, "ratio", "level0/level1-half");
    }
    if (levels > 2)
    {
      // The bound on any level's gain: level 0 against the coarsest level.
      const LevelRow& last = rows.back();
      const double evBound = rows[0].evMs / last.evMs, colBound = rows[0].colMs / last.colMs;
      std::printf("Level 0 (scalar) / the coarsest level timed (%s, %dx%dx%d): Monte Carlo %.2fx expected-value, "
                  "%.2fx collision, %.2fx unbiased march; ray march %.2fx\n",
        last.name.c_str(), last.dims[0], last.dims[1], last.dims[2], evBound, colBound,
        rows[0].mcMarchMs / last.mcMarchMs, rows[0].marchMs / last.marchMs);
      const std::string coarsest = "level0/level" + last.name;
      bench.row("pyramid", ds, s.volume.numChannels(), o.macrocell, "expected-value", evBound, "ratio", coarsest);
      bench.row("pyramid", ds, s.volume.numChannels(), o.macrocell, "collision", colBound, "ratio", coarsest);
    }
  }
  std::printf("\n");
  std::fflush(stdout);
  runLevelRebuild(bench);
}
} // namespace mcvolbench
