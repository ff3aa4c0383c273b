// SPDX-License-Identifier: BSD-3-Clause
// Whole-image properties of the Monte Carlo renderer (Documentation/design.md,
// "What the tests prove"):
// - the N-DDA and 1-DDA trackers render the same image (statistically;
//   Sahistan et al., Sec. 4);
// - images do not depend on the thread count, and progressive accumulation
//   equals one render of all samples;
// - the blend modes (max, mix Eq. 10, post-render compositing).
// Significance: each TEST has a family-wise level kAlpha = 0.001, split evenly
// (Bonferroni) over its statistical checks; seeds are fixed.
#include "TestUtil.h"

#include "mcvol/ray/Integrator.h"

#include <cstring>
#include <numeric>

using namespace mcvol;
using namespace mcvol::test;

namespace
{
constexpr double kAlpha = 1e-3;

Camera demoCamera(const DemoVolume& v, int W, int H, double az = 30, double el = 20)
{
  return orbitCamera(v.dims, v.spacing, W, H, az, el);
}
} // namespace

// ------------------------------------------------- N-DDA against 1-DDA

// Per-pixel pooled two-sample z-scores of 64 independent samples per pixel
// and tracker (different seeds): image-mean difference, sum of z^2
// (chi-square) and the largest |z| (Bonferroni over pixels) per component
// (see expectZeroDifference): 2 scenes x 4 components x 3 = 24 checks.
TEST(Trackers, NDDAMatches1DDA)
{
  for (const char* name : { "figure3", "cosmology" })
  {
    const DemoVolume v = makeDemo(name, { 24, 24, 24 });
    Scene scene;
    configureDemo(scene, v, 4);
    const Camera cam = demoCamera(v, 40, 40);
    RenderSettings rs;
    rs.estimator = Estimator::Collision; // the trackers' estimator (expected-value uses neither)
    rs.tracker = Tracker::OneDDA;
    const Moments one = renderMoments(scene, cam, rs, 64, 1000);
    rs.tracker = Tracker::NDDA;
    const Moments many = renderMoments(scene, cam, rs, 64, 5000);
    double alphaSum = 0;
    for (size_t p = 3; p < one.size(); p += 4)
      alphaSum += one.mean(p);
    EXPECT_GT(alphaSum / (40 * 40), 0.05) << name << ": the image is nearly empty; the test would be weak";
    expectSameImage(one, many, kAlpha / 24, std::string(name) + " 1-DDA vs N-DDA");
  }
}

// ------------------------------------------------------- reproducibility

TEST(Reproducibility, ThreadCountDoesNotChangeImage)
{
  const DemoVolume v = makeDemo("cosmology", { 32, 32, 32 });
  Scene scene;
  configureDemo(scene, v, 8);
  const Camera cam = demoCamera(v, 48, 37);
  for (BlendMode mode : { BlendMode::Density, BlendMode::Mix, BlendMode::Composite })
  {
    scene.setBlendMode(mode);
    scene.update();
    for (Estimator e : { Estimator::Collision, Estimator::ExpectedValue })
    for (Tracker t : { Tracker::OneDDA, Tracker::NDDA })
    {
      RenderSettings rs;
      rs.samplesPerPixel = 4;
      rs.seed = 77;
      rs.tracker = t;
      rs.estimator = e;
      std::vector<float> ref;
      RenderCounters refCounters;
      for (int threads : { 1, 2, 3 })
      {
        CPURenderer r;
        r.setThreads(threads);
        Accumulator acc;
        RenderCounters counters;
        r.render(scene, cam, rs, nullptr, acc, &counters);
        std::vector<float> img(acc.rgba(), acc.rgba() + size_t(cam.width) * cam.height * 4);
        if (threads == 1)
        {
          ref = img;
          refCounters = counters;
          continue;
        }
        EXPECT_EQ(0, std::memcmp(ref.data(), img.data(), ref.size() * sizeof(float)))
          << toString(mode) << " " << toString(t) << " " << toString(e) << ": " << threads
          << " threads differ from 1 thread";
        EXPECT_EQ(counters.tentativeCollisions, refCounters.tentativeCollisions);
        EXPECT_EQ(counters.ddaSteps, refCounters.ddaSteps);
        EXPECT_EQ(counters.realCollisions, refCounters.realCollisions);
      }
    }
  }
}

