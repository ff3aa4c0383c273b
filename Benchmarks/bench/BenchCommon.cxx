// SPDX-License-Identifier: BSD-3-Clause

#include "BenchCommon.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <sstream>
#include <stdexcept>

namespace mcvolbench
{
namespace
{
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
} // namespace

void usage()
{
  std::puts(
    "usage: mcvol-bench [--dataset NAME] [--dims X Y Z] [--channels N] [--size W H]\n"
    "                   [--warmup N] [--frames N] [--macrocell M] [--backend cpu|cuda|auto]\n"
    "                   [--sections trackers,channels,macrocell,rebuild,memory]\n"
    "                   [--channel-counts 1,2,4] [--macrocell-sizes 4,8,16] [--csv FILE]\n"
    "                   [--label TEXT] [--sampling texture|global] [--block X Y]\n"
    "                   [--psnr DB] [--reference-spp N] [--density F] [--pyramid-levels N]\n"
    "                   [--samplers independent,sobol] [--spp-max N]\n"
    "                   [--estimators collision,expected-value] [--min-samples-per-voxel 0.5,1]\n"
    "                   [--march-samples-per-voxel 1,2] [--no-collision]\n"
    "                   [--pixel-centres] [--centres-only] [--steady-frames N] [--only-automatic] [--choice-all]\n"
    "                   [--cost-model RAY,DDA,TENTATIVE,SAMPLE]\n"
    "sections: trackers channels macrocell rebuild memory paper converge sampling effects visibility estimate\n"
    "          sequences pyramid pilots");
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
    else if (a == "--estimators")
    {
      need(1);
      o.estimators = split(argv[++i], ',');
      for (const std::string& n : o.estimators)
      {
        if (n != "collision" && n != "expected-value" && n != "unbiased-march")
        {
          throw std::invalid_argument("--estimators takes collision, expected-value and/or unbiased-march, not " + n);
        }
      }
    }
    else if (a == "--samplers")
    {
      need(1);
      o.samplers = split(argv[++i], ',');
      for (const std::string& n : o.samplers)
      {
        if (n != "independent" && n != "sobol")
        {
          throw std::invalid_argument("--samplers takes independent and/or sobol, not " + n);
        }
      }
    }
    else if (a == "--pixel-centres")
    {
      o.pixelCentres = true;
    }
    else if (a == "--centres-only")
    {
      o.pixelCentres = true;
      o.centresOnly = true;
    }
    else if (a == "--min-samples-per-voxel")
    {
      need(1);
      for (const std::string& n : split(argv[++i], ','))
      {
        o.minSamplesPerVoxel.push_back(std::stof(n));
      }
    }
    else if (a == "--march-samples-per-voxel")
    {
      need(1);
      o.marchSamplesPerVoxel.clear();
      for (const std::string& n : split(argv[++i], ','))
      {
        o.marchSamplesPerVoxel.push_back(std::stof(n));
      }
    }
    else if (a == "--no-collision")
    {
      o.skipCollision = true;
    }
    else if (a == "--only-automatic")
    {
      o.onlyAutomatic = true;
    }
    else if (a == "--choice-all")
    {
      o.choiceAll = true;
    }
    else if (a == "--steady-frames")
    {
      need(1);
      o.steadyFrames = std::stoi(argv[++i]);
    }
    else if (a == "--cost-model")
    {
      need(1);
      o.costModel.clear();
      for (const std::string& n : split(argv[++i], ','))
      {
        o.costModel.push_back(std::stod(n));
      }
      if (o.costModel.size() != 4)
      {
        throw std::invalid_argument("--cost-model takes 4 weights: ray,dda,tentative,sample");
      }
    }
    else if (a == "--spp-max")
    {
      need(1);
      o.sppMax = std::stoi(argv[++i]);
    }
    else if (a == "--reference-spp")
    {
      need(1);
      o.referenceSpp = std::stoi(argv[++i]);
    }
    else if (a == "--pyramid-levels")
    {
      need(1);
      o.pyramidLevels = std::max(1, std::stoi(argv[++i]));
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

bool wants(const Options& o, const std::string& s)
{
  return std::find(o.sections.begin(), o.sections.end(), s) != o.sections.end();
}

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
    this->scene.setTransferFunction(n,
      mcvol::sampleTransferFunction(this->volume.transferFunctions[size_t(n)], this->ranges[size_t(n)][0],
        this->ranges[size_t(n)][1], o.tableSize, this->volume.spacing[0] / o.density));
  }
  this->scene.update();
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
    std::ofstream f(o.csv);
    for (const auto& l : csv)
    {
      f << l << "\n";
    }
  }
}
} // namespace mcvolbench
