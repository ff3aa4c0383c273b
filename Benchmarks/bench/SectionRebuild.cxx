// SPDX-License-Identifier: BSD-3-Clause
//
// mcvol-bench section "rebuild": majorant rebuild time after one channel's
// transfer function changes.

#include "BenchCommon.h"
#include "Sections.h"

#include <algorithm>
#include <cstdint>
#include <cstdio>
#include <string>
#include <vector>

namespace mcvolbench
{
void runRebuild(Bench& bench)
{
  const Options& o = bench.o;
  Setup& s = bench.s;
  s.load(o, o.channels, o.macrocell, bench.hostAccel);
  // Alternate between two transfer functions of channel 0 and time the
  // update() that rebuilds its majorants (only that channel).
  mcvol::DemoTransferFunction alt = s.volume.transferFunctions[0];
  for (auto& p : alt.opacity)
  {
    p[1] = std::min(1.f, p[1] * 0.5f + 0.05f);
  }
  std::vector<double> ms;
  int rebuilt = 0;
  for (int i = 0; i < 21; ++i)
  {
    const auto& tf = (i % 2) ? alt : s.volume.transferFunctions[0];
    s.scene.setTransferFunction(
      0, mcvol::sampleTransferFunction(tf, s.ranges[0][0], s.ranges[0][1], o.tableSize, s.volume.spacing[0]));
    s.scene.update();
    double one = 1e3 * s.scene.lastMajorantBuildSeconds();
    rebuilt = s.scene.lastMajorantChannelsRebuilt();
#ifdef MCVOL_WITH_CUDA
    if (mcvol::CUDARenderer* g = asCuda(bench.r))
    {
      // The GPU rebuilds at the next render: render one small frame.
      const uint64_t before = g->updateCounters().majorantChannelBuilds;
      mcvol::Camera cam = benchCamera(o, s.scene);
      cam.width = cam.height = 8;
      mcvol::Accumulator acc;
      bench.r.render(s.scene, cam, mcvol::RenderSettings(), nullptr, acc);
      one = g->updateCounters().lastMajorantMs;
      rebuilt = int(g->updateCounters().majorantChannelBuilds - before);
    }
#endif
    if (i > 0)
    {
      ms.push_back(one); // the first update builds every channel
    }
  }
  const int* g = s.scene.macrocellDims();
  std::printf("## Majorant rebuild after one transfer-function change (%s, macrocell %d, grid %dx%dx%d, table %d)\n\n"
              "| channels rebuilt | median ms | max ms |\n|---|---|---|\n| %d | %.3f | %.3f |\n\n",
    describe(o, s).c_str(), o.macrocell, g[0], g[1], g[2], o.tableSize, rebuilt, median(ms),
    *std::max_element(ms.begin(), ms.end()));
  bench.row("rebuild", describe(o, s), s.volume.numChannels(), o.macrocell, "-", median(ms), "ms", "one channel");
  std::fflush(stdout);
}
} // namespace mcvolbench
