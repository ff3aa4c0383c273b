// SPDX-License-Identifier: BSD-3-Clause
//
// mcvol-bench section "channels": frame time against channel count
// (--channel-counts, default 1, 2, 4, 8, 12, 16).

#include "BenchCommon.h"
#include "Sections.h"

#include <algorithm>
#include <cstdio>
#include <string>
#include <vector>

namespace mcvolbench
{
void runChannels(Bench& bench)
{
  const Options& o = bench.o;
  Setup& s = bench.s;
  mcvol::Renderer& r = bench.r;
  std::printf("## Frame time against channel count (%s, macrocell %d)\n\n", o.dataset.c_str(), o.macrocell);
  std::printf("| channels | 1-DDA ms | N-DDA ms | 1-DDA / 1 channel | mean alpha |\n|---|---|---|---|---|\n");
  double base = 0;
  s.loadedKey.clear();
  s.volume = mcvol::makeDemo(o.dataset, o.dims, *std::max_element(o.channelCounts.begin(), o.channelCounts.end()));
  for (int n : o.channelCounts)
  {
    s.configure(o, n, o.macrocell, bench.hostAccel);
    const FrameStats a = timeFrames(o, r, s.scene, mcvol::Tracker::OneDDA);
    const FrameStats b = timeFrames(o, r, s.scene, mcvol::Tracker::NDDA);
    if (base == 0)
    {
      base = a.medianMs;
    }
    std::printf("| %d | %.2f | %.2f | %.2fx | %.3f |\n", n, a.medianMs, b.medianMs, a.medianMs / base, a.alpha);
    bench.row("channels", describe(o, s), n, o.macrocell, "1-DDA", a.medianMs, "ms", "");
    bench.row("channels", describe(o, s), n, o.macrocell, "N-DDA", b.medianMs, "ms", "");
    std::fflush(stdout);
  }
  std::printf("\n");
}
} // namespace mcvolbench
