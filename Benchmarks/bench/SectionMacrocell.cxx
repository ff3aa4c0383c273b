// SPDX-License-Identifier: BSD-3-Clause
//
// mcvol-bench section "macrocell": frame time against macrocell size, plus
// memory (paper Fig. 8).

#include "BenchCommon.h"
#include "Sections.h"

#include <cstdio>
#include <string>
#include <vector>

namespace mcvolbench
{
void runMacrocell(Bench& bench)
{
  const Options& o = bench.o;
  Setup& s = bench.s;
  mcvol::Renderer& r = bench.r;
  s.load(o, o.channels, o.macrocell, bench.hostAccel);
  std::printf("## Frame time and memory against macrocell size (%s, %d channels)\n\n", describe(o, s).c_str(),
    s.volume.numChannels());
  std::printf("| macrocell (voxels) | grid | 1-DDA ms | N-DDA ms | macrocells+majorants / data | build ms |\n"
              "|---|---|---|---|---|---|\n");
  for (int m : o.macrocellSizes)
  {
    const auto t0 = Clock::now();
    s.scene.setMacrocellSize(m);
    s.scene.update();
    double buildMs = 1e3 * seconds(t0);
    const FrameStats a = timeFrames(o, r, s.scene, mcvol::Tracker::OneDDA);
    const FrameStats b = timeFrames(o, r, s.scene, mcvol::Tracker::NDDA);
    mcvol::MemoryStats mem = s.scene.memory();
#ifdef MCVOL_WITH_CUDA
    if (mcvol::CUDARenderer* g = asCuda(r))
    {
      const mcvol::CudaMemoryStats dm = g->memory();
      mem.macrocellBytes = dm.macrocellBytes;
      mem.majorantBytes = dm.majorantBytes;
      buildMs = g->updateCounters().lastRangeMs; // GPU range build (majorants: see rebuild)
    }
#endif
    const double frac = double(mem.macrocellBytes + mem.majorantBytes) / double(mem.dataBytes);
    const int* g = s.scene.macrocellDims();
    std::printf("| %d | %dx%dx%d | %.2f | %.2f | %.2f%% | %.1f |\n", m, g[0], g[1], g[2], a.medianMs, b.medianMs,
      100 * frac, buildMs);
    bench.row("macrocell", describe(o, s), s.volume.numChannels(), m, "1-DDA", a.medianMs, "ms", "");
    bench.row("macrocell", describe(o, s), s.volume.numChannels(), m, "N-DDA", b.medianMs, "ms", "");
    bench.row("macrocell", describe(o, s), s.volume.numChannels(), m, "-", 100 * frac, "percent_of_data", "memory");
    std::fflush(stdout);
  }
  std::printf("\n");
}
} // namespace mcvolbench
