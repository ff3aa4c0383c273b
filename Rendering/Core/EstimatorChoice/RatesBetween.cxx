// SPDX-License-Identifier: BSD-3-Clause
//
// A rate between two listed ones (EstimatorChoiceSettings::refineRates).
// Whole frames make the choice jump where a variant's rate needs more than
// one frame and the next listed rate needs one: the pilots may put the lower
// rate's MSE(1) just over the target, predict two frames, and choose the
// next rate although a rate in between would reach the target in one frame
// for less. Where the interpolation's cost is predicted below the best, the
// rate where MSE(1) is predicted to meet refineMargin x the target (log-log
// interpolation of MSE(1) in the rate, rounded up to kChoiceRateStep) gets a
// pilot of its own, and competes like the others (one frame only if its
// pilot is within the margin too).
#include "ChoiceSteps.h"

#include <algorithm>
#include <cmath>

namespace mcvol
{
namespace detail
{
bool RateSearch::planBetween(int variant, size_t scanned, Between& between) const
{
  int lo = -1;
  for (size_t i = 0; i < scanned; ++i)
  {
    const EstimatorTrial& t = this->trials[i];
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
    const EstimatorTrial& a = this->trials[size_t(lo)];
    const double r0 = a.candidate.marchSamplesPerVoxel, r1 = t.candidate.marchSamplesPerVoxel;
    if (!(a.firstFrameMSE > this->choice.targetMSE && t.firstFrameMSE > 0 && t.firstFrameMSE < a.firstFrameMSE))
    {
      return false;
    }
    const double slope = std::log(a.firstFrameMSE / t.firstFrameMSE) / std::log(r1 / r0);
    between.aim = this->choice.refineMargin * this->choice.targetMSE;
    double r = r0 * std::pow(a.firstFrameMSE / between.aim, 1.0 / slope);
    r = std::ceil(r / kChoiceRateStep - 1e-9) * kChoiceRateStep;
    between.cost = a.costPerSample + (r - r0) / (r1 - r0) * (t.costPerSample - a.costPerSample);
    between.candidate = t.candidate;
    between.candidate.marchSamplesPerVoxel = float(r);
    return r > r0 && r < r1 && between.cost < this->best;
  }
  return false;
}

bool RateSearch::hintedTrial(const Between& between, EstimatorTrial& trial) const
{
  for (const EstimatorTrial& h : this->hinted)
  {
    if (sameCandidate(h.candidate, between.candidate))
    {
      trial = h;
      return true;
    }
  }
  return false;
}

void RateSearch::searchRatesBetween()
{
  // Variant by variant, as the search takes them: a variant's rate between
  // is tried where its interpolated cost is below the best so far, the first
  // variant's between included. Where the backend renders at once, both
  // variants' are rendered in one round (planned from the listed trials
  // alone), and the second's result is dropped where the first's lowered
  // `best` below its cost.
  const size_t scanned = this->trials.size();
  Between planned[2];
  bool wanted[2] = { this->planBetween(0, scanned, planned[0]), false };
  EstimatorTrial tried[2];
  bool done[2] = { false, false };
  if (this->ahead)
  {
    wanted[1] = this->planBetween(1, scanned, planned[1]);
    std::vector<EstimatorCandidate> round;
    std::vector<int> of;
    for (int v = 0; v < 2; ++v)
    {
      if (!wanted[v])
      {
        continue;
      }
      done[v] = this->hintedTrial(planned[v], tried[v]);
      if (!done[v])
      {
        round.push_back(planned[v].candidate);
        of.push_back(v);
      }
    }
    if (!round.empty())
    {
      const std::vector<EstimatorTrial> rendered = this->pilots.render(round);
      for (size_t k = 0; k < rendered.size(); ++k)
      {
        tried[of[k]] = rendered[k];
        done[of[k]] = true;
      }
    }
  }
  for (int variant = 0; variant < 2; ++variant)
  {
    if (variant == 1 && !this->ahead)
    {
      wanted[1] = this->planBetween(1, scanned, planned[1]);
    }
    if (!wanted[variant] || !(planned[variant].cost < this->best))
    {
      continue;
    }
    if (!done[variant])
    {
      tried[variant] = this->pilots.render({ planned[variant].candidate }).front();
    }
    EstimatorTrial between = tried[variant];
    between.refined = true;
    if (between.firstFrameMSE > planned[variant].aim)
    {
      // Its own pilot misses the margin: two frames at least
      // (EstimatorChoiceSettings::refineMargin says why).
      between.frames = std::max(between.frames, 2.0);
      between.score = between.frames * between.costPerSample;
    }
    this->trials.push_back(between);
    this->best = std::min(this->best, between.score);
  }
}
} // namespace detail
} // namespace mcvol
