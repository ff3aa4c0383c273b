// SPDX-License-Identifier: BSD-3-Clause
// The ray-marching reference (RayMarch.h, RayMarcher): analytic slabs, the
// Kraus and Buerger one-voxel wall, exact empty-space skipping, termination,
// reproducibility, hard cases, and the Monte Carlo trackers converging to it.
//
// Significance: MonteCarloConvergesToRayMarch makes 2 datasets x 4 modes x 4
// components x 4 statistics = 128 checks at family-wise level kAlpha = 0.001
// (Bonferroni). The 1/sqrt(spp) slope test is deterministic for its fixed
// seeds; its tolerance (0.05) is about 5 times the slope's standard error,
// which the test prints. Seeds are fixed.
#include "TestUtil.h"

#include "mcvol/RayMarcher.h"
#include "mcvol/RenderSetup.h"

#include <limits>

using namespace mcvol;
using namespace mcvol::test;

namespace
{
constexpr double kAlpha = 1e-3;

std::vector<float> march(
  const Scene& scene, const Camera& cam, const MarchSettings& ms, MarchCounters* c = nullptr, int threads = 0)
{
  RayMarcher r;
  r.setThreads(threads);
  Accumulator acc;
  r.render(scene, cam, ms, nullptr, acc, c);
  EXPECT_EQ(acc.samples(), 1u);
  return std::vector<float>(acc.rgba(), acc.rgba() + size_t(cam.width) * cam.height * 4);
}

/// A transfer function over scalars [0, 1] whose extinction is linear in the
/// scalar: sigma(s) = tau * s (texel opacities 1 - exp(-tau s u)).
TransferFunctionDesc linearExtinctionTF(double tau, float r, float g, float b, int K = 1025)
{
  TransferFunctionDesc tf = flatTF(0.f, r, g, b, 1.f, K, 0.f, 1.f);
  for (int i = 0; i < K; ++i)
  {
    tf.opacity[size_t(i)] = float(-std::expm1(-tau * double(i) / double(K - 1)));
  }
  return tf;
}

Camera demoCam(const DemoVolume& v, int W, int H)
{
  return orbitCamera(v.dims, v.spacing, W, H, 30, 20);
}

double rmse(const std::vector<float>& a, const std::vector<float>& b)
{
  double s = 0;
  for (size_t i = 0; i < a.size(); ++i)
  {
    s += double(a[i] - b[i]) * double(a[i] - b[i]);
  }
  return std::sqrt(s / double(a.size()));
}
} // namespace

// A slab of constant extinction seen along z: alpha = 1 - exp(-sigma L) and
// colour c * alpha for any step dividing L, in both compositing models
// (constant fields make them agree), every blend mode over one channel.
TEST(RayMarch, ConstantSlabIsAnalytic)
{
  TestVolume v(6, 6, 16, 1, 1.f);
  const double sigma = 0.13;
  Scene scene;
  configure(scene, v, { flatTF(opacityFor(sigma, 1.0), 0.2f, 0.5f, 0.9f) }, 4);
  // Straight down the z axis through the middle: a ray of length 15.
  const Camera axis = orthoAlongZ(4, 4, 2, 3, 2, 3, 20, 40);
  const double expected = -std::expm1(-sigma * 15.0);
  for (double step : { 1.0, 0.5, 0.25, 3.0 })
  {
    for (Compositing model : { Compositing::Extinction, Compositing::Opacity })
    {
      MarchSettings ms;
      ms.step = step;
      ms.compositing = model;
      ms.terminateTransmittance = 0.f;
      for (BlendMode mode : { BlendMode::Density, BlendMode::Max, BlendMode::Mix, BlendMode::Composite })
      {
        scene.setBlendMode(mode);
        scene.update();
        const std::vector<float> img = march(scene, axis, ms);
        for (size_t p = 0; p < img.size() / 4; ++p)
        {
          ASSERT_NEAR(img[4 * p + 3], expected, 2e-6) << "step " << step << " model " << int(model);
          ASSERT_NEAR(img[4 * p + 0], 0.2 * expected, 2e-6);
          ASSERT_NEAR(img[4 * p + 2], 0.9 * expected, 2e-6);
        }
      }
    }
  }
}