TEST(Reproducibility, ProgressiveEqualsOneRender)
{
  const DemoVolume v = makeDemo("figure3", { 32, 32, 32 });
  Scene scene;
  configureDemo(scene, v, 8);
  const Camera cam = demoCamera(v, 40, 40, 60, -15);
  CPURenderer r;
  for (Tracker t : { Tracker::OneDDA, Tracker::NDDA })
  {
    RenderSettings rs;
    rs.seed = 5;
    rs.tracker = t;
    Accumulator progressive, once;
    rs.samplesPerPixel = 1;
    for (int k = 0; k < 4; ++k)
    {
      r.render(scene, cam, rs, nullptr, progressive);
    }
    EXPECT_EQ(progressive.samples(), 4u);
    rs.samplesPerPixel = 4;
    r.render(scene, cam, rs, nullptr, once);
    EXPECT_EQ(once.samples(), 4u);
    double maxDiff = 0, sum = 0;
    for (size_t i = 0; i < size_t(cam.width) * cam.height * 4; ++i)
    {
      maxDiff = std::max(maxDiff, double(std::fabs(progressive.rgba()[i] - once.rgba()[i])));
      sum += once.rgba()[i];
    }
    EXPECT_LE(maxDiff, 1e-5) << toString(t);
    EXPECT_GT(sum, 10.0) << "empty image";
  }
}

// Each sample is added to the pixel's sum of all the samples before it, so
// the batching of samples into renders changes nothing, bit for bit: neither
// the image nor the error estimate's even half.
TEST(Reproducibility, BatchingDoesNotChangeImageBitForBit)
{
  const DemoVolume v = makeDemo("figure3", { 32, 32, 32 });
  Scene scene;
  configureDemo(scene, v, 8);
  const Camera cam = demoCamera(v, 40, 40, 60, -15);
  const size_t n = size_t(cam.width) * cam.height * 4;
  CPURenderer r;
  for (Estimator e : { Estimator::Collision, Estimator::ExpectedValue })
  {
    std::vector<float> ref, refEven;
    double refMSE = 0;
    for (const std::vector<int>& batches : { std::vector<int>{ 24 }, std::vector<int>(24, 1), { 5, 7, 12 },
           { 8, 8, 8 } })
    {
      RenderSettings rs;
      rs.seed = 5;
      rs.estimator = e;
      Accumulator acc;
      for (int b : batches)
      {
        rs.samplesPerPixel = b;
        r.render(scene, cam, rs, nullptr, acc);
      }
      ASSERT_EQ(acc.samples(), 24u);
      ASSERT_NE(acc.evenRGBA(), nullptr);
      std::vector<float> img(acc.rgba(), acc.rgba() + n), even(acc.evenRGBA(), acc.evenRGBA() + n);
      if (ref.empty())
      {
        ref = img;
        refEven = even;
        refMSE = acc.estimatedMSE();
        EXPECT_GT(std::accumulate(ref.begin(), ref.end(), 0.0), 10.0) << "empty image";
        continue;
      }
      EXPECT_EQ(0, std::memcmp(ref.data(), img.data(), n * sizeof(float)))
        << toString(e) << ": " << batches.size() << " batches differ from one render";
      EXPECT_EQ(0, std::memcmp(refEven.data(), even.data(), n * sizeof(float)))
        << toString(e) << ": even half, " << batches.size() << " batches";
      EXPECT_EQ(acc.estimatedMSE(), refMSE) << toString(e);
    }
  }
}

// ------------------------------------------------------ long accumulation

