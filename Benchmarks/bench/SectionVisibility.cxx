// SPDX-License-Identifier: BSD-3-Clause
//
// mcvol-bench section "visibility": what the visibility optimization (paper
// 004) costs: the unoptimized frame against the optimized one (camera rays),
// the refining renders, importance samples per ray, and the memory of the
// per-pixel segment lists (paper Table 3).

#include "BenchCommon.h"
#include "Sections.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <string>
#include <vector>

namespace mcvolbench
{
void runVisibility(Bench& bench)
{
  const Options& o = bench.o;
  Setup& s = bench.s;
  mcvol::Renderer& r = bench.r;
  s.load(o, o.channels, o.macrocell, bench.hostAccel);
  const std::string ds = describe(o, s);
  const int nch = s.volume.numChannels();
  // The last channel is important where its value is in the upper half of
  // its range (a step function, as the paper's examples).
  mcvol::ImportanceDesc imp;
  imp.enabled = true;
  imp.tables.assign(size_t(nch), std::vector<float>());
  std::vector<float>& t = imp.tables[size_t(nch - 1)];
  t.resize(size_t(o.tableSize));
  for (int i = 0; i < o.tableSize; ++i)
  {
    t[size_t(i)] = 2 * i >= o.tableSize ? 1.f : 0.f;
  }
  const mcvol::Camera cam = benchCamera(o, s.scene);
  std::printf("## Visibility optimization: cost (%s, macrocell %d, %dx%d)\n\n"
              "Last channel important in the upper half of its range; p = 1, q = 70, r = 30, lambda = 1, %d "
              "importance samples per ray and pass. Frame: 1 spp, median over %d frames (the first 4 of an image "
              "refine the segment lists); refine: mean of the first 4 renders of a new image.\n\n"
              "| mode | frame ms | x unoptimized | refining render ms | importance samples/ray | segments/pixel "
              "| list memory MB | overflows |\n|---|---|---|---|---|---|---|---|\n",
    ds.c_str(), o.macrocell, o.width, o.height, imp.samplesPerPass, o.frames);
  s.scene.setImportance(mcvol::ImportanceDesc());
  s.scene.update();
  const FrameStats plain = timeFrames(o, r, s.scene, mcvol::Tracker::OneDDA);
  std::printf("| unoptimized | %.3f | 1.00x | - | 0 | - | 0 | - |\n", plain.medianMs);
  bench.row("visibility", ds, nch, o.macrocell, "unoptimized", plain.medianMs, "ms", "");
  s.scene.setImportance(imp);
  s.scene.update();
  const FrameStats opt = timeFrames(o, r, s.scene, mcvol::Tracker::OneDDA);
  // The refining renders of a new image, and the lists they leave.
  mcvol::Accumulator acc;
  mcvol::RenderSettings st;
  st.readBack = false;
  mcvol::RenderCounters c;
  double refineMs = 0;
  for (int i = 0; i < imp.refinePasses; ++i)
  {
    const auto t0 = Clock::now();
    r.render(s.scene, cam, st, nullptr, acc, &c);
    r.finish();
    refineMs += 1e3 * seconds(t0);
  }
  refineMs /= imp.refinePasses;
  const mcvol::Accumulator::ImportancePool& pool = acc.importancePoolIfAny();
  double segments = -1;
  if (!pool.counts.empty())
  {
    double sum = 0;
    for (uint8_t n : pool.counts)
    {
      sum += n;
    }
    segments = sum / double(pool.counts.size());
  }
  const double mb = double(pool.bytes()) / (1024.0 * 1024.0);
  const double perRay = double(c.importanceSamples) / double(c.rays);
  char seg[32];
  std::snprintf(seg, sizeof(seg), segments < 0 ? "(on device)" : "%.2f", segments);
  std::printf("| optimized (camera rays) | %.3f | %.2fx | %.3f | %.2f | %s | %.1f | %llu |\n\n", opt.medianMs,
    opt.medianMs / plain.medianMs, refineMs, perRay, seg, mb, static_cast<unsigned long long>(pool.overflows));
  bench.row("visibility", ds, nch, o.macrocell, "optimized", opt.medianMs, "ms", "");
  bench.row("visibility", ds, nch, o.macrocell, "optimized", refineMs, "ms_refining", "");
  bench.row("visibility", ds, nch, o.macrocell, "optimized", mb, "MB_segment_lists", "");
  bench.row("visibility", ds, nch, o.macrocell, "optimized", double(pool.overflows), "overflows", "");
  // What accuracy costs in time: each quality knob of the optimization
  // against the error of the image it gives (RMSE of premultiplied RGB
  // against a converged image of the same settings' limit).
  auto render = [&](int spp, uint32_t seed, double* ms)
  {
    mcvol::Accumulator a;
    mcvol::RenderSettings rs;
    rs.seed = seed;
    rs.readBack = false;
    rs.samplesPerPixel = 1;
    const auto t0 = Clock::now();
    // One sample per render for the first passes (they refine the lists),
    // then in batches of up to 16.
    while (int(a.samples()) < spp)
    {
      rs.samplesPerPixel = a.samples() < 4 ? 1 : std::min(16, spp - int(a.samples()));
      r.render(s.scene, cam, rs, nullptr, a);
    }
    r.readBack(a);
    r.finish();
    if (ms)
    {
      *ms = 1e3 * seconds(t0);
    }
    return std::vector<float>(a.rgba(), a.rgba() + size_t(4) * a.width() * a.height());
  };
  auto rmse = [](const std::vector<float>& a, const std::vector<float>& b)
  {
    double se = 0;
    for (size_t i = 0; i < a.size(); ++i)
    {
      if (i % 4 != 3)
      {
        se += (double(a[i]) - b[i]) * (double(a[i]) - b[i]);
      }
    }
    return std::sqrt(se / double(a.size() / 4 * 3));
  };
  const int refSpp = o.referenceSpp;
  // (1) Samples per pixel (paper Fig. 8): error and time of the optimized
  // image against its own converged image.
  s.scene.setImportance(imp);
  s.scene.update();
  {
    const std::vector<float> ref = render(refSpp, 7777, nullptr);
    std::printf("### Optimized image against samples per pixel (camera rays; reference %d spp)\n\n"
                "| spp | ms | RMSE |\n|---|---|---|\n",
      refSpp);
    for (int spp : { 1, 4, 16, 64, 256 })
    {
      double ms = 0;
      const std::vector<float> img = render(spp, 11, &ms);
      const double e = rmse(img, ref);
      std::printf("| %d | %.2f | %.5f |\n", spp, ms, e);
      bench.row("visibility-spp", ds, nch, o.macrocell, std::to_string(spp), e, "rmse", std::to_string(ms));
    }
    std::printf("\n");
  }
  // (2) Importance samples per pass: the refinement's cost and what it buys
  // at 64 spp, against a reference refined with 64 samples per pass.
  {
    mcvol::ImportanceDesc fine = imp;
    fine.samplesPerPass = 64;
    s.scene.setImportance(fine);
    s.scene.update();
    const std::vector<float> ref = render(refSpp, 7778, nullptr);
    std::printf("### Importance samples per camera ray and pass (64 spp; reference: 64 samples, %d spp)\n\n"
                "| samples | ms (64 spp) | RMSE |\n|---|---|---|\n",
      refSpp);
    for (int n : { 4, 8, 16, 32, 64 })
    {
      mcvol::ImportanceDesc d = imp;
      d.samplesPerPass = n;
      s.scene.setImportance(d);
      s.scene.update();
      double ms = 0;
      const std::vector<float> img = render(64, 12, &ms);
      const double e = rmse(img, ref);
      std::printf("| %d | %.2f | %.5f |\n", n, ms, e);
      bench.row("visibility-samples", ds, nch, o.macrocell, std::to_string(n), e, "rmse", std::to_string(ms));
    }
    std::printf("\n");
  }
  // (3) Light rays (paper Fig. 12): one light; samples of each light ray's
  // list against the error at 64 spp (reference: 1000 samples, refSpp).
  {
    mcvol::LightingDesc ld = lightingPreset("shadows", nch);
    ld.anisotropy.clear(); // isotropic scattering
    s.scene.setLighting(ld);
    mcvol::ImportanceDesc ref1000 = imp;
    ref1000.lightRaySamples = 1000;
    s.scene.setImportance(ref1000);
    s.scene.update();
    const std::vector<float> ref = render(refSpp, 7779, nullptr);
    std::printf("### Light-ray importance samples (one light, 64 spp; reference: 1000 samples, %d spp)\n\n"
                "| light-ray samples | ms (64 spp) | RMSE |\n|---|---|---|\n",
      refSpp);
    for (int n : { 0, 8, 32, 100, 200 })
    {
      mcvol::ImportanceDesc d = imp;
      d.lightRays = n > 0;
      d.lightRaySamples = n > 0 ? n : 2;
      s.scene.setImportance(d);
      s.scene.update();
      double ms = 0;
      const std::vector<float> img = render(64, 13, &ms);
      const double e = rmse(img, ref);
      std::printf("| %s | %.2f | %.5f |\n", n > 0 ? std::to_string(n).c_str() : "off (camera rays only)", ms, e);
      bench.row("visibility-lightrays", ds, nch, o.macrocell, std::to_string(n), e, "rmse", std::to_string(ms));
    }
    std::printf("\n");
    s.scene.setLighting(mcvol::LightingDesc());
  }
  s.scene.setImportance(mcvol::ImportanceDesc());
  s.scene.update();
  std::fflush(stdout);
}
} // namespace mcvolbench