// Kraus and Buerger, Section 3.6: a one-voxel-thick opaque wall, rays
// perpendicular to it, every phase of the sample lattice. The analytic
// opacity is 1 - exp(-tau) (the interpolated extinction is tau times a tent
// of unit area). The largest step at which the worst phase stays within
// 0.02 of it: the paper sees the first artifacts near d = 0.6 for
// opacity-based and d = 1.6 for extinction-based sampling; here (tau = 8,
// tolerance 0.02) the extinction model holds to d = 1.70 and the opacity
// model only to 0.35, and the test asserts the extinction model's range is at
// least 3 times wider, above 1.5 voxels, and the opacity model's below 0.6.
TEST(RayMarch, OneVoxelWallExtinctionBeatsOpacity)
{
  TestVolume v(9, 3, 3, 1, 0.f);
  for (int k = 0; k < 3; ++k)
    for (int j = 0; j < 3; ++j)
      v.channels[0][v.index(4, j, k)] = 1.f;
  const double tau = 8.0;
  Scene scene;
  configure(scene, v, { linearExtinctionTF(tau, 1, 1, 1) }, 2);
  SceneView s = scene.view();
  const double truth = -std::expm1(-tau);
  const double tol = 0.02;
  const int phases = 64;
  double reach[2] = { 0, 0 };
  for (Compositing model : { Compositing::Extinction, Compositing::Opacity })
  {
    double last = 0;
    for (int di = 1; di <= 60; ++di)
    {
      const double d = 0.05 * di;
      MarchParams mp;
      mp.step = float(d);
      mp.compositing = model;
      mp.terminateTransmittance = 0.f;
      double worst = 0;
      for (int r = 0; r < phases; ++r)
      {
        MarchCounters mc;
        const Vec4f px = marchChannels<BlendMode::Density>(
          s, mp, s.active, s.numActive, Vec3f(0.f, 1.f, 1.f), Vec3f(1.f, 0.f, 0.f), 8.f, float(r) / phases, mc);
        ASSERT_TRUE(std::isfinite(px.a));
        worst = std::max(worst, std::fabs(double(px.a) - truth));
      }
      if (worst > tol)
      {
        break;
      }
      last = d;
    }
    reach[int(model)] = last;
  }
  std::printf(
    "one-voxel wall, tau %.0f, tolerance %.2f: extinction-based holds to d = %.2f, opacity-based to d = %.2f\n", tau,
    tol, reach[0], reach[1]);
  EXPECT_GE(reach[0], 1.5) << "extinction-based sampling should hold beyond 1.5 voxels";
  EXPECT_LE(reach[1], 0.6) << "opacity-based sampling should show artifacts below 0.6 voxels";
  EXPECT_GE(reach[0], 3 * reach[1]);
}

// Skipping empty macrocells changes nothing (bit for bit) and saves samples;
// the image does not depend on the thread count.
TEST(RayMarch, SkippingIsExactAndThreadsDoNotMatter)
{
  const DemoVolume v = makeDemo("figure3", { 32, 32, 32 }); // cubes in empty space
  Scene scene;
  configureDemo(scene, v, 4);
  const Camera cam = demoCam(v, 40, 36);
  for (Compositing model : { Compositing::Extinction, Compositing::Opacity })
  {
    for (BlendMode mode : { BlendMode::Density, BlendMode::Max, BlendMode::Mix, BlendMode::Composite })
    {
      scene.setBlendMode(mode);
      scene.update();
      MarchSettings ms;
      ms.compositing = model;
      ms.jitter = true;
      ms.seed = 4;
      MarchCounters with, without;
      const std::vector<float> a = march(scene, cam, ms, &with, 2);
      ms.skipEmpty = false;
      const std::vector<float> b = march(scene, cam, ms, &without, 1);
      ASSERT_EQ(a, b) << "mode " << toString(mode) << " model " << int(model);
      EXPECT_LT(with.samples, without.samples) << "skipping must save samples";
      EXPECT_GT(with.skippedCells, 0u);
    }
  }
}

// Early ray termination changes the image by at most the threshold.
TEST(RayMarch, TerminationBoundsTheError)
{
  const DemoVolume v = makeDemo("cosmology", { 32, 32, 32 });
  Scene scene;
  configureDemo(scene, v, 8, 128, 0.1); // dense: most rays terminate
  const Camera cam = demoCam(v, 32, 32);
  MarchSettings ms;
  ms.terminateTransmittance = 0.f;
  MarchCounters full, early;
  const std::vector<float> a = march(scene, cam, ms, &full);
  ms.terminateTransmittance = 1e-3f;
  const std::vector<float> b = march(scene, cam, ms, &early);
  EXPECT_GT(early.terminated, 100u);
  EXPECT_LT(early.samples, full.samples);
  for (size_t i = 0; i < a.size(); ++i)
  {
    ASSERT_NEAR(a[i], b[i], 1e-3 + 1e-6) << "value " << i;
  }
}

