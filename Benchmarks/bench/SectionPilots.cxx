// SPDX-License-Identifier: BSD-3-Clause
//
// mcvol-bench section "pilots": what the automatic estimator choice's pilots
// (chooseEstimator()) cost, jittered pixels and pixel centres, each run
// three times (the first after the data's first frames; median reported).
// On CUDA both ways: the renders one after the other (Renderer::renderPilots)
// and all of a round's samples at once
// (CUDARenderer::renderPilots, the default; with it chooseEstimator() renders
// ahead the rates it will most likely reach), and at once with the previous
// choice's candidates as the hint (EstimatorChoiceSettings::hint, what the
// mapper passes after a transfer-function edit), with whether every way
// chose the same estimator from the same trials and their largest
// difference in predicted time.

#include "BenchCommon.h"
#include "Sections.h"

#include "mcvol/EstimatorChoice.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <string>
#include <vector>

namespace mcvolbench
{
void runPilots(Bench& bench)
{
  const Options& o = bench.o;
  Setup& s = bench.s;
  mcvol::Renderer& r = bench.r;
  s.load(o, o.channels, o.macrocell, bench.hostAccel);
  const std::string ds = describe(o, s);
  const mcvol::Camera cam = benchCamera(o, s.scene);
  {
    // The data's first frames (uploads, the device's acceleration build).
    mcvol::Accumulator w;
    mcvol::RenderSettings st;
    st.readBack = false;
    for (int i = 0; i < 3; ++i)
    {
      r.render(s.scene, cam, st, nullptr, w);
    }
    r.finish();
  }
  {
    // One pilot-sized render (48 pixels on the longer side, the image's
    // pixel footprint), as the pilots render one after the other: median of
    // 20, with the counters and the read-back, at 1 and 8 samples per pixel,
    // and at the full image size for scale.
    const mcvol::Camera pilot = mcvol::pilotCamera(cam, mcvol::EstimatorChoiceSettings().pilotSize);
    std::printf("\n## One pilot-sized render: %s, %dx%d, jittered (median of 20; counters and read-back)\n\n",
      ds.c_str(), pilot.width, pilot.height);
    std::printf("| estimator | 1 spp ms | 8 spp ms | %dx%d, 1 spp ms |\n|---|---|---|---|\n", cam.width, cam.height);
    struct E
    {
      const char* name;
      mcvol::Estimator e;
      float rate;
    };
    for (const E& e : { E{ "ExpectedValue", mcvol::Estimator::ExpectedValue, 2.f },
           E{ "UnbiasedMarch(1/16)", mcvol::Estimator::UnbiasedMarch, 1.f / 16.f },
           E{ "UnbiasedMarch(1)", mcvol::Estimator::UnbiasedMarch, 1.f } })
    {
      double ms[3] = { 0, 0, 0 };
      for (int v = 0; v < 3; ++v)
      {
        const mcvol::Camera& c = v == 2 ? cam : pilot;
        mcvol::RenderSettings st;
        st.estimator = e.e;
        st.marchSamplesPerVoxel = e.rate;
        st.samplesPerPixel = v == 1 ? 8 : 1;
        st.readBack = true;
        std::vector<double> t;
        for (int i = 0; i < 23; ++i)
        {
          mcvol::Accumulator a;
          a.setErrorEstimation(false);
          mcvol::RenderCounters counters;
          r.finish();
          const auto t0 = Clock::now();
          r.render(s.scene, c, st, nullptr, a, &counters);
          r.finish();
          if (i >= 3)
          {
            t.push_back(1e3 * seconds(t0));
          }
        }
        ms[v] = median(t);
      }
      std::printf("| %s | %.3f | %.3f | %.3f |\n", e.name, ms[0], ms[1], ms[2]);
    }
  }
  std::printf("\n## Automatic choice's pilots: %s, %dx%d (median of 3 runs)\n\n", ds.c_str(), o.width, o.height);
  std::printf("| pixels | pilot renders | ms (3 runs) | median ms | rounds | candidates reached | choice | predicted |\n");
  std::printf("|---|---|---|---|---|---|---|---|\n");
  std::string reports;
  for (int centres = 0; centres < 2; ++centres)
  {
    std::vector<std::string> modes = { "one after the other" };
#ifdef MCVOL_WITH_CUDA
    mcvol::CUDARenderer* cuda = asCuda(r);
    if (cuda)
    {
      modes.push_back("concurrent");
      // A transfer-function edit after a first choice: the mapper hands the
      // previous choice's candidates over as the hint (here the same scene's,
      // so the first round holds every candidate the search reaches).
      modes.push_back("concurrent, the previous choice as hint");
    }
#endif
    std::vector<mcvol::EstimatorChoice> choices;
    for (size_t m = 0; m < modes.size(); ++m)
    {
#ifdef MCVOL_WITH_CUDA
      if (cuda)
      {
        cuda->setConcurrentPilots(m >= 1);
      }
#endif
      mcvol::EstimatorChoiceSettings cs;
      if (m == 2)
      {
        cs.hint = choices[0].hint();
      }
      mcvol::RenderSettings st;
      st.seed = 7;
      st.jitterPixels = centres == 0;
      std::vector<double> ms;
      mcvol::EstimatorChoice choice;
      for (int run = 0; run < 3; ++run)
      {
        r.finish();
        const auto t0 = Clock::now();
        choice = mcvol::chooseEstimator(r, s.scene, cam, st, cs);
        r.finish();
        ms.push_back(1e3 * seconds(t0));
      }
      char buf[512];
      std::snprintf(buf, sizeof(buf), "| %s | %s | %.1f / %.1f / %.1f | **%.1f** | %d | %zu of %d rendered | %s | %.4g |\n",
        centres ? "centres" : "jittered", modes[m].c_str(), ms[0], ms[1], ms[2], median(ms), choice.rounds,
        choice.trials.size(), choice.rendered, choice.chosenName().c_str(),
        choice.chosen >= 0 ? choice.trials[size_t(choice.chosen)].score : 0.0);
      std::fputs(buf, stdout);
      bench.row("pilots", ds, s.volume.numChannels(), o.macrocell,
        std::string(centres ? "centres" : "jittered") + ", " + modes[m], median(ms), "ms", choice.chosenName());
      reports += std::string("\n") + (centres ? "centres" : "jittered") + ", " + modes[m] + ":\n" + choice.report();
      choices.push_back(choice);
    }
    if (choices.size() >= 2)
    {
      // Every way against the first (one after the other).
      double worst = 0;
      bool sameTrials = true, sameChoice = true;
      for (size_t k = 1; k < choices.size(); ++k)
      {
        sameChoice = sameChoice && choices[0].chosenName() == choices[k].chosenName();
        sameTrials = sameTrials && choices[0].trials.size() == choices[k].trials.size();
        for (size_t i = 0; sameTrials && i < choices[0].trials.size(); ++i)
        {
          const double a = choices[0].trials[i].score, b = choices[k].trials[i].score;
          worst = std::max(worst, std::fabs(a - b) / std::max(1e-30, std::fabs(a)));
        }
      }
      std::printf("| %s | same choice: %s; same candidates: %s; largest relative difference in predicted time: %.2g | | | | | | |\n",
        centres ? "centres" : "jittered", sameChoice ? "yes" : "**no**", sameTrials ? "yes" : "no", worst);
    }
  }
#ifdef MCVOL_WITH_CUDA
  if (mcvol::CUDARenderer* cuda = asCuda(r))
  {
    cuda->setConcurrentPilots(true);
  }
#endif
  std::printf("\nReports:\n\n```%s```\n", reports.c_str());
}
} // namespace mcvolbench
