// SPDX-License-Identifier: BSD-3-Clause
//
// mcvol-bench: VTK-free benchmark of the core and its backends. It builds on
// any machine with a C++17 compiler and OpenMP (the GPU machine included) and
// prints Markdown tables; --csv also writes the rows as CSV.
//
// Sections (select with --sections a,b,...):
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
//              unlit image and 1-spp noise (issue 6)
//
// On the CUDA backend frames are timed as render() + finish() with the image
// left on the device (RenderSettings::readBack = false); a separate column
// gives the time with the image copied back each frame.

#include "mcvol/CameraMath.h"
#include "mcvol/DemoData.h"
#include "mcvol/Renderer.h"
#ifdef MCVOL_WITH_CUDA
#include "mcvol/CUDARenderer.h"
#endif

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <sstream>
#include <stdexcept>
#include <string>
#include <vector>

#ifdef _OPENMP
#include <omp.h>
#endif

namespace
{
struct Options
{
  std::string dataset = "cosmology";
  std::array<int, 3> dims = { 256, 256, 256 };
  int channels = 0;
  int width = 512;
  int height = 512;
  int warmup = 3;
  int frames = 10;
  int macrocell = 8;
  int tableSize = 1024;
  mcvol::Backend backend = mcvol::Backend::CPU;
  std::vector<std::string> sections = { "trackers", "channels", "macrocell", "rebuild", "memory" };
  std::vector<int> channelCounts = { 1, 2, 4, 8, 12, 16 };
  std::vector<int> macrocellSizes = { 2, 4, 8, 16, 32, 64 };
  std::string csv;
  std::string label; ///< e.g. "NYX-like", printed with the dataset
  std::string sampling = "texture";
  int blockX = 8;
  int blockY = 8;
  double psnr = 35.0;
  int referenceSpp = 2048;
  int maxConvergeFrames = 4096;
  double density = 1.0; ///< divides every opacity unit distance (denser volumes)
};

using Clock = std::chrono::steady_clock;

double seconds(Clock::time_point t0)
{
  return std::chrono::duration<double>(Clock::now() - t0).count();
}

double median(std::vector<double> v)
{
  std::sort(v.begin(), v.end());
  const size_t n = v.size();
  return n % 2 ? v[n / 2] : 0.5 * (v[n / 2 - 1] + v[n / 2]);
}

std::vector<std::string> split(const std::string& s, char sep)
{
  std::vector<std::string> out;
  std::stringstream ss(s);
  std::string item;
  while (std::getline(ss, item, sep))
  {
    if (!item.empty())
    {
      out.push_back(item);
    }
  }
  return out;
}

std::vector<int> splitInts(const std::string& s)
{
  std::vector<int> out;
  for (const auto& t : split(s, ','))
  {
    out.push_back(std::stoi(t));
  }
  return out;
}

void usage()
{
  std::puts("usage: mcvol-bench [--dataset NAME] [--dims X Y Z] [--channels N] [--size W H]\n"
            "                   [--warmup N] [--frames N] [--macrocell M] [--backend cpu|cuda|auto]\n"
            "                   [--sections trackers,channels,macrocell,rebuild,memory]\n"
            "                   [--channel-counts 1,2,4] [--macrocell-sizes 4,8,16] [--csv FILE]\n"
            "                   [--label TEXT] [--sampling texture|global] [--block X Y]\n"
            "                   [--psnr DB] [--reference-spp N] [--density F]\n"
            "sections: trackers channels macrocell rebuild memory paper converge sampling effects");
}

Options parse(int argc, char** argv)
{
  Options o;
  for (int i = 1; i < argc; ++i)
  {
    const std::string a = argv[i];
    auto need = [&](int n)
    {
      if (i + n >= argc)
      {
        throw std::invalid_argument(a + " needs " + std::to_string(n) + " value(s)");
      }
    };
    if (a == "--dataset")
    {
      need(1);
      o.dataset = argv[++i];
    }
    else if (a == "--dims")
    {
      need(3);
      for (int k = 0; k < 3; ++k)
        o.dims[size_t(k)] = std::stoi(argv[++i]);
    }
    else if (a == "--channels")
    {
      need(1);
      o.channels = std::stoi(argv[++i]);
    }
    else if (a == "--size")
    {
      need(2);
      o.width = std::stoi(argv[++i]);
      o.height = std::stoi(argv[++i]);
    }
    else if (a == "--warmup")
    {
      need(1);
      o.warmup = std::stoi(argv[++i]);
    }
    else if (a == "--frames")
    {
      need(1);
      o.frames = std::stoi(argv[++i]);
    }
    else if (a == "--macrocell")
    {
      need(1);
      o.macrocell = std::stoi(argv[++i]);
    }
    else if (a == "--backend")
    {
      need(1);
      const std::string b = argv[++i];
      o.backend = b == "cuda" ? mcvol::Backend::CUDA : (b == "auto" ? mcvol::Backend::Auto : mcvol::Backend::CPU);
    }
    else if (a == "--label")
    {
      need(1);
      o.label = argv[++i];
    }
    else if (a == "--sampling")
    {
      need(1);
      o.sampling = argv[++i];
      if (o.sampling != "texture" && o.sampling != "global")
      {
        throw std::invalid_argument("--sampling takes texture or global");
      }
    }
    else if (a == "--block")
    {
      need(2);
      o.blockX = std::stoi(argv[++i]);
      o.blockY = std::stoi(argv[++i]);
    }
    else if (a == "--density")
    {
      need(1);
      o.density = std::stod(argv[++i]);
    }
    else if (a == "--psnr")
    {
      need(1);
      o.psnr = std::stod(argv[++i]);
    }
    else if (a == "--reference-spp")
    {
      need(1);
      o.referenceSpp = std::stoi(argv[++i]);
    }
    else if (a == "--sections")
    {
      need(1);
      o.sections = split(argv[++i], ',');
    }
    else if (a == "--channel-counts")
    {
      need(1);
      o.channelCounts = splitInts(argv[++i]);
    }
    else if (a == "--macrocell-sizes")
    {
      need(1);
      o.macrocellSizes = splitInts(argv[++i]);
    }
    else if (a == "--csv")
    {
      need(1);
      o.csv = argv[++i];
    }
    else if (a == "--help" || a == "-h")
    {
      usage();
      std::exit(0);
    }
    else
    {
      throw std::invalid_argument("unknown option " + a);
    }
  }
  return o;
}

/// A loaded dataset with its scene.
struct Setup
{
  mcvol::DemoVolume volume;
  std::vector<std::array<float, 2>> ranges;
  mcvol::Scene scene;

