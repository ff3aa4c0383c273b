// SPDX-License-Identifier: BSD-3-Clause
//
// mcvol-bench section "trackers": frame time at 1 spp, 1-DDA and N-DDA.

#include "BenchCommon.h"
#include "Sections.h"

#include <cstdio>
#include <string>
#include <vector>

namespace mcvolbench
{
void runTrackers(Bench& bench)
{
  const Options& o = bench.o;
  Setup& s = bench.s;
  mcvol::Renderer& r = bench.r;
  s.load(o, o.channels, o.macrocell, bench.hostAccel);
  const std::string ds = describe(o, s);
  std::printf(
    "## Frame time at 1 spp: %s, %d channels, macrocell %d\n\n", ds.c_str(), s.volume.numChannels(), o.macrocell);
  std::printf("| tracker | median ms | min ms | tentative collisions/ray | DDA steps/ray | mean alpha "
              "|\n|---|---|---|---|---|---|\n");
  for (auto t : { mcvol::Tracker::OneDDA, mcvol::Tracker::NDDA })
  {
    const FrameStats f = timeFrames(o, r, s.scene, t);
    std::printf("| %s | %.2f | %.2f | %.2f | %.2f | %.3f |\n", mcvol::toString(t), f.medianMs, f.minMs,
      f.tentativePerRay, f.ddaPerRay, f.alpha);
    bench.row("trackers", ds, s.volume.numChannels(), o.macrocell, mcvol::toString(t), f.medianMs, "ms", "");
  }
  std::printf("\n");
  std::fflush(stdout);
}
} // namespace mcvolbench