// Past 2^24 samples per pixel a float running mean stops taking samples
// close to it (a float mean of 0.5 moves by at least half its spacing,
// 3e-8, only for a step of more than 2^-25 x the difference: with one
// sample per render and 2^25 samples, never). The image is a double sum
// over the count, so it keeps converging. A 2^25-sample image is set up
// without rendering it: a mean written through rgbaForOverwrite() and the
// count through addSamples() (the sums are derived from them), then 64
// renders of one sample each. Image B holds the same 64 samples on a zero
// mean, so image A must equal 0.5 x 2^25 / N + B (N = 2^25 + 64) to within
// the rounding of A (under one float spacing at 0.5, 6e-8); a stalled mean
// stays at 0.5, 9.5e-7 off where the samples are 0 (the background) or 1.
TEST(Accumulation, KeepsConvergingPast2To24Samples)
{
  const DemoVolume v = makeDemo("figure3", { 32, 32, 32 });
  Scene scene;
  configureDemo(scene, v, 8);
  const Camera cam = demoCamera(v, 24, 24, 60, -15);
  const uint32_t preset = 1u << 25;
  const int renders = 64;
  CPURenderer r;
  RenderSettings rs;
  rs.seed = 3;
  rs.samplesPerPixel = 1;
  Accumulator a, b;
  presetLongImages(a, b, cam, preset, false);
  for (int k = 0; k < renders; ++k)
  {
    r.render(scene, cam, rs, nullptr, a);
    r.render(scene, cam, rs, nullptr, b);
  }
  expectLongMean(a, b, preset, renders);

  // A synthetic stream through the same per-pixel sums (loadSum, addSample,
  // storeSum): 2^25 samples of k / 2^16, in renders of 8. Their sum is
  // exact in double, so the mean is the exact mean rounded once.
  double stored[4] = { 0, 0, 0, 0 };
  float streamMean[4] = { 0, 0, 0, 0 };
  uint64_t exact = 0; // in units of 2^-16
  uint32_t count = 0;
  uint32_t state = 12345u;
  while (count < preset)
  {
    Vec4d sum = loadSum(stored, count);
    for (int k = 0; k < 8; ++k)
    {
      state = state * 1664525u + 1013904223u;
      const uint32_t units = state >> 16; // 0 ... 2^16 - 1
      exact += units;
      const float x = float(units) * 0x1p-16f;
      addSample(sum, Vec4f{ x, x, x, 1.f });
    }
    count += 8;
    storeSum(streamMean, stored, sum, count);
  }
  const float want = float(double(exact) * 0x1p-16 / double(count));
  EXPECT_EQ(streamMean[0], want);
  EXPECT_EQ(streamMean[3], 1.f);
}

// ----------------------------------------------------------- blend modes

namespace
{
/// Two overlapping homogeneous channels filling an 8 x 8 x 17 volume, seen
/// along z by an orthographic camera, so every ray crosses 16 units.
struct TwoChannelSlab
{
  TestVolume v{ 8, 8, 17, 2, 0.5f };
  Scene scene;
  Camera cam = orthoAlongZ(16, 16, 0.5, 6.5, 0.5, 6.5, 20.0, 40.0);
  static constexpr double kThickness = 16.0;

  TwoChannelSlab(double sigma0, double sigma1, BlendMode mode)
  {
    configure(
      scene, v, { flatTF(opacityFor(sigma0, 1.0), 1, 0, 0), flatTF(opacityFor(sigma1, 1.0), 0, 1, 0) }, 4, mode);
  }

  /// One render of `spp` samples; returns total alpha (= number of
  /// collided samples) and checks per-pixel colour against `rgb` * alpha.
  double render(Tracker t, int spp, uint32_t seed, const float rgb[3], const std::string& what)
  {
    CPURenderer r;
    Accumulator acc;
    RenderSettings rs;
    rs.samplesPerPixel = spp;
    rs.seed = seed;
    rs.tracker = t;
    rs.estimator = Estimator::Collision; // alpha counts collided samples
    r.render(scene, cam, rs, nullptr, acc);
    double hits = 0;
    for (int p = 0; p < cam.width * cam.height; ++p)
    {
      const float* px = acc.rgba() + 4 * p;
      for (int c = 0; c < 3; ++c)
      {
        EXPECT_NEAR(px[c], rgb[c] * px[3], 1e-5) << what << " pixel " << p << " component " << c;
      }
      hits += double(px[3]) * spp;
    }
    return std::round(hits);
  }
};
} // namespace