  void load(const Options& o, int channels, int macrocell, bool hostAcceleration = true)
  {
    this->volume = mcvol::makeDemo(o.dataset, o.dims, channels);
    this->configure(o, this->volume.numChannels(), macrocell, hostAcceleration);
  }

  /// A new scene over the first `channels` channels of the loaded volume (the
  /// channel sweep generates the largest count once).
  void configure(const Options& o, int channels, int macrocell, bool hostAcceleration)
  {
    this->ranges.clear();
    std::vector<mcvol::ChannelSource> src;
    for (int n = 0; n < channels; ++n)
    {
      src.push_back(this->volume.source(n));
      this->ranges.push_back(this->volume.range(n));
    }
    this->scene = mcvol::Scene();
    this->scene.setHostAcceleration(hostAcceleration);
    this->scene.setVolume(this->volume.dims, channels, src.data());
    this->scene.setMacrocellSize(macrocell);
    for (int n = 0; n < channels; ++n)
    {
      this->scene.setTransferFunction(n,
        mcvol::sampleTransferFunction(this->volume.transferFunctions[size_t(n)], this->ranges[size_t(n)][0],
          this->ranges[size_t(n)][1], o.tableSize, this->volume.spacing[0] / o.density));
    }
    this->scene.update();
  }
};

struct FrameStats
{
  double medianMs = 0;
  double minMs = 0;
  double meanMs = 0;
  double readBackMs = 0; ///< median frame time with the image copied back (device backends)
  double tentativePerRay = 0;
  double ddaPerRay = 0;
  double scatterPerRay = 0;
  double shadowPerRay = 0;
  double gradientPerRay = 0;
  double alpha = 0;
};

mcvol::Camera benchCamera(const Options& o, const mcvol::Scene& scene)
{
  return mcvol::orbitCamera(scene.dims(), std::array<double, 3>{ 1, 1, 1 }.data(), o.width, o.height, 30, 20);
}

/// Times frames of 1 spp. Device backends: render() + finish() per frame with
/// the image left on the device; then a few frames with it copied back.
FrameStats timeFrames(const Options& o, mcvol::Renderer& r, const mcvol::Scene& scene, mcvol::Tracker tracker)
{
  const mcvol::Camera cam = benchCamera(o, scene);
  mcvol::Accumulator acc;
  mcvol::RenderSettings st;
  st.samplesPerPixel = 1;
  st.tracker = tracker;
  st.readBack = false;
  for (int i = 0; i < o.warmup; ++i)
  {
    r.render(scene, cam, st, nullptr, acc);
  }
  r.finish();
  acc.reset();
  std::vector<double> ms;
  for (int i = 0; i < o.frames; ++i)
  {
    const auto t0 = Clock::now();
    r.render(scene, cam, st, nullptr, acc);
    r.finish();
    ms.push_back(1e3 * seconds(t0));
  }
  FrameStats s;
  s.medianMs = median(ms);
  s.minMs = *std::min_element(ms.begin(), ms.end());
  double sum = 0;
  for (double x : ms)
  {
    sum += x;
  }
  s.meanMs = sum / double(ms.size());
  // Copy-back cost, and the counters (one counted frame: counting adds atomics).
  std::vector<double> rb;
  st.readBack = true;
  for (int i = 0; i < std::min(o.frames, 20); ++i)
  {
    const auto t0 = Clock::now();
    r.render(scene, cam, st, nullptr, acc);
    rb.push_back(1e3 * seconds(t0));
  }
  s.readBackMs = median(rb);
  mcvol::RenderCounters c;
  r.render(scene, cam, st, nullptr, acc, &c);
  s.tentativePerRay = double(c.tentativeCollisions) / double(c.rays);
  s.ddaPerRay = double(c.ddaSteps) / double(c.rays);
  s.scatterPerRay = double(c.scatteringEvents) / double(c.rays);
  s.shadowPerRay = double(c.shadowRays) / double(c.rays);
  s.gradientPerRay = double(c.gradientEvaluations) / double(c.rays);
  double a = 0;
  for (int p = 0; p < acc.width() * acc.height(); ++p)
  {
    a += acc.rgba()[4 * p + 3];
  }
  s.alpha = a / double(acc.width() * acc.height());
  return s;
}

/// PSNR (peak 1) of the premultiplied RGB (the image over black) against a reference.
double psnrOf(const mcvol::Accumulator& a, const std::vector<float>& ref)
{
  double se = 0;
  const size_t P = size_t(a.width()) * size_t(a.height());
  for (size_t p = 0; p < P; ++p)
  {
    for (int c = 0; c < 3; ++c)
    {
      const double d = double(a.rgba()[4 * p + c]) - double(ref[4 * p + c]);
      se += d * d;
    }
  }
  const double mse = se / double(3 * P);
  return mse > 0 ? -10.0 * std::log10(mse) : 200.0;
}

#ifdef MCVOL_WITH_CUDA
mcvol::CUDARenderer* asCuda(mcvol::Renderer& r)
{
  return dynamic_cast<mcvol::CUDARenderer*>(&r);
}
#endif

std::string describe(const Options& o, const Setup& s)
{
  std::ostringstream ss;
  if (!o.label.empty())
  {
    ss << o.label << " = ";
  }
  if (o.density != 1.0)
  {
    ss << "density x" << o.density << " ";
  }
  ss << o.dataset << " " << s.volume.dims[0] << "x" << s.volume.dims[1] << "x" << s.volume.dims[2] << " "
     << mcvol::toString(s.volume.type);
  return ss.str();
}

bool wants(const Options& o, const std::string& s)
{
  return std::find(o.sections.begin(), o.sections.end(), s) != o.sections.end();
}
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
    device = g->deviceDescription() + "; sampling " + o.sampling + "; block " + std::to_string(o.blockX) + "x" +
      std::to_string(o.blockY);
  }
