// SPDX-License-Identifier: BSD-3-Clause
//
// chooseEstimator(): list the candidates, render their pilots in rounds,
// search the listed march rates and the rates between them, and keep the
// lowest predicted time to the target. The steps live beside this file
// (ChoiceSteps.h lists them).
#include "ChoiceSteps.h"

#include <chrono>
#include <cstdio>
#include <stdexcept>
#include <utility>

namespace mcvol
{
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
    return detail::candidateName(c);
  }
  return detail::candidateName(this->trials[size_t(this->chosen)].candidate);
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
    return "estimator choice: not needed (lit: the expected-value estimator; optimized or composite: the "
           "collision estimator)\n";
  }
  std::string out;
  char line[256];
  for (size_t i = 0; i < this->trials.size(); ++i)
  {
    const EstimatorTrial& t = this->trials[i];
    std::snprintf(line, sizeof(line),
      "%s %-38s MSE(1) %.4g  MSE(%d) %.4g  decay %.2f  frames %g  cost/sample %.4g  predicted %.4g%s\n",
      int(i) == this->chosen ? "*" : " ", detail::candidateName(t.candidate).c_str(), t.firstFrameMSE, t.pilotSamples,
      t.pilotSamples > 0 ? t.variance / double(t.pilotSamples) : 0.0, t.decay, t.frames, t.costPerSample, t.score,
      t.refined ? "  (between listed rates)" : "");
    out += line;
  }
  std::snprintf(line, sizeof(line), "pilots took %.1f ms (%d rounds, %d candidates rendered)\n", 1e3 * this->seconds,
    this->rounds, this->rendered);
  out += line;
  return out;
}

namespace
{
/// ChoiceAhead's frames, queued first: on a device they run while the
/// pilots are issued on streams that do not wait for them.
void renderFramesAhead(
  Renderer& renderer, const Scene& scene, const Camera& camera, const RenderSettings& base, ChoiceAhead& frames)
{
  RenderSettings st = candidateSettings(base, camera, frames.candidate);
  st.readBack = false;
  for (int i = 0; i < frames.renders; ++i)
  {
    renderer.render(scene, camera, st, frames.depth, *frames.accum);
  }
  frames.rendered = true;
}

/// The lowest prediction; ties (e.g. nothing visible: one frame each) go to
/// the earlier candidate, the expected-value estimator first.
int lowestScore(const std::vector<EstimatorTrial>& trials)
{
  int chosen = 0;
  for (size_t i = 1; i < trials.size(); ++i)
  {
    if (trials[i].score < trials[size_t(chosen)].score)
    {
      chosen = int(i);
    }
  }
  return chosen;
}

EstimatorChoice choose(Renderer& renderer, const Scene& scene, const Camera& camera, const RenderSettings& base,
  const EstimatorChoiceSettings& choice, ChoiceAhead* frames)
{
  detail::checkChoiceSettings(choice);
  EstimatorChoice out;
  out.settings = base;
  RenderSettings probe = base;
  probe.estimator = Estimator::ExpectedValue;
  if (effectiveEstimator(scene, probe) == Estimator::Collision)
  {
    return out; // the estimator setting does not reach these renders
  }
  if (scene.lit())
  {
    // Lit: the expected-value estimator of lit camera rays, without pilots
    // (it reached every lit target sooner than the collision estimator on
    // every dataset measured, Documentation/performance.md; the unbiased
    // march does not light).
    out.settings.estimator = Estimator::ExpectedValue;
    return out;
  }
  out.applies = true;
  if (frames && frames->accum && renderer.rendersPilotsAtOnce())
  {
    renderFramesAhead(renderer, scene, camera, base, *frames);
  }
  const auto start = std::chrono::steady_clock::now();

  const detail::OfferedVariants offered = detail::offeredVariants(base, camera);
  const std::vector<EstimatorCandidate> candidates = detail::listCandidates(base, choice.marchRates, offered);
  const CostModel model = choice.customModel ? choice.model : defaultCostModel(renderer.name());
  detail::PilotRounds pilots(renderer, scene, camera, base, choice, model);
  detail::RateSearch search(candidates, choice, pilots, renderer.rendersPilotsAtOnce() && !choice.tryAllRates);
  search.renderFirstRound(offered);
  search.searchListedRates();
  if (choice.refineRates)
  {
    search.searchRatesBetween();
  }
  out.trials = std::move(search.trials);
  out.rounds = pilots.rounds;
  out.rendered = pilots.rendered;

  out.chosen = lowestScore(out.trials);
  out.settings = candidateSettings(base, camera, out.trials[size_t(out.chosen)].candidate);
  out.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  if (frames && frames->rendered)
  {
    frames->kept = detail::sameCandidate(out.trials[size_t(out.chosen)].candidate, frames->candidate);
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
