// SPDX-License-Identifier: BSD-3-Clause
// The error estimate of the progressive image
// (Documentation/user-guide/accumulation-and-estimators.md):
// Accumulator::estimatedMSE() from the even-sample half against the true
// error measured with a reference. Backend-generic (testRenderer(): the CPU,
// or the CUDA backend with MCVOL_TEST_BACKEND=cuda). Seeds are fixed; the
// agreement factor is stated in each test.
#include "TestUtil.h"

#include "mcvol/EstimatorChoice.h"
#include "mcvol/RenderSetup.h"

#include <cstdio>

using namespace mcvol;
using namespace mcvol::test;

namespace
{
/// The estimated RMSE must be within this factor of the true RMSE (either
/// way). The estimate averages ~5000 pixel-channel values of a few degrees of
/// freedom each, so it is typically within a few percent; 1.25 leaves room
/// for the heavy tails of Monte Carlo noise while failing a missing factor
/// such as the 1/4 of equal halves (which would make the ratio exactly 2)
/// or a wrong split of odd sample counts.
constexpr double kFactor = 1.25;

/// With Owen-scrambled Sobol' points the samples of a pixel are negatively
/// correlated (that is the sequences' gain), so the two halves differ more
/// than the noise of their union: the estimate is conservative. Measured:
/// 1.04-1.17x the true RMSE with the collision estimator, 1.45-2.02x with the
/// expected-value estimator, whose samples gain most from the stratified
/// first flight. Adaptive stopping (SetTargetError) then stops late, never
/// early. The bound keeps the estimate an upper bound within this factor.
constexpr double kSobolFactor = 2.5;

Camera demoCam(const DemoVolume& v, int W, int H)
{
  return orbitCamera(v.dims, v.spacing, W, H, 30, 20);
}

std::vector<float> image(const Accumulator& a)
{
  return std::vector<float>(a.rgba(), a.rgba() + size_t(4) * size_t(a.width()) * size_t(a.height()));
}

/// MSE over premultiplied R, G, B (alpha left out, as estimatedMSE does).
double mseRGB(const std::vector<float>& a, const std::vector<float>& b)
{
  double s = 0;
  size_t n = 0;
  for (size_t i = 0; i < a.size(); ++i)
  {
    if (i % 4 == 3)
    {
      continue;
    }
    const double d = double(a[i]) - double(b[i]);
    s += d * d;
    ++n;
  }
  return s / double(n);
}

void renderBatches(Renderer& r, const Scene& scene, const Camera& cam, Accumulator& acc, int total, int batch,
  uint32_t seed, Sampler sampler = RenderSettings().sampler, Estimator estimator = RenderSettings().estimator)
{
  RenderSettings rs;
  rs.seed = seed;
  rs.sampler = sampler;
  rs.estimator = estimator;
  for (int done = 0; done < total; done += batch)
  {
    rs.samplesPerPixel = std::min(batch, total - done);
    r.render(scene, cam, rs, nullptr, acc);
  }
}
} // namespace

// After N samples (16, 33, 64, 256: an odd count splits into unequal
// halves) the estimated RMSE is within kFactor of the true RMSE, measured
// against an independent 4096-spp reference (independent sampler, collision
// estimator, another seed) whose own (estimated, 16 to 256 times smaller)
// MSE is subtracted. Two datasets and blend modes, both estimators; with the
// independent sampler within kFactor either way, with Sobol' points between
// truth / kFactor and kSobolFactor * truth (conservative, see above).
TEST(ErrorEstimate, MatchesTheTrueErrorWithinAFactor)
{
  std::unique_ptr<Renderer> r = testRenderer();
  struct Case
  {
    const char* demo;
    BlendMode mode;
  };
  for (const Case& cs : { Case{ "cosmology", BlendMode::Density }, Case{ "figure3", BlendMode::Max } })
  {
    const DemoVolume v = makeDemo(cs.demo, { 24, 24, 24 });
    Scene scene;
    configureDemo(scene, v, 4, 128, 1.0, cs.mode);
    const Camera cam = demoCam(v, 40, 40);
    Accumulator ref;
    renderBatches(*r, scene, cam, ref, 4096, 512, 999, Sampler::Independent, Estimator::Collision);
    const double refMSE = ref.estimatedMSE();
    ASSERT_GE(refMSE, 0.0);
    const std::vector<float> refImg = image(ref);
    for (Sampler sampler : { Sampler::Independent, Sampler::Sobol })
      for (Estimator estimator : { Estimator::Collision, Estimator::ExpectedValue })
        for (int n : { 16, 33, 64, 256 })
        {
          Accumulator acc;
          renderBatches(*r, scene, cam, acc, n, 8, 7, sampler, estimator);
          const double est = std::sqrt(acc.estimatedMSE());
          const double truth = std::sqrt(std::max(0.0, mseRGB(image(acc), refImg) - refMSE));
          const std::string what = std::string(cs.demo) + " " + toString(cs.mode) + " " + toString(sampler) + " " +
            toString(estimator) + ", " + std::to_string(n) + " spp";
          std::printf("%s: estimated RMSE %.5f, true RMSE %.5f (ratio %.3f)\n", what.c_str(), est, truth, est / truth);
          EXPECT_GT(truth, 0.0);
          EXPECT_LE(est, (sampler == Sampler::Sobol ? kSobolFactor : kFactor) * truth) << what;
          EXPECT_GE(est, truth / kFactor) << what;
        }
  }
}

// Nothing visible: every sample is 0, the estimate exactly 0. One sample:
// no estimate (negative), for any scene; two samples: a finite estimate.
TEST(ErrorEstimate, DeterministicImageAndFewSamples)
{
  std::unique_ptr<Renderer> r = testRenderer();
  const DemoVolume v = makeDemo("cosmology", { 16, 16, 16 });
  {
    Scene scene;
    configureDemo(scene, v, 4);
    for (int n = 0; n < v.numChannels(); ++n)
    {
      const std::array<float, 2> range = v.range(n);
      TransferFunctionDesc tf = sampleTransferFunction(v.transferFunctions[size_t(n)], range[0], range[1], 128, 1.0);
      std::fill(tf.opacity.begin(), tf.opacity.end(), 0.f);
      scene.setTransferFunction(n, tf);
    }
    scene.update();
    Accumulator acc;
    renderBatches(*r, scene, demoCam(v, 24, 24), acc, 16, 4, 3);
    EXPECT_EQ(acc.estimatedMSE(), 0.0);
  }
  Scene scene;
  configureDemo(scene, v, 4);
  Accumulator acc;
  EXPECT_LT(acc.estimatedMSE(), 0.0); // no image at all
  renderBatches(*r, scene, demoCam(v, 24, 24), acc, 1, 1, 3);
  EXPECT_LT(acc.estimatedMSE(), 0.0);
  renderBatches(*r, scene, demoCam(v, 24, 24), acc, 1, 1, 3);
  EXPECT_EQ(acc.samples(), 2u);
  EXPECT_GT(acc.estimatedMSE(), 0.0);
  EXPECT_TRUE(std::isfinite(acc.estimatedMSE()));
  acc.reset();
  EXPECT_LT(acc.estimatedMSE(), 0.0);
}

