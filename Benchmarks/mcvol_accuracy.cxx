// SPDX-License-Identifier: BSD-3-Clause
//
// mcvol-accuracy: renders the images of the accuracy-versus-time study for
// one dataset and blend mode (VTK-free; Benchmarks/studies/accuracy_study.py runs it
// for every dataset and mode and scores the images):
//   reference.f32        ray march, extinction model, --ref-step voxels
//   reference_mc.f32     Monte Carlo (1-DDA) at --ref-spp, the cross-check
//   mc_<estimator>_<sampler>_<tracker>_<spp>.f32
//                        progressive Monte Carlo, spp = 1, 2, 4, ... --spp-max,
//                        one series per --mc-configs entry
//   rm_<model>_<step>.f32   ray march at each --steps (voxels), both models
//   timings.csv          method,variant,param,ms[,rmse,psnr],backend,estimator,
//                        sampler (MC: cumulative render time; backend: where
//                        it ran; variant: the tracker or march model)
// Images are W x H premultiplied RGBA float32, rows from the bottom. Monte
// Carlo samples pixel centres (no pixel jitter) like the ray marcher, so both
// estimate the same image. --backend picks where Monte Carlo runs and
// --march-backend (default: the same) where the ray marches run, so that
// both are timed on the same hardware; --march-textures makes the CUDA march
// read voxels through the hardware texture filter, as the Monte Carlo
// renders do (the reference march never does). --sampler independent|sobol
// (default sobol, the renderer's default) picks the progressive series'
// sample sequence, and --estimator expected-value|collision (default
// expected-value, the renderer's default) its estimator; the cross-check
// uses the same.
// Without --mc-configs the series are that estimator and sampler with both
// trackers; --mc-configs lists estimator:sampler:tracker triples instead
// (e.g. expected-value:sobol:1dda,collision:independent:1dda; a 4th field,
// expected-value:sobol:1dda:1, sets RenderSettings::minSamplesPerVoxel and
// names the series' variant 1dda-min1; the estimator "automatic" makes the
// automatic choice, mcvol::chooseEstimator at 35 dB, from that base and
// renders what it chose, its pilots' wall time counted first, with the
// choice in meta.txt; on a backend that renders pilots at once, meta.txt
// also gets a transfer-function edit timed to 35 dB three ways: the hinted
// choice then the frames, the frames rendered during the pilots, and
// expected value's frames), so that one run, with one reference, times
// several Monte Carlo configurations. A
// configuration the renderer would not run as asked (the expected-value
// estimator under the composite blend, which keeps the collision estimator)
// is recorded under the estimator it runs, once: the CSV never holds two
// copies of one series under different names.
// --lighting shadows|ambient|multiple (lightingPreset() in BenchUtil.h) lights
// the scene: the Monte Carlo series run the expected-value estimator of lit
// camera rays or the collision estimator (an unbiased-march series runs the
// collision one), the marches are the lit march (extinction model only), and
// with multiple scattering, which the march does not render, the reference is
// a Monte Carlo image at --ref-spp with its own seed and no marches are run.

#include "bench/ArgParser.h"
#include "bench/BenchUtil.h"

#include "mcvol/CameraMath.h"
#include "mcvol/DemoData.h"
#include "mcvol/EstimatorChoice.h"
#include "mcvol/ray/Integrator.h"
#include "mcvol/MarchSetup.h"
#include "mcvol/ray/RayMarch.h"
#include "mcvol/Renderer.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <stdexcept>
#include <string>
#include <vector>

#ifdef _OPENMP
#include <omp.h>
#endif

using namespace mcvolbench;