#endif
  const bool hostAccel = !r->buildsAccelerationOnDevice();
  std::vector<std::string> csv = { "section,dataset,channels,macrocell,tracker,backend,value,unit,extra" };
  auto row = [&](const std::string& section, const std::string& ds, int ch, int mc, const std::string& tr, double value,
               const std::string& unit, const std::string& extra)
  {
    std::ostringstream ss;
    ss << section << "," << ds << "," << ch << "," << mc << "," << tr << "," << r->name() << "," << value << "," << unit
       << "," << extra;
    csv.push_back(ss.str());
  };
  int threads = 1;
#ifdef _OPENMP
  threads = omp_get_max_threads();
#endif
  std::printf("# mcvol-bench\n\nbackend: %s (%s); device: %s; host threads: %d; image %dx%d; 1 spp per frame; %d "
              "warm-up + %d timed frames (median)\n\n",
    r->name(), why.c_str(), device.c_str(), threads, o.width, o.height, o.warmup, o.frames);

  Setup s;
  if (wants(o, "trackers"))
  {
    s.load(o, o.channels, o.macrocell, hostAccel);
    const std::string ds = describe(o, s);
    std::printf(
      "## Frame time at 1 spp: %s, %d channels, macrocell %d\n\n", ds.c_str(), s.volume.numChannels(), o.macrocell);
    std::printf("| tracker | median ms | min ms | tentative collisions/ray | DDA steps/ray | mean alpha "
                "|\n|---|---|---|---|---|---|\n");
    for (auto t : { mcvol::Tracker::OneDDA, mcvol::Tracker::NDDA })
    {
      const FrameStats f = timeFrames(o, *r, s.scene, t);
      std::printf("| %s | %.2f | %.2f | %.2f | %.2f | %.3f |\n", mcvol::toString(t), f.medianMs, f.minMs,
        f.tentativePerRay, f.ddaPerRay, f.alpha);
      row("trackers", ds, s.volume.numChannels(), o.macrocell, mcvol::toString(t), f.medianMs, "ms", "");
    }
    std::printf("\n");
    std::fflush(stdout);
  }
  if (wants(o, "channels"))
  {
    std::printf("## Frame time against channel count (%s, macrocell %d)\n\n", o.dataset.c_str(), o.macrocell);
    std::printf("| channels | 1-DDA ms | N-DDA ms | 1-DDA / 1 channel | mean alpha |\n|---|---|---|---|---|\n");
    double base = 0;
    s.volume = mcvol::makeDemo(o.dataset, o.dims, *std::max_element(o.channelCounts.begin(), o.channelCounts.end()));
    for (int n : o.channelCounts)
    {
      s.configure(o, n, o.macrocell, hostAccel);
      const FrameStats a = timeFrames(o, *r, s.scene, mcvol::Tracker::OneDDA);
      const FrameStats b = timeFrames(o, *r, s.scene, mcvol::Tracker::NDDA);
      if (base == 0)
      {
        base = a.medianMs;
      }
      std::printf("| %d | %.2f | %.2f | %.2fx | %.3f |\n", n, a.medianMs, b.medianMs, a.medianMs / base, a.alpha);
      row("channels", describe(o, s), n, o.macrocell, "1-DDA", a.medianMs, "ms", "");
      row("channels", describe(o, s), n, o.macrocell, "N-DDA", b.medianMs, "ms", "");
      std::fflush(stdout);
    }
    std::printf("\n");
  }
  if (wants(o, "macrocell"))
  {
    s.load(o, o.channels, o.macrocell, hostAccel);
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
      const FrameStats a = timeFrames(o, *r, s.scene, mcvol::Tracker::OneDDA);
      const FrameStats b = timeFrames(o, *r, s.scene, mcvol::Tracker::NDDA);
      mcvol::MemoryStats mem = s.scene.memory();
#ifdef MCVOL_WITH_CUDA
      if (mcvol::CUDARenderer* g = asCuda(*r))
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
      row("macrocell", describe(o, s), s.volume.numChannels(), m, "1-DDA", a.medianMs, "ms", "");
      row("macrocell", describe(o, s), s.volume.numChannels(), m, "N-DDA", b.medianMs, "ms", "");
      row("macrocell", describe(o, s), s.volume.numChannels(), m, "-", 100 * frac, "percent_of_data", "memory");
      std::fflush(stdout);
    }
    std::printf("\n");
  }
  if (wants(o, "rebuild"))
  {
    s.load(o, o.channels, o.macrocell, hostAccel);
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
      if (mcvol::CUDARenderer* g = asCuda(*r))
      {
        // The GPU rebuilds at the next render: render one small frame.
        const uint64_t before = g->updateCounters().majorantChannelBuilds;
        mcvol::Camera cam = benchCamera(o, s.scene);
        cam.width = cam.height = 8;
        mcvol::Accumulator acc;
        r->render(s.scene, cam, mcvol::RenderSettings(), nullptr, acc);
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
    row("rebuild", describe(o, s), s.volume.numChannels(), o.macrocell, "-", median(ms), "ms", "one channel");
    std::fflush(stdout);
  }
  if (wants(o, "memory"))
  {
    s.load(o, o.channels, o.macrocell, hostAccel);
    mcvol::MemoryStats m = s.scene.memory();
    const double MiB = 1024.0 * 1024.0;
#ifdef MCVOL_WITH_CUDA
    if (mcvol::CUDARenderer* g = asCuda(*r))
    {
      mcvol::Accumulator acc;
      r->render(s.scene, benchCamera(o, s.scene), mcvol::RenderSettings(), nullptr, acc);
      const mcvol::CudaMemoryStats dm = g->memory();
      m.dataBytes = dm.dataBytes;
      m.macrocellBytes = dm.macrocellBytes;
      m.majorantBytes = dm.majorantBytes;
      std::printf("GPU memory: data %.2f MiB, texture copies %.2f MiB (texture sampling), image buffers %.2f MiB\n\n",
        dm.dataBytes / MiB, dm.textureBytes / MiB, dm.imageBytes / MiB);
    }
#endif
    std::printf(
      "## Memory (%s, %d channels, macrocell %d; paper Table 1)\n\n| data MiB | macrocells MiB | majorants MiB "
      "| total MiB | (macrocells+majorants)/data |\n|---|---|---|---|---|\n| %.2f | %.2f | %.2f | %.2f | %.2f%% |\n\n",
      describe(o, s).c_str(), s.volume.numChannels(), o.macrocell, m.dataBytes / MiB, m.macrocellBytes / MiB,
      m.majorantBytes / MiB, (m.dataBytes + m.macrocellBytes + m.majorantBytes) / MiB,
      100.0 * double(m.macrocellBytes + m.majorantBytes) / double(m.dataBytes));
    row("memory", describe(o, s), s.volume.numChannels(), o.macrocell, "-",
      100.0 * double(m.macrocellBytes + m.majorantBytes) / double(m.dataBytes), "percent_of_data", "");
  }
  if (wants(o, "paper"))
  {
    s.load(o, o.channels, o.macrocell, hostAccel);
    const std::string ds = describe(o, s);
    std::printf("## Paper protocol: %s, %d channels, macrocell %d, %dx%d, 1 spp, %d warm-up + %d timed frames\n\n",
      ds.c_str(), s.volume.numChannels(), o.macrocell, o.width, o.height, o.warmup, o.frames);
    std::printf("| tracker | FPS (1000 / mean ms) | mean ms | median ms | min ms | ms with copy-back | tentative/ray | "
                "DDA steps/ray | mean alpha |\n|---|---|---|---|---|---|---|---|---|\n");
    for (auto t : { mcvol::Tracker::OneDDA, mcvol::Tracker::NDDA })
    {
      const FrameStats f = timeFrames(o, *r, s.scene, t);
      std::printf("| %s | %.1f | %.3f | %.3f | %.3f | %.3f | %.2f | %.2f | %.3f |\n", mcvol::toString(t),
        1000.0 / f.meanMs, f.meanMs, f.medianMs, f.minMs, f.readBackMs, f.tentativePerRay, f.ddaPerRay, f.alpha);
      row("paper", ds, s.volume.numChannels(), o.macrocell, mcvol::toString(t), 1000.0 / f.meanMs, "fps", "");
      row("paper", ds, s.volume.numChannels(), o.macrocell, mcvol::toString(t), f.meanMs, "ms", "mean");
      row("paper", ds, s.volume.numChannels(), o.macrocell, mcvol::toString(t), f.readBackMs, "ms", "with copy-back");
      std::fflush(stdout);
    }
    std::printf("\n");
  }
  if (wants(o, "sampling"))
  {
#ifdef MCVOL_WITH_CUDA
    if (mcvol::CUDARenderer* g = asCuda(*r))
    {
      s.load(o, o.channels, o.macrocell, hostAccel);
      const std::string ds = describe(o, s);
      std::printf("## Texture against global-memory sampling: %s, macrocell %d\n\n| sampling | 1-DDA ms | N-DDA ms "
                  "|\n|---|---|---|\n",
        ds.c_str(), o.macrocell);
      const mcvol::CudaSampling keep = g->sampling();
      for (auto smp : { mcvol::CudaSampling::Texture, mcvol::CudaSampling::Global })
      {
        g->setSampling(smp);
        const FrameStats a = timeFrames(o, *r, s.scene, mcvol::Tracker::OneDDA);
        const FrameStats b = timeFrames(o, *r, s.scene, mcvol::Tracker::NDDA);
        const char* name = smp == mcvol::CudaSampling::Texture ? "texture" : "global";
        std::printf("| %s | %.3f | %.3f |\n", name, a.meanMs, b.meanMs);
        row("sampling", ds, s.volume.numChannels(), o.macrocell, "1-DDA", a.meanMs, "ms", name);
        row("sampling", ds, s.volume.numChannels(), o.macrocell, "N-DDA", b.meanMs, "ms", name);
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
  if (wants(o, "effects"))
  {
    // Issue 6: what each lighting effect costs and what it changes. The
    // emission-absorption row runs the unlit kernel; the others the lit one.
    s.load(o, o.channels, o.macrocell, hostAccel);
    const std::string ds = describe(o, s);
    const int nch = s.volume.numChannels();
    struct Effect
    {
      std::string name;
      mcvol::LightingDesc desc;
    };
    auto base = [&]()
    {
      mcvol::LightingDesc d;
      mcvol::LightDesc sun;
      sun.vector[0] = 1;
      sun.vector[1] = 2;
      sun.vector[2] = 1.5;
      sun.intensity = 4.0;
      d.lights.push_back(sun);
      d.albedo.assign(size_t(nch), 0.8f);
      d.anisotropy.assign(size_t(nch), 0.3f);
      return d;
    };
    std::vector<Effect> effects;
    effects.push_back({ "emission-absorption (no light)", mcvol::LightingDesc() });
    {
      Effect e{ "1 light, no shadows", base() };
      e.desc.shadows = false;
      effects.push_back(e);
    }
    effects.push_back({ "1 light, ratio-tracking shadows", base() });
    {
      Effect e{ "1 light, delta-tracking shadows", base() };
      e.desc.deltaShadows = true;
      effects.push_back(e);
    }
    {
      Effect e{ "1 light, ratio shadows, gradient shading", base() };
      e.desc.gradientShading = true;
      effects.push_back(e);
    }
    {
      Effect e{ "1 light, ratio shadows, ambient 0.3", base() };
      e.desc.ambient[0] = e.desc.ambient[1] = e.desc.ambient[2] = 0.3;
      effects.push_back(e);
    }
    {
      Effect e{ "1 light, ratio shadows, ambient 0.3, multiple scattering (depth 8)", base() };
      e.desc.ambient[0] = e.desc.ambient[1] = e.desc.ambient[2] = 0.3;
      e.desc.maxDepth = 8;
      effects.push_back(e);
    }
    const mcvol::Camera cam = benchCamera(o, s.scene);
    auto converged = [&](uint32_t seed)
    {
      mcvol::Accumulator acc;
      mcvol::RenderSettings rs;
      rs.seed = seed;
      rs.samplesPerPixel = 16;
      rs.readBack = false;
      while (int(acc.samples()) < o.referenceSpp)
      {
        r->render(s.scene, cam, rs, nullptr, acc);
      }
      r->readBack(acc);
      return std::vector<float>(acc.rgba(), acc.rgba() + size_t(4) * acc.width() * acc.height());
    };
    auto rmse = [](const std::vector<float>& a, const float* b)
    {
      double se = 0;
      for (size_t i = 0; i < a.size(); ++i)
      {
        if (i % 4 != 3)
        {
          se += (double(a[i]) - b[i]) * (double(a[i]) - b[i]);
        }
      }
      return std::sqrt(se / double(a.size() / 4 * 3));
    };
    std::printf("## Lighting effects: cost and effect (%s, macrocell %d, %dx%d)\n\n"
                "Times: 1 spp per frame, median. Image change: RMSE of the %d-spp image against the unlit %d-spp "
                "image; noise: RMSE of one 1-spp frame against its own %d-spp image (premultiplied RGB).\n\n"
                "| effect | 1-DDA ms | x unlit | scattering events/ray | shadow rays/ray | gradients/ray | image change "
                "| 1-spp noise |\n|---|---|---|---|---|---|---|---|\n",
      ds.c_str(), o.macrocell, o.width, o.height, o.referenceSpp, o.referenceSpp, o.referenceSpp);
    std::vector<float> unlit;
    double unlitMs = 0;
    for (const Effect& e : effects)
    {
      s.scene.setLighting(e.desc);
      const FrameStats f = timeFrames(o, *r, s.scene, mcvol::Tracker::OneDDA);
      const std::vector<float> conv = converged(4242);
      if (unlit.empty())
      {
        unlit = conv;
        unlitMs = f.medianMs;
      }
      mcvol::Accumulator one;
      mcvol::RenderSettings rs;
      rs.seed = 99;
      r->render(s.scene, cam, rs, nullptr, one);
      const double change = rmse(conv, unlit.data());
      const double noise = rmse(conv, one.rgba());
      std::printf("| %s | %.3f | %.2fx | %.3f | %.3f | %.3f | %.4f | %.4f |\n", e.name.c_str(), f.medianMs,
        f.medianMs / unlitMs, f.scatterPerRay, f.shadowPerRay, f.gradientPerRay, change, noise);
      row("effects", ds, nch, o.macrocell, e.name, f.medianMs, "ms", "");
      row("effects", ds, nch, o.macrocell, e.name, change, "rmse_vs_unlit", "");
      row("effects", ds, nch, o.macrocell, e.name, noise, "rmse_1spp_vs_converged", "");
      std::fflush(stdout);
    }
    s.scene.setLighting(mcvol::LightingDesc());
    std::printf("\n");
  }
  if (wants(o, "converge"))
  {
    s.load(o, o.channels, o.macrocell, hostAccel);
    const std::string ds = describe(o, s);
    const mcvol::Camera cam = benchCamera(o, s.scene);
    // Converged reference: many samples, another seed, in batches.
    mcvol::Accumulator ref;
    mcvol::RenderSettings rs;
    rs.seed = 12345;
    rs.samplesPerPixel = std::min(64, o.referenceSpp);
    rs.readBack = false;
    for (int k = 0; k < o.referenceSpp; k += rs.samplesPerPixel)
    {
      r->render(s.scene, cam, rs, nullptr, ref);
    }
    r->readBack(ref);
    const std::vector<float> refImg(ref.rgba(), ref.rgba() + size_t(4) * ref.width() * ref.height());
    std::printf("## Time to converge: %s, %dx%d, 1 spp per frame, target PSNR %.1f dB (peak 1, RGB over black) "
                "against %u spp\n\n| tracker | frames | ms (rendering only) | PSNR reached |\n|---|---|---|---|\n",
      ds.c_str(), o.width, o.height, o.psnr, ref.samples());
    for (auto t : { mcvol::Tracker::OneDDA, mcvol::Tracker::NDDA })
    {
      mcvol::Accumulator acc;
      mcvol::RenderSettings st;
      st.tracker = t;
      st.seed = 7;
      st.readBack = false;
      // Warm-up on a throw-away accumulator, then timed frames; the PSNR is
      // checked between frames (not timed).
      {
        mcvol::Accumulator w;
        for (int i = 0; i < 5; ++i)
        {
          r->render(s.scene, cam, st, nullptr, w);
        }
        r->finish();
      }
      double ms = 0;
      double q = 0;
      int frames = 0;
      while (frames < o.maxConvergeFrames)
      {
        const auto t0 = Clock::now();
        r->render(s.scene, cam, st, nullptr, acc);
        r->finish();
        ms += 1e3 * seconds(t0);
        ++frames;
        r->readBack(acc);
        q = psnrOf(acc, refImg);
        if (q >= o.psnr)
        {
          break;
        }
      }
      std::printf("| %s | %d | %.2f | %.2f |\n", mcvol::toString(t), frames, ms, q);
      row("converge", ds, s.volume.numChannels(), o.macrocell, mcvol::toString(t), ms, "ms",
        "frames=" + std::to_string(frames) + " psnr=" + std::to_string(q));
      std::fflush(stdout);
    }
    std::printf("\n");
  }
  if (!o.csv.empty())
  {
    std::ofstream f(o.csv);
    for (const auto& l : csv)
    {
      f << l << "\n";
    }
  }
  return 0;
}