// Max (Eq. 8/9): only the channel of larger extinction exists: its colour
// alone appears, and alpha follows 1 - exp(-sigma_max d) (binomial tests,
// 8 checks). Density adds the extinctions (Eq. 6) for contrast.
TEST(BlendModes, MaxShowsOnlyTheDenserChannel)
{
  uint32_t seed = 1;
  for (Tracker t : { Tracker::OneDDA, Tracker::NDDA })
  {
    for (int order = 0; order < 2; ++order)
    {
      const double s0 = order == 0 ? 0.04 : 0.1, s1 = order == 0 ? 0.1 : 0.04;
      TwoChannelSlab slab(s0, s1, BlendMode::Max);
      const float rgb[3] = { order == 0 ? 0.f : 1.f, order == 0 ? 1.f : 0.f, 0.f };
      const int spp = 64;
      const double n = double(slab.cam.width * slab.cam.height * spp);
      const std::string what = std::string("max ") + toString(t) + " order " + std::to_string(order);
      const double hits = slab.render(t, spp, ++seed, rgb, what);
      expectBinomial(hits, n, -std::expm1(-0.1 * slab.kThickness), kAlpha / 8, what);

      TwoChannelSlab density(s0, s1, BlendMode::Density);
      CPURenderer r;
      Accumulator acc;
      RenderSettings rs;
      rs.samplesPerPixel = spp;
      rs.seed = ++seed;
      rs.tracker = t;
      rs.estimator = Estimator::Collision;
      r.render(density.scene, density.cam, rs, nullptr, acc);
      double dh = 0;
      for (int p = 0; p < density.cam.width * density.cam.height; ++p)
        dh += double(acc.rgba()[4 * p + 3]) * spp;
      expectBinomial(
        std::round(dh), n, -std::expm1(-0.14 * slab.kThickness), kAlpha / 8, std::string("density ") + toString(t));
    }
  }
}

// Mix (Eq. 8 and 10): extinction max_n sigma_n, colour
// sum_n w_n sigma_n c_n / max_n sigma_n with weights (3, 1) normalised to
// (0.75, 0.25). Colour is checked per pixel (deterministic per collision),
// alpha by binomial tests (4 checks).
TEST(BlendModes, MixFollowsEquation10)
{
  uint32_t seed = 50;
  const float w[2] = { 3.f, 1.f };
  for (Tracker t : { Tracker::OneDDA, Tracker::NDDA })
  {
    for (int order = 0; order < 2; ++order)
    {
      const double s0 = order == 0 ? 0.04 : 0.1, s1 = order == 0 ? 0.1 : 0.04;
      TwoChannelSlab slab(s0, s1, BlendMode::Mix);
      slab.scene.setMixWeights(w, 2);
      slab.scene.setMixAverage(false);
      slab.scene.update();
      EXPECT_FLOAT_EQ(slab.scene.view().blend.mixWeights[0], 0.75f);
      EXPECT_FLOAT_EQ(slab.scene.view().blend.mixWeights[1], 0.25f);
      // Red from channel 0, green from channel 1.
      const float rgb[3] = { float(0.75 * s0 / 0.1), float(0.25 * s1 / 0.1), 0.f };
      const int spp = 64;
      const double n = double(slab.cam.width * slab.cam.height * spp);
      const std::string what = std::string("mix ") + toString(t) + " order " + std::to_string(order);
      const double hits = slab.render(t, spp, ++seed, rgb, what);
      expectBinomial(hits, n, -std::expm1(-0.1 * slab.kThickness), kAlpha / 4, what);
    }
  }
}

