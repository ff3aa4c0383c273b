// SPDX-License-Identifier: BSD-3-Clause
//
// The search over the listed candidates, in rounds of pilots
// (Renderer::renderPilots: a device backend renders a round's samples all at
// once). The first round holds expected value and the lowest rate of each
// offered variant, which every search renders; each later one the candidate
// the stop rule reaches next.
//
// A backend that renders a round at once (Renderer::rendersPilotsAtOnce)
// also gets, in that round, the variants' higher rates the search will reach
// if the best prediction so far stays: each rate whose predecessor in its
// variant costs less per sample than that best (known where the predecessor
// was tried, else extrapolated in proportion to the rate, which overstates a
// cost with a fixed part per ray), at most kMaxRound. The search itself is
// the same either way: it takes a rendered result only where it reaches that
// candidate, so the trials and the choice are those of the pilots rendered
// one after the other, and a rate rendered ahead and not reached costs only
// its share of the round.
#include "ChoiceSteps.h"

#include <algorithm>
#include <cmath>

namespace mcvol
{
namespace detail
{
namespace
{
constexpr size_t kMaxRound = 8;       // a later round: the candidate and those ahead
constexpr size_t kMaxFirstRound = 16; // the first round with the hint
} // namespace

RateSearch::RateSearch(const std::vector<EstimatorCandidate>& candidates_, const EstimatorChoiceSettings& choice_,
  PilotRounds& pilots_, bool ahead_)
  : candidates(candidates_)
  , choice(choice_)
  , pilots(pilots_)
  , ahead(ahead_)
  , results(candidates_.size())
  , have(candidates_.size(), 0)
{
}

void RateSearch::runRound(const std::vector<size_t>& round, const std::vector<EstimatorCandidate>& extra)
{
  std::vector<EstimatorCandidate> cs;
  for (size_t i : round)
  {
    cs.push_back(this->candidates[i]);
  }
  cs.insert(cs.end(), extra.begin(), extra.end());
  const std::vector<EstimatorTrial> rendered = this->pilots.render(cs);
  for (size_t k = 0; k < round.size(); ++k)
  {
    this->results[round[k]] = rendered[k];
    this->have[round[k]] = 1;
  }
  this->hinted.insert(this->hinted.end(), rendered.begin() + std::ptrdiff_t(round.size()), rendered.end());
}

void RateSearch::renderFirstRound(const OfferedVariants& offered)
{
  std::vector<size_t> round;
  bool seen[2] = { false, false };
  for (size_t i = 0; i < this->candidates.size(); ++i)
  {
    const EstimatorCandidate& c = this->candidates[i];
    const int variant = marchVariant(c);
    if (c.estimator != Estimator::UnbiasedMarch || !seen[variant])
    {
      round.push_back(i);
      seen[variant] = seen[variant] || c.estimator == Estimator::UnbiasedMarch;
    }
  }
  std::vector<EstimatorCandidate> extra;
  if (this->ahead)
  {
    extra = this->hintedExtras(round, offered);
  }
  this->runRound(round, extra);
}

std::vector<EstimatorCandidate> RateSearch::hintedExtras(
  std::vector<size_t>& round, const OfferedVariants& offered) const
{
  // The hint (e.g. the previous choice's trials, EstimatorChoiceSettings::
  // hint) joins the first round where the backend renders at once: the
  // search will likely reach the same candidates again, and what it does not
  // reach costs only its share of the round.
  std::vector<EstimatorCandidate> extra;
  for (const EstimatorCandidate& h : this->choice.hint)
  {
    if (round.size() + extra.size() >= kMaxFirstRound)
    {
      break;
    }
    if (h.estimator != Estimator::UnbiasedMarch || !offered.offers(h) || !(h.marchSamplesPerVoxel > 0.f) ||
      !std::isfinite(h.marchSamplesPerVoxel))
    {
      continue;
    }
    const auto listed = std::find_if(this->candidates.begin(), this->candidates.end(),
      [&](const EstimatorCandidate& c) { return sameCandidate(c, h); });
    if (listed != this->candidates.end())
    {
      const size_t k = size_t(listed - this->candidates.begin());
      if (std::find(round.begin(), round.end(), k) == round.end())
      {
        round.push_back(k);
      }
    }
    else if (std::none_of(extra.begin(), extra.end(), [&](const EstimatorCandidate& e) { return sameCandidate(e, h); }))
    {
      extra.push_back(h);
    }
  }
  return extra;
}

void RateSearch::searchListedRates()
{
  for (size_t i = 0; i < this->candidates.size(); ++i)
  {
    const EstimatorCandidate& c = this->candidates[i];
    const int variant = marchVariant(c);
    if (!this->choice.tryAllRates && c.estimator == Estimator::UnbiasedMarch && this->lastOf[variant] >= 0)
    {
      // A higher rate of the same variant costs at least as much per sample
      // and takes at least one: no better than `best` once the variant's
      // last rate's sample cost that. There is no stop where a prediction
      // merely rose: at the lowest rates the majorant's strata floor keeps
      // the noise nearly flat, and the prediction's own noise can make it
      // rise there before a higher rate wins by far.
      if (this->trials[size_t(this->lastOf[variant])].costPerSample >= this->best)
      {
        continue;
      }
    }
    if (!this->have[i])
    {
      this->runRound(this->roundFrom(i), {});
    }
    this->trials.push_back(this->results[i]);
    if (c.estimator == Estimator::UnbiasedMarch)
    {
      this->lastOf[variant] = int(this->trials.size()) - 1;
    }
    this->best = this->trials.size() == 1 ? this->trials.back().score : std::min(this->best, this->trials.back().score);
  }
}

std::vector<size_t> RateSearch::roundFrom(size_t i) const
{
  std::vector<size_t> round = { i };
  if (!this->ahead)
  {
    return round;
  }
  // The search reaches a later rate of a variant while the cost per sample
  // of the variant's rate before it is below `best` (the stop rule of
  // searchListedRates()). That cost is known for a rate already tried; for
  // one in this round it is extrapolated from the variant's last known rate
  // in proportion to the rate (an upper bound where the cost has a fixed
  // part per ray).
  double lastCost[2] = { -1, -1 }, lastRate[2] = { 0, 0 };
  for (int v = 0; v < 2; ++v)
  {
    if (this->lastOf[v] >= 0)
    {
      lastCost[v] = this->trials[size_t(this->lastOf[v])].costPerSample;
      lastRate[v] = this->trials[size_t(this->lastOf[v])].candidate.marchSamplesPerVoxel;
    }
  }
  // Candidate k joins the chain of its variant (known or predicted).
  const auto step = [&](size_t k)
  {
    const EstimatorCandidate& d = this->candidates[k];
    const int v = marchVariant(d);
    if (this->have[k])
    {
      lastCost[v] = this->results[k].costPerSample;
    }
    else if (lastCost[v] >= 0)
    {
      lastCost[v] *= double(d.marchSamplesPerVoxel) / lastRate[v];
    }
    lastRate[v] = d.marchSamplesPerVoxel;
  };
  if (this->candidates[i].estimator == Estimator::UnbiasedMarch)
  {
    step(i);
  }
  bool open[2] = { true, true };
  for (size_t k = i + 1; k < this->candidates.size() && round.size() < kMaxRound; ++k)
  {
    const EstimatorCandidate& d = this->candidates[k];
    const int v = marchVariant(d);
    if (d.estimator != Estimator::UnbiasedMarch || !open[v] || lastCost[v] < 0)
    {
      continue;
    }
    if (!(lastCost[v] < this->best))
    {
      open[v] = false; // the search stops this variant before d
      continue;
    }
    if (!this->have[k])
    {
      round.push_back(k);
    }
    step(k);
  }
  return round;
}
} // namespace detail
} // namespace mcvol
