// SPDX-License-Identifier: BSD-3-Clause
//
// mcvol-bench section "estimate": the progressive image's estimated error
// (Accumulator::estimatedMSE) against its true error at
// 16, 64 and 256 spp, and the frame time with and without the even-sample
// half the estimate keeps.

#include "BenchCommon.h"
#include "Sections.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <string>
#include <vector>

namespace mcvolbench
{
namespace
{
/// MSE over premultiplied RGB (alpha left out, as estimatedMSE).
double mseRGB(const mcvol::Accumulator& a, const std::vector<float>& ref)
{
  double s = 0;
  const size_t P = size_t(a.width()) * size_t(a.height());
  for (size_t p = 0; p < P; ++p)
  {
    for (int c = 0; c < 3; ++c)
    {
      const double d = double(a.rgba()[4 * p + c]) - double(ref[4 * p + c]);
      s += d * d;
    }
  }
  return s / double(3 * P);
}
} // namespace

void runEstimate(Bench& bench)
{
  const Options& o = bench.o;
  Setup& s = bench.s;
  mcvol::Renderer& r = bench.r;
  s.load(o, o.channels, o.macrocell, bench.hostAccel);
  const std::string ds = describe(o, s);
  const mcvol::Camera cam = benchCamera(o, s.scene);

  // Estimate against truth: a reference of --reference-spp samples of
  // another seed, whose own (estimated) MSE is taken off the measured one.
  mcvol::Accumulator ref;
  const std::vector<float> refImg = renderReference(o, r, s.scene, cam, ref);
  const double refMSE = std::max(0.0, ref.estimatedMSE());
  std::printf("## Error estimate: %s, %dx%d, against %u spp (its own estimated RMSE %.5f removed)\n\n"
              "| spp | estimated RMSE | true RMSE | ratio | estimated PSNR (dB) |\n|---|---|---|---|---|\n",
    ds.c_str(), o.width, o.height, ref.samples(), std::sqrt(refMSE));
  mcvol::Accumulator acc;
  mcvol::RenderSettings st;
  st.seed = 7;
  st.samplesPerPixel = 4;
  for (int target : { 16, 64, 256 })
  {
    while (int(acc.samples()) < target)
    {
      r.render(s.scene, cam, st, nullptr, acc);
    }
    const double est = std::sqrt(acc.estimatedMSE());
    const double truth = std::sqrt(std::max(0.0, mseRGB(acc, refImg) - refMSE));
    std::printf("| %d | %.5f | %.5f | %.3f | %.2f |\n", target, est, truth, est / truth, -20.0 * std::log10(est));
    bench.row("estimate", ds, s.volume.numChannels(), o.macrocell, "1-DDA", est / truth, "ratio",
      "spp=" + std::to_string(target));
  }
  std::printf("\n");

  // Cost of the half buffer: 1-spp frames into an image with the estimate
  // on and one with it off, alternated so that drift hits both alike.
  std::vector<double> on, off;
  mcvol::Accumulator withHalf, without;
  without.setErrorEstimation(false);
  mcvol::RenderSettings ft;
  ft.readBack = true; // the estimate needs the host copy (CUDA: one more download)
  for (int i = 0; i < o.warmup; ++i)
  {
    r.render(s.scene, cam, ft, nullptr, withHalf);
    r.render(s.scene, cam, ft, nullptr, without);
  }
  for (int i = 0; i < o.frames; ++i)
  {
    auto t0 = Clock::now();
    r.render(s.scene, cam, ft, nullptr, withHalf);
    r.finish();
    on.push_back(1e3 * seconds(t0));
    t0 = Clock::now();
    r.render(s.scene, cam, ft, nullptr, without);
    r.finish();
    off.push_back(1e3 * seconds(t0));
  }
  auto t0 = Clock::now();
  const double e = withHalf.estimatedMSE();
  const double estimateMs = 1e3 * seconds(t0);
  const double mOn = median(on), mOff = median(off);
  std::printf("## Error estimate cost: %s, %dx%d, 1 spp per frame, image read back, median of %d frames\n\n"
              "| half buffer | ms per frame | overhead |\n|---|---|---|\n| off | %.2f | |\n| on | %.2f | %+.1f %% |\n\n"
              "estimatedMSE() itself: %.2f ms (one pass over the image; MSE %.3g)\n\n",
    ds.c_str(), o.width, o.height, o.frames, mOff, mOn, 100.0 * (mOn / mOff - 1.0), estimateMs, e);
  bench.row("estimate", ds, s.volume.numChannels(), o.macrocell, "1-DDA", mOff, "ms", "half=off");
  bench.row("estimate", ds, s.volume.numChannels(), o.macrocell, "1-DDA", mOn, "ms", "half=on");
  std::fflush(stdout);
}
} // namespace mcvolbench
