// SPDX-License-Identifier: BSD-3-Clause
//
// mcvol-bench section "effects": lighting effects one by one: frame time, work
// per ray (shadow rays, scattering events, gradients), image change against the
// unlit image and 1-spp noise.

#include "BenchCommon.h"
#include "Sections.h"

#include <cmath>
#include <cstdint>
#include <cstdio>
#include <string>
#include <vector>

namespace mcvolbench
{
void runEffects(Bench& bench)
{
  const Options& o = bench.o;
  Setup& s = bench.s;
  mcvol::Renderer& r = bench.r;
  // What each lighting effect costs and what it changes. The
  // emission-absorption row runs the unlit kernel; the others the lit one.
  s.load(o, o.channels, o.macrocell, bench.hostAccel);
  const std::string ds = describe(o, s);
  const int nch = s.volume.numChannels();
  struct Effect
  {
    std::string name;
    mcvol::LightingDesc desc;
  };
  auto base = [&]() { return lightingPreset("shadows", nch, o.scatterRoulette); };
  std::vector<Effect> effects;
  effects.push_back({ "emission-absorption (no light)", mcvol::LightingDesc() });
  {
    Effect e{ "1 light, no shadows", base() };
    e.desc.shadows = false;
    effects.push_back(e);
  }
  effects.push_back({ "1 light, ratio-tracking shadows", base() });
  {
    Effect e{ "1 light, delta-tracking shadows", base() };
    e.desc.deltaShadows = true;
    effects.push_back(e);
  }
  // Cached shadows (LightingDesc::cacheShadows) at three node spacings.
  for (float spacing : { 1.f, 2.f, 4.f })
  {
    char name[64];
    std::snprintf(name, sizeof(name), "1 light, cached shadows (node spacing %g)", double(spacing));
    Effect e{ name, base() };
    e.desc.cacheShadows = true;
    e.desc.cacheSpacing = spacing;
    effects.push_back(e);
  }
  {
    Effect e{ "1 light, ratio shadows, gradient shading", base() };
    e.desc.gradientShading = true;
    effects.push_back(e);
  }
  {
    Effect e{ "1 light, ratio shadows, ambient 0.3", base() };
    e.desc.ambient[0] = e.desc.ambient[1] = e.desc.ambient[2] = 0.3;
    effects.push_back(e);
  }
  {
    Effect e{ "1 light, ratio shadows, ambient 0.3, multiple scattering (depth 8)", base() };
    e.desc.ambient[0] = e.desc.ambient[1] = e.desc.ambient[2] = 0.3;
    e.desc.maxDepth = 8;
    effects.push_back(e);
  }
  const mcvol::Camera cam = benchCamera(o, s.scene);
  auto converged = [&](uint32_t seed)
  {
    mcvol::Accumulator acc;
    mcvol::RenderSettings rs;
    rs.seed = seed;
    rs.samplesPerPixel = 16;
    rs.readBack = false;
    while (int(acc.samples()) < o.referenceSpp)
    {
      r.render(s.scene, cam, rs, nullptr, acc);
    }
    r.readBack(acc);
    return std::vector<float>(acc.rgba(), acc.rgba() + size_t(4) * acc.width() * acc.height());
  };
  auto rmse = [](const std::vector<float>& a, const float* b)
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
  std::printf("## Lighting effects: cost and effect (%s, macrocell %d, %dx%d)\n\n"
              "Times: 1 spp per frame, median. Image change: RMSE of the %d-spp image against the unlit %d-spp "
              "image; noise: RMSE of one 1-spp frame against its own %d-spp image (premultiplied RGB).\n\n"
              "Collision: the collision estimator, 1-DDA; expected value: the expected-value estimator (lit: "
              "traceLitExpected()), each against the unlit frame of the same estimator.\n\n"
              "| effect | collision ms | x unlit | expected value ms | x unlit | scattering events/ray | shadow rays/ray "
              "| gradients/ray | image change | 1-spp noise |\n|---|---|---|---|---|---|---|---|---|---|\n",
    ds.c_str(), o.macrocell, o.width, o.height, o.referenceSpp, o.referenceSpp, o.referenceSpp);
  std::vector<float> unlit;
  std::vector<float> ratio; // the converged image with ratio-tracking shadows
  double unlitMs = 0, unlitExpectedMs = 0;
  struct CacheRow
  {
    std::string name;
    double buildMs, bias, noise;
  };
  std::vector<CacheRow> cacheRows;
  for (const Effect& e : effects)
  {
    s.scene.setLighting(e.desc);
    double buildMs = 0;
    if (e.desc.cacheShadows)
    {
      // The grid's fill: the first render after the change less the same
      // render again (a fresh image each, so that both pay its set-up).
      mcvol::RenderSettings rs;
      rs.readBack = false;
      double ms[2];
      for (double& m : ms)
      {
        mcvol::Accumulator fresh;
        r.finish();
        const auto t0 = Clock::now();
        r.render(s.scene, cam, rs, nullptr, fresh);
        r.finish();
        m = 1e3 * seconds(t0);
      }
      buildMs = ms[0] - ms[1];
    }
    const FrameStats f = timeFrames(o, r, s.scene, mcvol::Tracker::OneDDA);
    const FrameStats fe = timeFrames(o, r, s.scene, mcvol::Tracker::OneDDA, mcvol::Estimator::ExpectedValue);
    const std::vector<float> conv = converged(4242);
    if (unlit.empty())
    {
      unlit = conv;
      unlitMs = f.medianMs;
      unlitExpectedMs = fe.medianMs;
    }
    mcvol::Accumulator one;
    mcvol::RenderSettings rs;
    rs.seed = 99;
    r.render(s.scene, cam, rs, nullptr, one);
    const double change = rmse(conv, unlit.data());
    const double noise = rmse(conv, one.rgba());
    if (e.name == "1 light, ratio-tracking shadows")
    {
      ratio = conv;
    }
    if (e.desc.cacheShadows && !ratio.empty())
    {
      cacheRows.push_back({ e.name, buildMs, rmse(conv, ratio.data()), noise });
      bench.row("effects", ds, nch, o.macrocell, e.name, buildMs, "cache_fill_ms", "");
      bench.row("effects", ds, nch, o.macrocell, e.name, rmse(conv, ratio.data()), "rmse_vs_ratio_shadows", "");
    }
    std::printf("| %s | %.3f | %.2fx | %.3f | %.2fx | %.3f | %.3f | %.3f | %.4f | %.4f |\n", e.name.c_str(),
      f.medianMs, f.medianMs / unlitMs, fe.medianMs, fe.medianMs / unlitExpectedMs, f.scatterPerRay, f.shadowPerRay,
      f.gradientPerRay, change, noise);
    bench.row("effects", ds, nch, o.macrocell, e.name, f.medianMs, "ms", "");
    bench.row("effects", ds, nch, o.macrocell, e.name, fe.medianMs, "ms_expected_value", "");
    bench.row("effects", ds, nch, o.macrocell, e.name, change, "rmse_vs_unlit", "");
    bench.row("effects", ds, nch, o.macrocell, e.name, noise, "rmse_1spp_vs_converged", "");
    std::fflush(stdout);
  }
  s.scene.setLighting(mcvol::LightingDesc());
  std::printf("\n");
  if (!cacheRows.empty())
  {
    std::printf("Cached shadows: the grid's fill (the first frame after the change less the same frame again) and the bias "
                "(RMSE of the converged image against the converged image with ratio-tracking shadows).\n\n"
                "| effect | fill ms | bias RMSE | 1-spp noise |\n|---|---|---|---|\n");
    for (const CacheRow& c : cacheRows)
    {
      std::printf("| %s | %.3f | %.5f | %.4f |\n", c.name.c_str(), c.buildMs, c.bias, c.noise);
    }
    std::printf("\n");
  }
}
} // namespace mcvolbench
