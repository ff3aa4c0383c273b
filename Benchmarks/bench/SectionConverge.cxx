// SPDX-License-Identifier: BSD-3-Clause
//
// mcvol-bench section "converge": ms until the progressive image reaches --psnr
// dB (default 35) against a converged reference (--reference-spp samples),
// for the default settings (expected-value estimator, Sobol' points) and the
// collision estimator with each tracker, with Sobol' points and with the
// independent sampler (the renderer's former default), and the unbiased march
// (--march-samples-per-voxel, default 2; --no-collision leaves the collision
// rows out), and the automatic choice (chooseEstimator(): its pilots' time
// is added to its row's). On a backend that renders pilots at once, the
// automatic choice is also timed after an edit: hinted pilots then the
// frames, against frames rendered during the pilots (mcvol::ChoiceAhead).
// A second table gives each configuration's work
// counters per pixel and frame with its back-to-back frame time: the data
// the automatic choice's cost model (defaultCostModel()) is fitted to.

#include "BenchCommon.h"
#include "Sections.h"

#include "mcvol/EstimatorChoice.h"

#include <algorithm>
#include <cstdio>
#include <string>
#include <vector>

namespace mcvolbench
{
void runConverge(Bench& bench)
{
  const Options& o = bench.o;
  Setup& s = bench.s;
  mcvol::Renderer& r = bench.r;
  s.load(o, o.channels, o.macrocell, bench.hostAccel);
  const std::string ds = describe(o, s);
  const mcvol::Camera cam = benchCamera(o, s.scene);
  // Converged reference: many samples, another seed, in batches. With
  // --pixel-centres a second one at pixel centres, for the same
  // configurations at pixel centres (each scored against its own limit).
  mcvol::Accumulator ref;
  // Cached shadows are scored against tracked shadows: their bias counts.
  const bool cached = s.scene.view().lighting.cacheShadows;
  if (cached)
  {
    s.scene.setLighting(benchLighting(o, s.scene.numChannels(), false));
  }
  const std::vector<float> refImg = o.centresOnly ? std::vector<float>() : renderReference(o, r, s.scene, cam, ref);
  std::vector<float> refCentres;
  uint32_t refSamples = ref.samples();
  if (o.pixelCentres)
  {
    mcvol::Accumulator refC;
    mcvol::RenderSettings rc;
    rc.jitterPixels = false;
    refCentres = renderReference(o, r, s.scene, cam, refC, rc);
    refSamples = refC.samples();
  }
  if (cached)
  {
    s.scene.setLighting(benchLighting(o, s.scene.numChannels()));
  }
  std::printf("## Time to converge: %s, %dx%d, 1 spp per frame, target PSNR %.1f dB (peak 1, RGB over black) "
              "against %u spp\n\n| estimator, tracker, sampler | frames | ms (rendering only) | PSNR reached | ms per frame back to back "
              "| frames x that | one render of that many samples, ms |\n|---|---|---|---|---|---|---|\n",
    ds.c_str(), o.width, o.height, o.psnr, refSamples);
  struct Config
  {
    std::string name;
    mcvol::Estimator estimator;
    mcvol::Tracker tracker;
    mcvol::Sampler sampler;
    float minSamplesPerVoxel = 0.f;
    bool centres = false;
    float marchSamplesPerVoxel = 2.f;
    bool automatic = false;
    bool controlVariates = true; ///< RenderSettings::marchControlVariates
    bool controlAtAnyRate = false; ///< RenderSettings::marchControlVariatesFrom = 0
  };
  std::vector<Config> configs = {
    { "expected-value, sobol (default)", mcvol::Estimator::ExpectedValue, mcvol::Tracker::OneDDA,
      mcvol::Sampler::Sobol },
    { "collision, 1-DDA, sobol", mcvol::Estimator::Collision, mcvol::Tracker::OneDDA, mcvol::Sampler::Sobol },
    { "collision, N-DDA, sobol", mcvol::Estimator::Collision, mcvol::Tracker::NDDA, mcvol::Sampler::Sobol },
    { "collision, 1-DDA, independent (former default)", mcvol::Estimator::Collision, mcvol::Tracker::OneDDA,
      mcvol::Sampler::Independent },
    { "collision, N-DDA, independent", mcvol::Estimator::Collision, mcvol::Tracker::NDDA,
      mcvol::Sampler::Independent },
  };
  for (float m : o.minSamplesPerVoxel)
  {
    char name[96];
    std::snprintf(name, sizeof(name), "expected-value, sobol, >= %g tentative per voxel", double(m));
    configs.push_back({ name, mcvol::Estimator::ExpectedValue, mcvol::Tracker::OneDDA, mcvol::Sampler::Sobol, m });
  }
  for (float m : o.marchSamplesPerVoxel)
  {
    char name[96];
    std::snprintf(name, sizeof(name), "unbiased-march, sobol, %g strata per voxel", double(m));
    Config c{ name, mcvol::Estimator::UnbiasedMarch, mcvol::Tracker::OneDDA, mcvol::Sampler::Sobol };
    c.marchSamplesPerVoxel = m;
    configs.push_back(c);
  }
  {
    Config a{ "automatic", mcvol::Estimator::ExpectedValue, mcvol::Tracker::OneDDA, mcvol::Sampler::Sobol };
    a.automatic = true;
    configs.push_back(a);
  }
  if (s.scene.lit())
  {
    // A lit camera ray runs the expected-value or the collision estimator
    // (unlitEstimator() in Integrator.h; the automatic choice takes the
    // expected-value one without pilots): the unbiased-march and automatic
    // rows would repeat the collision and expected-value ones under other
    // names.
    configs.erase(std::remove_if(configs.begin(), configs.end(),
                    [](const Config& c) { return c.automatic || c.estimator == mcvol::Estimator::UnbiasedMarch; }),
      configs.end());
  }
  if (o.onlyAutomatic)
  {
    configs.erase(std::remove_if(configs.begin(), configs.end(),
                    [](const Config& c) { return !c.automatic && c.name != "expected-value, sobol (default)"; }),
      configs.end());
  }
  if (o.skipCollision)
  {
    configs.erase(std::remove_if(configs.begin(), configs.end(),
                    [](const Config& c) { return c.estimator == mcvol::Estimator::Collision; }),
      configs.end());
  }
  if (o.pixelCentres)
  {
    const size_t n = configs.size();
    for (size_t i = 0; i < n; ++i)
    {
      Config c = configs[i];
      c.name += ", pixel centres";
      c.centres = true;
      configs.push_back(c);
      if (c.estimator == mcvol::Estimator::UnbiasedMarch && !c.automatic &&
        c.marchSamplesPerVoxel >= mcvol::kMarchControlVariateRate)
      {
        // The same strata without the control variates they take there.
        c.name += ", plain strata";
        c.controlVariates = false;
        configs.push_back(c);
      }
      else if (c.estimator == mcvol::Estimator::UnbiasedMarch && !c.automatic)
      {
        // Below the rule's rate: the same strata with control variates (the
        // automatic choice offers both at pixel centres).
        c.name += ", control variates";
        c.controlAtAnyRate = true;
        configs.push_back(c);
      }
    }
  }
  if (o.centresOnly)
  {
    configs.erase(
      std::remove_if(configs.begin(), configs.end(), [](const Config& c) { return !c.centres; }), configs.end());
  }
  std::string costRows;
  std::string choiceReport;
  std::string editRows;
  for (Config config : configs)
  {
    const std::vector<float>& target = config.centres ? refCentres : refImg;
    mcvol::Accumulator acc;
    mcvol::RenderSettings st;
    st.tracker = config.tracker;
    st.estimator = config.estimator;
    st.sampler = config.sampler;
    st.minSamplesPerVoxel = config.minSamplesPerVoxel;
    st.marchSamplesPerVoxel = config.marchSamplesPerVoxel;
    st.jitterPixels = !config.centres;
    st.marchControlVariates = config.controlVariates;
    st.marchControlVariatesFrom = config.controlAtAnyRate ? 0.f : mcvol::kMarchControlVariateRate;
    st.seed = 7;
    st.readBack = false;
    double pilotMs = 0;
    const mcvol::RenderSettings unchosen = st;
    mcvol::EstimatorChoiceSettings cs;
    mcvol::EstimatorChoice choice;
    if (config.automatic)
    {
      r.finish();
      const auto t0 = Clock::now();
      cs.tryAllRates = o.choiceAll;
      if (!o.marchSamplesPerVoxel.empty() && o.choiceAll)
      {
        cs.marchRates = o.marchSamplesPerVoxel; // predictions for the rows measured
      }
      if (!o.costModel.empty())
      {
        cs.customModel = true;
        cs.model.perRay = o.costModel[0];
        cs.model.perDdaStep = o.costModel[1];
        cs.model.perTentative = o.costModel[2];
        cs.model.perChannelSample = o.costModel[3];
      }
      choice = mcvol::chooseEstimator(r, s.scene, cam, st, cs);
      r.finish();
      pilotMs = 1e3 * seconds(t0);
      st = choice.settings;
      config.name = "automatic: " + choice.chosenName() + " (pilots " + std::to_string(pilotMs).substr(0, 5) +
        " ms, included)";
      choiceReport = choice.report();
    }
    // Warm-up on a throw-away accumulator, then timed frames; the PSNR is
    // checked between frames (not timed).
    {
      mcvol::Accumulator w;
      for (int i = 0; i < 5; ++i)
      {
        r.render(s.scene, cam, st, nullptr, w);
      }
      r.finish();
    }
    double ms = pilotMs;
    double q = 0;
    int frames = 0;
    while (frames < o.maxConvergeFrames)
    {
      const auto t0 = Clock::now();
      r.render(s.scene, cam, st, nullptr, acc);
      r.finish();
      ms += 1e3 * seconds(t0);
      ++frames;
      r.readBack(acc);
      q = psnrOf(acc, target);
      if (q >= o.psnr)
      {
        break;
      }
    }
    // The loop above syncs and reads back after every frame (to score it),
    // and the GPU clocks down in the gaps; frames rendered back to back, as
    // an application draws them, cost this (after a warm-up, so that the
    // figure is the steady state's, as the frame-rate section's is):
    const int steady = std::max(1, o.steadyFrames);
    {
      mcvol::Accumulator w;
      for (int i = 0; i < 50; ++i)
      {
        r.render(s.scene, cam, st, nullptr, w);
      }
      r.finish();
      w.reset();
      const auto t0 = Clock::now();
      for (int i = 0; i < steady; ++i)
      {
        r.render(s.scene, cam, st, nullptr, w);
      }
      r.finish();
      const double per = 1e3 * seconds(t0) / steady;
      // The work of one frame, per pixel (for the cost model's fit).
      mcvol::RenderCounters rc;
      w.reset();
      mcvol::RenderSettings sc = st;
      sc.readBack = true;
      r.render(s.scene, cam, sc, nullptr, w, &rc);
      const double px = double(cam.width) * double(cam.height);
      char line[256];
      std::snprintf(line, sizeof(line), "| %s | %.4f | %.3f | %.3f | %.3f | %.3f |\n", config.name.c_str(),
        double(rc.rays) / px, double(rc.ddaSteps) / px, double(rc.tentativeCollisions) / px,
        double(rc.channelSamples) / px, per);
      costRows += line;
      // A still image asked for at once (pvbatch, a saved screenshot): the
      // same samples in one render, which a backend may trace several at a
      // time. Median of 5 after a warm-up.
      double still = 0;
      {
        mcvol::RenderSettings sa = st;
        sa.samplesPerPixel = frames;
        std::vector<double> t;
        for (int i = 0; i < 6; ++i)
        {
          w.reset();
          const auto t1 = Clock::now();
          r.render(s.scene, cam, sa, nullptr, w);
          r.finish();
          if (i > 0)
          {
            t.push_back(1e3 * seconds(t1));
          }
        }
        still = median(t);
      }
      std::printf("| %s | %d | %.2f | %.2f | %.3f | %.2f | %.2f |\n", config.name.c_str(), frames, ms, q, per,
        per * frames, still);
      bench.row("converge", ds, s.volume.numChannels(), o.macrocell, config.name, ms, "ms",
        "frames=" + std::to_string(frames) + " psnr=" + std::to_string(q) +
          " back_to_back_ms_per_frame=" + std::to_string(per) + " one_render_ms=" + std::to_string(still));
    }
    if (config.automatic && choice.applies && r.rendersPilotsAtOnce() && !o.choiceAll)
    {
      // A transfer-function edit on a warm renderer, as the mapper handles
      // it: the choice made again with the previous one's candidates as the
      // hint, then the frames the loop above needed, back to back; against
      // the same with the previous choice's first frame, or all of them,
      // rendered during the pilots (mcvol::ChoiceAhead). Wall time from the
      // pilots' start to the last frame's end, median of 5; the PSNR of
      // each way's image checked after the timing.
      mcvol::EstimatorChoiceSettings hinted = cs;
      hinted.hint = choice.hint();
      const char* ways[3] = { "hinted pilots, then the frames", "the first frame rendered during the pilots",
        "every frame rendered during the pilots" };
      for (int way = 0; way < 3; ++way)
      {
        std::vector<double> t;
        double reached = 0;
        bool kept = true;
        for (int run = 0; run < 6; ++run)
        {
          mcvol::Accumulator a;
          a.resize(cam.width, cam.height); // an application's image is sized before the edit
          mcvol::ChoiceAhead ahead;
          ahead.candidate = choice.chosenCandidate();
          ahead.renders = way == 1 ? 1 : frames;
          ahead.accum = way == 0 ? nullptr : &a; // null: nothing rendered ahead
          r.finish();
          const auto t0 = Clock::now();
          const mcvol::EstimatorChoice c = mcvol::chooseEstimator(r, s.scene, cam, unchosen, hinted, ahead);
          for (int f = ahead.kept ? ahead.renders : 0; f < frames; ++f)
          {
            r.render(s.scene, cam, c.settings, nullptr, a);
          }
          r.finish();
          if (run > 0) // the first run warms the hinted round's path
          {
            t.push_back(1e3 * seconds(t0));
          }
          kept = kept && (way == 0 || ahead.kept);
          r.readBack(a);
          reached = psnrOf(a, target);
        }
        std::string runs;
        for (double x : t)
        {
          char b[32];
          std::snprintf(b, sizeof(b), "%s%.2f", runs.empty() ? "" : " / ", x);
          runs += b;
        }
        char line[512];
        std::snprintf(line, sizeof(line), "| %s | %s | %d | %s | **%.2f** | %.2f | %s |\n", config.centres ? "centres" : "jittered",
          ways[way], frames, runs.c_str(), median(t), reached, way == 0 ? "-" : (kept ? "yes" : "**no**"));
        editRows += line;
        bench.row("converge-after-edit", ds, s.volume.numChannels(), o.macrocell,
          std::string(config.centres ? "centres, " : "jittered, ") + ways[way], median(t), "ms",
          "frames=" + std::to_string(frames) + " psnr=" + std::to_string(reached) + " kept=" + (kept ? "1" : "0"));
      }
    }
    std::fflush(stdout);
  }
  if (!editRows.empty())
  {
    std::printf("\nAfter an edit (warm renderer, the automatic choice made again with the previous one's hint), "
                "time to the target: the pilots' start to the last frame's end (median of 5; PSNR checked after):\n\n"
                "| pixels | way | frames | ms (5 runs) | median ms | PSNR | frames ahead kept |\n"
                "|---|---|---|---|---|---|---|\n%s",
      editRows.c_str());
  }
  std::printf("\nWork per pixel and frame (the automatic choice's cost model is fitted to these):\n\n"
              "| configuration | rays | DDA steps | tentative | channel samples | ms per frame |\n"
              "|---|---|---|---|---|---|\n%s\n",
    costRows.c_str());
  if (!choiceReport.empty())
  {
    std::printf("Automatic choice's pilots:\n\n```\n%s```\n\n", choiceReport.c_str());
  }
}
} // namespace mcvolbench
