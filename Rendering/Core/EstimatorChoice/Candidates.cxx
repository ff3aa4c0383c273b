// SPDX-License-Identifier: BSD-3-Clause
//
// The candidates of the estimator choice: expected value, and the unbiased
// march at each listed rate in the variants the settings offer.
#include "ChoiceSteps.h"

#include "mcvol/ray/Integrator.h"
#include "mcvol/RenderSetup.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <stdexcept>

namespace mcvol
{
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

namespace detail
{
void checkChoiceSettings(const EstimatorChoiceSettings& choice)
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
}

OfferedVariants offeredVariants(const RenderSettings& base, const Camera& camera)
{
  // Both variants at pixel centres: the plain strata may reach a loose
  // target in one cheaper frame, the control variates a tight one, or a
  // dense set's target in fewer samples even below kMarchControlVariateRate.
  const bool centres = pixelCentres(base, camera);
  OfferedVariants offered;
  offered.plain = !centres || !base.marchControlVariates || base.marchControlVariatesFrom > 0.f;
  offered.controlVariates = centres && base.marchControlVariates;
  return offered;
}

std::vector<EstimatorCandidate> listCandidates(
  const RenderSettings& base, const std::vector<float>& marchRates, const OfferedVariants& offered)
{
  std::vector<EstimatorCandidate> candidates;
  {
    EstimatorCandidate ev;
    ev.estimator = Estimator::ExpectedValue;
    ev.marchSamplesPerVoxel = base.marchSamplesPerVoxel;
    candidates.push_back(ev);
  }
  std::vector<float> rates = marchRates;
  std::sort(rates.begin(), rates.end());
  for (float r : rates)
  {
    for (int variant = 0; variant < 2; ++variant)
    {
      if (variant == 0 ? !offered.plain : !offered.controlVariates)
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
  return candidates;
}

bool sameCandidate(const EstimatorCandidate& a, const EstimatorCandidate& b)
{
  return a.estimator == b.estimator && a.marchSamplesPerVoxel == b.marchSamplesPerVoxel &&
    a.controlVariates == b.controlVariates;
}

std::string candidateName(const EstimatorCandidate& c)
{
  return estimatorName(c.estimator, c.marchSamplesPerVoxel, c.controlVariates);
}
} // namespace detail
} // namespace mcvol