// Samples are numbered per pixel: 64 samples give the same estimate (and
// image) in batches of 1, 16 or 64, up to float rounding of the running means.
TEST(ErrorEstimate, IndependentOfBatching)
{
  std::unique_ptr<Renderer> r = testRenderer();
  const DemoVolume v = makeDemo("cosmology", { 20, 20, 20 });
  Scene scene;
  configureDemo(scene, v, 4);
  const Camera cam = demoCam(v, 24, 24);
  double first = -1;
  std::vector<float> firstImg;
  for (int batch : { 1, 16, 64, 5 })
  {
    Accumulator acc;
    renderBatches(*r, scene, cam, acc, 64, batch, 11);
    const double e = acc.estimatedMSE();
    ASSERT_GT(e, 0.0) << "batch " << batch;
    if (first < 0)
    {
      first = e;
      firstImg = image(acc);
      continue;
    }
    EXPECT_NEAR(e, first, 1e-4 * first) << "batch " << batch;
    EXPECT_LT(mseRGB(image(acc), firstImg), 1e-10) << "batch " << batch;
  }
}

// The split changes nothing in the image; off, there is no estimate; turned
// on mid-image there is none until the image restarts.
TEST(ErrorEstimate, OffChangesNothingElse)
{
  std::unique_ptr<Renderer> r = testRenderer();
  const DemoVolume v = makeDemo("figure3", { 20, 20, 20 });
  Scene scene;
  configureDemo(scene, v, 4);
  const Camera cam = demoCam(v, 24, 24);
  Accumulator on, off;
  off.setErrorEstimation(false);
  EXPECT_FALSE(off.errorEstimation());
  renderBatches(*r, scene, cam, on, 12, 3, 5);
  renderBatches(*r, scene, cam, off, 12, 3, 5);
  EXPECT_EQ(image(on), image(off));
  EXPECT_GT(on.estimatedMSE(), 0.0);
  EXPECT_LT(off.estimatedMSE(), 0.0);
  EXPECT_EQ(off.evenRGBA(), nullptr);
  off.setErrorEstimation(true);
  renderBatches(*r, scene, cam, off, 4, 4, 5);
  EXPECT_LT(off.estimatedMSE(), 0.0);
  off.reset();
  renderBatches(*r, scene, cam, off, 12, 3, 5);
  EXPECT_EQ(off.estimatedMSE(), on.estimatedMSE());
}

// Device backends: with readBack off the estimate waits for the image
// (negative while it is on the device) and then equals the read-back one.
TEST(ErrorEstimate, FollowsReadBack)
{
  std::unique_ptr<Renderer> r = testRenderer();
  const DemoVolume v = makeDemo("figure3", { 20, 20, 20 });
  Scene scene;
  configureDemo(scene, v, 4);
  const Camera cam = demoCam(v, 24, 24);
  Accumulator eager, lazy;
  renderBatches(*r, scene, cam, eager, 8, 4, 5);
  RenderSettings rs;
  rs.seed = 5;
  rs.samplesPerPixel = 4;
  rs.readBack = false;
  r->render(scene, cam, rs, nullptr, lazy);
  r->render(scene, cam, rs, nullptr, lazy);
  if (lazy.pendingOnDevice())
  {
    EXPECT_LT(lazy.estimatedMSE(), 0.0);
  }
  r->readBack(lazy);
  EXPECT_EQ(lazy.estimatedMSE(), eager.estimatedMSE());
}

// reset() defers the host image's zeros to its first host access (a device
// backend starts the image on the device and never pays for the clear). The
// deferred clear must be invisible: after a reset, the host image and its
// even half read as zeros, the estimate is unavailable, and a new image
// rendered after the reset equals one rendered into a fresh Accumulator,
// with the same estimate, whether or not the host image was read in between.
TEST(ErrorEstimate, ResetClearsLazilyButCompletely)
{
  std::unique_ptr<Renderer> r = testRenderer();
  const DemoVolume v = makeDemo("figure3", { 20, 20, 20 });
  Scene scene;
  configureDemo(scene, v, 4);
  const Camera cam = demoCam(v, 24, 24);
  Accumulator fresh, touched, untouched;
  renderBatches(*r, scene, cam, fresh, 8, 4, 7);
  renderBatches(*r, scene, cam, touched, 6, 3, 11);
  renderBatches(*r, scene, cam, untouched, 6, 3, 11);
  const std::vector<float> before = image(touched);
  ASSERT_GT(*std::max_element(before.begin(), before.end()), 0.f);

  touched.reset();
  untouched.reset();
  EXPECT_TRUE(touched.hostClearPending());
  EXPECT_EQ(touched.samples(), 0u);
  EXPECT_LT(touched.estimatedMSE(), 0.0);
  const std::vector<float> cleared = image(touched); // writes the zeros
  EXPECT_FALSE(touched.hostClearPending());
  EXPECT_TRUE(std::all_of(cleared.begin(), cleared.end(), [](float x) { return x == 0.f; }));
  ASSERT_NE(touched.evenRGBA(), nullptr);
  const float* even = touched.evenRGBA();
  EXPECT_TRUE(std::all_of(even, even + cleared.size(), [](float x) { return x == 0.f; }));

  // `untouched` goes straight into the next render.
  EXPECT_TRUE(untouched.hostClearPending());
  renderBatches(*r, scene, cam, touched, 8, 4, 7);
  renderBatches(*r, scene, cam, untouched, 8, 4, 7);
  EXPECT_EQ(image(touched), image(fresh));
  EXPECT_EQ(image(untouched), image(fresh));
  EXPECT_EQ(touched.estimatedMSE(), fresh.estimatedMSE());
  EXPECT_EQ(untouched.estimatedMSE(), fresh.estimatedMSE());

  // rgbaForOverwrite() hands the buffer over without writing the zeros.
  untouched.reset();
  float* raw = untouched.rgbaForOverwrite();
  std::fill(raw, raw + cleared.size(), 0.5f);
  EXPECT_EQ(untouched.rgba()[0], 0.5f); // not cleared behind the caller's back
  EXPECT_EQ(untouched.evenRGBA()[0], 0.f); // the even half was still pending: cleared
}

// ------------------------------------------------- the automatic estimator

