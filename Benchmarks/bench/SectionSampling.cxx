// SPDX-License-Identifier: BSD-3-Clause
//
// mcvol-bench section "sampling": CUDA only: texture (hardware trilinear)
// against global-memory (software trilinear) sampling, both trackers.

#include "BenchCommon.h"
#include "Sections.h"

#include <cstdio>
#include <string>
#include <vector>

namespace mcvolbench
{
void runSampling([[maybe_unused]] Bench& bench)
{
#ifdef MCVOL_WITH_CUDA
  if (mcvol::CUDARenderer* g = asCuda(bench.r))
  {
    const Options& o = bench.o;
    Setup& s = bench.s;
    mcvol::Renderer& r = bench.r;
    s.load(o, o.channels, o.macrocell, bench.hostAccel);
    const std::string ds = describe(o, s);
    std::printf("## Texture against global-memory sampling: %s, macrocell %d\n\n| sampling | 1-DDA ms | N-DDA ms "
                "|\n|---|---|---|\n",
      ds.c_str(), o.macrocell);
    const mcvol::CudaSampling keep = g->sampling();
    for (auto smp : { mcvol::CudaSampling::Texture, mcvol::CudaSampling::Global })
    {
      g->setSampling(smp);
      const FrameStats a = timeFrames(o, r, s.scene, mcvol::Tracker::OneDDA);
      const FrameStats b = timeFrames(o, r, s.scene, mcvol::Tracker::NDDA);
      const char* name = smp == mcvol::CudaSampling::Texture ? "texture" : "global";
      std::printf("| %s | %.3f | %.3f |\n", name, a.meanMs, b.meanMs);
      bench.row("sampling", ds, s.volume.numChannels(), o.macrocell, "1-DDA", a.meanMs, "ms", name);
      bench.row("sampling", ds, s.volume.numChannels(), o.macrocell, "N-DDA", b.meanMs, "ms", name);
      std::fflush(stdout);
    }
    g->setSampling(keep);
    std::printf("\n");
  }
  else
#endif
  {
    std::printf("(sampling: CUDA backend only)\n\n");
  }
}
} // namespace mcvolbench
