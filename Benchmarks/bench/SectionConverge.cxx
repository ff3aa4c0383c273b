// SPDX-License-Identifier: BSD-3-Clause
//
// mcvol-bench section "converge": ms until the progressive image reaches --psnr
// dB (default 35) against a converged reference (--reference-spp samples).

#include "BenchCommon.h"
#include "Sections.h"

#include <algorithm>
#include <cstdio>
#include <string>
#include <vector>

namespace mcvolbench
{
void runConverge(Bench& bench)
{
  const Options& o = bench.o;
  Setup& s = bench.s;
  mcvol::Renderer& r = bench.r;
  s.load(o, o.channels, o.macrocell, bench.hostAccel);
  const std::string ds = describe(o, s);
  const mcvol::Camera cam = benchCamera(o, s.scene);
  // Converged reference: many samples, another seed, in batches.
  mcvol::Accumulator ref;
  mcvol::RenderSettings rs;
  rs.seed = 12345;
  rs.samplesPerPixel = std::min(64, o.referenceSpp);
  rs.readBack = false;
  for (int k = 0; k < o.referenceSpp; k += rs.samplesPerPixel)
  {
    r.render(s.scene, cam, rs, nullptr, ref);
  }
  r.readBack(ref);
  const std::vector<float> refImg(ref.rgba(), ref.rgba() + size_t(4) * ref.width() * ref.height());
  std::printf("## Time to converge: %s, %dx%d, 1 spp per frame, target PSNR %.1f dB (peak 1, RGB over black) "
              "against %u spp\n\n| tracker | frames | ms (rendering only) | PSNR reached |\n|---|---|---|---|\n",
    ds.c_str(), o.width, o.height, o.psnr, ref.samples());
  for (auto t : { mcvol::Tracker::OneDDA, mcvol::Tracker::NDDA })
  {
    mcvol::Accumulator acc;
    mcvol::RenderSettings st;
    st.tracker = t;
    st.seed = 7;
    st.readBack = false;
    // Warm-up on a throw-away accumulator, then timed frames; the PSNR is
    // checked between frames (not timed).
    {
      mcvol::Accumulator w;
      for (int i = 0; i < 5; ++i)
      {
        r.render(s.scene, cam, st, nullptr, w);
      }
      r.finish();
    }
    double ms = 0;
    double q = 0;
    int frames = 0;
    while (frames < o.maxConvergeFrames)
    {
      const auto t0 = Clock::now();
      r.render(s.scene, cam, st, nullptr, acc);
      r.finish();
      ms += 1e3 * seconds(t0);
      ++frames;
      r.readBack(acc);
      q = psnrOf(acc, refImg);
      if (q >= o.psnr)
      {
        break;
      }
    }
    std::printf("| %s | %d | %.2f | %.2f |\n", mcvol::toString(t), frames, ms, q);
    bench.row("converge", ds, s.volume.numChannels(), o.macrocell, mcvol::toString(t), ms, "ms",
      "frames=" + std::to_string(frames) + " psnr=" + std::to_string(q));
    std::fflush(stdout);
  }
  std::printf("\n");
}
} // namespace mcvolbench