// Bad settings are errors; hard cases give finite, correct images.
TEST(RayMarch, ErrorsAndHardCases)
{
  TestVolume v(8, 8, 8, 1, 1.f);
  Scene scene;
  configure(scene, v, { flatTF(1.f, 1, 1, 1) }, 4); // opacity exactly 1
  const Camera cam = orthoAlongZ(8, 8, 0, 7, 0, 7, 20, 40);
  MarchSettings ms;
  ms.step = -1;
  EXPECT_THROW(march(scene, cam, ms), std::invalid_argument);
  ms.step = 1e-9;
  EXPECT_THROW(march(scene, cam, ms), std::invalid_argument);
  ms.step = 0;
  ms.terminateTransmittance = 1.f;
  EXPECT_THROW(march(scene, cam, ms), std::invalid_argument);
  ms.terminateTransmittance = 0.f;
  for (Compositing model : { Compositing::Extinction, Compositing::Opacity })
  {
    ms.compositing = model;
    const std::vector<float> img = march(scene, cam, ms);
    for (size_t p = 0; p < img.size() / 4; ++p)
    {
      ASSERT_TRUE(std::isfinite(img[4 * p]));
      ASSERT_NEAR(img[4 * p + 3], 1.0, 1e-6) << "opacity 1 through 7 voxels is opaque";
    }
  }
  // NaN voxels are transparent in both models; the rest renders.
  TestVolume n(8, 8, 8, 1, 1.f);
  for (int k = 0; k < 8; ++k)
    for (int j = 0; j < 8; ++j)
      for (int i = 0; i < 4; ++i)
        n.channels[0][n.index(i, j, k)] = std::numeric_limits<float>::quiet_NaN();
  Scene ns;
  configure(ns, n, { flatTF(0.3f, 1, 1, 1) }, 2);
  for (Compositing model : { Compositing::Extinction, Compositing::Opacity })
  {
    ms.compositing = model;
    const std::vector<float> img = march(ns, cam, ms);
    for (int y = 0; y < 8; ++y)
    {
      for (int x = 0; x < 8; ++x)
      {
        const float a = img[4 * (size_t(y) * 8 + size_t(x)) + 3];
        ASSERT_TRUE(std::isfinite(a));
        if (x <= 3)
        {
          EXPECT_EQ(a, 0.f) << "NaN region, pixel " << x << "," << y << " model " << int(model);
        }
        if (x >= 5)
        {
          EXPECT_GT(a, 0.5f);
        }
      }
    }
  }
  // A single voxel and extreme spacing: finite.
  TestVolume one(1, 1, 1, 1, 1.f);
  for (double sp : { 1e-6, 1.0, 1e6 })
  {
    Scene os; // opacity 0.5 over one voxel's length
    configure(os, one, { flatTF(0.5f, 1, 1, 1, float(sp)) }, 1);
    const double spacing[3] = { sp, sp, sp };
    const double origin[3] = { 0, 0, 0 };
    Camera c = orthoAlongZ(4, 4, -sp, sp, -sp, sp, 10 * sp, 20 * sp);
    setWorldToIndex(c, spacing, origin);
    ms.compositing = Compositing::Extinction;
    const std::vector<float> img = march(os, c, ms);
    for (float x : img)
    {
      ASSERT_TRUE(std::isfinite(x));
    }
    EXPECT_GT(img[4 * 5 + 3], 0.1f) << "the single voxel is visible at spacing " << sp;
  }
}

// Each Monte Carlo blend mode converges to the ray-marched image of the same
// mode (extinction model, fine step). One render of N = 2048 samples per
// pixel at pixel centres; per component, one sample lies in [0, 1], so with
// the reference's mean mu its variance is at most mu (1 - mu) (exactly that
// for alpha, a Bernoulli variable; composite colours lie in [0, channels]):
// the z-scores below are conservative.
// Components with N mu (1 - mu) >= 100 are tested one by one (image-mean z,
// sum of z^2, largest |z|: the largest |z| needs the normal tail near 5
// sigma, which a binomial with fewer expected hits does not have); the
// others, rare or nearly certain hits, are pooled into one z-score of their
// summed differences. 4 checks per component, 4 components, 2 datasets, 4
// modes, 2 samplers, and the expected-value estimator with both samplers
// for the modes it serves (density, max, mix). Its colour per sample lies in
// [0, 1 + kRouletteThreshold] (a roulette survivor's transmittance rises to
// the threshold), alpha in [0, 1]; the bound below uses that range. With the Sobol' sampler (randomized QMC: each sample is
// uniform, so the mean is unbiased) the variance of the mean falls faster
// than 1/N in practice, which keeps the bound conservative; N = 2048 is a
// power of two, a whole block of each pixel's nets.
TEST(RayMarch, MonteCarloConvergesToRayMarch)
{
  const double alpha = kAlpha / (4 * 4 * 2 * 4 * 4);
  const int N = 2048;
  for (Estimator estimator : { Estimator::Collision, Estimator::ExpectedValue })
  for (Sampler sampler : { Sampler::Independent, Sampler::Sobol })
    for (const char* name : { "figure3", "cosmology" })
    {
      const DemoVolume v = makeDemo(name, { 24, 24, 24 });
      const Camera cam = demoCam(v, 32, 32);
      for (BlendMode mode : { BlendMode::Density, BlendMode::Max, BlendMode::Mix, BlendMode::Composite })
      {
        if (estimator == Estimator::ExpectedValue && mode == BlendMode::Composite)
        {
          continue; // composite keeps the collision estimator
        }
        Scene scene;
        configureDemo(scene, v, 4, 128, 1.0, mode);
        MarchSettings ms;
        ms.step = 1.0 / 16.0;
        ms.terminateTransmittance = 0.f;
        const std::vector<float> ref = march(scene, cam, ms);
        CPURenderer mc;
        Accumulator acc;
        RenderSettings rs;
        rs.jitterPixels = false; // the reference samples pixel centres
        rs.samplesPerPixel = N;
        rs.seed = 300;
        rs.sampler = sampler;
        rs.estimator = estimator;
        mc.render(scene, cam, rs, nullptr, acc);
        const std::string what = std::string(name) + " " + toString(mode) + " " + toString(sampler) + " " +
          toString(estimator) + " MC vs ray march";
        // Composite adds the channels' colours: a sample's colour lies in
        // [0, channels], and its variance is at most mu (channels - mu).
        const double top = (mode == BlendMode::Composite ? double(scene.view().numActive) : 1.0) *
          (estimator == Estimator::ExpectedValue ? 1.0 + kRouletteThreshold : 1.0);
        expectMeanOfSamples(acc, ref, N, top, alpha, what);
      }
    }
}

