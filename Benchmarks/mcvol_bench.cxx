// SPDX-License-Identifier: BSD-3-Clause
//
// mcvol-bench: VTK-free benchmark of the core and its backends. It builds on
// any machine with a C++17 compiler and OpenMP (the GPU machine included) and
// prints Markdown tables; --csv also writes the rows as CSV; --help lists
// every option (bench/BenchCommon.cxx, the parser's table). Benchmarks/README.md
// says which figures of the performance page each section produces.
//
// Sections (select with --sections a,b,...; one file each, bench/Section*.cxx):
//   trackers   frame time at 1 spp, 1-DDA and N-DDA
//   channels   frame time against channel count (1, 2, 4, 8, 12, 16)
//   macrocell  frame time against macrocell size, plus memory (paper Fig. 8)
//   rebuild    majorant rebuild time after one channel's transfer function changes
//   memory     data, macrocell and majorant bytes (paper Table 1)
//   paper      the paper's frame-rate protocol (1024^2, 1 spp, 25 warm-up + 500
//              timed frames), both trackers: FPS = 1000 / mean frame ms
//   converge   ms until the progressive image reaches --psnr dB (default 35)
//              against a converged reference (--reference-spp samples)
//   sampling   CUDA only: texture (hardware trilinear) against global-memory
//              (software trilinear) sampling, both trackers
//   effects    lighting effects one by one: frame time, work per ray (shadow
//              rays, scattering events, gradients), image change against the
//              unlit image and 1-spp noise
//   visibility the visibility optimization (Lerzer and Dachsbacher): frame
//              time against the unoptimized frame, refining renders,
//              segment-list memory
//   estimate   the error estimate against the true error (--reference-spp)
//              at 16, 64, 256 spp, and the frame time with and without it
//   sequences  error against spp for the independent sampler and Owen-scrambled
//              Sobol' points (--samplers, --spp-max): fitted slopes, spp and
//              ms to RMSE 0.01 and to --psnr dB
//   pyramid    levels of detail: 1-spp frame time of level 0 (scalar
//              channels) against the pre-classified level 0 and box4 pyramid
//              levels 1..--pyramid-levels (density blend), classify/build
//              time, memory, the level rebuild after an edit
//   pilots     what the automatic estimator choice's pilots cost
//   blends     the paper's Table 2 protocol: converged images of every blend
//              with flat red, green, blue, white colour maps, scored against
//              density blending (PSNR, mean absolute difference)
//   raymarch   the paper's Fig. 10: the ray marcher (mix) at 1-16x the
//              Nyquist step against 1-DDA MDWT (mix) at 1-16 spp: ms, PSNR
//   split      one of N processes' rows of a split image (the exact stand-in
//              across MPI ranks): render time of k spp against the whole
//              image's, deferred and inline shadow rays on CUDA
//
// The image quality of the levels is mcvol-pyramid's (mcvol_pyramid.cxx);
// the accuracy-versus-time images are mcvol-accuracy's (mcvol_accuracy.cxx).
// All three share the option parser and helpers of bench/ArgParser.h and
// bench/BenchUtil.h.
//
// On the CUDA backend frames are timed as render() + finish() with the image
// left on the device (RenderSettings::readBack = false); a separate column
// gives the time with the image copied back each frame.

#include "bench/BenchCommon.h"
#include "bench/Sections.h"
#include "mcvol/DeviceRenderer.h"

#include <cstdio>
#include <exception>
#include <memory>
#include <string>

#ifdef _OPENMP
#include <omp.h>
#endif

using namespace mcvolbench;

namespace
{
struct Section
{
  const char* name;
  void (*run)(Bench&);
};

// Sections run in this order whatever the order given to --sections.
const Section sections[] = {
  { "trackers", runTrackers },
  { "channels", runChannels },
  { "macrocell", runMacrocell },
  { "rebuild", runRebuild },
  { "memory", runMemory },
  { "paper", runPaper },
  { "sampling", runSampling },
  { "effects", runEffects },
  { "converge", runConverge },
  { "visibility", runVisibility },
  { "estimate", runEstimate },
  { "sequences", runSequences },
  { "pyramid", runPyramid },
  { "pilots", runPilots },
  { "blends", runBlends },
  { "raymarch", runRaymarch },
  { "split", runSplit },
};
} // namespace

int main(int argc, char** argv)
{
  Options o;
  try
  {
    o = parse(argc, argv);
  }
  catch (const std::exception& e)
  {
    std::fprintf(stderr, "mcvol-bench: %s\n", e.what());
    usage();
    return 2;
  }
  std::string why;
  std::unique_ptr<mcvol::Renderer> r;
  try
  {
    r = mcvol::Renderer::create(o.backend, &why);
  }
  catch (const std::exception& e)
  {
    std::fprintf(stderr, "mcvol-bench: %s\n", e.what());
    return 3;
  }
  std::string device = "CPU";
#ifdef MCVOL_WITH_CUDA
  if (mcvol::CUDARenderer* g = asCuda(*r))
  {
    g->setSampling(o.sampling == "global" ? mcvol::CudaSampling::Global : mcvol::CudaSampling::Texture);
    g->setBlockSize(o.blockX, o.blockY);
    g->setPlainKernels(!o.generalKernels);
    g->setDeferredShadows(!o.inlineShadows);
    if (o.deferredBatch > 0)
    {
      g->setDeferredBatch(o.deferredBatch);
    }
    device = g->deviceDescription() + "; sampling " + o.sampling + "; block " + std::to_string(o.blockX) + "x" +
      std::to_string(o.blockY) + (o.generalKernels ? "; general kernels" : "") +
      (o.inlineShadows ? "; inline shadow rays" : "") + "; deferred batch " + std::to_string(g->deferredBatch());
  }
#endif
  const bool hostAccel = !(r->device() && r->device()->buildsAccelerationOnDevice());
  int threads = 1;
#ifdef _OPENMP
  threads = omp_get_max_threads();
#endif
  std::printf("# mcvol-bench\n\nbackend: %s (%s); device: %s; host threads: %d; image %dx%d; 1 spp per frame; %d "
              "warm-up + %d timed frames (median)\n\n",
    r->name(), why.c_str(), device.c_str(), threads, o.width, o.height, o.warmup, o.frames);
  Bench bench(o, *r, hostAccel);
  for (const Section& section : sections)
  {
    if (wants(o, section.name))
    {
      section.run(bench);
    }
  }
  bench.writeCsv();
  return 0;
}
