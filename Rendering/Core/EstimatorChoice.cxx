// SPDX-License-Identifier: BSD-3-Clause
#include "mcvol/EstimatorChoice.h"

#include "mcvol/Integrator.h"
#include "mcvol/RenderSetup.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <stdexcept>

namespace mcvol
{
double CostModel::cost(const RenderCounters& c) const
{
  return this->perRay * double(c.rays) + this->perDdaStep * double(c.ddaSteps) +
    this->perTentative * double(c.tentativeCollisions) + this->perChannelSample * double(c.channelSamples);
}

CostModel defaultCostModel(const std::string& backendName)
{
  // Fitted by Benchmarks/fit_cost_model.py to the frame times of
  // `mcvol-bench --sections converge` on the four paper-sized datasets at
  // 1024^2 (CUDA, H100) and on the four demo datasets at 256^2 (CPU, 2
  // cores): Benchmarks/RESULTS.md, "The automatic estimator". The fit keeps
  // the weights non-negative; the per-ray weight came out 0 on both (the
  // DDA steps carry the per-ray cost).
  CostModel m;
  if (backendName == "cuda")
  {
    m.perRay = 0.0;
    m.perDdaStep = 0.02527;
    m.perTentative = 0.05904;
    m.perChannelSample = 0.01309;
    return m;
  }
  m.perRay = 0.0;
  m.perDdaStep = 34.42;
  m.perTentative = 11.61;
  m.perChannelSample = 10.57;
  return m;
}

Estimator effectiveEstimator(const Scene& scene, const RenderSettings& settings)
{
  switch (unlitEstimator(settings.estimator, scene.blendMode(), scene.lit(), scene.optimized()))
  {
    case 1:
      return Estimator::ExpectedValue;
    case 2:
    case 3:
      return Estimator::UnbiasedMarch;
    default:
      return Estimator::Collision;
  }
}

std::string estimatorName(Estimator estimator, float marchSamplesPerVoxel, bool controlVariates)
{
  if (estimator == Estimator::UnbiasedMarch)
  {
    char buf[64];
    std::snprintf(buf, sizeof(buf), "UnbiasedMarch(%g%s)", double(marchSamplesPerVoxel),
      controlVariates ? ", control variates" : "");
    return buf;
  }
  return estimator == Estimator::ExpectedValue ? "ExpectedValue" : "Collision";
}

namespace
{
std::string candidateName(const EstimatorCandidate& c)
{
  return estimatorName(c.estimator, c.marchSamplesPerVoxel, c.controlVariates);
}

bool sameCandidate(const EstimatorCandidate& a, const EstimatorCandidate& b)
{
  return a.estimator == b.estimator && a.marchSamplesPerVoxel == b.marchSamplesPerVoxel &&
    a.controlVariates == b.controlVariates;
}
} // namespace

EstimatorCandidate EstimatorChoice::chosenCandidate() const
{
  if (this->chosen < 0 || size_t(this->chosen) >= this->trials.size())
  {
    EstimatorCandidate c;
    c.marchSamplesPerVoxel = this->settings.marchSamplesPerVoxel;
    return c;
  }
  return this->trials[size_t(this->chosen)].candidate;
}

std::string EstimatorChoice::chosenName() const
{
  if (this->chosen < 0)
  {
    EstimatorCandidate c;
    c.estimator = this->settings.estimator;
    c.marchSamplesPerVoxel = this->settings.marchSamplesPerVoxel;
    return candidateName(c);
  }
  return candidateName(this->trials[size_t(this->chosen)].candidate);
}

std::vector<EstimatorCandidate> EstimatorChoice::hint() const
{
  std::vector<EstimatorCandidate> h;
  for (const EstimatorTrial& t : this->trials)
  {
    h.push_back(t.candidate);
  }
  return h;
}

std::string EstimatorChoice::report() const
{
  if (!this->applies)
  {
    return "estimator choice: not needed (lit, optimized or composite: the collision estimator)\n";
  }
  std::string out;
  char line[256];
  for (size_t i = 0; i < this->trials.size(); ++i)
  {
    const EstimatorTrial& t = this->trials[i];
    std::snprintf(line, sizeof(line), "%s %-38s MSE(1) %.4g  MSE(%d) %.4g  decay %.2f  frames %g  cost/sample %.4g  predicted %.4g%s\n",
      int(i) == this->chosen ? "*" : " ", candidateName(t.candidate).c_str(), t.firstFrameMSE, t.pilotSamples,
      t.pilotSamples > 0 ? t.variance / double(t.pilotSamples) : 0.0, t.decay, t.frames,
      t.costPerSample, t.score, t.refined ? "  (between listed rates)" : "");
    out += line;
  }
  std::snprintf(line, sizeof(line), "pilots took %.1f ms (%d rounds, %d candidates rendered)\n", 1e3 * this->seconds,
    this->rounds, this->rendered);
  out += line;
  return out;
}

RenderSettings candidateSettings(const RenderSettings& base, const Camera& camera, const EstimatorCandidate& c)
{
  RenderSettings st = base;
  st.estimator = c.estimator;
  st.marchSamplesPerVoxel = c.marchSamplesPerVoxel;
  if (c.estimator == Estimator::UnbiasedMarch && pixelCentres(base, camera))
  {
    st.marchControlVariates = c.controlVariates;
    st.marchControlVariatesFrom = c.controlVariates ? 0.f : base.marchControlVariatesFrom;
  }
  return st;
}

namespace
{
/// Mean over pixels and premultiplied R, G, B of the squared difference.
double meanSquaredDifference(const float* x, const float* y, int width, int height)
{
  const size_t n = size_t(width) * size_t(height);
  double sum = 0;
  for (size_t p = 0; p < n; ++p)
  {
    for (int c = 0; c < 3; ++c)
    {
      const double d = double(x[4 * p + size_t(c)]) - double(y[4 * p + size_t(c)]);
      sum += d * d;
    }
  }
  return n > 0 ? sum / double(3 * n) : 0.0;
}
} // namespace

void Renderer::renderPilots(const Scene& scene, const Camera& camera, std::vector<PilotJob>& jobs)
{
  for (const PilotJob& job : jobs)
  {
    checkPilotCheckpoints(job);
  }
  for (PilotJob& job : jobs)
  {
    RenderSettings st = job.settings;
    st.readBack = true;
    job.counters = RenderCounters();
    for (int r = 0; r < 2; ++r)
    {
      st.seed = job.seeds[r];
      Accumulator rep;
      rep.setErrorEstimation(false);
      rep.resize(camera.width, camera.height);
      rep.reset();
      job.means[r].clear();
      int done = 0;
      for (int upTo : job.checkpoints)
      {
        st.samplesPerPixel = upTo - done;
        this->render(scene, camera, st, nullptr, rep, r == 0 ? &job.counters : nullptr);
        done = upTo;
        job.means[r].emplace_back(rep.rgba(), rep.rgba() + 4 * size_t(camera.width) * size_t(camera.height));
      }
    }
  }
}

Camera pilotCamera(const Camera& camera, int pilotSize)
{
  Camera pilot = camera;
  const int longer = std::max(camera.width, camera.height);
  const int size = std::max(1, pilotSize);
  if (longer > size)
  {
    const double f = double(size) / double(longer);
    pilot.width = std::max(1, int(std::lround(camera.width * f)));
    pilot.height = std::max(1, int(std::lround(camera.height * f)));
    // Jitter over one image pixel's footprint: the image's own
    // anti-aliasing noise, which every candidate pays alike.
    pilot.jitterScale = float(camera.jitterScale * std::min(double(pilot.width) / double(camera.width),
                                                      double(pilot.height) / double(camera.height)));
  }
  return pilot;
}

namespace
{
EstimatorChoice choose(Renderer& renderer, const Scene& scene, const Camera& camera, const RenderSettings& base,
  const EstimatorChoiceSettings& choice, ChoiceAhead* frames)
{
  if (choice.pilotSamples < 2)
  {
    throw std::invalid_argument("mcvol: chooseEstimator needs at least 2 pilot samples per pixel");
  }
  if (!(choice.targetMSE > 0) || !std::isfinite(choice.targetMSE))
  {
    throw std::invalid_argument("mcvol: chooseEstimator's target MSE must be positive and finite");
  }
  if (!(choice.refineMargin > 0 && choice.refineMargin <= 1))
  {
    throw std::invalid_argument("mcvol: chooseEstimator's refine margin must be in (0, 1]");
  }
  for (float r : choice.marchRates)
  {
    if (!(r > 0.f) || !std::isfinite(r))
    {
      throw std::invalid_argument("mcvol: chooseEstimator's march rates must be positive and finite");
    }
  }
  EstimatorChoice out;
  out.settings = base;
  RenderSettings probe = base;
  probe.estimator = Estimator::ExpectedValue;
  if (effectiveEstimator(scene, probe) == Estimator::Collision)
  {
    return out; // the estimator setting does not reach these renders
  }
  out.applies = true;
  if (frames && frames->accum && renderer.rendersPilotsAtOnce())
  {
    // The frames go first: queued on the device, they run while the pilots
    // below are issued on streams that do not wait for them.
    RenderSettings st = candidateSettings(base, camera, frames->candidate);
    st.readBack = false;
    for (int i = 0; i < frames->renders; ++i)
    {
      renderer.render(scene, camera, st, frames->depth, *frames->accum);
    }
    frames->rendered = true;
  }
  const auto start = std::chrono::steady_clock::now();

  const Camera pilot = pilotCamera(camera, choice.pilotSize);
  const double pixels = double(pilot.width) * double(pilot.height);

  // At pixel centres the march is offered with and without its control
  // variates at every rate (the plain strata may reach a loose target in one
  // cheaper frame, the control variates a tight one, or a dense set's target
  // in fewer samples even below kMarchControlVariateRate), unless the
  // settings fix the variant: marchControlVariates off keeps the plain
  // strata, marchControlVariatesFrom 0 the control variates.
  const bool centres = pixelCentres(base, camera);
  const bool offerPlain = !centres || !base.marchControlVariates || base.marchControlVariatesFrom > 0.f;
  const bool offerControl = centres && base.marchControlVariates;
  std::vector<EstimatorCandidate> candidates;
  {
    EstimatorCandidate ev;
    ev.estimator = Estimator::ExpectedValue;
    ev.marchSamplesPerVoxel = base.marchSamplesPerVoxel;
    candidates.push_back(ev);
  }
  std::vector<float> rates = choice.marchRates;
  std::sort(rates.begin(), rates.end());
  for (float r : rates)
  {
    for (int variant = 0; variant < 2; ++variant)
    {
      if (variant == 0 ? !offerPlain : !offerControl)
      {
        continue;
      }
      EstimatorCandidate m;
      m.estimator = Estimator::UnbiasedMarch;
      m.marchSamplesPerVoxel = r;
      m.controlVariates = variant == 1;
      candidates.push_back(m);
    }
  }

  const CostModel model = choice.customModel ? choice.model : defaultCostModel(renderer.name());
  // Replicate seeds: fixed functions of the image's seed (any two distinct
  // seeds scramble independently).
  const uint32_t seeds[2] = { base.seed * 2654435761u + 0x2545F491u, base.seed * 2654435761u + 0x9E3779B9u };
  // A candidate's pilot: each replicate rendered in doublings (1, 2, 4, ...
  // samples per pixel, up to the candidate's pilot samples), and the
  // replicates' mean squared difference taken at each: MSE(1), MSE(2),
  // MSE(4), ... With Sobol' points a pixel's samples are negatively
  // correlated, so n MSE(n) understates the noise of a single sample: the
  // 1-sample images decide whether one frame suffices, the later ones
  // predict the frames beyond.
  const auto pilotJob = [&](const EstimatorCandidate& c) {
    PilotJob job;
    job.settings = candidateSettings(base, camera, c);
    job.seeds[0] = seeds[0];
    job.seeds[1] = seeds[1];
    const int samples = c.estimator == Estimator::ExpectedValue
      ? std::max(choice.pilotSamples, choice.expectedValuePilotSamples)
      : choice.pilotSamples;
    for (int k = 1; k < samples; k *= 2)
    {
      job.checkpoints.push_back(k);
    }
    job.checkpoints.push_back(samples);
    return job;
  };
  const auto trialOf = [&](const EstimatorCandidate& c, const PilotJob& job) {
    const std::vector<int>& checkpoints = job.checkpoints;
    const int samples = checkpoints.back();
    const std::vector<std::vector<float>>* images = job.means;
    const RenderCounters& counters = job.counters;
    // E[(m1 - m2)^2] = 2 MSE(n) for independent replicates of an n-sample mean.
    std::vector<double> mse(checkpoints.size());
    for (size_t i = 0; i < checkpoints.size(); ++i)
    {
      mse[i] = 0.5 * meanSquaredDifference(images[0][i].data(), images[1][i].data(), pilot.width, pilot.height);
    }
    EstimatorTrial t;
    t.candidate = c;
    t.counters = counters;
    t.pilotSamples = samples;
    t.firstFrameMSE = mse[0];
    t.variance = mse.back() * double(samples);
    // The decay between two checkpoints: MSE(N) ~ N^-a, held to [1, 2] (1:
    // independent samples; Sobol' points fall faster, and their gain fades
    // as N grows, so the last doubling is the one to extrapolate with).
    const auto decayBetween = [&](size_t i) {
      double a = 1.0;
      if (mse[i] > 0 && mse[i - 1] > mse[i])
      {
        a = std::log(mse[i - 1] / mse[i]) / std::log(double(checkpoints[i]) / double(checkpoints[i - 1]));
      }
      return std::min(2.0, std::max(1.0, a));
    };
    t.decay = decayBetween(checkpoints.size() - 1);
    if (mse[0] <= choice.targetMSE)
    {
      t.frames = 1.0;
    }
    else
    {
      // The first checkpoint at or below the target bounds the frames; they
      // are interpolated from the checkpoint before it with that doubling's
      // decay, or extrapolated from the last checkpoint with its decay.
      size_t i = 1;
      while (i < checkpoints.size() && mse[i] > choice.targetMSE)
      {
        ++i;
      }
      const size_t from = i < checkpoints.size() ? i - 1 : checkpoints.size() - 1;
      const double a = decayBetween(i < checkpoints.size() ? i : checkpoints.size() - 1);
      double f = std::ceil(double(checkpoints[from]) * std::pow(mse[from] / choice.targetMSE, 1.0 / a) - 1e-9);
      f = std::max(f, double(checkpoints[from] + 1));
      if (i < checkpoints.size())
      {
        f = std::min(f, double(checkpoints[i]));
      }
      t.frames = f;
    }
    t.costPerSample = model.cost(counters) / (pixels * double(samples));
    t.score = t.frames * t.costPerSample;
    return t;
  };

  // The pilots run in rounds (Renderer::renderPilots: a device backend
  // renders a round's samples all at once): first expected value and the
  // lowest rate of each offered variant, which every search renders, then
  // the candidate the stop rule below reaches next. A backend that renders
  // a round at once (Renderer::rendersPilotsAtOnce) also gets, in that
  // round, the variants' higher rates the search will reach if the best
  // prediction so far stays: each rate whose predecessor in its variant
  // costs less per sample than that best (known where the predecessor was
  // tried, else extrapolated in proportion to the rate, which overstates a
  // cost with a fixed part per ray), at most kMaxRound; and both variants'
  // rates between (below) share a round. The search itself is unchanged: it
  // takes a rendered result only where it reaches that candidate, so the
  // trials and the choice are those of the pilots one after the other; a
  // rate rendered ahead and not reached costs only its share of the round.
  std::vector<EstimatorTrial> results(candidates.size());
  std::vector<char> have(candidates.size(), 0);
  const bool ahead = renderer.rendersPilotsAtOnce() && !choice.tryAllRates;
  constexpr size_t kMaxRound = 8;       // a later round: the candidate and those ahead
  constexpr size_t kMaxFirstRound = 16; // the first round with the hint
  // Rates between two listed ones rendered ahead from the hint (below), for
  // the refinement to take where it plans the same rate.
  std::vector<EstimatorTrial> hinted;
  // One renderPilots() call (a round) of these candidates, and their trials.
  const auto renderRound = [&](const std::vector<EstimatorCandidate>& cs) {
    std::vector<PilotJob> jobs;
    for (const EstimatorCandidate& c : cs)
    {
      jobs.push_back(pilotJob(c));
    }
    renderer.renderPilots(scene, pilot, jobs);
    ++out.rounds;
    out.rendered += int(jobs.size());
    std::vector<EstimatorTrial> trials;
    for (size_t k = 0; k < cs.size(); ++k)
    {
      trials.push_back(trialOf(cs[k], jobs[k]));
    }
    return trials;
  };
  // The listed candidates `round` and the hinted rates between `extra`.
  const auto runRound = [&](const std::vector<size_t>& round, const std::vector<EstimatorCandidate>& extra) {
    std::vector<EstimatorCandidate> cs;
    for (size_t i : round)
    {
      cs.push_back(candidates[i]);
    }
    cs.insert(cs.end(), extra.begin(), extra.end());
    const std::vector<EstimatorTrial> trials = renderRound(cs);
    for (size_t k = 0; k < round.size(); ++k)
    {
      results[round[k]] = trials[k];
      have[round[k]] = 1;
    }
    hinted.insert(hinted.end(), trials.begin() + std::ptrdiff_t(round.size()), trials.end());
  };
  {
    std::vector<size_t> round;
    bool seen[2] = { false, false };
    for (size_t i = 0; i < candidates.size(); ++i)
    {
      const EstimatorCandidate& c = candidates[i];
      const int variant = c.controlVariates ? 1 : 0;
      if (c.estimator != Estimator::UnbiasedMarch || !seen[variant])
      {
        round.push_back(i);
        seen[variant] = seen[variant] || c.estimator == Estimator::UnbiasedMarch;
      }
    }
    // The hint (e.g. the previous choice's trials, EstimatorChoiceSettings::
    // hint) joins the first round where the backend renders at once: the
    // search will likely reach the same candidates again, and what it does
    // not reach costs only its share of the round.
    std::vector<EstimatorCandidate> extra;
    if (ahead)
    {
      for (const EstimatorCandidate& h : choice.hint)
      {
        if (round.size() + extra.size() >= kMaxFirstRound)
        {
          break;
        }
        if (h.estimator != Estimator::UnbiasedMarch || (h.controlVariates ? !offerControl : !offerPlain) ||
          !(h.marchSamplesPerVoxel > 0.f) || !std::isfinite(h.marchSamplesPerVoxel))
        {
          continue;
        }
        const auto listed = std::find_if(candidates.begin(), candidates.end(),
          [&](const EstimatorCandidate& c) { return sameCandidate(c, h); });
        if (listed != candidates.end())
        {
          const size_t k = size_t(listed - candidates.begin());
          if (std::find(round.begin(), round.end(), k) == round.end())
          {
            round.push_back(k);
          }
        }
        else if (std::none_of(
                   extra.begin(), extra.end(), [&](const EstimatorCandidate& e) { return sameCandidate(e, h); }))
        {
          extra.push_back(h);
        }
      }
    }
    runRound(round, extra);
  }
  double best = 0;
  // The last trial of each march variant (plain, control variates), for the
  // stop rule; -1: none yet.
  int lastOf[2] = { -1, -1 };
  for (size_t i = 0; i < candidates.size(); ++i)
  {
    const EstimatorCandidate& c = candidates[i];
    const int variant = c.controlVariates ? 1 : 0;
    if (!choice.tryAllRates && c.estimator == Estimator::UnbiasedMarch && lastOf[variant] >= 0)
    {
      // A higher rate of the same variant costs at least as much per sample
      // and takes at least one: no better than `best` once the variant's
      // last rate's sample cost that. (No stop where a prediction merely
      // rose: at the lowest rates the majorant's strata floor keeps the
      // noise nearly flat, and the prediction's own noise made one rise there
      // on the Zebrafish-like set, stopping the search before the rate that
      // won 4x.)
      if (out.trials[size_t(lastOf[variant])].costPerSample >= best)
      {
        continue;
      }
    }
    if (!have[i])
    {
      std::vector<size_t> round = { i };
      if (ahead)
      {
        // The search reaches a later rate of a variant while the cost per
        // sample of the variant's rate before it is below `best` (the stop
        // rule above). That cost is known for a rate already tried; for one
        // in this round it is extrapolated from the variant's last known
        // rate in proportion to the rate (an upper bound where the cost has
        // a fixed part per ray).
        double lastCost[2] = { -1, -1 }, lastRate[2] = { 0, 0 };
        for (int v = 0; v < 2; ++v)
        {
          if (lastOf[v] >= 0)
          {
            lastCost[v] = out.trials[size_t(lastOf[v])].costPerSample;
            lastRate[v] = out.trials[size_t(lastOf[v])].candidate.marchSamplesPerVoxel;
          }
        }
        const auto step = [&](size_t k) {
          // Candidate k joins the chain of its variant (known or predicted).
          const EstimatorCandidate& d = candidates[k];
          const int v = d.controlVariates ? 1 : 0;
          if (have[k])
          {
            lastCost[v] = results[k].costPerSample;
          }
          else if (lastCost[v] >= 0)
          {
            lastCost[v] *= double(d.marchSamplesPerVoxel) / lastRate[v];
          }
          lastRate[v] = d.marchSamplesPerVoxel;
        };
        if (c.estimator == Estimator::UnbiasedMarch)
        {
          step(i);
        }
        bool open[2] = { true, true };
        for (size_t k = i + 1; k < candidates.size() && round.size() < kMaxRound; ++k)
        {
          const EstimatorCandidate& d = candidates[k];
          const int v = d.controlVariates ? 1 : 0;
          if (d.estimator != Estimator::UnbiasedMarch || !open[v] || lastCost[v] < 0)
          {
            continue;
          }
          if (!(lastCost[v] < best))
          {
            open[v] = false; // the search stops this variant before d
            continue;
          }
          if (!have[k])
          {
            round.push_back(k);
          }
          step(k);
        }
      }
      runRound(round, {});
    }
    out.trials.push_back(results[i]);
    if (c.estimator == Estimator::UnbiasedMarch)
    {
      lastOf[variant] = int(out.trials.size()) - 1;
    }
    best = out.trials.size() == 1 ? out.trials.back().score : std::min(best, out.trials.back().score);
  }

  // Between two rates of a variant, the lower needing more than one frame and
  // the next one, it: a rate in between may reach the target in one frame for
  // less. Where the interpolation's cost is predicted below the best, the
  // rate where the one-frame MSE is predicted to meet refineMargin x the
  // target (log-log interpolation of MSE(1) in the rate, rounded up to
  // kChoiceRateStep) gets a pilot of its own, and competes like the others
  // (one frame only if its pilot is within the margin too). Whole frames make the
  // choice jump at such a boundary: on the CPU target's scene the pilots put
  // 1 per voxel's MSE(1) 1% over RMSE 0.01's, predicted 2 frames and took
  // 1.25 per voxel, 19% dearer (Benchmarks/RESULTS.md, "Fourteenth session").
  if (choice.refineRates)
  {
    // Each variant's rate between (at most one), planned from the scanned
    // trials; `cost` is its interpolated cost per sample.
    struct Between
    {
      EstimatorCandidate candidate;
      double cost = 0;
      double aim = 0;
    };
    const size_t scanned = out.trials.size();
    const auto plan = [&](int variant, Between& between) {
      int lo = -1;
      for (size_t i = 0; i < scanned; ++i)
      {
        const EstimatorTrial& t = out.trials[i];
        if (t.candidate.estimator != Estimator::UnbiasedMarch || int(t.candidate.controlVariates) != variant)
        {
          continue;
        }
        if (t.frames > 1.0)
        {
          lo = int(i);
          continue;
        }
        if (lo < 0)
        {
          return false; // the lowest rate already takes one frame
        }
        const EstimatorTrial& a = out.trials[size_t(lo)];
        const double r0 = a.candidate.marchSamplesPerVoxel, r1 = t.candidate.marchSamplesPerVoxel;
        if (!(a.firstFrameMSE > choice.targetMSE && t.firstFrameMSE > 0 && t.firstFrameMSE < a.firstFrameMSE))
        {
          return false;
        }
        const double slope = std::log(a.firstFrameMSE / t.firstFrameMSE) / std::log(r1 / r0);
        between.aim = choice.refineMargin * choice.targetMSE;
        double r = r0 * std::pow(a.firstFrameMSE / between.aim, 1.0 / slope);
        r = std::ceil(r / kChoiceRateStep - 1e-9) * kChoiceRateStep;
        between.cost = a.costPerSample + (r - r0) / (r1 - r0) * (t.costPerSample - a.costPerSample);
        between.candidate = t.candidate;
        between.candidate.marchSamplesPerVoxel = float(r);
        return r > r0 && r < r1 && between.cost < best;
      }
      return false;
    };
    // Variant by variant, as the search takes them: a variant's rate
    // between is tried where its interpolated cost is below the best so far,
    // the first variant's between included. Where the backend renders at
    // once, both variants' are rendered in one round and the second's result
    // is dropped where the first's lowered `best` below its cost.
    Between planned[2];
    bool wanted[2] = { plan(0, planned[0]), false };
    EstimatorTrial tried[2];
    bool done[2] = { false, false };
    const auto fromHint = [&](int v) {
      for (const EstimatorTrial& h : hinted)
      {
        if (sameCandidate(h.candidate, planned[v].candidate))
        {
          tried[v] = h;
          done[v] = true;
          break;
        }
      }
      return done[v];
    };
    if (ahead)
    {
      wanted[1] = plan(1, planned[1]);
      std::vector<EstimatorCandidate> round;
      std::vector<int> of;
      for (int v = 0; v < 2; ++v)
      {
        if (wanted[v] && !fromHint(v))
        {
          round.push_back(planned[v].candidate);
          of.push_back(v);
        }
      }
      if (!round.empty())
      {
        const std::vector<EstimatorTrial> trials = renderRound(round);
        for (size_t k = 0; k < trials.size(); ++k)
        {
          tried[of[k]] = trials[k];
          done[of[k]] = true;
        }
      }
    }
    for (int variant = 0; variant < 2; ++variant)
    {
      if (variant == 1 && !ahead)
      {
        wanted[1] = plan(1, planned[1]);
      }
      if (!wanted[variant] || !(planned[variant].cost < best))
      {
        continue;
      }
      if (!done[variant])
      {
        tried[variant] = renderRound({ planned[variant].candidate }).front();
      }
      EstimatorTrial between = tried[variant];
      between.refined = true;
      if (between.firstFrameMSE > planned[variant].aim)
      {
        between.frames = std::max(between.frames, 2.0);
        between.score = between.frames * between.costPerSample;
      }
      out.trials.push_back(between);
      best = std::min(best, between.score);
    }
  }

  // The lowest prediction; ties (e.g. nothing visible: one frame each) go to
  // the earlier candidate, the expected-value estimator first.
  out.chosen = 0;
  for (size_t i = 1; i < out.trials.size(); ++i)
  {
    if (out.trials[i].score < out.trials[size_t(out.chosen)].score)
    {
      out.chosen = int(i);
    }
  }
  out.settings = candidateSettings(base, camera, out.trials[size_t(out.chosen)].candidate);
  out.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  if (frames && frames->rendered)
  {
    frames->kept = sameCandidate(out.trials[size_t(out.chosen)].candidate, frames->candidate);
    if (!frames->kept)
    {
      frames->accum->reset(); // the next render starts the image anew, on the device too
    }
  }
  return out;
}
} // namespace

EstimatorChoice chooseEstimator(Renderer& renderer, const Scene& scene, const Camera& camera,
  const RenderSettings& base, const EstimatorChoiceSettings& choice)
{
  return choose(renderer, scene, camera, base, choice, nullptr);
}

EstimatorChoice chooseEstimator(Renderer& renderer, const Scene& scene, const Camera& camera,
  const RenderSettings& base, const EstimatorChoiceSettings& choice, ChoiceAhead& ahead)
{
  ahead.rendered = false;
  ahead.kept = false;
  if (ahead.renders < 1)
  {
    throw std::invalid_argument("mcvol: ChoiceAhead::renders must be at least 1");
  }
  if (ahead.accum && ahead.accum->samples() != 0)
  {
    throw std::invalid_argument(
      "mcvol: ChoiceAhead::accum must hold no samples (the frames rendered ahead are the image's first)");
  }
  return choose(renderer, scene, camera, base, choice, &ahead);
}
} // namespace mcvol