namespace
{
/// Delegates to a backend and counts the renders (the choice must not render
/// where the estimator does not matter).
class CountingRenderer : public Renderer
{
public:
  explicit CountingRenderer(Renderer& inner)
    : Inner(inner)
  {
  }
  void render(const Scene& scene, const Camera& camera, const RenderSettings& settings, const float* depth,
    Accumulator& accum, RenderCounters* counters) override
  {
    ++this->Renders;
    this->Inner.render(scene, camera, settings, depth, accum, counters);
  }
  void march(const Scene& scene, const Camera& camera, const MarchSettings& settings, const float* depth,
    Accumulator& accum, MarchCounters* counters) override
  {
    this->Inner.march(scene, camera, settings, depth, accum, counters);
  }
  const char* name() const override { return this->Inner.name(); }
  int Renders = 0;

private:
  Renderer& Inner;
};

/// 1-spp frames of candidate `c` until the image's MSE over premultiplied
/// RGB against `ref` (less the reference's own estimated MSE) is at most
/// `target`; `cap` if it never is.
int framesToTarget(Renderer& r, const Scene& scene, const Camera& cam, const RenderSettings& base,
  const EstimatorCandidate& c, double target, const std::vector<float>& ref, double refMSE, int cap)
{
  Accumulator acc;
  RenderSettings rs = candidateSettings(base, cam, c);
  rs.seed = 7;
  for (int f = 1; f <= cap; ++f)
  {
    r.render(scene, cam, rs, nullptr, acc);
    if (mseRGB(image(acc), ref) - refMSE <= target)
    {
      return f;
    }
  }
  return cap;
}

/// A renderer whose image after N samples per pixel is 0.5 + e(N) z, z =
/// +-1/sqrt(2) by the seed: two replicates (different seeds)
/// differ by sqrt(2) e(N), so the choice measures MSE(N) = e(N)^2 exactly.
/// MSE(N) is given per settings (estimator, march rate and variant), and so
/// is the work of one sample of one pixel (DDA steps; 1 if not given).
class SyntheticNoiseRenderer : public Renderer
{
public:
  std::function<double(const RenderSettings&, double)> Mse;
  std::function<double(const RenderSettings&)> Work;
  void render(const Scene&, const Camera& camera, const RenderSettings& settings, const float*, Accumulator& accum,
    RenderCounters* counters) override
  {
    accum.addSamples(uint32_t(settings.samplesPerPixel));
    const double e = std::sqrt(this->Mse(settings, double(accum.samples())));
    // The first seed seen gets +, the next one -, and so on.
    const auto it = this->Signs.emplace(settings.seed, this->Signs.size() % 2 == 0 ? 1.0 : -1.0).first;
    const float v = float(0.5 + it->second * e / std::sqrt(2.0));
    float* rgba = accum.rgbaForOverwrite();
    const size_t n = size_t(camera.width) * size_t(camera.height);
    for (size_t p = 0; p < 4 * n; ++p)
    {
      rgba[p] = v;
    }
    if (counters)
    {
      // Equal work per sample for every candidate unless given: the frames decide.
      const double work = this->Work ? this->Work(settings) : 1.0;
      counters->rays += uint64_t(n) * uint64_t(settings.samplesPerPixel);
      counters->ddaSteps += uint64_t(std::llround(work * double(n) * double(settings.samplesPerPixel)));
    }
  }
  void march(const Scene&, const Camera&, const MarchSettings&, const float*, Accumulator&, MarchCounters*) override
  {
  }
  const char* name() const override { return "cpu"; }
  bool rendersPilotsAtOnce() const override { return this->AtOnce; }
  void renderPilots(const Scene& scene, const Camera& camera, std::vector<PilotJob>& jobs) override
  {
    ++this->Rounds;
    Renderer::renderPilots(scene, camera, jobs);
  }
  std::map<uint32_t, double> Signs;
  bool AtOnce = false;
  int Rounds = 0;
};

/// Synthetic noise where expected value never reaches the target soon and
/// the march reaches it in one frame from 1/4 per voxel, its work in
/// proportion to the rate.
void quarterRateWins(SyntheticNoiseRenderer& r)
{
  r.Mse = [](const RenderSettings& st, double n) {
    return st.estimator == Estimator::ExpectedValue ? 1.0 / n : (st.marchSamplesPerVoxel < 0.2f ? 1.0 : 0.5e-4) / n;
  };
  r.Work = [](const RenderSettings& st) {
    return st.estimator == Estimator::ExpectedValue ? 1.0 : 16.0 * st.marchSamplesPerVoxel;
  };
}
} // namespace

// The choice is made where the estimator matters, and only there: the
// visibility optimization and composite blending take the collision
// estimator whatever is set, and lit scenes the expected-value estimator of
// lit camera rays, so no pilot renders.
TEST(EstimatorChoice, NoPilotsWhereTheEstimatorDoesNotApply)
{
  std::unique_ptr<Renderer> inner = testRenderer();
  CountingRenderer r(*inner);
  const DemoVolume v = makeDemo("cosmology", { 16, 16, 16 });
  const Camera cam = demoCam(v, 32, 32);
  {
    Scene scene;
    configureDemo(scene, v, 4, 128, 1.0, BlendMode::Composite);
    const EstimatorChoice c = chooseEstimator(r, scene, cam, RenderSettings());
    EXPECT_FALSE(c.applies);
    EXPECT_TRUE(c.trials.empty());
  }
  {
    Scene scene;
    configureDemo(scene, v, 4);
    LightingDesc ld;
    ld.ambient[0] = ld.ambient[1] = ld.ambient[2] = 0.5;
    scene.setLighting(ld);
    scene.update();
    ASSERT_TRUE(scene.lit());
    RenderSettings collision;
    collision.estimator = Estimator::Collision;
    const EstimatorChoice c = chooseEstimator(r, scene, cam, collision);
    EXPECT_FALSE(c.applies);
    EXPECT_EQ(c.settings.estimator, Estimator::ExpectedValue);
    EXPECT_EQ(effectiveEstimator(scene, c.settings), Estimator::ExpectedValue);
  }
  EXPECT_EQ(r.Renders, 0);
  Scene scene;
  configureDemo(scene, v, 4);
  const EstimatorChoice c = chooseEstimator(r, scene, cam, RenderSettings());
  EXPECT_TRUE(c.applies);
  // Two replicates each, rendered in doublings: the marches' of 1 + 1
  // samples, expected value's of 1 + 1 + 2 + 4 (its decay is taken between
  // 4 and 8).
  const EstimatorChoiceSettings defaults;
  ASSERT_EQ(defaults.expectedValuePilotSamples, 8);
  EXPECT_EQ(r.Renders, 2 * 4 + 4 * (int(c.trials.size()) - 1));
  ASSERT_FALSE(c.trials.empty());
  EXPECT_EQ(c.trials[0].candidate.estimator, Estimator::ExpectedValue);
  EXPECT_EQ(c.trials[0].pilotSamples, 8);
  for (size_t i = 1; i < c.trials.size(); ++i)
  {
    EXPECT_EQ(c.trials[i].pilotSamples, 2) << i;
  }
  EXPECT_GE(c.trials.size(), 3u); // expected value and at least two march rates
}

