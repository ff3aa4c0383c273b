// SPDX-License-Identifier: BSD-3-Clause

#include "BenchCommon.h"

#include "ArgParser.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <sstream>
#include <stdexcept>

namespace mcvolbench
{
namespace
{
/// The options of mcvol-bench, stored into `o`.
ArgParser makeParser(Options& o)
{
  ArgParser p("mcvol-bench",
    "sections (run in this order): trackers channels macrocell rebuild memory paper sampling effects converge\n"
    "          visibility estimate sequences pyramid pilots blends raymarch");
  p.add("--dataset", 1, "NAME", "demo dataset: cosmology, microscopy, weather, figure3 (default cosmology)",
     [&](const Args& v) { o.dataset = v[0]; })
    .add("--dims", 3, "X Y Z", "volume size in voxels (default 256 256 256)",
      [&](const Args& v)
      {
        for (size_t k = 0; k < 3; ++k)
          o.dims[k] = std::stoi(v[k]);
      })
    .add("--channels", 1, "N", "channels generated (default 0: the dataset's own count)",
      [&](const Args& v) { o.channels = std::stoi(v[0]); })
    .add("--size", 2, "W H", "image size in pixels (default 512 512)",
      [&](const Args& v)
      {
        o.width = std::stoi(v[0]);
        o.height = std::stoi(v[1]);
      })
    .add("--warmup", 1, "N", "untimed frames before the timed ones (default 3)",
      [&](const Args& v) { o.warmup = std::stoi(v[0]); })
    .add("--frames", 1, "N", "timed frames; their median is reported (default 10)",
      [&](const Args& v) { o.frames = std::stoi(v[0]); })
    .add("--macrocell", 1, "M", "macrocell edge in voxels (default 8)",
      [&](const Args& v) { o.macrocell = std::stoi(v[0]); })
    .add("--backend", 1, "cpu|cuda|auto", "where frames render (default cpu)",
      [&](const Args& v)
      {
        o.backend =
          v[0] == "cuda" ? mcvol::Backend::CUDA : (v[0] == "auto" ? mcvol::Backend::Auto : mcvol::Backend::CPU);
      })
    .add("--sections", 1, "A,B,...", "sections to run (default trackers,channels,macrocell,rebuild,memory)",
      [&](const Args& v) { o.sections = splitList(v[0]); })
    .add("--channel-counts", 1, "1,2,4", "channels: the counts swept (default 1,2,4,8,12,16)",
      [&](const Args& v) { o.channelCounts = splitInts(v[0]); })
    .add("--macrocell-sizes", 1, "4,8,16", "macrocell: the sizes swept (default 2,4,8,16,32,64)",
      [&](const Args& v) { o.macrocellSizes = splitInts(v[0]); })
    .add("--csv", 1, "FILE", "also write every row as CSV", [&](const Args& v) { o.csv = v[0]; })
    .add("--label", 1, "TEXT", "name printed with the dataset (e.g. NYX-like)", [&](const Args& v) { o.label = v[0]; })
    .add("--sampling", 1, "texture|global", "CUDA: hardware or software trilinear sampling (default texture)",
      [&](const Args& v)
      {
        o.sampling = v[0];
        if (o.sampling != "texture" && o.sampling != "global")
        {
          throw std::invalid_argument("--sampling takes texture or global");
        }
      })
    .add("--general-kernels", 0, "",
      "CUDA: render plain scenes with the general kernels, not their plain compilation (for comparisons)",
      [&](const Args&) { o.generalKernels = true; })
    .add("--inline-shadows", 0, "",
      "CUDA: trace shadow rays in the camera rays' kernel, not deferred to a kernel of their own (for comparisons)",
      [&](const Args&) { o.inlineShadows = true; })
    .add("--deferred-batch", 1, "N",
      "CUDA: samples per pixel one pair of deferred-shadow launches traces in renders of several (default 4)",
      [&](const Args& v)
      {
        o.deferredBatch = std::stoi(v[0]);
        if (o.deferredBatch < 1 || o.deferredBatch > 8)
        {
          throw std::invalid_argument("--deferred-batch takes 1 to 8");
        }
      })
    .add("--scatter-roulette", 1, "F",
      "lit, expected value: below this scattering weight a camera ray keeps its vertex with probability weight / F (default 0.5)",
      [&](const Args& v)
      {
        o.scatterRoulette = std::stof(v[0]);
        if (!(o.scatterRoulette > 0.f && o.scatterRoulette <= 1.f))
        {
          throw std::invalid_argument("--scatter-roulette takes a number in (0, 1]");
        }
      })
    .add("--cached-shadows", 1, "S",
      "lit scenes: cached shadows at node spacing S voxels (LightingDesc::cacheShadows; 0, the default: tracked); "
      "converge scores them against the tracked shadows' reference",
      [&](const Args& v)
      {
        o.cacheSpacing = std::stof(v[0]);
        if (!(o.cacheSpacing == 0.f || (o.cacheSpacing >= 0.5f && o.cacheSpacing <= 64.f)))
        {
          throw std::invalid_argument("--cached-shadows takes 0 or a spacing in [0.5, 64]");
        }
      })
    .add("--block", 2, "X Y", "CUDA: render-kernel block size (default 8 8)",
      [&](const Args& v)
      {
        o.blockX = std::stoi(v[0]);
        o.blockY = std::stoi(v[1]);
      })
    .add("--psnr", 1, "DB", "converge, sequences: the target PSNR (default 35)",
      [&](const Args& v) { o.psnr = std::stod(v[0]); })
    .add("--reference-spp", 1, "N", "samples per pixel of the converged reference (default 2048)",
      [&](const Args& v) { o.referenceSpp = std::stoi(v[0]); })
    .add("--lighting", 1, kLightingPresets,
      "the scene's lighting (default none): one light with shadows, plus ambient 0.2, plus multiple scattering",
      [&](const Args& v)
      {
        lightingPreset(v[0], 1); // refuses an unknown name here
        o.lighting = v[0];
      })
    .add("--density", 1, "F", "divides every opacity unit distance: F times denser (default 1)",
      [&](const Args& v) { o.density = std::stod(v[0]); })
    .add("--pyramid-levels", 1, "N", "pyramid: levels 1..N timed (default 2; half precision for 1 and 2 only)",
      [&](const Args& v) { o.pyramidLevels = std::max(1, std::stoi(v[0])); })
    .add("--samplers", 1, "independent,sobol", "sequences: the samplers compared (default both)",
      [&](const Args& v)
      {
        o.samplers = splitList(v[0]);
        for (const std::string& n : o.samplers)
        {
          if (n != "independent" && n != "sobol")
          {
            throw std::invalid_argument("--samplers takes independent and/or sobol, not " + n);
          }
        }
      })
    .add("--spp-max", 1, "N", "sequences: the largest sample count (default 256)",
      [&](const Args& v) { o.sppMax = std::stoi(v[0]); })
    .add("--estimators", 1, "collision,expected-value,unbiased-march", "sequences: the estimators (default collision)",
      [&](const Args& v)
      {
        o.estimators = splitList(v[0]);
        for (const std::string& n : o.estimators)
        {
          if (n != "collision" && n != "expected-value" && n != "unbiased-march")
          {
            throw std::invalid_argument(
              "--estimators takes collision, expected-value and/or unbiased-march, not " + n);
          }
        }
      })
    .add("--min-samples-per-voxel", 1, "0.5,1",
      "converge: expected-value rows with these RenderSettings::minSamplesPerVoxel (default none)",
      [&](const Args& v)
      {
        for (const std::string& n : splitList(v[0]))
        {
          o.minSamplesPerVoxel.push_back(std::stof(n));
        }
      })
    .add("--march-samples-per-voxel", 1, "1,2",
      "converge: unbiased-march rows with these RenderSettings::marchSamplesPerVoxel (default 2)",
      [&](const Args& v)
      {
        o.marchSamplesPerVoxel.clear();
        for (const std::string& n : splitList(v[0]))
        {
          o.marchSamplesPerVoxel.push_back(std::stof(n));
        }
      })
    .add("--no-collision", 0, "", "converge: leave out the collision-estimator rows",
      [&](const Args&) { o.skipCollision = true; })
    .add("--pixel-centres", 0, "", "converge: also every configuration at pixel centres (no pixel jitter)",
      [&](const Args&) { o.pixelCentres = true; })
    .add("--centres-only", 0, "", "converge: the pixel-centre rows alone",
      [&](const Args&)
      {
        o.pixelCentres = true;
        o.centresOnly = true;
      })
    .add("--steady-frames", 1, "N", "converge: back-to-back frames timed per configuration (default 200)",
      [&](const Args& v) { o.steadyFrames = std::stoi(v[0]); })
    .add("--only-automatic", 0, "", "converge: only the automatic row (with the expected-value row)",
      [&](const Args&) { o.onlyAutomatic = true; })
    .add("--choice-all", 0, "", "converge: the automatic choice tries (and reports) every rate",
      [&](const Args&) { o.choiceAll = true; })
    .add("--cost-model", 1, "RAY,DDA,TENTATIVE,SAMPLE",
      "converge: the automatic choice's 4 cost weights (default: the backend's defaultCostModel())",
      [&](const Args& v)
      {
        o.costModel.clear();
        for (const std::string& n : splitList(v[0]))
        {
          o.costModel.push_back(std::stod(n));
        }
        if (o.costModel.size() != 4)
        {
          throw std::invalid_argument("--cost-model takes 4 weights: ray,dda,tentative,sample");
        }
      });
  return p;
}
} // namespace

void usage()
{
  Options o;
  makeParser(o).printHelp();
}

Options parse(int argc, char** argv)
{
  Options o;
  makeParser(o).parse(argc, argv);
  return o;
}

bool wants(const Options& o, const std::string& s)
{
  return contains(o.sections, s);
}

void Setup::load(const Options& o, int channels, int macrocell, bool hostAcceleration)
{
  const std::string key = o.dataset + " " + std::to_string(o.dims[0]) + " " + std::to_string(o.dims[1]) + " " +
    std::to_string(o.dims[2]) + " " + std::to_string(channels);
  if (key != this->loadedKey)
  {
    this->volume = mcvol::DemoVolume(); // the old one goes first (host memory)
    this->volume = mcvol::makeDemo(o.dataset, o.dims, channels);
    this->loadedKey = key;
  }
  this->configure(o, this->volume.numChannels(), macrocell, hostAcceleration);
}

void Setup::configure(const Options& o, int channels, int macrocell, bool hostAcceleration)
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
    this->scene.setTransferFunction(
      n, demoTransferFunction(this->volume, n, this->ranges[size_t(n)], o.tableSize, o.density));
  }
  this->scene.setLighting(benchLighting(o, channels));
  this->scene.update();
}

