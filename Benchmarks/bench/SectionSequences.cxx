// SPDX-License-Identifier: BSD-3-Clause
//
// mcvol-bench section "sequences": the error of the progressive image against
// a converged reference at 1, 2, 4, ... --spp-max samples per pixel, for the
// independent sampler and for Owen-scrambled Sobol' points
// (RenderSettings::sampler), each with the --estimators given
// (RenderSettings::estimator: collision, expected-value), 1 spp per frame
// (1-DDA, pixel jitter on). Prints per sampler the RMSE and PSNR at each power of two, the
// fitted log-log slope of RMSE against spp (over all points and over 1-16
// spp), and the samples and rendering time (the scoring between frames is
// not timed) to reach RMSE 0.01 and --psnr dB (default 35).
//
// The reference is rendered with the independent sampler and another seed
// (--reference-spp samples): its own noise, RMSE_1spp / sqrt(reference spp),
// is the floor of what the series can show; keep it well below the errors
// compared.

#include "BenchCommon.h"
#include "Sections.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <string>
#include <vector>

namespace mcvolbench
{
namespace
{
/// Least-squares slope of log(y) against log(x).
double logSlope(const std::vector<double>& x, const std::vector<double>& y)
{
  double sx = 0, sy = 0, sxx = 0, sxy = 0;
  const double n = double(x.size());
  for (size_t i = 0; i < x.size(); ++i)
  {
    const double lx = std::log(x[i]), ly = std::log(y[i]);
    sx += lx;
    sy += ly;
    sxx += lx * lx;
    sxy += lx * ly;
  }
  return (n * sxy - sx * sy) / (n * sxx - sx * sx);
}
} // namespace

void runSequences(Bench& bench)
{
  const Options& o = bench.o;
  Setup& s = bench.s;
  mcvol::Renderer& r = bench.r;
  s.load(o, o.channels, o.macrocell, bench.hostAccel);
  const std::string ds = describe(o, s);
  const mcvol::Camera cam = benchCamera(o, s.scene);
  mcvol::Accumulator ref;
  mcvol::RenderSettings rs;
  rs.sampler = mcvol::Sampler::Independent;
  rs.estimator = mcvol::Estimator::Collision;
  const std::vector<float> refImg = renderReference(o, r, s.scene, cam, ref, rs);
  struct Config
  {
    mcvol::Sampler sampler;
    mcvol::Estimator estimator;
    std::string name;
  };
  std::vector<Config> configs;
  for (const std::string& est : o.estimators)
  {
    for (const std::string& name : o.samplers)
    {
      Config c;
      c.sampler = name == "sobol" ? mcvol::Sampler::Sobol : mcvol::Sampler::Independent;
      c.estimator = est == "expected-value" ? mcvol::Estimator::ExpectedValue
        : est == "unbiased-march"           ? mcvol::Estimator::UnbiasedMarch
                                            : mcvol::Estimator::Collision;
      c.name = o.estimators.size() > 1 ? name + " " + est : name;
      configs.push_back(c);
    }
  }
  std::vector<std::vector<double>> errs;
  std::vector<std::string> summary;
  for (const Config& config : configs)
  {
    mcvol::RenderSettings st;
    st.seed = 7;
    st.sampler = config.sampler;
    st.estimator = config.estimator;
    st.readBack = false;
    {
      mcvol::Accumulator w;
      for (int i = 0; i < 3; ++i)
      {
        r.render(s.scene, cam, st, nullptr, w);
      }
      r.finish();
    }
    mcvol::Accumulator acc;
    double ms = 0;
    int sppRmse = -1, sppPsnr = -1;
    double msRmse = 0, msPsnr = 0;
    std::vector<double> x, e;
    for (int spp = 1; spp <= o.sppMax; ++spp)
    {
      const auto t0 = Clock::now();
      r.render(s.scene, cam, st, nullptr, acc);
      r.finish();
      ms += 1e3 * seconds(t0);
      r.readBack(acc);
      const double q = psnrOf(acc, refImg);
      const double err = std::pow(10.0, -q / 20.0);
      if (sppRmse < 0 && err <= 0.01)
      {
        sppRmse = spp;
        msRmse = ms;
      }
      if (sppPsnr < 0 && q >= o.psnr)
      {
        sppPsnr = spp;
        msPsnr = ms;
      }
      if ((spp & (spp - 1)) == 0)
      {
        x.push_back(spp);
        e.push_back(err);
      }
    }
    errs.push_back(e);
    const size_t lowN = std::min<size_t>(x.size(), 5); // 1 to 16 spp
    const double slope = logSlope(x, e);
    const double lowSlope = logSlope(
      std::vector<double>(x.begin(), x.begin() + long(lowN)), std::vector<double>(e.begin(), e.begin() + long(lowN)));
    char line[512];
    std::snprintf(line, sizeof(line), "| %s | %.2f | %.3f | %.3f | %s | %s | %s | %s |", config.name.c_str(),
      ms / o.sppMax, slope, lowSlope, sppRmse > 0 ? std::to_string(sppRmse).c_str() : "-",
      sppRmse > 0 ? (std::to_string(int(std::lround(msRmse))) + " ms").c_str() : "-",
      sppPsnr > 0 ? std::to_string(sppPsnr).c_str() : "-",
      sppPsnr > 0 ? (std::to_string(int(std::lround(msPsnr))) + " ms").c_str() : "-");
    summary.push_back(line);
    bench.row("sequences", ds, s.volume.numChannels(), o.macrocell, config.name, slope, "slope",
      "ms_per_spp=" + std::to_string(ms / o.sppMax) + " low_slope=" + std::to_string(lowSlope) +
        " spp_rmse001=" + std::to_string(sppRmse) + " ms_rmse001=" + std::to_string(msRmse) +
        " spp_psnr=" + std::to_string(sppPsnr) + " ms_psnr=" + std::to_string(msPsnr));
    for (size_t i = 0; i < x.size(); ++i)
    {
      bench.row("sequences", ds, s.volume.numChannels(), o.macrocell, config.name, e[i], "rmse",
        "spp=" + std::to_string(int(x[i])));
    }
  }
  std::printf("## Sample sequences: %s, %dx%d, 1-DDA, 1 spp per frame, RMSE (RGB over black) against %u spp of "
              "the independent sampler and collision estimator (another seed)\n\n| spp |",
    ds.c_str(), o.width, o.height, ref.samples());
  for (const Config& config : configs)
  {
    std::printf(" RMSE %s |", config.name.c_str());
  }
  std::printf("\n|---|");
  for (size_t k = 0; k < configs.size(); ++k)
  {
    std::printf("---|");
  }
  std::printf("\n");
  for (size_t i = 0; !errs.empty() && i < errs[0].size(); ++i)
  {
    std::printf("| %d |", 1 << i);
    for (const auto& e : errs)
    {
      std::printf(" %.5f |", e[i]);
    }
    std::printf("\n");
  }
  std::printf(
    "\n| sampler | ms per spp | RMSE slope (1-%d spp) | slope 1-16 spp | spp to RMSE 0.01 | ms to RMSE 0.01 | "
    "spp to %.0f dB | ms to %.0f dB |\n|---|---|---|---|---|---|---|---|\n",
    o.sppMax, o.psnr, o.psnr);
  for (const std::string& l : summary)
  {
    std::printf("%s\n", l.c_str());
  }
  std::printf("\n");
  std::fflush(stdout);
}
} // namespace mcvolbench
