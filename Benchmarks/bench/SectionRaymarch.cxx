// SPDX-License-Identifier: BSD-3-Clause
//
// mcvol-bench section "raymarch": Sahistan et al.'s Fig. 10, the ray marcher
// (RM, mix blending) against 1-DDA multi-density Woodcock tracking (MDWT,
// mix blending, the paper's collision estimator), on the backend chosen:
// - similar quality: MDWT at 1, 2, 4, 8 and 16 spp against RM at the
//   Nyquist step (half the smallest voxel spacing, marchNyquistStep());
// - similar performance: RM with the step 1, 2, 4, 8 and 16 times the
//   Nyquist step against MDWT at 1 spp.
// Time = median of --frames frames after --warmup (RM: one march each; MDWT:
// one render of that many samples each, finished), PSNR against a converged
// MDWT image (--reference-spp samples, the march's limit too).

#include "BenchCommon.h"
#include "Sections.h"

#include "mcvol/MarchSetup.h"

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <string>
#include <vector>

namespace mcvolbench
{
namespace
{
template <class F>
double medianMs(const Options& o, F frame)
{
  std::vector<double> ms;
  for (int i = 0; i < o.warmup + o.frames; ++i)
  {
    const auto t0 = std::chrono::steady_clock::now();
    frame(i);
    const double t = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
    if (i >= o.warmup)
    {
      ms.push_back(t);
    }
  }
  std::sort(ms.begin(), ms.end());
  return ms.empty() ? 0.0 : ms[ms.size() / 2];
}
} // namespace

void runRaymarch(Bench& bench)
{
  const Options& o = bench.o;
  Setup& s = bench.s;
  mcvol::Renderer& r = bench.r;
  s.load(o, o.channels, o.macrocell, bench.hostAccel);
  s.scene.setBlendMode(mcvol::BlendMode::Mix);
  s.scene.update();
  const std::string ds = describe(o, s);
  const mcvol::Camera cam = benchCamera(o, s.scene);
  mcvol::RenderSettings rrs;
  rrs.estimator = mcvol::Estimator::Collision;
  mcvol::Accumulator ref;
  const std::vector<float> refImg = renderReference(o, r, s.scene, cam, ref, rrs);
  const double nyquist = mcvol::marchNyquistStep(cam);
  std::printf("## Ray marcher against MDWT (Sahistan et al. Fig. 10): %s, mix blending, %dx%d, median of %d "
              "frames, PSNR against %d spp\n\n| method | setting | ms | PSNR (dB) |\n|---|---|---|---|\n",
    ds.c_str(), o.width, o.height, o.frames, o.referenceSpp);
  auto march = [&](double factor)
  {
    mcvol::MarchSettings ms;
    ms.step = nyquist * factor;
    mcvol::Accumulator acc;
    const double t = medianMs(o, [&](int) { r.march(s.scene, cam, ms, nullptr, acc); });
    const double q = psnrOf(acc, refImg);
    std::printf("| RM-Mix | step %gx Nyquist (%.4g) | %.3f | %.2f |\n", factor, ms.step, t, q);
    bench.row("raymarch", ds, s.volume.numChannels(), o.macrocell, "RM step x" + std::to_string(int(factor)), t, "ms",
      "");
    bench.row("raymarch", ds, s.volume.numChannels(), o.macrocell, "RM step x" + std::to_string(int(factor)), q, "dB",
      "PSNR");
  };
  auto mdwt = [&](int spp)
  {
    mcvol::RenderSettings rs;
    rs.estimator = mcvol::Estimator::Collision;
    rs.samplesPerPixel = spp;
    mcvol::Accumulator acc;
    acc.resize(cam.width, cam.height);
    const double t = medianMs(o,
      [&](int i)
      {
        acc.reset();
        rs.seed = uint32_t(100 + i);
        r.render(s.scene, cam, rs, nullptr, acc);
        r.finish();
        r.readBack(acc);
      });
    const double q = psnrOf(acc, refImg);
    std::printf("| MDWT-Mix (1-DDA) | %d spp | %.3f | %.2f |\n", spp, t, q);
    bench.row("raymarch", ds, s.volume.numChannels(), o.macrocell, "MDWT " + std::to_string(spp) + " spp", t, "ms", "");
    bench.row("raymarch", ds, s.volume.numChannels(), o.macrocell, "MDWT " + std::to_string(spp) + " spp", q, "dB",
      "PSNR");
  };
  march(1.0);
  for (int spp : { 1, 2, 4, 8, 16 })
  {
    mdwt(spp);
    std::fflush(stdout);
  }
  for (double f : { 2.0, 4.0, 8.0, 16.0 })
  {
    march(f);
    std::fflush(stdout);
  }
  std::printf("\n");
}
} // namespace mcvolbench