namespace
{
double fittedSlope(const std::vector<double>& xs, const std::vector<double>& ys, double* seOut = nullptr)
{
  const double n = double(xs.size());
  double sx = 0, sy = 0, sxx = 0, sxy = 0;
  for (size_t i = 0; i < xs.size(); ++i)
  {
    sx += xs[i];
    sy += ys[i];
    sxx += xs[i] * xs[i];
    sxy += xs[i] * ys[i];
  }
  const double slope = (n * sxy - sx * sy) / (n * sxx - sx * sx);
  const double icept = (sy - slope * sx) / n;
  double rss = 0;
  for (size_t i = 0; i < xs.size(); ++i)
  {
    const double r = ys[i] - (icept + slope * xs[i]);
    rss += r * r;
  }
  if (seOut)
  {
    *seOut = std::sqrt(rss / (n - 2) / (sxx - sx * sx / n));
  }
  return slope;
}
} // namespace

// The error of the Monte Carlo image against a fine-step reference falls like
// 1/sqrt(spp) over 4 doublings (spp 4 to 64), for each blend mode: the
// fitted log-log slope is within 0.05 of -0.5. Independent samples: the
// rate is the Monte Carlo one (Sobol' points fall faster, tested below).
TEST(RayMarch, MonteCarloErrorFallsAsInverseSquareRoot)
{
  const DemoVolume v = makeDemo("cosmology", { 24, 24, 24 });
  const Camera cam = demoCam(v, 40, 40);
  for (Estimator estimator : { Estimator::Collision, Estimator::ExpectedValue })
  for (BlendMode mode : { BlendMode::Density, BlendMode::Max, BlendMode::Mix, BlendMode::Composite })
  {
    if (estimator == Estimator::ExpectedValue && mode == BlendMode::Composite)
    {
      continue; // composite keeps the collision estimator
    }
    Scene scene;
    configureDemo(scene, v, 4, 128, 1.0, mode);
    MarchSettings ms;
    ms.step = 1.0 / 16.0;
    ms.terminateTransmittance = 0.f;
    const std::vector<float> ref = march(scene, cam, ms);
    CPURenderer mc;
    std::vector<double> xs, ys;
    for (int spp : { 4, 8, 16, 32, 64 })
    {
      // Mean squared error over 8 independent images of spp samples each.
      double mse = 0;
      for (int rep = 0; rep < 8; ++rep)
      {
        Accumulator acc;
        RenderSettings rs;
        rs.jitterPixels = false;
        rs.samplesPerPixel = spp;
        rs.seed = uint32_t(1000 * spp + rep);
        rs.sampler = Sampler::Independent;
        rs.estimator = estimator;
        mc.render(scene, cam, rs, nullptr, acc);
        const std::vector<float> img(acc.rgba(), acc.rgba() + ref.size());
        const double e = rmse(img, ref);
        mse += e * e / 8;
      }
      xs.push_back(std::log(double(spp)));
      ys.push_back(0.5 * std::log(mse));
    }
    double se = 0;
    const double slope = fittedSlope(xs, ys, &se);
    std::printf("%s %s: RMSE slope %.4f (standard error %.4f)\n", toString(mode), toString(estimator), slope, se);
    EXPECT_NEAR(slope, -0.5, 0.05) << toString(mode) << " " << toString(estimator);
  }
}

// The expected-value estimator's noise (Documentation/design.md, "The
// default estimator"): mean squared
// error against the fine-step reference at 16 spp, over 8 seeds, for each
// estimator and blend mode it serves, on two semi-transparent scenes. The
// expected-value estimator scores every tentative collision, so its error
// must be well below the collision estimator's: less than half the MSE
// (measured: printed below). Deterministic (fixed seeds), not a
// significance test; a factor of two leaves room for the seeds' spread
// (8 images of 40x40 pixels).
TEST(RayMarch, ExpectedValueEstimatorHasLessNoise)
{
  for (const char* name : { "cosmology", "microscopy" })
  {
    const DemoVolume v = makeDemo(name, { 24, 24, 24 });
    const Camera cam = demoCam(v, 40, 40);
    for (BlendMode mode : { BlendMode::Density, BlendMode::Max, BlendMode::Mix })
    {
      Scene scene;
      configureDemo(scene, v, 4, 128, 1.0, mode);
      MarchSettings ms;
      ms.step = 1.0 / 16.0;
      ms.terminateTransmittance = 0.f;
      const std::vector<float> ref = march(scene, cam, ms);
      CPURenderer mc;
      double mse[2] = { 0, 0 };
      RenderCounters counters[2];
      for (Estimator estimator : { Estimator::Collision, Estimator::ExpectedValue })
      {
        for (int rep = 0; rep < 8; ++rep)
        {
          Accumulator acc;
          RenderSettings rs;
          rs.jitterPixels = false;
          rs.samplesPerPixel = 16;
          rs.seed = uint32_t(77 + rep);
          rs.estimator = estimator;
          mc.render(scene, cam, rs, nullptr, acc, &counters[int(estimator)]);
          const std::vector<float> img(acc.rgba(), acc.rgba() + ref.size());
          const double e = rmse(img, ref);
          mse[int(estimator)] += e * e / 8;
        }
      }
      std::printf("%s %s: MSE collision %.3g, expected-value %.3g (ratio %.3f); tentative collisions %llu, %llu\n",
        name, toString(mode), mse[0], mse[1], mse[1] / mse[0],
        (unsigned long long)counters[0].tentativeCollisions, (unsigned long long)counters[1].tentativeCollisions);
      EXPECT_LT(mse[1], 0.5 * mse[0]) << name << " " << toString(mode);
    }
  }
}