// The frames predicted from the pilots' checkpoints, as documented in
// EstimatorChoice.h: expected value's MSE falls as N^-1.6 over its first
// two samples and as N^-1 after (a Sobol' gain that fades), so the decay
// must come from its last doubling (4 to 8), where the first one's would
// predict far too few frames; a checkpoint below the target bounds the
// frames from above; one frame where MSE(1) is under it.
TEST(EstimatorChoice, FramesFromTheLastDoubling)
{
  const DemoVolume v = makeDemo("cosmology", { 16, 16, 16 });
  Scene scene;
  configureDemo(scene, v, 4);
  const Camera cam = demoCam(v, 32, 32);
  SyntheticNoiseRenderer r;
  const double target = 1e-4;
  // Expected value: V(1) = 0.01, V(2) = 0.01 2^-1.6, then V(N) = V(2) 2 / N.
  const auto ev = [](double n) { return n <= 1 ? 0.01 : 0.01 * std::pow(2.0, -1.6) * 2.0 / n; };
  // The march: W(N) = W1 / N, W1 set per case.
  double w1 = 1.0;
  r.Mse = [&](const RenderSettings& st, double n) { return st.estimator == Estimator::ExpectedValue ? ev(n) : w1 / n; };
  EstimatorChoiceSettings cs;
  cs.targetMSE = target;
  cs.marchRates = { 1.f };
  cs.tryAllRates = true;
  {
    const EstimatorChoice c = chooseEstimator(r, scene, cam, RenderSettings(), cs);
    ASSERT_EQ(c.trials.size(), 2u);
    const EstimatorTrial& e = c.trials[0];
    EXPECT_EQ(e.pilotSamples, cs.expectedValuePilotSamples);
    EXPECT_NEAR(e.decay, 1.0, 1e-3);
    // V(N) <= 1e-4 from N = 2 * V(2) / 1e-4 = 65.98: 66 frames. The first
    // doubling's decay (1.6) would have predicted (V(1)/target)^(1/1.6) = 18.
    EXPECT_EQ(e.frames, 66.0);
    // The march: 1 / N <= 1e-4 at N = 10000, extrapolated from MSE(2) with a = 1.
    EXPECT_EQ(c.trials[1].pilotSamples, 2);
    EXPECT_EQ(c.trials[1].frames, 10000.0);
    EXPECT_EQ(c.chosen, 0);
  }
  {
    // The march's MSE(2) under the target: 2 frames (interpolated within (1, 2]).
    w1 = 1.5e-4;
    const EstimatorChoice c = chooseEstimator(r, scene, cam, RenderSettings(), cs);
    EXPECT_EQ(c.trials[1].frames, 2.0);
    EXPECT_EQ(c.chosen, 1);
    // Under the target with one sample: 1 frame.
    w1 = 0.9e-4;
    const EstimatorChoice d = chooseEstimator(r, scene, cam, RenderSettings(), cs);
    EXPECT_EQ(d.trials[1].frames, 1.0);
  }
  {
    // Expected value's MSE(4) under the target: its frames lie in (2, 4].
    cs.targetMSE = ev(3.5);
    const EstimatorChoice c = chooseEstimator(r, scene, cam, RenderSettings(), cs);
    EXPECT_EQ(c.trials[0].frames, 4.0);
    cs.targetMSE = ev(2.9);
    const EstimatorChoice d = chooseEstimator(r, scene, cam, RenderSettings(), cs);
    EXPECT_EQ(d.trials[0].frames, 3.0);
    // Its MSE(8) under the target: (4, 8].
    cs.targetMSE = ev(6.5);
    const EstimatorChoice f = chooseEstimator(r, scene, cam, RenderSettings(), cs);
    EXPECT_EQ(f.trials[0].frames, 7.0);
    // With 4 pilot samples the decay comes from 2 to 4 and still fits.
    cs.expectedValuePilotSamples = 4;
    cs.targetMSE = target;
    const EstimatorChoice g = chooseEstimator(r, scene, cam, RenderSettings(), cs);
    EXPECT_EQ(g.trials[0].pilotSamples, 4);
    EXPECT_EQ(g.trials[0].frames, 66.0);
  }
}

// Nothing visible: every candidate is exact (no noise); the tie keeps the
// expected-value estimator. Bad settings are refused.
TEST(EstimatorChoice, NothingVisibleAndBadSettings)
{
  std::unique_ptr<Renderer> r = testRenderer();
  const DemoVolume v = makeDemo("cosmology", { 16, 16, 16 });
  Scene scene;
  configureDemo(scene, v, 4);
  for (int n = 0; n < v.numChannels(); ++n)
  {
    scene.setTransferFunction(n, flatTF(0.f, 1.f, 1.f, 1.f, 1.f, 128));
  }
  scene.update();
  const Camera cam = demoCam(v, 32, 32);
  const EstimatorChoice c = chooseEstimator(*r, scene, cam, RenderSettings());
  ASSERT_TRUE(c.applies);
  for (const EstimatorTrial& t : c.trials)
  {
    EXPECT_EQ(t.variance, 0.0);
  }
  EXPECT_EQ(c.chosen, 0);
  EXPECT_EQ(c.settings.estimator, Estimator::ExpectedValue);

  EstimatorChoiceSettings bad;
  bad.pilotSamples = 1;
  EXPECT_THROW(chooseEstimator(*r, scene, cam, RenderSettings(), bad), std::invalid_argument);
  bad = EstimatorChoiceSettings();
  bad.marchRates = { 0.5f, 0.f };
  EXPECT_THROW(chooseEstimator(*r, scene, cam, RenderSettings(), bad), std::invalid_argument);
  bad.marchRates = { std::nanf("") };
  EXPECT_THROW(chooseEstimator(*r, scene, cam, RenderSettings(), bad), std::invalid_argument);
  bad = EstimatorChoiceSettings();
  bad.targetMSE = 0.0;
  EXPECT_THROW(chooseEstimator(*r, scene, cam, RenderSettings(), bad), std::invalid_argument);
  for (double margin : { 0.0, 1.5, double(std::nanf("")) })
  {
    bad = EstimatorChoiceSettings();
    bad.refineMargin = margin;
    EXPECT_THROW(chooseEstimator(*r, scene, cam, RenderSettings(), bad), std::invalid_argument) << margin;
  }
}

// A fixed seed gives the same choice, to the bit, whatever the thread count
// (the pilots are images, and images are reproducible) and on every call.
TEST(EstimatorChoice, Reproducible)
{
  const DemoVolume v = makeDemo("microscopy", { 32, 28, 16 });
  Scene scene;
  configureDemo(scene, v, 4);
  const Camera cam = demoCam(v, 48, 40);
  RenderSettings base;
  base.seed = 5;
  std::unique_ptr<Renderer> r1 = testRenderer(1);
  std::unique_ptr<Renderer> r2 = testRenderer(2);
  const EstimatorChoice a = chooseEstimator(*r1, scene, cam, base);
  const EstimatorChoice b = chooseEstimator(*r2, scene, cam, base);
  const EstimatorChoice c = chooseEstimator(*r2, scene, cam, base);
  for (const EstimatorChoice* x : { &b, &c })
  {
    ASSERT_EQ(x->trials.size(), a.trials.size());
    EXPECT_EQ(x->chosen, a.chosen);
    for (size_t i = 0; i < a.trials.size(); ++i)
    {
      EXPECT_EQ(x->trials[i].variance, a.trials[i].variance) << i;
      EXPECT_EQ(x->trials[i].costPerSample, a.trials[i].costPerSample) << i;
    }
  }
}

