// SPDX-License-Identifier: BSD-3-Clause
// mcvol-soak: long progressive accumulation, past 2^24 samples per pixel.
//
//   mcvol-soak precision [--max-log2 N]     the image's accumulation
//       (Integrator.h: loadSum, addSample, storeSum) fed batches of known
//       samples, against their exact mean: its error at every other power
//       of two up to 2^N samples per pixel, for batches of 8, 64 and 4096
//       samples ("double-sum"), and the same for a float running mean
//       scaled by previous / n ("float-mean", what a float accumulation
//       buffer gives)
//   mcvol-soak render [--spp N] [--size WxH]     a progressive CPU render of
//       figure3 on a small image to N samples per pixel (default 2^20), twice
//       with different seeds: at every power of two, the RMS difference of
//       the two images (it falls as n^-1/2 while the image converges), the
//       process's resident memory, and the seconds so far
//
// Output: CSV on stdout (Benchmarks/results/accumulation-soak/ keeps a run).
#include "mcvol/CPURenderer.h"
#include "mcvol/CameraMath.h"
#include "mcvol/DemoData.h"
#include "mcvol/Renderer.h"
#include "mcvol/Scene.h"
#include "mcvol/ray/Integrator.h"

#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <string>
#include <vector>

namespace
{
long ResidentKiB()
{
  std::ifstream f("/proc/self/status");
  std::string line;
  while (std::getline(f, line))
  {
    if (line.rfind("VmRSS:", 0) == 0)
    {
      return std::atol(line.c_str() + 6);
    }
  }
  return -1;
}

/// A deterministic stream of per-sample values in [0, 1) (a pixel's alpha
/// and colour are such), multiples of 2^-24 so that each is a float and
/// their sum is exact in integers: uniform from a 64-bit LCG.
struct Stream
{
  unsigned long long s = 0x9E3779B97F4A7C15ull;
  unsigned Next()
  {
    s = s * 6364136223846793005ull + 1442695040888963407ull;
    return unsigned(s >> 40); // 24 bits
  }
};

int Precision(int maxLog2)
{
  std::printf("section,formula,batch,samples,mean,exact_mean,abs_error,error_in_float_ulps\n");
  for (int batch : { 8, 64, 4096 })
  for (bool floatMean : { false, true })
  {
    float mean[4] = { 0, 0, 0, 0 };
    double sums[4] = { 0, 0, 0, 0 };
    unsigned long long exact = 0; // the samples' sum in units of 2^-24
    Stream stream;
    unsigned long long n = 0;
    int nextLog2 = 10;
    const auto start = std::chrono::steady_clock::now();
    while (nextLog2 <= maxLog2)
    {
      mcvol::Vec4d sum = mcvol::loadSum(sums, uint32_t(n));
      float batchSum = 0.f;
      for (int k = 0; k < batch; ++k)
      {
        const unsigned units = stream.Next();
        exact += units;
        const float x = float(units) * 0x1p-24f;
        mcvol::addSample(sum, mcvol::Vec4f{ x, x, x, x });
        batchSum += x;
      }
      if (floatMean)
      {
        // A float running mean: scaled by previous / n, the batch's float
        // sum added over n.
        const float inv = 1.f / float(n + batch);
        mean[0] = mean[0] * (float(n) * inv) + batchSum * inv;
      }
      else
      {
        mcvol::storeSum(mean, sums, sum, uint32_t(n + batch));
      }
      n += batch;
      if (n >= (1ull << nextLog2))
      {
        const long double want = (long double)(exact) * 0x1p-24L / (long double)(n);
        const double err = double(std::fabs((long double)(mean[0]) - want));
        const float w = float(want);
        const double ulp = std::nextafter(w, 2.f) - w;
        std::printf("precision,%s,%d,%llu,%.9f,%.9f,%.3g,%.2f\n", floatMean ? "float-mean" : "double-sum", batch, n,
          double(mean[0]), double(want), err, err / ulp);
        nextLog2 += 2;
      }
    }
    const double secs = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    std::fprintf(stderr, "batch %d %s: %.2f s (stream and reference included)\n", batch,
      floatMean ? "float-mean" : "double-sum", secs);
  }
  return 0;
}

int Render(unsigned long long spp, int width, int height)
{
  mcvol::DemoVolume volume = mcvol::makeDemo("figure3", { 32, 32, 32 });
  std::vector<mcvol::ChannelSource> src;
  for (int n = 0; n < volume.numChannels(); ++n)
  {
    src.push_back(volume.source(n));
  }
  mcvol::Scene scene;
  scene.setVolume(volume.dims, volume.numChannels(), src.data());
  for (int n = 0; n < volume.numChannels(); ++n)
  {
    const std::array<float, 2> r = volume.range(n);
    scene.setTransferFunction(n, mcvol::sampleTransferFunction(volume.transferFunctions[size_t(n)], r[0], r[1], 256, 1.0));
  }
  scene.update();
  const mcvol::Camera camera = mcvol::orbitCamera(volume.dims, volume.spacing, width, height, 30, 20);
  mcvol::CPURenderer renderer;
  mcvol::Accumulator a, b;
  mcvol::RenderSettings settings;
  settings.samplesPerPixel = 4096;
  std::printf("section,samples,rms_difference,rss_kib,seconds\n");
  const auto start = std::chrono::steady_clock::now();
  int nextLog2 = 12;
  for (unsigned long long n = 0; n < spp; n += unsigned(settings.samplesPerPixel))
  {
    settings.seed = 1;
    renderer.render(scene, camera, settings, nullptr, a);
    settings.seed = 2;
    renderer.render(scene, camera, settings, nullptr, b);
    const unsigned long long done = n + unsigned(settings.samplesPerPixel);
    if (done >= (1ull << nextLog2) || done >= spp)
    {
      const float* pa = a.rgba();
      const float* pb = b.rgba();
      double sq = 0.0;
      for (int i = 0; i < width * height * 4; ++i)
      {
        sq += double(pa[i] - pb[i]) * double(pa[i] - pb[i]);
      }
      const double secs = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
      std::printf("render,%llu,%.4g,%ld,%.1f\n", done, std::sqrt(sq / (width * height * 4)), ResidentKiB(), secs);
      std::fflush(stdout);
      ++nextLog2;
    }
  }
  return 0;
}
} // namespace

int main(int argc, char** argv)
{
  const std::string what = argc > 1 ? argv[1] : "";
  int maxLog2 = 28;
  unsigned long long spp = 1ull << 20;
  int width = 8, height = 8;
  for (int i = 2; i + 1 < argc; i += 2)
  {
    if (!std::strcmp(argv[i], "--max-log2"))
    {
      maxLog2 = std::atoi(argv[i + 1]);
    }
    else if (!std::strcmp(argv[i], "--spp"))
    {
      spp = std::strtoull(argv[i + 1], nullptr, 10);
    }
    else if (!std::strcmp(argv[i], "--size") && std::sscanf(argv[i + 1], "%dx%d", &width, &height) == 2)
    {
    }
    else
    {
      std::fprintf(stderr, "mcvol-soak: unknown option %s\n", argv[i]);
      return 2;
    }
  }
  if (what == "precision")
  {
    return Precision(maxLog2);
  }
  if (what == "render" && width > 0 && height > 0 && spp > 0)
  {
    return Render(spp, width, height);
  }
  std::fprintf(stderr, "usage: mcvol-soak precision [--max-log2 N] | render [--spp N] [--size WxH]\n");
  return what == "--help" ? 0 : 2;
}