// A floor on the expected-value estimator's tentative rate
// (RenderSettings::minSamplesPerVoxel) keeps it unbiased: with 2 tentative
// collisions per voxel length at least, N = 1024 samples per pixel converge
// to the fine-step ray march (the z-tests of MonteCarloConvergesToRayMarch,
// significance kAlpha over all checks), and the floor adds tentative
// collisions (counters). The MSE at 16 spp with and without it is printed.
TEST(RayMarch, MinimumTentativeRateStaysUnbiased)
{
  const double alpha = kAlpha / (4 * 4 * 2 * 3);
  const int N = 1024;
  for (const char* name : { "figure3", "microscopy" })
  {
    const DemoVolume v = makeDemo(name, { 24, 24, 24 });
    const Camera cam = demoCam(v, 32, 32);
    for (BlendMode mode : { BlendMode::Density, BlendMode::Max, BlendMode::Mix })
    {
      Scene scene;
      configureDemo(scene, v, 4, 128, 1.0, mode);
      MarchSettings ms;
      ms.step = 1.0 / 16.0;
      ms.terminateTransmittance = 0.f;
      const std::vector<float> ref = march(scene, cam, ms);
      CPURenderer mc;
      RenderCounters counters[2];
      double mse[2] = { 0, 0 };
      for (int floor = 0; floor < 2; ++floor)
      {
        RenderSettings rs;
        rs.jitterPixels = false;
        rs.minSamplesPerVoxel = floor ? 2.f : 0.f;
        for (int rep = 0; rep < 4; ++rep)
        {
          Accumulator acc;
          rs.samplesPerPixel = 16;
          rs.seed = uint32_t(40 + rep);
          mc.render(scene, cam, rs, nullptr, acc, &counters[floor]);
          const double e = rmse(std::vector<float>(acc.rgba(), acc.rgba() + ref.size()), ref);
          mse[floor] += e * e / 4;
        }
        if (floor)
        {
          Accumulator acc;
          rs.samplesPerPixel = N;
          rs.seed = 301;
          mc.render(scene, cam, rs, nullptr, acc);
          expectMeanOfSamples(acc, ref, N, 1.0 + kRouletteThreshold, alpha,
            std::string(name) + " " + toString(mode) + " expected value, >= 2 per voxel");
        }
      }
      std::printf("%s %s: 16 spp MSE %.3g without the floor, %.3g with 2 per voxel; tentative collisions %llu, %llu\n",
        name, toString(mode), mse[0], mse[1], (unsigned long long)counters[0].tentativeCollisions,
        (unsigned long long)counters[1].tentativeCollisions);
      EXPECT_GT(counters[1].tentativeCollisions, counters[0].tentativeCollisions) << name << " " << toString(mode);
    }
  }
  // A negative, NaN or infinite floor is refused.
  const DemoVolume small = makeDemo("figure3", { 8, 8, 8 });
  Scene scene;
  configureDemo(scene, small, 4, 16, 1.0, BlendMode::Density);
  RenderSettings bad;
  for (float m : { -1.f, std::numeric_limits<float>::quiet_NaN(), std::numeric_limits<float>::infinity() })
  {
    bad.minSamplesPerVoxel = m;
    CPURenderer mc;
    Accumulator acc;
    EXPECT_THROW(mc.render(scene, demoCam(small, 4, 4), bad, nullptr, acc), std::invalid_argument);
  }
}

