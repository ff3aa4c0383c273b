// SPDX-License-Identifier: BSD-3-Clause
#pragma once

// The steps of chooseEstimator() (EstimatorChoice.cxx), one file each:
//   Candidates.cxx   which estimators and march rates compete;
//   Pilots.cxx       a candidate's pilot images and the time to the target
//                    they predict;
//   CostModel.cxx    the cost of one sample, from the work counters;
//   RateSearch.cxx   the order in which candidates are tried and when the
//                    search stops, in rounds of pilots;
//   RatesBetween.cxx a rate between two listed ones where whole frames make
//                    the choice jump.
// Private to the core: callers see mcvol/EstimatorChoice.h only.

#include "mcvol/EstimatorChoice.h"

#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

namespace mcvol
{
namespace detail
{
// ---- Candidates.cxx -------------------------------------------------------

/// Throws std::invalid_argument where `choice` cannot be searched (fewer
/// than 2 pilot samples, a target or a march rate that is not positive and
/// finite, a refine margin outside (0, 1]).
void checkChoiceSettings(const EstimatorChoiceSettings& choice);

/// Which variants of the unbiased march the choice offers.
struct OfferedVariants
{
  bool plain = true;
  bool controlVariates = false;
  bool offers(const EstimatorCandidate& c) const { return c.controlVariates ? this->controlVariates : this->plain; }
};

/// At pixel centres both variants, unless `base` fixes one
/// (marchControlVariates off: the plain strata; marchControlVariatesFrom 0:
/// the control variates); with jittered pixels the plain strata, which is
/// all the march renders there.
OfferedVariants offeredVariants(const RenderSettings& base, const Camera& camera);

/// Expected value (at base's march rate) first, then each of `marchRates`
/// in ascending order, the plain strata before the control variates: the
/// order the search takes them in, which also breaks ties.
std::vector<EstimatorCandidate> listCandidates(
  const RenderSettings& base, const std::vector<float>& marchRates, const OfferedVariants& offered);

/// 0: the march's plain strata; 1: its control variates.
inline int marchVariant(const EstimatorCandidate& c)
{
  return c.controlVariates ? 1 : 0;
}

bool sameCandidate(const EstimatorCandidate& a, const EstimatorCandidate& b);
std::string candidateName(const EstimatorCandidate& c);

// ---- Pilots.cxx -----------------------------------------------------------

/// MSE(N) ~ N^-a between checkpoints i - 1 and i of a pilot (`mse[k]` after
/// `checkpoints[k]` samples), held to [1, 2].
double decayBetween(const std::vector<double>& mse, const std::vector<int>& checkpoints, size_t i);

/// Predicted samples per pixel to reach `targetMSE` from a pilot's MSE at
/// its checkpoints (EstimatorChoice.h gives the rule).
double framesToTarget(const std::vector<double>& mse, const std::vector<int>& checkpoints, double targetMSE);

/// Renders candidates' pilots in rounds (one Renderer::renderPilots() call
/// each) and turns each into its trial. Counts the rounds and the candidates
/// rendered, for EstimatorChoice::rounds and ::rendered.
struct PilotRounds
{
  PilotRounds(Renderer& renderer, const Scene& scene, const Camera& camera, const RenderSettings& base,
    const EstimatorChoiceSettings& choice, const CostModel& model);

  /// One round of `candidates`, and their trials in the same order.
  std::vector<EstimatorTrial> render(const std::vector<EstimatorCandidate>& candidates);

  /// What renderPilots() renders for `c`: two replicates with the choice's
  /// seeds, each to checkpoints 1, 2, 4, ... up to the candidate's samples.
  PilotJob jobOf(const EstimatorCandidate& c) const;
  /// The MSE at each checkpoint, the decay, the frames and the score of a
  /// rendered job.
  EstimatorTrial trialOf(const EstimatorCandidate& c, const PilotJob& job) const;

  Renderer& renderer;
  const Scene& scene;
  /// The image's camera (pixel centres or jittered: candidateSettings()).
  const Camera& camera;
  /// pilotCamera(camera, choice.pilotSize): what the pilots render through.
  const Camera pilot;
  const RenderSettings& base;
  const EstimatorChoiceSettings& choice;
  const CostModel model;
  uint32_t seeds[2];
  int rounds = 0;
  int rendered = 0;
};

// ---- RateSearch.cxx, RatesBetween.cxx -------------------------------------

/// The search: the listed candidates in order, with a stop rule per march
/// variant, then a rate between listed ones per variant. Rounds are rendered
/// through `pilots`; where `ahead`, a round also renders the rates the search
/// will most likely reach (RateSearch.cxx says why this leaves the trials
/// unchanged).
struct RateSearch
{
  RateSearch(const std::vector<EstimatorCandidate>& candidates, const EstimatorChoiceSettings& choice,
    PilotRounds& pilots, bool ahead);

  /// Expected value and the lowest rate of each offered variant, which every
  /// search renders; where `ahead`, with the hint's candidates.
  void renderFirstRound(const OfferedVariants& offered);
  /// The listed candidates in order, skipping a variant's rates once the
  /// stop rule says they cannot win.
  void searchListedRates();
  /// EstimatorChoiceSettings::refineRates.
  void searchRatesBetween();

  const std::vector<EstimatorCandidate>& candidates;
  const EstimatorChoiceSettings& choice;
  PilotRounds& pilots;
  const bool ahead;

  /// The trials the search reached, in order: EstimatorChoice::trials.
  std::vector<EstimatorTrial> trials;
  /// The lowest score in `trials`.
  double best = 0;

private:
  /// Renders the listed candidates `round` and the hinted rates between
  /// `extra`; keeps the first in `results`, the others in `hinted`.
  void runRound(const std::vector<size_t>& round, const std::vector<EstimatorCandidate>& extra);
  /// Candidate i and, where `ahead`, the later rates the search will reach
  /// if `best` stays.
  std::vector<size_t> roundFrom(size_t i) const;
  /// The hint's candidates that join the first round (`round` gets the
  /// listed ones, the result the others).
  std::vector<EstimatorCandidate> hintedExtras(std::vector<size_t>& round, const OfferedVariants& offered) const;

  /// A variant's rate between two listed ones, planned from the first
  /// `scanned` trials; `cost` is its interpolated cost per sample, `aim`
  /// the MSE(1) it aims at.
  struct Between
  {
    EstimatorCandidate candidate;
    double cost = 0;
    double aim = 0;
  };
  bool planBetween(int variant, size_t scanned, Between& between) const;
  /// The trial of `between` rendered ahead from the hint, if any.
  bool hintedTrial(const Between& between, EstimatorTrial& trial) const;

  /// Each listed candidate's trial once rendered (have[i]).
  std::vector<EstimatorTrial> results;
  std::vector<char> have;
  /// Rates between listed ones rendered ahead from the hint.
  std::vector<EstimatorTrial> hinted;
  /// The index in `trials` of each march variant's last trial; -1: none yet.
  int lastOf[2] = { -1, -1 };
};
} // namespace detail
} // namespace mcvol