// The choice is close to the fastest to the target error. For every
// candidate the pilot tried, the true time to the target (1-spp frames of
// the full image until its MSE against a 1024-spp reference reaches the
// target, times the candidate's modelled cost per sample) is measured; the
// chosen candidate's is within 2x of the best. The pilot predicts from two
// 2-spp replicates of a smaller image at pixel centres, so near-equal
// candidates (and frame counts of 1 against 2) may swap; a candidate
// several times slower must not win. Three scenes where the winner differs
// (the thin cosmology phantom: expected value; the dense microscopy one at
// a target it reaches late with expected value: the march; the same at
// pixel centres, where every rate is offered with and without control
// variates). The rate search goes on, per variant, while the variant's last
// rate's cost per sample is below the best prediction so far, and stops
// there (a higher rate cannot win); a rate between two listed ones
// (refineRates) comes last.
TEST(EstimatorChoice, NearTheFastestToTheTarget)
{
  std::unique_ptr<Renderer> r = testRenderer();
  struct Case
  {
    const char* demo;
    std::array<int, 3> dims;
    double targetMSE;
    bool centres;
  };
  for (const Case& cs : { Case{ "cosmology", { 32, 32, 32 }, 3.1622776601683794e-4, false },
         Case{ "microscopy", { 64, 56, 32 }, 1e-4, false }, Case{ "microscopy", { 64, 56, 32 }, 1e-4, true } })
  {
    const DemoVolume v = makeDemo(cs.demo, cs.dims);
    Scene scene;
    configureDemo(scene, v, 4);
    Camera cam = demoCam(v, 64, 64);
    if (cs.centres)
    {
      cam.jitterScale = 0.f;
    }
    EstimatorChoiceSettings settings;
    settings.targetMSE = cs.targetMSE;
    const EstimatorChoice c = chooseEstimator(*r, scene, cam, RenderSettings(), settings);
    ASSERT_TRUE(c.applies);
    std::printf("%s%s:\n%s", cs.demo, cs.centres ? " (pixel centres)" : "", c.report().c_str());
    Accumulator ref;
    renderBatches(*r, scene, cam, ref, 1024, 256, 999, Sampler::Independent, Estimator::ExpectedValue);
    const std::vector<float> refImg = image(ref);
    const double refMSE = ref.estimatedMSE();
    std::vector<double> truth;
    bool sawControl = false;
    for (const EstimatorTrial& t : c.trials)
    {
      const int frames =
        framesToTarget(*r, scene, cam, RenderSettings(), t.candidate, cs.targetMSE, refImg, refMSE, 128);
      truth.push_back(double(frames) * t.costPerSample);
      sawControl = sawControl || t.candidate.controlVariates;
      std::printf("  true frames %d, time %.4g\n", frames, truth.back());
    }
    EXPECT_EQ(sawControl, cs.centres) << "control variates are offered at pixel centres only";
    const double best = *std::min_element(truth.begin(), truth.end());
    EXPECT_LE(truth[size_t(c.chosen)], 2.0 * best) << cs.demo;
    // The stop rule, per variant, over the listed rates (the refined rate,
    // if any, comes after them).
    double bestSoFar = c.trials[0].score;
    int lastOf[2] = { -1, -1 };
    int listed[2] = { 0, 0 };
    for (size_t i = 1; i < c.trials.size(); ++i)
    {
      const EstimatorTrial& t = c.trials[i];
      const int variant = t.candidate.controlVariates ? 1 : 0;
      if (t.refined)
      {
        EXPECT_TRUE(i + 1 == c.trials.size() || c.trials[i + 1].refined) << "refined rates come last";
        continue;
      }
      if (lastOf[variant] >= 0)
      {
        EXPECT_LT(c.trials[size_t(lastOf[variant])].costPerSample, bestSoFar)
          << cs.demo << " trial " << i << " was not worth trying";
        EXPECT_GT(t.candidate.marchSamplesPerVoxel, c.trials[size_t(lastOf[variant])].candidate.marchSamplesPerVoxel);
      }
      lastOf[variant] = int(i);
      ++listed[variant];
      bestSoFar = std::min(bestSoFar, t.score);
    }
    const int rates = int(settings.marchRates.size());
    for (int variant = 0; variant < (cs.centres ? 2 : 1); ++variant)
    {
      ASSERT_GE(lastOf[variant], 0);
      if (listed[variant] < rates)
      {
        EXPECT_GE(c.trials[size_t(lastOf[variant])].costPerSample, bestSoFar)
          << cs.demo << ": the search stopped early (variant " << variant << ")";
      }
    }
  }
}

// At pixel centres every march rate is offered twice, with the plain strata
// and with control variates (below kMarchControlVariateRate too), and each
// pilot renders what its name says: the control variates read each stratum's
// two ends besides its point, so their channel samples per stratum are
// higher (RayMarch.ControlVariatesFollowTheRule: 3.4 against 2.3). Jittered
// pixels get the plain strata only; the settings can fix the variant. The
// chosen settings are the chosen candidate's.
TEST(EstimatorChoice, BothVariantsAtPixelCentres)
{
  std::unique_ptr<Renderer> r = testRenderer();
  const DemoVolume v = makeDemo("microscopy", { 32, 28, 16 });
  Scene scene;
  configureDemo(scene, v, 4);
  Camera centres = demoCam(v, 48, 40);
  centres.jitterScale = 0.f;
  EstimatorChoiceSettings cs;
  cs.marchRates = { 2.f, 0.5f };
  cs.tryAllRates = true;
  cs.refineRates = false;
  const EstimatorChoice c = chooseEstimator(*r, scene, centres, RenderSettings(), cs);
  ASSERT_EQ(c.trials.size(), 5u);
  const char* names[] = { "ExpectedValue", "UnbiasedMarch(0.5)", "UnbiasedMarch(0.5, control variates)",
    "UnbiasedMarch(2)", "UnbiasedMarch(2, control variates)" };
  for (size_t i = 0; i < 5; ++i)
  {
    const EstimatorCandidate& k = c.trials[i].candidate;
    EXPECT_EQ(estimatorName(k.estimator, k.marchSamplesPerVoxel, k.controlVariates), names[i]);
    const RenderSettings st = candidateSettings(RenderSettings(), centres, k);
    if (i > 0)
    {
      EXPECT_EQ(marchControlVariates(st, centres), k.controlVariates) << names[i];
    }
  }
  const auto perStratum = [](const EstimatorTrial& t) {
    return double(t.counters.channelSamples) / double(t.counters.tentativeCollisions);
  };
  for (size_t i : { 1u, 3u })
  {
    EXPECT_GT(perStratum(c.trials[i + 1]), 1.2 * perStratum(c.trials[i])) << names[i + 1];
    // Less noise for the same strata.
    EXPECT_LT(c.trials[i + 1].firstFrameMSE, c.trials[i].firstFrameMSE) << names[i + 1];
  }
  const RenderSettings chosen = candidateSettings(RenderSettings(), centres, c.trials[size_t(c.chosen)].candidate);
  EXPECT_EQ(c.settings.estimator, chosen.estimator);
  EXPECT_EQ(c.settings.marchSamplesPerVoxel, chosen.marchSamplesPerVoxel);
  EXPECT_EQ(c.settings.marchControlVariates, chosen.marchControlVariates);
  EXPECT_EQ(c.settings.marchControlVariatesFrom, chosen.marchControlVariatesFrom);

  // Jittered: the plain strata only (what the march renders there).
  const Camera jittered = demoCam(v, 48, 40);
  const EstimatorChoice j = chooseEstimator(*r, scene, jittered, RenderSettings(), cs);
  ASSERT_EQ(j.trials.size(), 3u);
  EXPECT_FALSE(j.trials[1].candidate.controlVariates || j.trials[2].candidate.controlVariates);
  RenderSettings noJitter;
  noJitter.jitterPixels = false;
  EXPECT_EQ(chooseEstimator(*r, scene, jittered, noJitter, cs).trials.size(), 5u)
    << "jitterPixels off is pixel centres too";
  // The variant fixed by the settings.
  RenderSettings plainOnly;
  plainOnly.marchControlVariates = false;
  const EstimatorChoice p = chooseEstimator(*r, scene, centres, plainOnly, cs);
  ASSERT_EQ(p.trials.size(), 3u);
  EXPECT_FALSE(p.trials[1].candidate.controlVariates || p.trials[2].candidate.controlVariates);
  RenderSettings controlOnly;
  controlOnly.marchControlVariatesFrom = 0.f;
  const EstimatorChoice q = chooseEstimator(*r, scene, centres, controlOnly, cs);
  ASSERT_EQ(q.trials.size(), 3u);
  EXPECT_TRUE(q.trials[1].candidate.controlVariates && q.trials[2].candidate.controlVariates);
  // A bad threshold is refused by the render.
  RenderSettings bad;
  bad.marchControlVariatesFrom = std::nanf("");
  Accumulator acc;
  EXPECT_THROW(r->render(scene, centres, bad, nullptr, acc), std::invalid_argument);
  bad.marchControlVariatesFrom = -1.f;
  EXPECT_THROW(r->render(scene, centres, bad, nullptr, acc), std::invalid_argument);
}