// The unbiased-march estimator (Estimator::UnbiasedMarch), with plain strata
// (0.5 per voxel) and with control variates (2 per voxel, the default;
// kMarchControlVariateRate), converges to the ray march at 1/128 voxel (at 1/16 voxel, the reference's own error where
// max blending's colour jumps between channels, up to 0.006 on figure3,
// is larger than this estimator's standard error): per pixel, the mean of 128 renders of 8 samples with
// independent seeds against the reference, with the batches' own variance
// (its samples are not bounded, so the bound of expectMeanOfSamples does
// not apply): expectZeroDifference's image-mean z, sum of z^2 and largest
// |z| per component, family-wise level kAlpha over all checks. Its noise
// against the expected-value estimator's at 16 spp (MSE over 4 seeds) is
// printed, and at the default rate must be lower: it samples every stratum
// of every non-empty cell, where the expected-value estimator samples at the
// majorant's rate.
TEST(RayMarch, UnbiasedMarchConvergesToRayMarch)
{
  const double alpha = kAlpha / (2 * 2 * 3 * 4 * 3);
  // 0.5 per voxel: the plain strata; 2 (the default): the control variates.
  for (const float rate : { 0.5f, 2.f })
  {
  for (const char* name : { "figure3", "microscopy" })
  {
    const DemoVolume v = makeDemo(name, { 24, 24, 24 });
    const Camera cam = demoCam(v, 33, 33);
    for (BlendMode mode : { BlendMode::Density, BlendMode::Max, BlendMode::Mix })
    {
      Scene scene;
      configureDemo(scene, v, 4, 128, 1.0, mode);
      MarchSettings ms;
      ms.step = 1.0 / 128.0;
      ms.terminateTransmittance = 0.f;
      const std::vector<float> ref = march(scene, cam, ms);
      CPURenderer mc;
      RenderSettings rs;
      rs.jitterPixels = false;
      rs.estimator = Estimator::UnbiasedMarch;
      rs.marchSamplesPerVoxel = rate;
      // 128 batch means of 8 samples each (seeds 900...): closer to normal
      // than single samples of a heavy-tailed estimator.
      rs.samplesPerPixel = 8;
      const int batches = 128;
      std::vector<double> sum(ref.size(), 0.0), sumSq(ref.size(), 0.0);
      for (int b = 0; b < batches; ++b)
      {
        Accumulator acc;
        rs.seed = uint32_t(900 + b);
        mc.render(scene, cam, rs, nullptr, acc);
        for (size_t i = 0; i < ref.size(); ++i)
        {
          sum[i] += acc.rgba()[i];
          sumSq[i] += double(acc.rgba()[i]) * acc.rgba()[i];
        }
      }
      // Variance of the mean: the batches' own, plus the roulette's share
      // that so few samples may not show (a pixel whose transmittance T falls
      // far below kRouletteThreshold survives it with probability T /
      // threshold, contributing variance at most T threshold per sample to
      // alpha and to each colour component, which is below 1).
      std::vector<double> D(ref.size()), V(ref.size());
      for (size_t i = 0; i < ref.size(); ++i)
      {
        const double mean = sum[i] / batches;
        const double var = std::max(0.0, (sumSq[i] - batches * mean * mean) / (batches - 1));
        const double T = std::max(0.0, 1.0 - double(ref[i - i % 4 + 3]));
        D[i] = mean - double(ref[i]);
        const double threshold = rate >= kMarchControlVariateRate ? kControlRouletteThreshold : kRouletteThreshold;
        V[i] = var / batches + T * threshold / (8.0 * batches);
      }
      const std::string what = std::string(name) + " " + toString(mode) + " unbiased march " + std::to_string(rate);
      expectZeroDifference(D, V, alpha, what);
      double mse[2] = { 0, 0 };
      RenderCounters counters[2];
      const Estimator estimators[2] = { Estimator::ExpectedValue, Estimator::UnbiasedMarch };
      for (int e = 0; e < 2; ++e)
      {
        for (int rep = 0; rep < 4; ++rep)
        {
          Accumulator acc;
          RenderSettings r16 = rs;
          r16.estimator = estimators[e];
          r16.samplesPerPixel = 16;
          r16.seed = uint32_t(60 + rep);
          mc.render(scene, cam, r16, nullptr, acc, &counters[e]);
          const double err = rmse(std::vector<float>(acc.rgba(), acc.rgba() + ref.size()), ref);
          mse[e] += err * err / 4;
        }
      }
      std::printf("%s: 16 spp MSE expected value %.3g, unbiased march %.3g (ratio %.3f); channel samples %llu, %llu\n",
        what.c_str(), mse[0], mse[1], mse[1] / mse[0], (unsigned long long)counters[0].channelSamples,
        (unsigned long long)counters[1].channelSamples);
      if (rate >= 2.f)
      {
        EXPECT_LT(mse[1], mse[0]) << what; // at 0.5 per voxel it takes fewer samples than expected value on figure3
      }
    }
  }
  }
  // Samples per voxel out of range are refused.
  const DemoVolume small = makeDemo("figure3", { 8, 8, 8 });
  Scene scene;
  configureDemo(scene, small, 4, 16, 1.0, BlendMode::Density);
  RenderSettings bad;
  bad.estimator = Estimator::UnbiasedMarch;
  for (float m : { 0.f, -1.f, std::numeric_limits<float>::quiet_NaN(), std::numeric_limits<float>::infinity() })
  {
    bad.marchSamplesPerVoxel = m;
    CPURenderer mc;
    Accumulator acc;
    EXPECT_THROW(mc.render(scene, demoCam(small, 4, 4), bad, nullptr, acc), std::invalid_argument);
  }
}

