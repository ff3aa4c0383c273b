// SPDX-License-Identifier: BSD-3-Clause
//
// mcvol-bench section "split": what each of N processes traces when they
// split the image (vtkMultiChannelVolumeMapper::SplitImageWithExactStandIn):
// the render of k samples per pixel with one process's rows only, the other
// rows masked as the mapper masks them (depth 0), against the whole image.
// With perfect scaling the slowest process's render takes 1/N of the whole
// one; what it takes beyond that is work that does not shrink with the rows,
// or rows that cost more than others. On
// CUDA both with the shadow rays deferred to a kernel of their own (one
// camera-and-shadow launch pair per sample) and traced inline (one launch
// for all k samples).

#include "BenchCommon.h"
#include "Sections.h"

#include "mcvol/DeviceRenderer.h"

#include <algorithm>
#include <cstdio>
#include <string>
#include <vector>

namespace mcvolbench
{
void runSplit(Bench& bench)
{
  const Options& o = bench.o;
  Setup& s = bench.s;
  mcvol::Renderer& r = bench.r;
  s.load(o, o.channels, o.macrocell, bench.hostAccel);
  const std::string ds = describe(o, s);
  const mcvol::Camera cam = benchCamera(o, s.scene);
  std::vector<bool> deferModes{ true };
#ifdef MCVOL_WITH_CUDA
  mcvol::CUDARenderer* cuda = asCuda(r);
  const bool deferredBefore = cuda ? cuda->deferredShadows() : false;
  if (cuda)
  {
    deferModes = { true, false };
  }
#endif
  std::printf("## Split image: the processes' rows (%s, %dx%d, stripes of %d rows)\n\n"
              "Median of %d renders of k samples per pixel each (fresh image, expected value, Sobol') with the "
              "rows of one process of N only, for each process; the slowest process sets the pace. Scaling: the "
              "whole image's time over the slowest process's (N is perfect).\n\n"
              "| shadow rays | k spp | N | slowest ms | mean ms | scaling | ideal ms | slowest beyond ideal (ms) "
              "|\n|---|---|---|---|---|---|---|---|\n",
    ds.c_str(), o.width, o.height, mcvol::kSplitImageStripeRows, o.frames);
  for (const bool defer : deferModes)
  {
#ifdef MCVOL_WITH_CUDA
    if (cuda)
    {
      cuda->setDeferredShadows(defer);
    }
#endif
    const char* mode = !bench.r.device() ? "CPU" : (defer ? "deferred" : "inline");
    for (const int k : { 1, 16, 96 })
    {
      double whole = 0.0;
      for (const int ranks : { 1, 2, 4, 8 })
      {
        double slowest = 0.0, mean = 0.0;
        for (int rank = 0; rank < ranks; ++rank)
        {
          std::vector<float> mask;
          mcvol::maskSplitImageRows(mask, o.width, o.height, ranks, rank);
          mcvol::RenderSettings rs;
          rs.samplesPerPixel = k;
          rs.readBack = false;
          std::vector<double> ms;
          mcvol::Accumulator acc;
          for (int i = 0; i < o.warmup + o.frames; ++i)
          {
            acc.reset(); // a fresh image, the device buffers kept
            rs.seed = uint32_t(i);
            const auto t0 = Clock::now();
            r.render(s.scene, cam, rs, ranks > 1 ? mask.data() : nullptr, acc);
            r.finish();
            if (i >= o.warmup)
            {
              ms.push_back(1e3 * seconds(t0));
            }
          }
          const double t = median(ms);
          slowest = std::max(slowest, t);
          mean += t / ranks;
        }
        if (ranks == 1)
        {
          whole = slowest;
        }
        std::printf("| %s | %d | %d | %.3f | %.3f | %.2fx | %.3f | %.3f |\n", mode, k, ranks, slowest, mean,
          whole / slowest, whole / ranks, slowest - whole / ranks);
        bench.row("split", ds, s.volume.numChannels(), o.macrocell,
          std::string(mode) + " k=" + std::to_string(k) + " N=" + std::to_string(ranks), slowest, "ms_slowest", "");
        std::fflush(stdout);
      }
    }
  }
#ifdef MCVOL_WITH_CUDA
  if (cuda)
  {
    cuda->setDeferredShadows(deferredBefore);
  }
#endif
  std::printf("\n");
}
} // namespace mcvolbench