namespace
{
/// One Monte Carlo series of the study.
struct McConfig
{
  mcvol::Estimator estimator;
  mcvol::Sampler sampler;
  mcvol::Tracker tracker;
  float minSamplesPerVoxel = 0.f; ///< RenderSettings::minSamplesPerVoxel
  /// The automatic choice (mcvol::chooseEstimator at the study's 35 dB,
  /// from `estimator` as the base): the series renders what it chose, and
  /// its cumulative time starts with the pilots' wall time.
  bool automatic = false;
};

struct Options
{
  std::string dataset = "cosmology";
  std::array<int, 3> dims = { 0, 0, 0 };
  std::string blend = "density";
  int width = 256;
  int height = 256;
  std::string out = ".";
  int sppMax = 1024;
  std::vector<double> steps = { 4, 2, 1, 0.5, 0.25, 0.125 };
  double refStep = 1.0 / 16.0;
  int refSpp = 4096;
  int macrocell = 8;
  int reps = 3;
  mcvol::Backend backend = mcvol::Backend::CPU;
  int marchBackend = -1;      ///< a mcvol::Backend; -1: the same as backend
  bool marchTextures = false; ///< CUDA march: hardware texture filtering (not for the reference)
  bool scoreOnly = false;     ///< no image files: RMSE and PSNR in the CSV instead
  mcvol::Sampler sampler = mcvol::Sampler::Sobol;
  mcvol::Estimator estimator = mcvol::Estimator::ExpectedValue;
  std::vector<McConfig> mcConfigs; ///< empty: estimator and sampler, both trackers
  std::string lighting = "none";   ///< lightingPreset() name
};

mcvol::Estimator estimatorOf(const std::string& s, const std::string& option)
{
  if (s != "expected-value" && s != "collision" && s != "unbiased-march")
  {
    throw std::invalid_argument(option + " takes expected-value, unbiased-march or collision, not " + s);
  }
  return s == "collision"   ? mcvol::Estimator::Collision
    : s == "unbiased-march" ? mcvol::Estimator::UnbiasedMarch
                            : mcvol::Estimator::ExpectedValue;
}

mcvol::Sampler samplerOf(const std::string& s, const std::string& option)
{
  if (s != "independent" && s != "sobol")
  {
    throw std::invalid_argument(option + " takes independent or sobol, not " + s);
  }
  return s == "sobol" ? mcvol::Sampler::Sobol : mcvol::Sampler::Independent;
}

/// "estimator:sampler:tracker,..." (tracker 1dda or ndda).
std::vector<McConfig> splitConfigs(const std::string& s)
{
  std::vector<McConfig> v;
  for (const std::string& item : splitList(s))
  {
    const size_t a = item.find(':');
    const size_t b = a == std::string::npos ? a : item.find(':', a + 1);
    if (b == std::string::npos)
    {
      throw std::invalid_argument("--mc-configs takes estimator:sampler:tracker entries, not " + item);
    }
    const size_t c = item.find(':', b + 1); // optional 4th field: minimum samples per voxel
    const std::string t = item.substr(b + 1, c == std::string::npos ? std::string::npos : c - b - 1);
    if (t != "1dda" && t != "ndda")
    {
      throw std::invalid_argument("--mc-configs: tracker 1dda or ndda, not " + t);
    }
    const std::string e = item.substr(0, a);
    const bool automatic = e == "automatic";
    v.push_back({ automatic ? mcvol::Estimator::ExpectedValue : estimatorOf(e, "--mc-configs"),
      samplerOf(item.substr(a + 1, b - a - 1), "--mc-configs"),
      t == "ndda" ? mcvol::Tracker::NDDA : mcvol::Tracker::OneDDA,
      c == std::string::npos ? 0.f : std::stof(item.substr(c + 1)), automatic });
  }
  return v;
}

mcvol::Backend backendOf(const std::string& s, const std::string& option)
{
  if (s != "cuda" && s != "cpu")
  {
    throw std::invalid_argument(option + " takes cpu or cuda, not " + s);
  }
  return s == "cuda" ? mcvol::Backend::CUDA : mcvol::Backend::CPU;
}

/// The options of mcvol-accuracy, stored into `o`.
ArgParser makeParser(Options& o)
{
  ArgParser p("mcvol-accuracy");
  p.add("--dataset", 1, "NAME", "demo dataset: cosmology, microscopy, weather, figure3 (default cosmology)",
     [&](const Args& v) { o.dataset = v[0]; })
    .add("--dims", 3, "X Y Z", "volume size in voxels (default 0 0 0: the dataset's own)",
      [&](const Args& v)
      {
        for (size_t k = 0; k < 3; ++k)
          o.dims[k] = std::stoi(v[k]);
      })
    .add("--blend", 1, "density|max|mix|composite", "blend mode (default density)",
      [&](const Args& v) { o.blend = v[0]; })
    .add("--size", 2, "W H", "image size in pixels (default 256 256)",
      [&](const Args& v)
      {
        o.width = std::stoi(v[0]);
        o.height = std::stoi(v[1]);
      })
    .add("--out", 1, "DIR", "folder for the images, timings.csv and meta.txt (default .)",
      [&](const Args& v) { o.out = v[0]; })
    .add("--spp-max", 1, "N", "the progressive series' last sample count (default 1024)",
      [&](const Args& v) { o.sppMax = std::stoi(v[0]); })
    .add("--steps", 1, "4,2,1,...", "ray-march steps in voxels (default 4,2,1,0.5,0.25,0.125)",
      [&](const Args& v) { o.steps = splitDoubles(v[0]); })
    .add("--ref-step", 1, "S", "the reference march's step in voxels (default 0.0625)",
      [&](const Args& v) { o.refStep = std::stod(v[0]); })
    .add("--ref-spp", 1, "N", "samples per pixel of the Monte Carlo cross-check (default 4096)",
      [&](const Args& v) { o.refSpp = std::stoi(v[0]); })
    .add("--macrocell", 1, "M", "macrocell edge in voxels (default 8)",
      [&](const Args& v) { o.macrocell = std::stoi(v[0]); })
    .add("--reps", 1, "N", "ray marches timed per step; the median is reported (default 3)",
      [&](const Args& v) { o.reps = std::stoi(v[0]); })
    .add("--score-only", 0, "", "no image files: RMSE and PSNR against the reference in timings.csv instead",
      [&](const Args&) { o.scoreOnly = true; })
    .add("--estimator", 1, "expected-value|collision|unbiased-march",
      "estimator of the default series and the cross-check (default expected-value)",
      [&](const Args& v) { o.estimator = estimatorOf(v[0], "--estimator"); })
    .add("--sampler", 1, "independent|sobol", "sampler of the default series and the cross-check (default sobol)",
      [&](const Args& v) { o.sampler = samplerOf(v[0], "--sampler"); })
    .add("--mc-configs", 1, "E:S:T[:MIN],...",
      "Monte Carlo series as estimator:sampler:tracker[:min samples per voxel] (estimator automatic: the "
      "automatic choice)",
      [&](const Args& v) { o.mcConfigs = splitConfigs(v[0]); })
    .add("--backend", 1, "cpu|cuda", "where Monte Carlo renders (default cpu)",
      [&](const Args& v) { o.backend = backendOf(v[0], "--backend"); })
    .add("--march-backend", 1, "cpu|cuda", "where the ray marches run (default: --backend)",
      [&](const Args& v) { o.marchBackend = int(backendOf(v[0], "--march-backend")); })
    .add("--lighting", 1, kLightingPresets,
      "the scene's lighting (default none): one light with shadows, plus ambient 0.2, plus multiple scattering",
      [&](const Args& v)
      {
        lightingPreset(v[0], 1); // refuses an unknown name here
        o.lighting = v[0];
      })
    .add("--march-textures", 0, "", "CUDA march: read voxels through the hardware texture filter",
      [&](const Args&) { o.marchTextures = true; });
  return p;
}

Options parse(int argc, char** argv)
{
  Options o;
  makeParser(o).parse(argc, argv);
  return o;
}

mcvol::BlendMode blendOf(const std::string& s)
{
  if (s == "density")
    return mcvol::BlendMode::Density;
  if (s == "max")
    return mcvol::BlendMode::Max;
  if (s == "mix")
    return mcvol::BlendMode::Mix;
  if (s == "composite")
    return mcvol::BlendMode::Composite;
  throw std::invalid_argument("unknown blend mode " + s);
}

/// The image's error against the reference, as the study scores images
/// (clipped RGB, peak 1).
ImageError score(const mcvol::Accumulator& a, const std::vector<float>& ref)
{
  return clippedRgbError(a.rgba(), ref.data(), size_t(a.width()) * size_t(a.height()));
}

void writeImage(const std::string& path, const mcvol::Accumulator& a)
{
  std::ofstream f(path, std::ios::binary);
  f.write(reinterpret_cast<const char*>(a.rgba()), std::streamsize(sizeof(float) * 4 * a.width() * a.height()));
  if (!f)
  {
    throw std::runtime_error("cannot write " + path);
  }
}

std::string stepName(double s)
{
  char b[32];
  std::snprintf(b, sizeof(b), "%g", s);
  return b;
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
    std::fprintf(stderr, "mcvol-accuracy: %s\n", e.what());
    return 2;
  }
  try
  {
    std::filesystem::create_directories(o.out); // images, timings.csv and meta.txt go there
    const mcvol::DemoVolume v = mcvol::makeDemo(o.dataset, o.dims);
    mcvol::Scene scene;
    std::vector<mcvol::ChannelSource> src;
    for (int n = 0; n < v.numChannels(); ++n)
    {
      src.push_back(v.source(n));
    }
    scene.setVolume(v.dims, v.numChannels(), src.data());
    for (int n = 0; n < v.numChannels(); ++n)
    {
      const std::array<float, 2> r = v.range(n);
      scene.setTransferFunction(n, demoTransferFunction(v, n, r));
    }
    scene.setMacrocellSize(o.macrocell);
    scene.setBlendMode(blendOf(o.blend));
    scene.setLighting(lightingPreset(o.lighting, v.numChannels()));
    scene.update();
    // The march renders single scattering only: with more, the reference is
    // a Monte Carlo image.
    const bool marchable = o.lighting != "multiple";
    const mcvol::Camera cam = mcvol::orbitCamera(v.dims, v.spacing, o.width, o.height, 30, 20);
    const double voxel = 2.0 * mcvol::marchNyquistStep(cam); // smallest spacing
    // Monte Carlo's backend, and the march's: the same renderer when both
    // are the same backend (the march then reads the device copies the
    // Monte Carlo renders use, as vtkMultiChannelRayMarchMapper does).
    std::unique_ptr<mcvol::Renderer> r = mcvol::Renderer::create(o.backend);
    const mcvol::Backend marchBackend = o.marchBackend < 0 ? o.backend : mcvol::Backend(o.marchBackend);
    std::unique_ptr<mcvol::Renderer> ownMarcher;
    if (marchBackend != o.backend)
    {
      ownMarcher = mcvol::Renderer::create(marchBackend);
    }
    mcvol::Renderer* marcher = ownMarcher ? ownMarcher.get() : r.get();
    // The estimator and sampler columns come last: readers go by column name.
    std::vector<std::string> rows = { o.scoreOnly ? "method,variant,param,ms,rmse,psnr,backend,estimator,sampler"
                                                  : "method,variant,param,ms,backend,estimator,sampler" };
    std::vector<float> refImage;
    const mcvol::BlendMode blend = blendOf(o.blend);
    // The estimator a render asked for `e` runs (not optimized).
    auto effective = [&](mcvol::Estimator e)
    { return mcvol::unlitEstimator(e, blend, scene.lit(), false) != 0 ? e : mcvol::Estimator::Collision; };
    // Writes the image (or, with --score-only, scores it) and adds its row;
    // `mc` (Monte Carlo rows) names the estimator and sampler that ran.
    auto emit = [&](const std::string& m, const std::string& var, double p, double ms, const std::string& file,
                  const mcvol::Accumulator& a, const McConfig* mc = nullptr)
    {
      std::ostringstream s;
      s << m << "," << var << "," << p << "," << ms;
      if (o.scoreOnly)
      {
        const auto e = score(a, refImage);
        s << "," << e.rmse << "," << e.psnr;
      }
      else
      {
        writeImage(o.out + "/" + file, a);
      }
      const bool isMc = m == "montecarlo" || var == "montecarlo" || var == "montecarlo-reference";
      const bool textures = m == "raymarch" && o.marchTextures && std::string(marcher->name()) == "cuda";
      s << "," << (isMc ? r->name() : marcher->name()) << (textures ? "+textures" : "");
      s << "," << (mc ? (mc->automatic ? "automatic" : mcvol::toString(effective(mc->estimator))) : "") << ","
        << (mc ? mcvol::toString(mc->sampler) : "");
      rows.push_back(s.str());
    };
    int threads = 1;
#ifdef _OPENMP
    threads = omp_get_max_threads();
#endif
    std::fprintf(stderr, "mcvol-accuracy: %s %dx%dx%d, %s, lighting %s, %dx%d, %d threads\n", o.dataset.c_str(),
      v.dims[0], v.dims[1], v.dims[2], o.blend.c_str(), o.lighting.c_str(), o.width, o.height, threads);

    // Reference: fine-step ray march (no early termination), after an
    // untimed coarse march (threads, device upload and kernel loading); or,
    // where the march cannot render the scene, Monte Carlo at refSpp.
    mcvol::Accumulator img;
    mcvol::MarchSettings ms;
    mcvol::RenderSettings rs;
    rs.jitterPixels = false;
    rs.sampler = o.sampler;
    rs.estimator = o.estimator;
    rs.readBack = false; // device backends: the copy-back is not part of the timed render
    // refSpp samples into `acc` with `seed`, in batches; returns the ms.
    auto renderMany = [&](mcvol::Accumulator& acc, uint32_t seed)
    {
      rs.seed = seed;
      const auto start = Clock::now();
      while (int(acc.samples()) < o.refSpp)
      {
        rs.samplesPerPixel = std::min(64, o.refSpp - int(acc.samples()));
        r->render(scene, cam, rs, nullptr, acc);
      }
      r->readBack(acc);
      return msSince(start);
    };
    const McConfig cross = { o.estimator, o.sampler, mcvol::Tracker::OneDDA };
    if (marchable)
    {
      ms.terminateTransmittance = 0.f;
      ms.step = 4 * voxel;
      marcher->march(scene, cam, ms, nullptr, img);
      ms.step = o.refStep * voxel;
      auto t0 = Clock::now();
      marcher->march(scene, cam, ms, nullptr, img);
      const double refMs = msSince(t0);
      refImage.assign(img.rgba(), img.rgba() + size_t(4) * img.width() * img.height());
      emit("reference", "raymarch", o.refStep, refMs, "reference.f32", img);
    }
    else
    {
      mcvol::Accumulator acc;
      const double refMs = renderMany(acc, 12345);
      refImage.assign(acc.rgba(), acc.rgba() + size_t(4) * acc.width() * acc.height());
      emit("reference", "montecarlo-reference", o.refSpp, refMs, "reference.f32", acc, &cross);
    }
    auto t0 = Clock::now();

    // Monte Carlo: cross-check at refSpp, then the progressive series.
    {
      mcvol::Accumulator acc;
      const double crossMs = renderMany(acc, 999);
      emit("reference", "montecarlo", o.refSpp, crossMs, "reference_mc.f32", acc, &cross);
    }
    std::vector<McConfig> configs = o.mcConfigs;
    if (configs.empty())
    {
      configs = { { o.estimator, o.sampler, mcvol::Tracker::OneDDA },
        { o.estimator, o.sampler, mcvol::Tracker::NDDA } };
    }
    std::vector<McConfig> done;
    std::vector<std::string> choices; // meta.txt lines of the automatic series
    for (McConfig c : configs)
    {
      if (c.automatic && effective(c.estimator) != c.estimator)
      {
        std::fprintf(stderr, "mcvol-accuracy: the automatic choice does not apply to the %s blend (it keeps the "
                             "collision estimator): no automatic series\n",
          o.blend.c_str());
        continue;
      }
      c.estimator = effective(c.estimator);
      if (c.estimator == mcvol::Estimator::ExpectedValue)
      {
        // trackExpected walks one DDA over the macrocells whatever the
        // tracker: an N-DDA series of it would be the 1-DDA one again.
        c.tracker = mcvol::Tracker::OneDDA;
      }
      const bool again = std::any_of(done.begin(), done.end(),
        [&](const McConfig& d)
        {
          return d.estimator == c.estimator && d.sampler == c.sampler && d.tracker == c.tracker &&
            d.minSamplesPerVoxel == c.minSamplesPerVoxel && d.automatic == c.automatic;
        });
      if (c.minSamplesPerVoxel > 0.f && c.estimator != mcvol::Estimator::ExpectedValue)
      {
        std::fprintf(stderr, "mcvol-accuracy: a minimum sample rate serves the expected-value estimator only; "
                             "skipped for the %s blend\n",
          o.blend.c_str());
        continue;
      }
      std::string trk = c.tracker == mcvol::Tracker::OneDDA ? "1dda" : "ndda";
      if (c.minSamplesPerVoxel > 0.f)
      {
        char m[32];
        std::snprintf(m, sizeof(m), "-min%g", double(c.minSamplesPerVoxel));
        trk += m;
      }
      const std::string tag = std::string(c.automatic ? "automatic" : mcvol::toString(c.estimator)) + "_" +
        mcvol::toString(c.sampler) + "_" + trk;
      if (again)
      {
        std::fprintf(stderr, "mcvol-accuracy: %s: the same series as an earlier configuration here (%s blend)\n",
          tag.c_str(), o.blend.c_str());
        continue;
      }
      done.push_back(c);
      rs.estimator = c.estimator;
      rs.sampler = c.sampler;
      rs.minSamplesPerVoxel = c.minSamplesPerVoxel;
      // Warm-up (threads, caches) on a throw-away image.
      {
        mcvol::Accumulator w;
        rs.samplesPerPixel = 2;
        rs.tracker = c.tracker;
        r->render(scene, cam, rs, nullptr, w);
      }
      mcvol::Accumulator acc;
      rs.seed = 1;
      rs.tracker = c.tracker;
      double total = 0;
      // The settings the series renders: rs, or what the automatic choice
      // made of it (its pilots timed as a transfer-function edit after the
      // first one in the process: an untimed choice first loads what the
      // first pilots would, e.g. the CUDA streams).
      mcvol::RenderSettings run = rs;
      mcvol::EstimatorChoice choice;
      if (c.automatic)
      {
        mcvol::chooseEstimator(*r, scene, cam, rs);
        choice = mcvol::chooseEstimator(*r, scene, cam, rs);
        run = choice.settings;
        total = 1e3 * choice.seconds;
        // The same edit with the previous choice's candidates as the hint
        // (what the mapper passes): recorded, not added to the series, whose
        // time stays that of a choice without one. Same trials, same choice.
        mcvol::EstimatorChoiceSettings hinted;
        hinted.hint = choice.hint();
        const mcvol::EstimatorChoice again = mcvol::chooseEstimator(*r, scene, cam, rs, hinted);
        if (again.chosenName() != choice.chosenName())
        {
          throw std::runtime_error("mcvol-accuracy: the hinted choice differs: " + again.chosenName() + " against " +
            choice.chosenName());
        }
        char line[320];
        std::snprintf(line, sizeof(line),
          "automatic_choice %s %s pilots_ms %.3f rounds %d rendered %d hinted_ms %.3f hinted_rounds %d",
          tag.c_str(), choice.chosenName().c_str(), total, choice.rounds, choice.rendered, 1e3 * again.seconds,
          again.rounds);
        choices.push_back(line);
        std::fprintf(stderr, "mcvol-accuracy: %s\n%s", line, choice.report().c_str());
      }
      for (int spp = 1; spp <= o.sppMax; spp *= 2)
      {
        run.samplesPerPixel = spp - int(acc.samples());
        t0 = Clock::now();
        r->render(scene, cam, run, nullptr, acc);
        r->finish();
        total += msSince(t0);
        r->readBack(acc);
        emit("montecarlo", trk, spp, total, "mc_" + tag + "_" + std::to_string(spp) + ".f32", acc, &c);
      }
      if (c.automatic && choice.applies && r->rendersPilotsAtOnce())
      {
        // A transfer-function edit on a warm renderer, timed to 35 dB: the
        // hinted choice then the frames, the same with the frames rendered
        // during the pilots (mcvol::ChoiceAhead), and expected value's frames
        // (no pilots). The frames each way needs are counted first (one
        // sample per pixel, scored against the reference, untimed); each way
        // is then timed from its start to the last frame's end, median of 5
        // after a warm-up run.
        const double targetDb = 35.0;
        mcvol::RenderSettings one = rs;
        one.samplesPerPixel = 1;
        mcvol::RenderSettings ev = one;
        ev.estimator = mcvol::Estimator::ExpectedValue;
        const auto framesTo = [&](const mcvol::RenderSettings& st) {
          mcvol::Accumulator a;
          int n = 0;
          while (n < 1024)
          {
            r->render(scene, cam, st, nullptr, a);
            ++n;
            r->readBack(a);
            if (score(a, refImage).psnr >= targetDb)
            {
              break;
            }
          }
          return n;
        };
        mcvol::RenderSettings chosen = choice.settings;
        chosen.samplesPerPixel = 1;
        const int n = framesTo(chosen);
        const int nEv = framesTo(ev);
        mcvol::EstimatorChoiceSettings hinted;
        hinted.hint = choice.hint();
        double ms[3] = { 0, 0, 0 };
        bool kept = true;
        for (int way = 0; way < 3; ++way)
        {
          std::vector<double> t;
          for (int k = 0; k < 6; ++k)
          {
            mcvol::Accumulator a;
            a.resize(cam.width, cam.height);
            mcvol::ChoiceAhead ahead;
            ahead.candidate = choice.chosenCandidate();
            ahead.renders = n;
            ahead.accum = way == 1 ? &a : nullptr; // null: nothing rendered ahead
            r->finish();
            t0 = Clock::now();
            int done = 0;
            mcvol::RenderSettings st = ev;
            if (way < 2)
            {
              const mcvol::EstimatorChoice e = mcvol::chooseEstimator(*r, scene, cam, one, hinted, ahead);
              st = e.settings;
              done = ahead.kept ? n : 0;
              kept = kept && (way == 0 || ahead.kept);
            }
            for (int f = done; f < (way < 2 ? n : nEv); ++f)
            {
              r->render(scene, cam, st, nullptr, a);
            }
            r->finish();
            if (k > 0)
            {
              t.push_back(msSince(t0));
            }
          }
          std::sort(t.begin(), t.end());
          ms[way] = t[t.size() / 2];
        }
        char line[320];
        std::snprintf(line, sizeof(line),
          "automatic_edit %s frames %d then_ms %.3f ahead_ms %.3f kept %d expected_value_frames %d "
          "expected_value_ms %.3f",
          tag.c_str(), n, ms[0], ms[1], kept ? 1 : 0, nEv, ms[2]);
        choices.push_back(line);
        std::fprintf(stderr, "mcvol-accuracy: %s\n", line);
      }
    }

    // Ray marching at each step, both models (early termination at 1e-4, the
    // mapper's default); the median of --reps runs. A march always copies its
    // image back to the host: on a device that copy (W x H x 16 bytes) is
    // part of its time, where the Monte Carlo times above leave it out.
    ms.deviceTextures = o.marchTextures;
    std::vector<mcvol::Compositing> models = { mcvol::Compositing::Extinction, mcvol::Compositing::Opacity };
    if (scene.lit())
    {
      // The lit march composites extinctions only; with multiple
      // scattering there is no march at all.
      models.resize(marchable ? 1 : 0);
      if (!marchable)
      {
        std::fprintf(stderr, "mcvol-accuracy: the ray marcher renders single scattering only: no march rows\n");
      }
    }
    for (auto model : models)
    {
      const std::string name = model == mcvol::Compositing::Extinction ? "extinction" : "opacity";
      ms.compositing = model;
      ms.terminateTransmittance = 1e-4f;
      for (double s : o.steps)
      {
        ms.step = s * voxel;
        std::vector<double> t;
        for (int k = 0; k < std::max(1, o.reps); ++k)
        {
          t0 = Clock::now();
          marcher->march(scene, cam, ms, nullptr, img);
          t.push_back(msSince(t0));
        }
        std::sort(t.begin(), t.end());
        emit("raymarch", name, s, t[t.size() / 2], "rm_" + name + "_" + stepName(s) + ".f32", img);
      }
    }
    writeLines(o.out + "/timings.csv", rows);
    std::ofstream m(o.out + "/meta.txt");
    m << "dataset " << o.dataset << "\ndims " << v.dims[0] << " " << v.dims[1] << " " << v.dims[2] << "\nchannels "
      << v.numChannels() << "\nblend " << o.blend << "\nsize " << o.width << " " << o.height << "\nthreads " << threads
      << "\nbackend " << r->name() << "\nmarch_backend " << marcher->name() << (o.marchTextures ? " (textures)" : "")
      << "\nvoxel " << voxel << "\nlighting " << o.lighting << "\nsampler " << mcvol::toString(o.sampler) << "\nestimator "
      << mcvol::toString(o.estimator) << "\n";
    for (const McConfig& c : done)
    {
      m << "mc_series " << (c.automatic ? "automatic" : mcvol::toString(c.estimator)) << " "
        << mcvol::toString(c.sampler) << " " << mcvol::toString(c.tracker) << " " << c.minSamplesPerVoxel << "\n";
    }
    for (const std::string& l : choices)
    {
      m << l << "\n";
    }
  }
  catch (const std::exception& e)
  {
    std::fprintf(stderr, "mcvol-accuracy: %s\n", e.what());
    return 1;
  }
  return 0;
}