mcvol::LightingDesc benchLighting(const Options& o, int channels, bool cached)
{
  mcvol::LightingDesc d = lightingPreset(o.lighting, channels, o.scatterRoulette);
  if (cached && o.cacheSpacing > 0.f)
  {
    d.cacheShadows = true;
    d.cacheSpacing = o.cacheSpacing;
  }
  return d;
}

mcvol::Camera benchCamera(const Options& o, const mcvol::Scene& scene)
{
  return mcvol::orbitCamera(scene.dims(), std::array<double, 3>{ 1, 1, 1 }.data(), o.width, o.height, 30, 20);
}

FrameStats timeFrames(
  const Options& o, mcvol::Renderer& r, const mcvol::Scene& scene, mcvol::Tracker tracker, mcvol::Estimator estimator)
{
  const mcvol::Camera cam = benchCamera(o, scene);
  mcvol::Accumulator acc;
  mcvol::RenderSettings st;
  st.samplesPerPixel = 1;
  st.tracker = tracker;
  st.estimator = estimator;
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

std::vector<float> renderReference(const Options& o, mcvol::Renderer& r, const mcvol::Scene& scene,
  const mcvol::Camera& cam, mcvol::Accumulator& ref, mcvol::RenderSettings rs)
{
  rs.seed = 12345;
  rs.readBack = false;
  for (int k = 0; k < o.referenceSpp; k += rs.samplesPerPixel)
  {
    rs.samplesPerPixel = std::min(64, o.referenceSpp - k);
    r.render(scene, cam, rs, nullptr, ref);
  }
  r.readBack(ref);
  return std::vector<float>(ref.rgba(), ref.rgba() + size_t(4) * ref.width() * ref.height());
}

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
  if (o.lighting != "none")
  {
    ss << ", lighting " << o.lighting;
  }
  return ss.str();
}

void Bench::row(const std::string& section, const std::string& ds, int ch, int mc, const std::string& tr, double value,
  const std::string& unit, const std::string& extra)
{
  std::ostringstream ss;
  ss << section << "," << ds << "," << ch << "," << mc << "," << tr << "," << r.name() << "," << value << "," << unit
     << "," << extra;
  csv.push_back(ss.str());
}

void Bench::writeCsv() const
{
  if (!o.csv.empty())
  {
    writeLines(o.csv, csv);
  }
}
} // namespace mcvolbench