// Channels absent from a macrocell are not read there (blendMajorant()'s
// mask): two channels in disjoint halves of the volume (red for x < 32,
// green from 32; macrocell 4, so the two cells at the boundary hold both),
// seen along z at pixel centres, with every unlit estimator that reads all
// channels at a point (expected value, the march's plain strata and its
// control variates). Channel samples per point (tentative collision or
// stratum) are under 3/4 of those of the same volume with both channels
// everywhere, where every point reads both; without the mask the two were
// equal. The images stay the model's: away from the boundary each half's
// mean pixel is the analytic slab (alpha = 1 - exp(-sigma 7), the half's
// colour), within 0.005 over 16 spp x 8 x 26 pixels (fixed seed; the
// deviations are printed).
TEST(RayMarch, ChannelsAbsentFromACellAreNotRead)
{
  const double sigma = 0.2;
  TransferFunctionDesc red = flatTF(opacityFor(sigma, 1.0), 1.f, 0.f, 0.f);
  TransferFunctionDesc green = flatTF(opacityFor(sigma, 1.0), 0.f, 1.f, 0.f);
  red.opacity[0] = 0.f; // scalar 0: transparent; scalar 1: sigma
  green.opacity[0] = 0.f;
  const int nx = 64;
  TestVolume halves(nx, 8, 8, 2, 0.f);
  TestVolume both(nx, 8, 8, 2, 1.f);
  for (int k = 0; k < 8; ++k)
    for (int j = 0; j < 8; ++j)
      for (int i = 0; i < nx; ++i)
      {
        halves.channels[i < nx / 2 ? 0 : 1][halves.index(i, j, k)] = 1.f;
      }
  Scene sh, sb;
  configure(sh, halves, { red, green }, 4);
  configure(sb, both, { red, green }, 4);
  ASSERT_EQ(sh.view().numActive, 2);
  // Pixel centres on the voxel columns x = 0..63, y = 0..7.
  const Camera cam = orthoAlongZ(nx, 8, -0.5, nx - 0.5, -0.5, 7.5, 20.0, 40.0);
  const double alpha = -std::expm1(-sigma * 7.0);
  struct Case
  {
    Estimator estimator;
    bool control;
    const char* name;
  };
  const Case cases[] = { { Estimator::ExpectedValue, false, "expected value" },
    { Estimator::UnbiasedMarch, false, "march, plain strata" },
    { Estimator::UnbiasedMarch, true, "march, control variates" } };
  CPURenderer mc;
  for (const Case& k : cases)
  {
    RenderSettings rs;
    rs.estimator = k.estimator;
    rs.marchSamplesPerVoxel = 2.f;
    rs.marchControlVariates = k.control;
    rs.jitterPixels = false;
    rs.samplesPerPixel = 16;
    rs.seed = 11;
    double perPoint[2] = { 0, 0 };
    std::vector<float> img;
    for (int b = 0; b < 2; ++b)
    {
      Accumulator acc;
      RenderCounters c;
      mc.render(b == 0 ? sh : sb, cam, rs, nullptr, acc, &c);
      ASSERT_GT(c.tentativeCollisions, 0u) << k.name;
      perPoint[b] = double(c.channelSamples) / double(c.tentativeCollisions);
      if (b == 0)
      {
        img.assign(acc.rgba(), acc.rgba() + size_t(cam.width) * cam.height * 4);
      }
    }
    EXPECT_LT(perPoint[0], 0.75 * perPoint[1]) << k.name;
    // Mean (r, g, b, alpha) of each half, the 6 columns nearest the
    // boundary on either side left out.
    double mean[2][4] = {};
    int count[2] = { 0, 0 };
    for (int y = 0; y < cam.height; ++y)
      for (int x = 0; x < cam.width; ++x)
      {
        if (std::abs(2 * x + 1 - nx) < 12)
        {
          continue;
        }
        const int half = x < nx / 2 ? 0 : 1;
        const float* px = img.data() + 4 * (size_t(y) * size_t(cam.width) + size_t(x));
        for (int ch = 0; ch < 4; ++ch)
        {
          mean[half][ch] += px[ch];
        }
        ++count[half];
      }
    double worst = 0;
    for (int half = 0; half < 2; ++half)
    {
      const double expect[4] = { half == 0 ? alpha : 0.0, half == 1 ? alpha : 0.0, 0.0, alpha };
      for (int ch = 0; ch < 4; ++ch)
      {
        worst = std::max(worst, std::abs(mean[half][ch] / count[half] - expect[ch]));
      }
    }
    std::printf("%s: %.3f channel samples per point (both everywhere: %.3f); largest deviation of a half's "
                "mean %.2e\n",
      k.name, perPoint[0], perPoint[1], worst);
    EXPECT_LT(worst, 0.005) << k.name;
  }
}

// Sobol' points (the default sampler) against independent samples on the
// same scene, error against the fine-step reference at 1 to 64 spp (mean
// squared error over 8 images of independent seeds per count), pixel jitter
// on and off, density and max blending: the Sobol' error is lower at every
// count from 4 spp, and its fitted log-log slope is at least as steep (up to
// 0.02, the slopes' standard errors being about 0.01). Measured: see the
// printed slopes.