// Mix, weighted-average colour (the default): extinction max_n sigma_n,
// colour sum_n w_n sigma_n c_n / sum_n w_n sigma_n. Weights (3, 1); red from
// channel 0, green from channel 1. Then one channel alone (the other at zero
// opacity) keeps its full colour, where Eq. 10 shows w_0 of it. Alpha by
// binomial tests (8 checks, kAlpha / 8 each).
TEST(BlendModes, MixAverageKeepsALoneChannelsColour)
{
  uint32_t seed = 150;
  const float w[2] = { 3.f, 1.f };
  for (Tracker t : { Tracker::OneDDA, Tracker::NDDA })
  {
    for (int order = 0; order < 2; ++order)
    {
      const double s0 = order == 0 ? 0.04 : 0.1, s1 = order == 0 ? 0.1 : 0.04;
      TwoChannelSlab slab(s0, s1, BlendMode::Mix);
      slab.scene.setMixWeights(w, 2);
      slab.scene.update();
      EXPECT_TRUE(slab.scene.view().blend.mixAverage) << "the default";
      const double sum = 0.75 * s0 + 0.25 * s1;
      const float rgb[3] = { float(0.75 * s0 / sum), float(0.25 * s1 / sum), 0.f };
      const int spp = 64;
      const double n = double(slab.cam.width * slab.cam.height * spp);
      const std::string what = std::string("mix average ") + toString(t) + " order " + std::to_string(order);
      const double hits = slab.render(t, spp, ++seed, rgb, what);
      expectBinomial(hits, n, -std::expm1(-0.1 * slab.kThickness), kAlpha / 8, what);
    }
    // Channel 1 absent: channel 0's own colour, full (Eq. 10: 0.75 of it).
    for (bool average : { true, false })
    {
      TwoChannelSlab slab(0.1, 0.0, BlendMode::Mix);
      slab.scene.setMixWeights(w, 2);
      slab.scene.setMixAverage(average);
      slab.scene.update();
      const float rgb[3] = { average ? 1.f : 0.75f, 0.f, 0.f };
      const int spp = 64;
      const double n = double(slab.cam.width * slab.cam.height * spp);
      const std::string what = std::string(average ? "average" : "Eq. 10") + ", channel 0 alone, " + toString(t);
      const double hits = slab.render(t, spp, ++seed, rgb, what);
      expectBinomial(hits, n, -std::expm1(-0.1 * slab.kThickness), kAlpha / 8, what);
    }
  }
}

// Post-render compositing: the composite's RGB equals the sum of the
// channels rendered alone (the others at zero opacity), and its alpha
// 1 - prod(1 - alpha_n). Per-pixel z-scores with unpooled variances (the
// alpha product's by the delta method; the product of independent unbiased
// estimates is unbiased): image mean, chi-square and largest |z| per
// component (12 checks). No pixel jitter: every sample of a pixel is the
// same ray (with jitter, the channels' hit probabilities would be correlated
// through the shared sub-pixel position and the product would not hold).
TEST(BlendModes, CompositeIsSumOfChannels)
{
  const DemoVolume v = makeDemo("cosmology", { 24, 24, 24 });
  const int N = v.numChannels();
  const Camera cam = demoCamera(v, 32, 32);
  const int n = 128;
  Scene scene;
  configureDemo(scene, v, 4, 64, 1.0, BlendMode::Composite);
  RenderSettings rs;
  rs.jitterPixels = false;
  rs.estimator = Estimator::Collision; // the single-channel renders below compare sample by sample
  const Moments C = renderMoments(scene, cam, rs, n, 100);
  std::vector<Moments> S;
  for (int k = 0; k < N; ++k)
  {
    Scene alone;
    configureDemo(alone, v, 4, 64, 1.0, BlendMode::Density);
    for (int m = 0; m < N; ++m)
    {
      if (m != k)
      {
        alone.setTransferFunction(m, flatTF(0.f, 1, 1, 1, 1.f, 64));
      }
    }
    alone.update();
    ASSERT_EQ(alone.view().numActive, 1);
    S.push_back(renderMoments(alone, cam, rs, n, 1000 + 1000 * uint32_t(k)));
  }
  std::vector<double> D(C.size()), V(C.size());
  for (size_t p = 0; p < C.size() / 4; ++p)
  {
    for (int c = 0; c < 3; ++c)
    {
      const size_t i = p * 4 + size_t(c);
      double sum = 0, var = C.var(i) / n;
      for (const Moments& s : S)
      {
        sum += s.mean(i);
        var += s.var(i) / n;
      }
      D[i] = C.mean(i) - sum;
      V[i] = var;
    }
    const size_t i = p * 4 + 3;
    double prod = 1;
    for (const Moments& s : S)
      prod *= 1 - s.mean(i);
    double var = C.var(i) / n;
    for (size_t k = 0; k < S.size(); ++k)
    {
      double others = 1;
      for (size_t m = 0; m < S.size(); ++m)
        others *= m == k ? 1.0 : 1 - S[m].mean(i);
      var += others * others * S[k].var(i) / n;
    }
    D[i] = C.mean(i) - (1 - prod);
    V[i] = var;
  }
  expectZeroDifference(D, V, kAlpha / 12, "composite vs sum of channels");
}
