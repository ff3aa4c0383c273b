// SPDX-License-Identifier: BSD-3-Clause
//
// mcvol-bench section "paper": the paper's frame-rate protocol (1024^2, 1 spp,
// 25 warm-up + 500 timed frames), both trackers: FPS = 1000 / mean frame ms.

#include "BenchCommon.h"
#include "Sections.h"

#include <cstdio>
#include <string>
#include <vector>

namespace mcvolbench
{
void runPaper(Bench& bench)
{
  const Options& o = bench.o;
  Setup& s = bench.s;
  mcvol::Renderer& r = bench.r;
  s.load(o, o.channels, o.macrocell, bench.hostAccel);
  const std::string ds = describe(o, s);
  std::printf("## Paper protocol: %s, %d channels, macrocell %d, %dx%d, 1 spp, %d warm-up + %d timed frames\n\n",
    ds.c_str(), s.volume.numChannels(), o.macrocell, o.width, o.height, o.warmup, o.frames);
  std::printf("| tracker | FPS (1000 / mean ms) | mean ms | median ms | min ms | ms with copy-back | tentative/ray | "
              "DDA steps/ray | mean alpha |\n|---|---|---|---|---|---|---|---|---|\n");
  // The paper's protocol is its collision estimator with each tracker; the
  // last row is the default expected-value estimator (one DDA).
  for (int k = 0; k < 3; ++k)
  {
    const mcvol::Tracker t = k == 1 ? mcvol::Tracker::NDDA : mcvol::Tracker::OneDDA;
    const mcvol::Estimator e = k == 2 ? mcvol::Estimator::ExpectedValue : mcvol::Estimator::Collision;
    const std::string name = k == 2 ? "expected-value" : mcvol::toString(t);
    const FrameStats f = timeFrames(o, r, s.scene, t, e);
    std::printf("| %s | %.1f | %.3f | %.3f | %.3f | %.3f | %.2f | %.2f | %.3f |\n", name.c_str(), 1000.0 / f.meanMs,
      f.meanMs, f.medianMs, f.minMs, f.readBackMs, f.tentativePerRay, f.ddaPerRay, f.alpha);
    bench.row("paper", ds, s.volume.numChannels(), o.macrocell, name, 1000.0 / f.meanMs, "fps", "");
    bench.row("paper", ds, s.volume.numChannels(), o.macrocell, name, f.meanMs, "ms", "mean");
    bench.row("paper", ds, s.volume.numChannels(), o.macrocell, name, f.readBackMs, "ms", "with copy-back");
    std::fflush(stdout);
  }
  std::printf("\n");
}
} // namespace mcvolbench
