// SPDX-License-Identifier: BSD-3-Clause
//
// A candidate's pilot: a small image of the whole view rendered as two
// replicates with independent scrambles, each in doublings (1, 2, 4, ...
// samples per pixel), and the time to the target its errors predict.
#include "ChoiceSteps.h"

#include "mcvol/RenderSetup.h"

#include <algorithm>
#include <cmath>

namespace mcvol
{
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
    pilot.jitterScale = float(camera.jitterScale *
      std::min(double(pilot.width) / double(camera.width), double(pilot.height) / double(camera.height)));
  }
  return pilot;
}

namespace detail
{
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

double decayBetween(const std::vector<double>& mse, const std::vector<int>& checkpoints, size_t i)
{
  // 1 for independent samples. Sobol' points fall faster, and their gain
  // fades as N grows, so the last doubling is the one to extrapolate with.
  double a = 1.0;
  if (mse[i] > 0 && mse[i - 1] > mse[i])
  {
    a = std::log(mse[i - 1] / mse[i]) / std::log(double(checkpoints[i]) / double(checkpoints[i - 1]));
  }
  return std::min(2.0, std::max(1.0, a));
}

double framesToTarget(const std::vector<double>& mse, const std::vector<int>& checkpoints, double targetMSE)
{
  // One frame where the first sample meets the target: a rate that is clean
  // in one frame is all an image needs, whatever a higher one would give.
  if (mse[0] <= targetMSE)
  {
    return 1.0;
  }
  // The first checkpoint at or below the target bounds the frames; they are
  // interpolated from the checkpoint before it with that doubling's decay,
  // or extrapolated from the last checkpoint with its decay.
  size_t i = 1;
  while (i < checkpoints.size() && mse[i] > targetMSE)
  {
    ++i;
  }
  const size_t from = i < checkpoints.size() ? i - 1 : checkpoints.size() - 1;
  const double a = decayBetween(mse, checkpoints, i < checkpoints.size() ? i : checkpoints.size() - 1);
  double f = std::ceil(double(checkpoints[from]) * std::pow(mse[from] / targetMSE, 1.0 / a) - 1e-9);
  f = std::max(f, double(checkpoints[from] + 1));
  if (i < checkpoints.size())
  {
    f = std::min(f, double(checkpoints[i]));
  }
  return f;
}

PilotRounds::PilotRounds(Renderer& renderer_, const Scene& scene_, const Camera& camera_, const RenderSettings& base_,
  const EstimatorChoiceSettings& choice_, const CostModel& model_)
  : renderer(renderer_)
  , scene(scene_)
  , camera(camera_)
  , pilot(pilotCamera(camera_, choice_.pilotSize))
  , base(base_)
  , choice(choice_)
  , model(model_)
  // Fixed functions of the image's seed: any two distinct seeds scramble
  // independently, and the same image seed gives the same choice.
  , seeds{ base_.seed * 2654435761u + 0x2545F491u, base_.seed * 2654435761u + 0x9E3779B9u }
{
}

PilotJob PilotRounds::jobOf(const EstimatorCandidate& c) const
{
  PilotJob job;
  job.settings = candidateSettings(this->base, this->camera, c);
  job.seeds[0] = this->seeds[0];
  job.seeds[1] = this->seeds[1];
  // Expected value's Sobol' gain fades over its first samples, so its decay
  // is measured further out (EstimatorChoiceSettings::
  // expectedValuePilotSamples).
  const int samples = c.estimator == Estimator::ExpectedValue
    ? std::max(this->choice.pilotSamples, this->choice.expectedValuePilotSamples)
    : this->choice.pilotSamples;
  for (int k = 1; k < samples; k *= 2)
  {
    job.checkpoints.push_back(k);
  }
  job.checkpoints.push_back(samples);
  return job;
}

EstimatorTrial PilotRounds::trialOf(const EstimatorCandidate& c, const PilotJob& job) const
{
  const std::vector<int>& checkpoints = job.checkpoints;
  const int samples = checkpoints.back();
  // E[(m1 - m2)^2] = 2 MSE(n) for independent replicates of an n-sample
  // mean. With Sobol' points a pixel's samples are negatively correlated, so
  // n MSE(n) understates the noise of a single sample: the 1-sample images
  // decide whether one frame suffices, the later ones predict the frames
  // beyond.
  std::vector<double> mse(checkpoints.size());
  for (size_t i = 0; i < checkpoints.size(); ++i)
  {
    mse[i] = 0.5 *
      meanSquaredDifference(job.means[0][i].data(), job.means[1][i].data(), this->pilot.width, this->pilot.height);
  }
  EstimatorTrial t;
  t.candidate = c;
  t.counters = job.counters;
  t.pilotSamples = samples;
  t.firstFrameMSE = mse[0];
  t.variance = mse.back() * double(samples);
  t.decay = decayBetween(mse, checkpoints, checkpoints.size() - 1);
  t.frames = framesToTarget(mse, checkpoints, this->choice.targetMSE);
  const double pixels = double(this->pilot.width) * double(this->pilot.height);
  t.costPerSample = this->model.cost(job.counters) / (pixels * double(samples));
  t.score = t.frames * t.costPerSample;
  return t;
}

std::vector<EstimatorTrial> PilotRounds::render(const std::vector<EstimatorCandidate>& candidates)
{
  std::vector<PilotJob> jobs;
  for (const EstimatorCandidate& c : candidates)
  {
    jobs.push_back(this->jobOf(c));
  }
  this->renderer.renderPilots(this->scene, this->pilot, jobs);
  ++this->rounds;
  this->rendered += int(jobs.size());
  std::vector<EstimatorTrial> trials;
  for (size_t k = 0; k < candidates.size(); ++k)
  {
    trials.push_back(this->trialOf(candidates[k], jobs[k]));
  }
  return trials;
}
} // namespace detail
} // namespace mcvol
