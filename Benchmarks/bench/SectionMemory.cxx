// SPDX-License-Identifier: BSD-3-Clause
//
// mcvol-bench section "memory": data, macrocell and majorant bytes
// (paper Table 1).

#include "BenchCommon.h"
#include "Sections.h"

#include <cstdio>
#include <string>
#include <vector>

namespace mcvolbench
{
void runMemory(Bench& bench)
{
  const Options& o = bench.o;
  Setup& s = bench.s;
  s.load(o, o.channels, o.macrocell, bench.hostAccel);
  mcvol::MemoryStats m = s.scene.memory();
  const double MiB = 1024.0 * 1024.0;
#ifdef MCVOL_WITH_CUDA
  if (mcvol::CUDARenderer* g = asCuda(bench.r))
  {
    mcvol::Accumulator acc;
    bench.r.render(s.scene, benchCamera(o, s.scene), mcvol::RenderSettings(), nullptr, acc);
    const mcvol::CudaMemoryStats dm = g->memory();
    const double data = double(s.scene.memory().dataBytes); // on the host, in the native types
    const double held = double(dm.dataBytes + dm.textureBytes);
    const double total = double(g->deviceBytes());
    m.dataBytes = dm.dataBytes + dm.textureBytes;
    m.macrocellBytes = dm.macrocellBytes;
    m.majorantBytes = dm.majorantBytes;
    std::printf("GPU memory: channels %.2f MiB (arrays %.2f, textures %.2f; host data %.2f MiB), image buffers "
                "%.2f MiB, everything %.2f MiB = data x %.4f + image buffers\n\n",
      held / MiB, dm.dataBytes / MiB, dm.textureBytes / MiB, data / MiB, dm.imageBytes / MiB, total / MiB,
      (total - double(dm.imageBytes)) / data);
    bench.row("memory", describe(o, s), s.volume.numChannels(), o.macrocell, "device",
      (total - double(dm.imageBytes)) / data, "device_bytes_over_data", "");
  }
#endif
  std::printf(
    "## Memory (%s, %d channels, macrocell %d; paper Table 1)\n\n| data MiB | macrocells MiB | majorants MiB "
    "| total MiB | (macrocells+majorants)/data |\n|---|---|---|---|---|\n| %.2f | %.2f | %.2f | %.2f | %.2f%% |\n\n",
    describe(o, s).c_str(), s.volume.numChannels(), o.macrocell, m.dataBytes / MiB, m.macrocellBytes / MiB,
    m.majorantBytes / MiB, (m.dataBytes + m.macrocellBytes + m.majorantBytes) / MiB,
    100.0 * double(m.macrocellBytes + m.majorantBytes) / double(m.dataBytes));
  bench.row("memory", describe(o, s), s.volume.numChannels(), o.macrocell, "-",
    100.0 * double(m.macrocellBytes + m.majorantBytes) / double(m.dataBytes), "percent_of_data", "");
}
} // namespace mcvolbench