// The control variates are taken exactly where marchControlVariates() says:
// at pixel centres, from kMarchControlVariateRate strata per voxel, unless
// RenderSettings::marchControlVariates is off. Each stratum then reads the
// optics at its end too: one more channel sample per active channel and
// stratum (counters), and a different image from the plain strata's.
TEST(RayMarch, ControlVariatesFollowTheRule)
{
  const DemoVolume v = makeDemo("microscopy", { 24, 24, 24 });
  const Camera cam = demoCam(v, 33, 33);
  Scene scene;
  configureDemo(scene, v, 4, 128, 1.0, BlendMode::Density);
  CPURenderer mc;
  const double channels = double(scene.view().numActive);
  ASSERT_GT(channels, 0.0);
  struct Case
  {
    bool jitter;
    float rate;
    bool setting;
    bool expectControl;
  };
  const Case cases[] = { { false, 2.f, true, true }, { false, kMarchControlVariateRate, true, true },
    { false, 2.f, false, false }, { true, 2.f, true, false }, { false, 0.5f, true, false } };
  for (const Case& k : cases)
  {
    RenderSettings rs;
    rs.estimator = Estimator::UnbiasedMarch;
    rs.jitterPixels = k.jitter;
    rs.marchSamplesPerVoxel = k.rate;
    rs.marchControlVariates = k.setting;
    rs.samplesPerPixel = 4;
    rs.seed = 5;
    EXPECT_EQ(marchControlVariates(rs, cam), k.expectControl);
    Accumulator acc;
    RenderCounters n;
    mc.render(scene, cam, rs, nullptr, acc, &n);
    ASSERT_GT(n.tentativeCollisions, 0u);
    // Per stratum: 1 + K lookups (plain) or 2 + K plus the cells' first ends
    // (control variates), times the active channels. E[K] = 4/3.
    const double perStratum = double(n.channelSamples) / double(n.tentativeCollisions) / channels;
    std::printf("jitter %d, %g per voxel, setting %d: %.3f lookups per stratum and channel\n", int(k.jitter),
      double(k.rate), int(k.setting), perStratum);
    if (k.expectControl)
    {
      EXPECT_GT(perStratum, 3.0);
    }
    else
    {
      EXPECT_LT(perStratum, 2.6);
    }
  }
}
TEST(RayMarch, SobolErrorFallsFasterThanIndependent)
{
  const DemoVolume v = makeDemo("cosmology", { 24, 24, 24 });
  const Camera cam = demoCam(v, 40, 40);
  for (BlendMode mode : { BlendMode::Density, BlendMode::Max })
  {
    Scene scene;
    configureDemo(scene, v, 4, 128, 1.0, mode);
    MarchSettings ms;
    ms.step = 1.0 / 16.0;
    ms.terminateTransmittance = 0.f;
    // Jittered pixels estimate the pixel's box-filtered image, not the
    // centre's: that series is compared with a converged Monte Carlo image
    // (independent, 4096 spp, another seed), whose own error is an eighth
    // of the 64-spp one.
    const std::vector<float> march0 = march(scene, cam, ms);
    CPURenderer mc;
    for (bool jitter : { false, true })
    {
      std::vector<float> ref = march0;
      if (jitter)
      {
        Accumulator acc;
        RenderSettings rs;
        rs.samplesPerPixel = 4096;
        rs.seed = 99;
        rs.sampler = Sampler::Independent;
        mc.render(scene, cam, rs, nullptr, acc);
        ref.assign(acc.rgba(), acc.rgba() + ref.size());
      }
      double slopes[2] = { 0, 0 };
      std::vector<double> errs[2];
      for (Sampler sampler : { Sampler::Independent, Sampler::Sobol })
      {
        std::vector<double> xs, ys;
        for (int spp : { 1, 2, 4, 8, 16, 32, 64 })
        {
          double mse = 0;
          for (int rep = 0; rep < 8; ++rep)
          {
            Accumulator acc;
            RenderSettings rs;
            rs.jitterPixels = jitter;
            rs.samplesPerPixel = spp;
            rs.seed = uint32_t(1000 * spp + rep);
            rs.sampler = sampler;
            mc.render(scene, cam, rs, nullptr, acc);
            const std::vector<float> img(acc.rgba(), acc.rgba() + ref.size());
            const double e = rmse(img, ref);
            mse += e * e / 8;
          }
          xs.push_back(std::log(double(spp)));
          ys.push_back(0.5 * std::log(mse));
          errs[int(sampler)].push_back(std::sqrt(mse));
        }
        double se = 0;
        slopes[int(sampler)] = fittedSlope(xs, ys, &se);
        std::printf("%s, jitter %d, %s: RMSE slope %.4f (standard error %.4f); RMSE at 1, 4, 16, 64 spp %.5f %.5f "
                    "%.5f %.5f\n",
          toString(mode), int(jitter), toString(sampler), slopes[int(sampler)], se, std::sqrt(std::exp(2 * ys[0])),
          std::sqrt(std::exp(2 * ys[2])), std::sqrt(std::exp(2 * ys[4])), std::sqrt(std::exp(2 * ys[6])));
      }
      const std::string what = std::string(toString(mode)) + (jitter ? " jittered" : " pixel centres");
      EXPECT_LE(slopes[1], slopes[0] + 0.02) << what;
      for (size_t i = 2; i < errs[0].size(); ++i)
      {
        EXPECT_LT(errs[1][i], errs[0][i]) << what << ": Sobol' error not below independent at " << (1 << i) << " spp";
      }
    }
  }
}