// Between a rate that needs two frames and the next, which needs one, the
// choice tries the rate where the one-frame MSE, interpolated log-log, meets
// refineMargin (0.75) x the target, rounded up to a multiple of
// kChoiceRateStep; it wins where its pilot takes one frame within the margin
// for less. A renderer with exactly known noise, MSE(1) = 1.01e-4
// (1/rate)^3.4 for the march (the control variates' fall on the CPU target's
// scene between 1 and 1.25 per voxel), work per sample proportional to the
// rate, target 1e-4: 1 per voxel needs 2 frames (1% over), 1.25 one, and
// 1.125 one for less (MSE(1) 0.68e-4; 1.0915 aimed at).
// A backend that renders a round of pilots at once gets, with the candidate
// the search needs, the higher rates it will most likely reach (cost per
// sample extrapolated in proportion to the rate below the best prediction),
// and the search takes a result only where it reaches that candidate: the
// trials and the choice are those of the pilots one after the other, in
// fewer rounds. Synthetic noise: expected value never reaches the target
// soon, the march from 1/4 per voxel in one frame, the work in proportion
// to the rate (so the extrapolation is exact).
TEST(EstimatorChoice, RendersAheadWithoutChangingTheChoice)
{
  const DemoVolume v = makeDemo("cosmology", { 16, 16, 16 });
  Scene scene;
  configureDemo(scene, v, 4);
  const Camera cam = demoCam(v, 32, 32);
  EstimatorChoiceSettings cs;
  cs.targetMSE = 1e-4;
  cs.marchRates = { 0.0625f, 0.125f, 0.25f, 0.5f, 1.f };
  EstimatorChoice c[2];
  int rounds[2] = { 0, 0 };
  for (int atOnce = 0; atOnce < 2; ++atOnce)
  {
    SyntheticNoiseRenderer r;
    r.AtOnce = atOnce == 1;
    quarterRateWins(r);
    c[atOnce] = chooseEstimator(r, scene, cam, RenderSettings(), cs);
    rounds[atOnce] = r.Rounds;
    EXPECT_EQ(c[atOnce].rounds, r.Rounds);
    std::printf("%s", c[atOnce].report().c_str());
  }
  ASSERT_EQ(c[0].trials.size(), c[1].trials.size());
  EXPECT_EQ(c[0].chosen, c[1].chosen);
  for (size_t i = 0; i < c[0].trials.size(); ++i)
  {
    EXPECT_EQ(c[0].trials[i].candidate.marchSamplesPerVoxel, c[1].trials[i].candidate.marchSamplesPerVoxel) << i;
    EXPECT_EQ(c[0].trials[i].score, c[1].trials[i].score) << i;
  }
  // One after the other: expected value with 1/16, then 1/8, then 1/4 (one
  // frame: the best), after which 1/2 is not reached (1/4's sample cost is
  // the best prediction). No rate between 1/8 and 1/4: the interpolation
  // rounds up to 1/4.
  ASSERT_EQ(c[0].trials.size(), 4u);
  EXPECT_EQ(c[0].chosen, 3);
  EXPECT_EQ(c[0].rendered, 4);
  EXPECT_EQ(rounds[0], 3);
  EXPECT_FLOAT_EQ(c[0].settings.marchSamplesPerVoxel, c[0].trials[size_t(c[0].chosen)].candidate.marchSamplesPerVoxel);
  // At once: 1/8 with 1/4, 1/2 and 1 ahead (all predicted below the best
  // so far, expected value's score), the last two never reached.
  EXPECT_EQ(rounds[1], 2);
  EXPECT_EQ(c[1].rendered, 6);
}

// Frames rendered during the pilots (ChoiceAhead): only where the backend
// renders pilots at once; kept where the choice is their candidate (the
// image then holds them: renders x samples per pixel), dropped (the image
// reset) where it is not; the choice is the same either way. Bad input
// throws before anything is rendered.
TEST(EstimatorChoice, FramesAheadAreKeptOnlyWhereTheChoiceIsTheirs)
{
  const DemoVolume v = makeDemo("cosmology", { 16, 16, 16 });
  Scene scene;
  configureDemo(scene, v, 4);
  const Camera cam = demoCam(v, 32, 32);
  EstimatorChoiceSettings cs;
  cs.targetMSE = 1e-4;
  cs.marchRates = { 0.0625f, 0.125f, 0.25f, 0.5f, 1.f };
  const auto makeRenderer = [](bool atOnce) {
    auto r = std::make_unique<SyntheticNoiseRenderer>();
    r->AtOnce = atOnce;
    quarterRateWins(*r);
    return r;
  };
  RenderSettings base;
  base.samplesPerPixel = 3;
  const EstimatorChoice plain = chooseEstimator(*makeRenderer(true), scene, cam, base, cs);
  ASSERT_TRUE(plain.applies);
  const EstimatorCandidate chosen = plain.chosenCandidate();
  EXPECT_EQ(chosen.estimator, Estimator::UnbiasedMarch);
  EXPECT_FLOAT_EQ(chosen.marchSamplesPerVoxel, 0.25f);
  EstimatorCandidate other; // expected value: not the choice
  for (int atOnce = 0; atOnce < 2; ++atOnce)
  {
    for (const EstimatorCandidate& c : { chosen, other })
    {
      auto r = makeRenderer(atOnce == 1);
      Accumulator accum;
      accum.resize(cam.width, cam.height);
      ChoiceAhead ahead;
      ahead.candidate = c;
      ahead.renders = 2;
      ahead.accum = &accum;
      EstimatorChoiceSettings hinted = cs;
      hinted.hint = plain.hint();
      const EstimatorChoice got = chooseEstimator(*r, scene, cam, base, hinted, ahead);
      ASSERT_EQ(got.trials.size(), plain.trials.size());
      EXPECT_EQ(got.chosen, plain.chosen);
      EXPECT_EQ(ahead.rendered, atOnce == 1);
      const bool mine = atOnce == 1 && c.estimator == chosen.estimator;
      EXPECT_EQ(ahead.kept, mine);
      EXPECT_EQ(accum.samples(), mine ? 6u : 0u);
      if (mine)
      {
        // What the image's own frames would have been rendered with.
        EXPECT_EQ(got.settings.estimator, Estimator::UnbiasedMarch);
        EXPECT_FLOAT_EQ(got.settings.marchSamplesPerVoxel, 0.25f);
      }
    }
  }
  // Nothing rendered where the choice does not apply (composite blending).
  {
    Scene composite;
    configureDemo(composite, v, 4, 128, 1.0, BlendMode::Composite);
    auto r = makeRenderer(true);
    Accumulator accum;
    accum.resize(cam.width, cam.height);
    ChoiceAhead ahead;
    ahead.accum = &accum;
    const EstimatorChoice got = chooseEstimator(*r, composite, cam, base, cs, ahead);
    EXPECT_FALSE(got.applies);
    EXPECT_FALSE(ahead.rendered);
    EXPECT_EQ(accum.samples(), 0u);
  }
  // An image that already holds samples, or no render: refused.
  {
    auto r = makeRenderer(true);
    Accumulator accum;
    accum.resize(cam.width, cam.height);
    RenderSettings one;
    r->render(scene, cam, one, nullptr, accum, nullptr);
    ChoiceAhead ahead;
    ahead.accum = &accum;
    EXPECT_THROW(chooseEstimator(*r, scene, cam, base, cs, ahead), std::invalid_argument);
    EXPECT_EQ(accum.samples(), 1u);
    accum.reset();
    ahead.renders = 0;
    EXPECT_THROW(chooseEstimator(*r, scene, cam, base, cs, ahead), std::invalid_argument);
    EXPECT_EQ(accum.samples(), 0u);
  }
}

// Rendering ahead follows the search's own stop rule: a variant's next rate
// is reached while the sample cost of the rate before it is below the best
// prediction, so a rate whose predecessor is already known goes into the
// round whatever its own extrapolated cost. Both variants' rates between
// (pixel centres) share one round. Synthetic noise with a fixed part in the
// march's work (so the extrapolation in proportion to the rate is high):
// the trials and the choice equal those of the pilots one after the other.
// (A round that stopped at a rate whose own extrapolated cost reached the
// best would leave 1/2 per voxel out, and give each variant's rate between a
// round of its own.)
TEST(EstimatorChoice, RendersAheadWhatTheSearchReaches)
{
  const DemoVolume v = makeDemo("cosmology", { 16, 16, 16 });
  Scene scene;
  configureDemo(scene, v, 4);
  Camera centres = demoCam(v, 32, 32);
  centres.jitterScale = 0.f;
  EstimatorChoiceSettings cs;
  cs.targetMSE = 1e-4;
  cs.marchRates = { 0.25f, 0.5f, 1.f, 2.f };
  const auto control = [&](const RenderSettings& st) { return marchControlVariates(st, centres); };
  EstimatorChoice c[2];
  int rounds[2] = { 0, 0 };
  for (int atOnce = 0; atOnce < 2; ++atOnce)
  {
    SyntheticNoiseRenderer r;
    r.AtOnce = atOnce == 1;
    r.Mse = [&](const RenderSettings& st, double n) {
      if (st.estimator == Estimator::ExpectedValue)
      {
        return 1.0 / n;
      }
      const double rate = st.marchSamplesPerVoxel;
      return (control(st) ? 1.5e-4 / std::pow(rate, 3.4) : 1.3e-4 / (rate * rate)) / n;
    };
    r.Work = [&](const RenderSettings& st) {
      return st.estimator == Estimator::ExpectedValue
        ? 1.0
        : 16.0 * ((control(st) ? 0.5 : 0.25) + double(st.marchSamplesPerVoxel));
    };
    c[atOnce] = chooseEstimator(r, scene, centres, RenderSettings(), cs);
    rounds[atOnce] = r.Rounds;
    EXPECT_EQ(c[atOnce].rounds, r.Rounds);
    std::printf("%s%d rounds, %d rendered\n", c[atOnce].report().c_str(), c[atOnce].rounds, c[atOnce].rendered);
  }
  ASSERT_EQ(c[0].trials.size(), c[1].trials.size());
  EXPECT_EQ(c[0].chosen, c[1].chosen);
  for (size_t i = 0; i < c[0].trials.size(); ++i)
  {
    const EstimatorCandidate& a = c[0].trials[i].candidate;
    const EstimatorCandidate& b = c[1].trials[i].candidate;
    EXPECT_EQ(a.marchSamplesPerVoxel, b.marchSamplesPerVoxel) << i;
    EXPECT_EQ(a.controlVariates, b.controlVariates) << i;
    EXPECT_EQ(c[0].trials[i].refined, c[1].trials[i].refined) << i;
    EXPECT_EQ(c[0].trials[i].score, c[1].trials[i].score) << i;
  }
  // Both variants' 1 per voxel takes two frames and 2 per voxel one, so
  // each has a rate between to try. The plain one (1.375) is tried first and
  // takes one frame for less than any listed rate; that lowers the best
  // below the control variates' interpolated cost, so one after the other
  // their rate between is never rendered, and at once it is rendered in the
  // same round and dropped: one rate between among the trials either way.
  int refined = 0;
  for (const EstimatorTrial& t : c[0].trials)
  {
    refined += t.refined ? 1 : 0;
  }
  EXPECT_EQ(refined, 1);
  EXPECT_TRUE(c[0].trials[size_t(c[0].chosen)].refined);
  EXPECT_EQ(c[0].rendered, int(c[0].trials.size()));
  EXPECT_EQ(c[1].rendered, int(c[1].trials.size()) + 1);
  // One after the other: a round per candidate after the first three. At
  // once: the first round, every listed rate in the second (each one's
  // predecessor costs less per sample than the best so far, expected
  // value's), and both rates between in the third.
  EXPECT_EQ(rounds[0], int(c[0].trials.size()) - 2);
  EXPECT_EQ(rounds[1], 3);
}

// The same on rendered demo data: a backend that renders each round at once
// (here the test backend, wrapped to say so) gets the same trials, scores
// and choice as one after the other, in no more rounds, with the GPU's cost
// model (the one the CUDA backend's choice uses), jittered and at pixel
// centres, on a dense and a sparse set; and the same with any hint
// (EstimatorChoiceSettings::hint), in one round with its own.
TEST(EstimatorChoice, AtOnceEqualsOneAfterTheOtherOnDemoData)
{
  class AtOnce : public Renderer
  {
  public:
    explicit AtOnce(bool atOnce)
      : On(atOnce)
    {
    }
    void render(const Scene& s, const Camera& c, const RenderSettings& st, const float* d, Accumulator& a,
      RenderCounters* k) override
    {
      this->In->render(s, c, st, d, a, k);
    }
    void renderPilots(const Scene& s, const Camera& c, std::vector<PilotJob>& jobs) override
    {
      this->In->renderPilots(s, c, jobs);
    }
    bool rendersPilotsAtOnce() const override { return this->On; }
    void march(const Scene& s, const Camera& c, const MarchSettings& m, const float* d, Accumulator& a,
      MarchCounters* k) override
    {
      this->In->march(s, c, m, d, a, k);
    }
    const char* name() const override { return "cuda"; } // the GPU's cost model
    std::unique_ptr<Renderer> In = testRenderer();
    bool On;
  };
  std::vector<EstimatorCandidate> lastHint = { { Estimator::UnbiasedMarch, 0.3125f, true },
    { Estimator::UnbiasedMarch, 4.f, false } }; // a rate between and a high one
  for (const char* set : { "microscopy", "cosmology" })
  {
    const DemoVolume v = makeDemo(set, { 48, 40, 24 });
    Scene scene;
    configureDemo(scene, v, 4);
    Camera centres = demoCam(v, 96, 80);
    centres.jitterScale = 0.f;
    for (const Camera& cam : { demoCam(v, 96, 80), centres })
    {
      AtOnce one(false), all(true);
      const EstimatorChoice a = chooseEstimator(one, scene, cam, RenderSettings());
      const EstimatorChoice b = chooseEstimator(all, scene, cam, RenderSettings());
      const std::string where = std::string(set) + (cam.jitterScale > 0.f ? ", jittered" : ", centres");
      ASSERT_EQ(a.trials.size(), b.trials.size()) << where;
      EXPECT_EQ(a.chosen, b.chosen) << where;
      for (size_t i = 0; i < a.trials.size(); ++i)
      {
        EXPECT_EQ(a.trials[i].candidate.marchSamplesPerVoxel, b.trials[i].candidate.marchSamplesPerVoxel) << where;
        EXPECT_EQ(a.trials[i].candidate.controlVariates, b.trials[i].candidate.controlVariates) << where;
        EXPECT_EQ(a.trials[i].score, b.trials[i].score) << where << ", trial " << i;
      }
      EXPECT_LE(b.rounds, a.rounds) << where;
      EXPECT_GE(b.rendered, int(b.trials.size())) << where;
      // With a hint: the choice's own candidates (a transfer-function edit
      // that changed nothing the choice sees) render in one round, rates
      // between included; another set's candidates change only the rounds.
      // Either way the trials and the choice stay, and a backend that
      // renders one after the other ignores the hint.
      EstimatorChoiceSettings self;
      self.hint = b.hint();
      EstimatorChoiceSettings other;
      other.hint = lastHint;
      for (const EstimatorChoiceSettings* cs : { &self, &other })
      {
        AtOnce hinted(true), ignoring(false);
        const EstimatorChoice h = chooseEstimator(hinted, scene, cam, RenderSettings(), *cs);
        const EstimatorChoice g = chooseEstimator(ignoring, scene, cam, RenderSettings(), *cs);
        const std::string how = where + (cs == &self ? ", its own hint" : ", another set's hint");
        ASSERT_EQ(h.trials.size(), a.trials.size()) << how;
        EXPECT_EQ(h.chosen, a.chosen) << how;
        for (size_t i = 0; i < a.trials.size(); ++i)
        {
          EXPECT_EQ(h.trials[i].score, a.trials[i].score) << how << ", trial " << i;
          EXPECT_EQ(h.trials[i].refined, a.trials[i].refined) << how << ", trial " << i;
        }
        EXPECT_EQ(g.rounds, a.rounds) << how;
        EXPECT_EQ(g.rendered, a.rendered) << how;
        if (cs == &self)
        {
          EXPECT_EQ(h.rounds, 1) << how;
          EXPECT_EQ(h.rendered, int(h.trials.size())) << how;
        }
        std::printf("%s: %d rounds, %d rendered\n", how.c_str(), h.rounds, h.rendered);
      }
      lastHint = b.hint();
      std::printf("%s: %s; %d rounds one after the other, %d at once (%d rendered for %zu trials)\n", where.c_str(),
        b.chosenName().c_str(), a.rounds, b.rounds, b.rendered, b.trials.size());
    }
  }
}

// Renderer::renderPilots refuses checkpoints that are missing, not positive
// or not ascending with a clear error, on every backend (testRenderer()),
// and renders a valid job after that.
TEST(EstimatorChoice, PilotJobsAreChecked)
{
  const DemoVolume v = makeDemo("cosmology", { 16, 16, 16 });
  Scene scene;
  configureDemo(scene, v, 4);
  const Camera cam = demoCam(v, 16, 12);
  std::unique_ptr<Renderer> r = testRenderer();
  for (const std::vector<int>& bad : { std::vector<int>{}, std::vector<int>{ 0 }, std::vector<int>{ 2, 2 },
         std::vector<int>{ 2, 1 }, std::vector<int>{ -1, 2 } })
  {
    std::vector<PilotJob> jobs(2);
    jobs[0].checkpoints = { 1, 2 };
    jobs[1].checkpoints = bad;
    EXPECT_THROW(r->renderPilots(scene, cam, jobs), std::invalid_argument) << bad.size();
  }
  std::vector<PilotJob> jobs(1);
  jobs[0].checkpoints = { 1, 3 };
  jobs[0].seeds[1] = 9u;
  r->renderPilots(scene, cam, jobs);
  ASSERT_EQ(jobs[0].means[0].size(), 2u);
  ASSERT_EQ(jobs[0].means[1][1].size(), size_t(4) * 16 * 12);
  EXPECT_EQ(jobs[0].counters.rays, uint64_t(16 * 12 * 3));
  EXPECT_NE(jobs[0].means[0][1], jobs[0].means[1][1]);
}

TEST(EstimatorChoice, RefinesBetweenRates)
{
  const DemoVolume v = makeDemo("cosmology", { 16, 16, 16 });
  Scene scene;
  configureDemo(scene, v, 4);
  const Camera cam = demoCam(v, 32, 32);
  SyntheticNoiseRenderer r;
  double w1 = 1.01e-4;
  r.Mse = [&](const RenderSettings& st, double n) {
    return st.estimator == Estimator::ExpectedValue ? 1.0 / n
                                                    : w1 * std::pow(1.0 / st.marchSamplesPerVoxel, 3.4) / n;
  };
  r.Work = [](const RenderSettings& st) { return st.estimator == Estimator::ExpectedValue ? 1.0 : 16.0 * st.marchSamplesPerVoxel; };
  EstimatorChoiceSettings cs;
  cs.targetMSE = 1e-4;
  cs.marchRates = { 1.f, 1.25f };
  {
    const EstimatorChoice c = chooseEstimator(r, scene, cam, RenderSettings(), cs);
    std::printf("%s", c.report().c_str());
    ASSERT_EQ(c.trials.size(), 4u);
    EXPECT_EQ(c.trials[1].frames, 2.0);
    EXPECT_EQ(c.trials[2].frames, 1.0);
    const EstimatorTrial& between = c.trials[3];
    EXPECT_TRUE(between.refined);
    EXPECT_FLOAT_EQ(between.candidate.marchSamplesPerVoxel, 1.125f);
    EXPECT_EQ(between.frames, 1.0);
    EXPECT_EQ(c.chosen, 3);
    EXPECT_FLOAT_EQ(c.settings.marchSamplesPerVoxel, 1.125f);
    EXPECT_NE(c.report().find("between listed rates"), std::string::npos);
  }
  {
    // The rate between is tried, but its pilot is not within the margin (its
    // MSE(1) 1.01e-4 too: flat up to 1.2 per voxel): two frames, 1.25 stays.
    const auto smooth = r.Mse;
    r.Mse = [&](const RenderSettings& st, double n) {
      return st.estimator == Estimator::ExpectedValue ? 1.0 / n
                                                      : (st.marchSamplesPerVoxel < 1.2f ? 1.01e-4 : 0.47e-4) / n;
    };
    const EstimatorChoice c = chooseEstimator(r, scene, cam, RenderSettings(), cs);
    ASSERT_EQ(c.trials.size(), 4u);
    EXPECT_TRUE(c.trials[3].refined);
    EXPECT_EQ(c.trials[3].frames, 2.0);
    EXPECT_EQ(c.chosen, 2);
    r.Mse = smooth;
  }
  {
    // Off: the listed rates only, 1.25 chosen.
    EstimatorChoiceSettings off = cs;
    off.refineRates = false;
    const EstimatorChoice c = chooseEstimator(r, scene, cam, RenderSettings(), off);
    ASSERT_EQ(c.trials.size(), 3u);
    EXPECT_EQ(c.chosen, 2);
  }
  {
    // The lowest rate already takes one frame: nothing to refine (and the
    // stop rule skips 1.25, which costs more per sample).
    w1 = 0.9e-4;
    const EstimatorChoice c = chooseEstimator(r, scene, cam, RenderSettings(), cs);
    ASSERT_EQ(c.trials.size(), 2u);
    EXPECT_EQ(c.chosen, 1);
  }
  {
    // Far from the boundary: 1 per voxel 1.9x over, the interpolated rate
    // ((1.9 / 0.75)^(1/3.4) = 1.314) is above 1.25: nothing between to try.
    w1 = 1.9e-4;
    const EstimatorChoice c = chooseEstimator(r, scene, cam, RenderSettings(), cs);
    ASSERT_EQ(c.trials.size(), 3u);
    EXPECT_EQ(c.trials[1].frames, 2.0);
    EXPECT_EQ(c.chosen, 2);
  }
}
