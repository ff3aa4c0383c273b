// SPDX-License-Identifier: BSD-3-Clause
// Lighting building blocks (Lighting.h): the Henyey-Greenstein phase
// function and the shadow-ray transmittance estimators.
//
// Significance: each TEST has a family-wise level kAlpha = 0.001, split
// evenly (Bonferroni) over its statistical checks; seeds are fixed.
#include "TestUtil.h"

#include "mcvol/ray/Integrator.h"
#include "mcvol/ray/Lighting.h"
#include "mcvol/RayMarcher.h"
#include "mcvol/RenderSetup.h"

#include <cstring>

using namespace mcvol;
using namespace mcvol::test;

namespace
{
constexpr double kAlpha = 1e-3;

/// CDF of mu under Henyey-Greenstein, in double (for expected bin counts).
double hgCdf(double mu, double g)
{
  if (std::fabs(g) < 1e-3)
  {
    return 0.5 * (mu + 1.0);
  }
  // P(mu' <= mu) = (1 - g^2) / (2 g) * (1 / sqrt(1 + g^2 - 2 g mu) - 1 / (1 + g))
  return (1.0 - g * g) / (2.0 * g) * (1.0 / std::sqrt(1.0 + g * g - 2.0 * g * mu) - 1.0 / (1.0 + g));
}
} // namespace

// The phase function integrates to 1 over the sphere for every g.
TEST(HenyeyGreenstein, Normalised)
{
  for (float g : { -0.9f, -0.5f, 0.f, 0.3f, 0.8f, 0.95f })
  {
    // Midpoint rule on mu with many bins: 2 pi * integral of p(mu) dmu.
    const int n = 200000;
    double sum = 0;
    for (int i = 0; i < n; ++i)
    {
      const double mu = -1.0 + (i + 0.5) * 2.0 / n;
      sum += double(hgPhase(float(mu), g)) * 2.0 / n;
    }
    EXPECT_NEAR(2.0 * M_PI * sum, 1.0, 2e-3) << "g = " << g;
  }
}

// Sampled mu follow the HG density (chi-square over 20 bins of equal
// probability) and their mean is g (z-test); 6 values of g x 2 checks.
TEST(HenyeyGreenstein, SamplingMatchesDensityAndMeanCosineIsG)
{
  const double alpha = kAlpha / 12;
  const int n = 200000;
  const int bins = 20;
  uint32_t key = 0;
  for (float g : { -0.7f, -0.2f, 0.f, 0.4f, 0.8f, 0.95f })
  {
    std::vector<double> edges(bins + 1);
    edges[0] = -1.0;
    edges[bins] = 1.0;
    // Bin edges of equal probability by bisection on the CDF.
    for (int b = 1; b < bins; ++b)
    {
      double lo = -1.0, hi = 1.0;
      for (int it = 0; it < 100; ++it)
      {
        const double mid = 0.5 * (lo + hi);
        (hgCdf(mid, g) < double(b) / bins ? lo : hi) = mid;
      }
      edges[size_t(b)] = 0.5 * (lo + hi);
    }
    std::vector<double> counts(bins, 0.0), probs(bins, 1.0 / bins);
    double sum = 0, sumSq = 0;
    Rng rng(7, key++, 11);
    for (int i = 0; i < n; ++i)
    {
      const double mu = sampleHGCosine(g, rng.next());
      ASSERT_TRUE(mu >= -1.0 && mu <= 1.0);
      const int b = int(std::upper_bound(edges.begin(), edges.end(), mu) - edges.begin()) - 1;
      counts[size_t(std::min(std::max(b, 0), bins - 1))] += 1;
      sum += mu;
      sumSq += mu * mu;
    }
    EXPECT_GT(chiSquarePValue(counts, probs), alpha) << "g = " << g;
    const double mean = sum / n;
    const double var = sumSq / n - mean * mean;
    const double z = (mean - g) / std::sqrt(var / n);
    EXPECT_GT(normalTwoSided(z), alpha) << "g = " << g << ": mean cosine " << mean;
  }
}

// directionAround gives unit vectors at the requested angle.
TEST(HenyeyGreenstein, DirectionAroundKeepsTheAngle)
{
  TestRand r(3);
  for (int i = 0; i < 10000; ++i)
  {
    Vec3f d(float(r.uniform(-1, 1)), float(r.uniform(-1, 1)), float(r.uniform(-1, 1)));
    if (i % 100 == 0)
    {
      d = Vec3f(0.f, 0.f, i % 200 == 0 ? 1.f : -1.f); // the basis' special cases
    }
    d = d * (1.f / length(d));
    const float mu = float(r.uniform(-1, 1));
    const Vec3f w = directionAround(d, mu, float(r.uniform()));
    ASSERT_NEAR(length(w), 1.f, 1e-5f);
    ASSERT_NEAR(dot(w, d), mu, 2e-5f);
  }
}

// Transmittance along a ray through a field whose extinction grows linearly
// (trilinear interpolation of a linear field is exact, and so is the
// transfer function's linear extinction): T = exp(-integral sigma). Both
// estimators, density (one channel and two summed) and max blending;
// 2 estimators x 3 scenes x 1 z-test each.
TEST(ShadowTransmittance, LinearFieldIsAnalytic)
{
  const double alpha = kAlpha / 6;
  const int n = 40000;
  TestVolume v(33, 3, 3, 2, 0.f);
  for (int k = 0; k < 3; ++k)
    for (int j = 0; j < 3; ++j)
      for (int i = 0; i < 33; ++i)
      {
        v.channels[0][v.index(i, j, k)] = float(i) / 32.f;
        v.channels[1][v.index(i, j, k)] = 1.f - float(i) / 32.f;
      }
  const double tau = 0.1; // extinction per world unit at scalar 1
  auto tf = [&](int K)
  {
    TransferFunctionDesc t = flatTF(0.f, 1, 1, 1, 1.f, K, 0.f, 1.f);
    for (int i = 0; i < K; ++i)
    {
      t.opacity[size_t(i)] = float(-std::expm1(-tau * double(i) / double(K - 1)));
    }
    return t;
  };
  struct Case
  {
    const char* name;
    BlendMode mode;
    int channels;
    double opticalDepth; // along x from 2 to 30
  };
  // Channel 0: sigma = tau x / 32 -> integral over [2, 30] = tau (30^2 - 2^2) / 64.
  const double d0 = tau * (900.0 - 4.0) / 64.0;
  // Channel 1: sigma = tau (1 - x / 32) -> tau (28 - (900 - 4) / 64).
  const double d1 = tau * (28.0 - 896.0 / 64.0);
  // Max: the larger of the two, switching at x = 16.
  const double dmax = tau * ((16.0 - 2.0) - (256.0 - 4.0) / 64.0) + tau * (900.0 - 256.0) / 64.0;
  for (const Case& cs : { Case{ "density, one channel", BlendMode::Density, 1, d0 },
         Case{ "density, two channels", BlendMode::Density, 2, d0 + d1 },
         Case{ "max, two channels", BlendMode::Max, 2, dmax } })
  {
    Scene scene;
    TestVolume w = v;
    w.channels.resize(size_t(cs.channels));
    std::vector<TransferFunctionDesc> tfs(size_t(cs.channels), tf(1025));
    configure(scene, w, tfs, 4, cs.mode);
    const SceneView& s = scene.view();
    const double expected = std::exp(-cs.opticalDepth);
    for (ShadowEstimator est : { ShadowEstimator::Ratio, ShadowEstimator::Delta })
    {
      double sum = 0, sumSq = 0;
      ShadowCounters c;
      for (int i = 0; i < n; ++i)
      {
        Rng rng(uint32_t(i), 5u, uint32_t(est));
        float T = 0.f;
        if (cs.mode == BlendMode::Density)
        {
          T = shadowTransmittance<BlendMode::Density>(
            s, s.active, s.numActive, Vec3f(2.f, 1.f, 1.f), Vec3f(1.f, 0.f, 0.f), 28.f, est, rng, c);
        }
        else
        {
          T = shadowTransmittance<BlendMode::Max>(
            s, s.active, s.numActive, Vec3f(2.f, 1.f, 1.f), Vec3f(1.f, 0.f, 0.f), 28.f, est, rng, c);
        }
        ASSERT_TRUE(T >= 0.f && T <= 1.f);
        if (est == ShadowEstimator::Delta)
        {
          ASSERT_TRUE(T == 0.f || T == 1.f);
        }
        sum += T;
        sumSq += double(T) * T;
      }
      const double mean = sum / n;
      const double var = std::max(sumSq / n - mean * mean, 1e-12);
      const double z = (mean - expected) / std::sqrt(var / n);
      EXPECT_GT(normalTwoSided(z), alpha) << cs.name << (est == ShadowEstimator::Ratio ? " ratio" : " delta")
                                          << ": mean " << mean << ", expected " << expected << " (z = " << z << ")";
      EXPECT_EQ(c.rays, uint32_t(n));
      EXPECT_GT(c.tentative, 0u);
    }
  }
}

// Ratio tracking has less variance than delta tracking where the majorant
// is loose (the reason to offer it), and an empty path costs no tentative
// collision.
TEST(ShadowTransmittance, RatioIsSmootherAndEmptySpaceIsFree)
{
  // A field that varies inside each macrocell, so the majorant lies above
  // the extinction at most points (where the two estimators differ; with a
  // tight majorant ratio tracking degenerates to delta tracking).
  TestVolume v(33, 3, 3, 1, 0.f);
  for (int k = 0; k < 3; ++k)
    for (int j = 0; j < 3; ++j)
      for (int i = 0; i < 33; ++i)
        v.channels[0][v.index(i, j, k)] = float((i * 7) % 9) / 8.f;
  Scene scene;
  configure(scene, v, { flatTF(0.f, 1, 1, 1, 1.f, 2, 0.f, 1.f) }, 8);
  TransferFunctionDesc ramp = flatTF(0.f, 1, 1, 1, 1.f, 2, 0.f, 1.f);
  ramp.opacity[1] = opacityFor(0.1, 1.0);
  scene.setTransferFunction(0, ramp);
  scene.update();
  const SceneView& s = scene.view();
  double var[2];
  for (ShadowEstimator est : { ShadowEstimator::Ratio, ShadowEstimator::Delta })
  {
    double sum = 0, sumSq = 0;
    ShadowCounters c;
    for (int i = 0; i < 20000; ++i)
    {
      Rng rng(uint32_t(i), 9u, 1u);
      const float T = shadowTransmittance<BlendMode::Density>(
        s, s.active, s.numActive, Vec3f(0.f, 1.f, 1.f), Vec3f(1.f, 0.f, 0.f), 32.f, est, rng, c);
      sum += T;
      sumSq += double(T) * T;
    }
    var[int(est)] = sumSq / 20000 - (sum / 20000) * (sum / 20000);
  }
  std::printf("transmittance variance: ratio %.4f, delta %.4f\n", var[0], var[1]);
  EXPECT_LT(var[0], 0.5 * var[1]);

  TestVolume empty(17, 3, 3, 1, 0.f);
  Scene es;
  configure(es, empty, { flatTF(0.f, 1, 1, 1) }, 4);
  ShadowCounters c;
  Rng rng(1, 1, 1);
  const SceneView& e = es.view();
  const int all[1] = { 0 };
  EXPECT_EQ(shadowTransmittance<BlendMode::Density>(
              e, all, 1, Vec3f(0.f, 1.f, 1.f), Vec3f(1.f, 0.f, 0.f), 16.f, ShadowEstimator::Ratio, rng, c),
    1.f);
  EXPECT_EQ(c.tentative, 0u) << "zero majorants: no sampling at all";
}

namespace
{
/// Mean and standard error of per-pixel values f(R, G, B, A) over K renders
/// of one sample each (pixels and renders independent).
struct MeanSE
{
  double mean = 0, se = 0;
};

template <typename F>
MeanSE pixelStatistic(
  Renderer& r, const Scene& scene, const Camera& cam, int K, F f, RenderCounters* counters = nullptr)
{
  double sum = 0, sumSq = 0;
  long n = 0;
  for (int k = 0; k < K; ++k)
  {
    Accumulator acc;
    RenderSettings rs;
    rs.seed = uint32_t(100 + k);
    r.render(scene, cam, rs, nullptr, acc, counters);
    for (int p = 0; p < cam.width * cam.height; ++p)
    {
      const float* v = acc.rgba() + 4 * p;
      const double x = f(v[0], v[1], v[2], v[3]);
      sum += x;
      sumSq += x * x;
      ++n;
    }
  }
  MeanSE m;
  m.mean = sum / n;
  m.se = std::sqrt(std::max(0.0, sumSq / n - m.mean * m.mean) / n);
  return m;
}

/// A slab of constant extinction sigma, 12 voxels deep along z, white.
void slabScene(Scene& scene, TestVolume& v, double sigma)
{
  v = TestVolume(6, 6, 13, 1, 1.f);
  configure(scene, v, { flatTF(opacityFor(sigma, 1.0), 1, 1, 1) }, 4);
}
} // namespace

// Single scattering from a directional light on the viewer's side of a
// homogeneous slab (albedo 1, white): a collision at depth t has density
// sigma e^(-sigma t) and sends p(-1) E e^(-sigma t) back, so
// E[R] = E p(-1) (1 - e^(-2 sigma L)) / 2 and E[alpha] = 1 - e^(-sigma L);
// g = 0 and g = 0.5, ratio and delta shadows: 4 scenes x 2 z-tests.
TEST(Lighting, SingleScatteringSlabIsAnalytic)
{
  const double alpha = kAlpha / 8;
  const double sigma = 0.15, L = 12.0, E = 2.0;
  Scene scene;
  TestVolume v;
  slabScene(scene, v, sigma);
  const Camera cam = orthoAlongZ(8, 8, 1, 4, 1, 4, 20, 40); // rays along -z through the slab
  const std::unique_ptr<Renderer> rp = testRenderer();
  Renderer& r = *rp;
  for (float g : { 0.f, 0.5f })
  {
    for (bool delta : { false, true })
    {
      LightingDesc ld;
      LightDesc light;
      light.vector[0] = 0;
      light.vector[1] = 0;
      light.vector[2] = 1; // towards the light: back along the rays
      light.intensity = E;
      ld.lights.push_back(light);
      ld.albedo = { 1.f };
      ld.anisotropy = { g };
      ld.deltaShadows = delta;
      ld.maxDepth = 1;
      scene.setLighting(ld);
      ASSERT_TRUE(scene.lit());
      RenderCounters c;
      const MeanSE R = pixelStatistic(
        r, scene, cam, 64, [](float x, float, float, float) { return double(x); }, &c);
      const MeanSE A = pixelStatistic(r, scene, cam, 64, [](float, float, float, float a) { return double(a); });
      // Henyey-Greenstein at mu = -1, written out independently of hgPhase().
      const double p = (1.0 - double(g) * g) / (4.0 * M_PI * std::pow(1.0 + g, 3.0));
      const double expectR = E * p * (1.0 - std::exp(-2.0 * sigma * L)) / 2.0;
      const double expectA = 1.0 - std::exp(-sigma * L);
      std::printf("slab g %.1f %s: R %.5f +- %.5f (expected %.5f), alpha %.4f (expected %.4f)\n", g,
        delta ? "delta" : "ratio", R.mean, R.se, expectR, A.mean, expectA);
      EXPECT_GT(normalTwoSided((R.mean - expectR) / R.se), alpha)
        << "g " << g << (delta ? " delta" : " ratio") << ": R " << R.mean << " expected " << expectR;
      EXPECT_GT(normalTwoSided((A.mean - expectA) / A.se), alpha) << "alpha " << A.mean << " expected " << expectA;
      EXPECT_GT(c.scatteringEvents, 0u);
      EXPECT_EQ(c.shadowRays, c.scatteringEvents) << "one shadow ray per scattering event and light";
      EXPECT_EQ(c.gradientEvaluations, 0u);
    }
  }
}

// One light per scattering event (LightingDesc::sampleOneLight): three
// directional lights from behind the viewer, of intensities E1, E2 and 0
// (a light that is never chosen), on the slab above. The radiance is
// (E1 + E2) p(-1) (1 - e^(-2 sigma L)) / 2, as with every light sampled:
// one z-test on R. Exactly one shadow ray per scattering event, against
// three (one per light, the dark one included) with every light sampled.
TEST(Lighting, OneLightPerScatteringEventIsUnbiasedForOneShadowRay)
{
  const double alpha = kAlpha;
  const double sigma = 0.15, L = 12.0, E1 = 1.5, E2 = 0.5;
  Scene scene;
  TestVolume v;
  slabScene(scene, v, sigma);
  const Camera cam = orthoAlongZ(8, 8, 1, 4, 1, 4, 20, 40);
  const std::unique_ptr<Renderer> rp = testRenderer();
  LightingDesc ld;
  for (double E : { E1, E2, 0.0 })
  {
    LightDesc light;
    light.vector[0] = 0;
    light.vector[1] = 0;
    light.vector[2] = 1;
    light.intensity = E;
    ld.lights.push_back(light);
  }
  ld.albedo = { 1.f };
  ld.anisotropy = { 0.f };
  ld.sampleOneLight = true;
  scene.setLighting(ld);
  RenderCounters c;
  const MeanSE R = pixelStatistic(
    *rp, scene, cam, 64, [](float x, float, float, float) { return double(x); }, &c);
  const double p = 1.0 / (4.0 * M_PI);
  const double expectR = (E1 + E2) * p * (1.0 - std::exp(-2.0 * sigma * L)) / 2.0;
  std::printf("one light of three: R %.5f +- %.5f (expected %.5f)\n", R.mean, R.se, expectR);
  EXPECT_GT(normalTwoSided((R.mean - expectR) / R.se), alpha) << "R " << R.mean << " expected " << expectR;
  EXPECT_GT(c.scatteringEvents, 0u);
  EXPECT_EQ(c.shadowRays, c.scatteringEvents) << "one shadow ray per scattering event, whatever the lights";
  ld.sampleOneLight = false;
  scene.setLighting(ld);
  RenderCounters all;
  pixelStatistic(*rp, scene, cam, 4, [](float x, float, float, float) { return double(x); }, &all);
  EXPECT_EQ(all.shadowRays, 3 * all.scatteringEvents) << "every light: one shadow ray each";
}

// White furnace: an albedo-1 white medium under uniform ambient radiance A,
// with multiple scattering, returns A wherever the camera ray collides:
// E[R - A alpha] = 0 (z-test, 2 scenes).
TEST(Lighting, FurnaceConvergesToTheAmbientRadiance)
{
  const double alpha = kAlpha / 2;
  const double A = 0.6;
  for (double sigma : { 0.1, 0.5 })
  {
    Scene scene;
    TestVolume v;
    slabScene(scene, v, sigma);
    LightingDesc ld;
    ld.ambient[0] = ld.ambient[1] = ld.ambient[2] = A;
    ld.albedo = { 1.f };
    ld.anisotropy = { 0.3f };
    ld.maxDepth = 1024;
    scene.setLighting(ld);
    const Camera cam = orbitCamera(v.dims, std::array<double, 3>{ 1, 1, 1 }.data(), 16, 16, 30, 20);
    const std::unique_ptr<Renderer> rp = testRenderer();
    Renderer& r = *rp;
    const MeanSE D =
      pixelStatistic(r, scene, cam, 256, [A](float x, float, float, float a) { return double(x) - A * double(a); });
    std::printf("furnace sigma %.1f: mean R - A alpha = %.8f +- %.5f\n", sigma, D.mean, D.se);
    EXPECT_GT(normalTwoSided(D.mean / D.se), alpha) << "sigma " << sigma << ": mean R - A alpha = " << D.mean;
  }
}

// Effects that are off cost nothing: no lights and no ambient run the unlit
// kernel (the same image, bit for bit, and no lighting work); shadows off
// traces no shadow ray; albedo 0 never scatters; gradient shading off
// evaluates no gradient.
TEST(Lighting, EffectsThatAreOffCostNothing)
{
  const DemoVolume v = makeDemo("cosmology", { 24, 24, 24 });
  Scene scene;
  configureDemo(scene, v, 4);
  const Camera cam = orbitCamera(v.dims, v.spacing, 24, 24, 30, 20);
  const std::unique_ptr<Renderer> rp = testRenderer();
  Renderer& r = *rp;
  Accumulator a, b;
  RenderSettings rs;
  rs.samplesPerPixel = 4;
  RenderCounters c0;
  r.render(scene, cam, rs, nullptr, a, &c0);
  LightingDesc dark; // a light of intensity 0 and no ambient: not lit
  dark.lights.push_back(LightDesc());
  dark.lights[0].intensity = 0;
  scene.setLighting(dark);
  EXPECT_FALSE(scene.lit());
  RenderCounters c1;
  r.render(scene, cam, rs, nullptr, b, &c1);
  EXPECT_EQ(0, std::memcmp(a.rgba(), b.rgba(), sizeof(float) * 4 * 24 * 24)) << "unlit image changed";
  for (const RenderCounters& c : { c0, c1 })
  {
    EXPECT_EQ(c.scatteringEvents + c.shadowRays + c.gradientEvaluations, 0u);
  }
  LightingDesc ld;
  ld.lights.push_back(LightDesc());
  ld.albedo.assign(4, 0.8f);
  ld.shadows = false;
  scene.setLighting(ld);
  Accumulator acc;
  // The collision estimator scatters at its real collisions; the default
  // (expected value) scores that light in closed form, without a vertex.
  RenderSettings collision = rs;
  collision.estimator = Estimator::Collision;
  for (const RenderSettings& settings : { collision, rs })
  {
    RenderCounters c2;
    acc.reset();
    r.render(scene, cam, settings, nullptr, acc, &c2);
    EXPECT_NE(0, std::memcmp(a.rgba(), acc.rgba(), sizeof(float) * 4 * 24 * 24)) << "the light changes nothing";
    if (settings.estimator == Estimator::Collision)
    {
      EXPECT_GT(c2.scatteringEvents, 0u);
    }
    EXPECT_EQ(c2.shadowRays, 0u) << "shadows off";
    EXPECT_EQ(c2.gradientEvaluations, 0u) << "gradient shading off";
  }
  ld.albedo.assign(4, 0.f);
  ld.shadows = true;
  scene.setLighting(ld);
  RenderCounters c3;
  acc.reset();
  r.render(scene, cam, rs, nullptr, acc, &c3);
  EXPECT_EQ(c3.scatteringEvents + c3.shadowRays, 0u) << "albedo 0 never scatters";
  ld.albedo.assign(4, 0.8f);
  ld.gradientShading = true;
  scene.setLighting(ld);
  RenderCounters c4;
  acc.reset();
  r.render(scene, cam, rs, nullptr, acc, &c4);
  EXPECT_EQ(c4.gradientEvaluations, c4.scatteringEvents) << "one gradient per scattering event";
  EXPECT_GT(c4.shadowRays, 0u);
}

// Bad lighting input is an error.
TEST(Lighting, BadInputIsAnError)
{
  Scene scene;
  LightingDesc ld;
  ld.albedo = { 1.5f };
  EXPECT_THROW(scene.setLighting(ld), std::invalid_argument);
  ld.albedo = { 0.5f };
  ld.anisotropy = { 1.f };
  EXPECT_THROW(scene.setLighting(ld), std::invalid_argument);
  ld.anisotropy = { 0.f };
  ld.maxDepth = 0;
  EXPECT_THROW(scene.setLighting(ld), std::invalid_argument);
  ld.maxDepth = 1;
  for (float roulette : { 0.f, -0.5f, 1.5f, std::nanf("") })
  {
    ld.scatterRoulette = roulette;
    EXPECT_THROW(scene.setLighting(ld), std::invalid_argument) << "scatter roulette " << roulette;
  }
  ld.scatterRoulette = 1.f;
  EXPECT_NO_THROW(scene.setLighting(ld));
  LightDesc bad;
  bad.vector[0] = bad.vector[1] = bad.vector[2] = 0;
  ld.lights.push_back(bad);
  EXPECT_THROW(scene.setLighting(ld), std::invalid_argument);
  ld.lights[0].vector[2] = 1;
  ld.lights[0].intensity = -1;
  EXPECT_THROW(scene.setLighting(ld), std::invalid_argument);
  ld.lights.assign(9, LightDesc());
  EXPECT_THROW(scene.setLighting(ld), std::invalid_argument);
}

// Shadows and single scattering of the Monte Carlo mapper agree with the
// ray-marched lit reference (marchLit: shadow rays marched at the same
// step), for density, max, mix and composite blending (each channel lit
// alone) with a directional and a point light and per-channel albedo and
// anisotropy. 64 renders of 32 spp give the per-pixel variance of their
// mean; the image-mean difference of each component is tested (z, central
// limit over the pixels); 4 modes x 4 components. The CUDA backend refuses
// lit composite blending with an error.
TEST(Lighting, MonteCarloShadowsMatchTheRayMarchedReference)
{
  const double alpha = kAlpha / 16;
  const DemoVolume v = makeDemo("cosmology", { 20, 20, 20 });
  const Camera cam = orbitCamera(v.dims, v.spacing, 16, 16, 30, 20);
  for (BlendMode mode : { BlendMode::Density, BlendMode::Max, BlendMode::Mix, BlendMode::Composite })
  {
    Scene scene;
    configureDemo(scene, v, 4, 128, 0.5, mode);
    LightingDesc ld;
    const LightDesc sun = testSun(1.5);
    const LightDesc lamp = testLamp(400);
    ld.lights = { sun, lamp };
    ld.albedo = { 0.9f, 0.6f, 0.8f, 0.3f };
    ld.anisotropy = { 0.4f, -0.2f, 0.f, 0.7f };
    ld.maxDepth = 1;
    scene.setLighting(ld);
    RayMarcher rm;
    Accumulator ref;
    MarchSettings ms;
    ms.step = 0.125;
    ms.terminateTransmittance = 0.f;
    rm.render(scene, cam, ms, nullptr, ref);
    const std::unique_ptr<Renderer> r = testRenderer();
    if (mode == BlendMode::Composite && std::string(r->name()) == "cuda")
    {
      Accumulator acc;
      EXPECT_THROW(r->render(scene, cam, RenderSettings(), nullptr, acc), std::invalid_argument);
      continue;
    }
    const int K = 64;
    const size_t P = size_t(cam.width) * cam.height * 4;
    std::vector<double> sum(P, 0.0), sumSq(P, 0.0);
    for (int k = 0; k < K; ++k)
    {
      Accumulator acc;
      RenderSettings rs;
      rs.samplesPerPixel = 32;
      rs.jitterPixels = false;
      rs.seed = uint32_t(700 + k);
      r->render(scene, cam, rs, nullptr, acc);
      for (size_t i = 0; i < P; ++i)
      {
        sum[i] += acc.rgba()[i];
        sumSq[i] += double(acc.rgba()[i]) * acc.rgba()[i];
      }
    }
    std::array<double, 4> diff{};
    const std::array<double, 4> z = imageMeanZ(sum, sumSq, K, ref.rgba(), &diff);
    for (int c = 0; c < 4; ++c)
    {
      std::printf("%s component %d: image-mean difference %.5f, z = %.2f\n", toString(mode), c, diff[size_t(c)],
        z[size_t(c)]);
      EXPECT_GT(normalTwoSided(z[size_t(c)]), alpha) << toString(mode) << " component " << c;
    }
  }
}

// Lit composite blending is each channel lit alone, the images added: the
// ray-marched composite equals the sum of the density-blend marches of the
// scene with one channel visible at a time (the others' opacity zero), in
// colour exactly (float rounding) and in alpha as 1 - prod(1 - alpha_n).
TEST(Lighting, CompositeIsEachChannelLitAlone)
{
  const DemoVolume v = makeDemo("cosmology", { 16, 16, 16 });
  const Camera cam = orbitCamera(v.dims, v.spacing, 12, 12, 30, 20);
  LightingDesc ld = sunAndSky(2, 0.2);
  ld.albedo = { 0.9f, 0.6f, 0.8f, 0.3f };
  MarchSettings ms;
  ms.step = 0.25;
  RayMarcher rm;
  const size_t P = size_t(cam.width) * cam.height;
  Scene composite;
  configureDemo(composite, v, 4, 64, 0.5, BlendMode::Composite);
  composite.setLighting(ld);
  Accumulator all;
  rm.render(composite, cam, ms, nullptr, all);
  std::vector<double> rgb(P * 3, 0.0), clear(P, 1.0);
  for (int n = 0; n < v.numChannels(); ++n)
  {
    Scene alone;
    configureDemo(alone, v, 4, 64, 0.5, BlendMode::Density);
    for (int m = 0; m < v.numChannels(); ++m)
    {
      if (m != n)
      {
        TransferFunctionDesc off;
        off.rgb.assign(64 * 3, 0.f);
        off.opacity.assign(64, 0.f);
        alone.setTransferFunction(m, off);
      }
    }
    alone.setLighting(ld);
    alone.update();
    Accumulator one;
    rm.render(alone, cam, ms, nullptr, one);
    for (size_t p = 0; p < P; ++p)
    {
      for (int c = 0; c < 3; ++c)
      {
        rgb[p * 3 + size_t(c)] += one.rgba()[p * 4 + size_t(c)];
      }
      clear[p] *= 1.0 - one.rgba()[p * 4 + 3];
    }
  }
  double lit = 0;
  for (size_t p = 0; p < P; ++p)
  {
    for (int c = 0; c < 3; ++c)
    {
      EXPECT_NEAR(all.rgba()[p * 4 + size_t(c)], rgb[p * 3 + size_t(c)], 1e-5) << "pixel " << p;
      lit += rgb[p * 3 + size_t(c)];
    }
    EXPECT_NEAR(all.rgba()[p * 4 + 3], 1.0 - clear[p], 1e-5) << "pixel " << p;
  }
  EXPECT_GT(lit, 0.01 * double(P)) << "the scene is lit and visible";
}

namespace
{
/// A volume split at z = 12 into two pieces that share that plane (as
/// ParaView's pieces do), each a Scene over its part of one array, and the
/// whole volume's Scene, which stands in for the other piece (exact).
struct SplitScene
{
  static constexpr int kNx = 12, kNy = 12, kNz = 24, kSplit = 12;
  std::vector<float> values;
  Scene whole, lower, upper;

  explicit SplitScene(const LightingDesc& ld)
  {
    values.assign(size_t(kNx) * kNy * kNz, 0.f);
    for (int z = 0; z < kNz; ++z)
    {
      for (int i = 0; i < kNx * kNy; ++i)
      {
        // A thin, faint slab in the lower piece, a thick, denser one above
        // it in the upper piece.
        values[size_t(z) * kNx * kNy + size_t(i)] = (z >= 3 && z <= 5) ? 0.5f : (z >= 15 && z <= 20) ? 1.f : 0.f;
      }
    }
    build(whole, values.data(), kNz, ld);
    build(lower, values.data(), kSplit + 1, ld);
    build(upper, values.data() + size_t(kSplit) * kNx * kNy, kNz - kSplit, ld);
  }

  /// `scene` of the kNx x kNy x nz values at `values` (not copied), with
  /// the slabs' function: extinction 0.2 at 0.5 (the faint slab), 0.5 at 1
  /// (the dense one).
  static void build(Scene& scene, const float* values, int nz, const LightingDesc& ld)
  {
    TransferFunctionDesc tf = flatTF(0.f, 0.9f, 0.85f, 0.8f, 1.f, 64);
    for (int k = 0; k < 64; ++k)
    {
      const double v = k / 63.0;
      tf.opacity[size_t(k)] = opacityFor(v <= 0.5 ? 0.4 * v : 0.2 + 0.6 * (v - 0.5), 1.0);
    }
    const int dims[3] = { kNx, kNy, nz };
    const ChannelSource src{ values, ScalarType::Float32, 1, 0.0 };
    scene.setVolume(dims, 1, &src);
    scene.setTransferFunction(0, tf);
    scene.setMacrocellSize(4);
    scene.setLighting(ld);
    scene.update();
  }

  /// The whole volume as the pieces' stand-in; `exact` tells them it holds
  /// their voxels as they are (Scene::setOutside).
  void linkStandIn(bool exact = false)
  {
    const double one[3] = { 1, 1, 1 };
    const double none[3] = { 0, 0, 0 };
    const double up[3] = { 0, 0, double(kSplit) };
    lower.setOutside(&whole, one, none, exact);
    upper.setOutside(&whole, one, up, exact);
  }
};

/// Orthographic camera looking up (+z) at the volume, for a piece whose
/// index 0 is at world z = zOrigin.
Camera lookingUp(double zOrigin)
{
  const double center[3] = { 5.5, 5.5, -4 };
  const double right[3] = { 6, 0, 0 };
  const double up[3] = { 0, 6, 0 };
  const double dir[3] = { 0, 0, 1 };
  Camera cam = orthoCamera(12, 12, center, right, up, dir, 0.0, 40.0);
  const double spacing[3] = { 1, 1, 1 };
  const double origin[3] = { 0, 0, zOrigin };
  setWorldToIndex(cam, spacing, origin);
  return cam;
}

/// Moments of `renders` one-sample renders (seeds seed, seed + 1, ...),
/// with the window depth `depth` everywhere (1: none).
Moments litMoments(Renderer& r, const Scene& scene, const Camera& cam, int renders, uint32_t seed, float depth)
{
  Moments m;
  m.width = cam.width;
  m.height = cam.height;
  m.n = renders;
  const size_t P = size_t(cam.width) * size_t(cam.height);
  m.sum.assign(4 * P, 0.0);
  m.sumSq.assign(4 * P, 0.0);
  const std::vector<float> depths(P, depth);
  RenderSettings rs;
  rs.jitterPixels = false;
  for (int k = 0; k < renders; ++k)
  {
    Accumulator acc;
    rs.seed = seed + uint32_t(k);
    r.render(scene, cam, rs, depth < 1.f ? depths.data() : nullptr, acc);
    for (size_t i = 0; i < 4 * P; ++i)
    {
      m.sum[i] += acc.rgba()[i];
      m.sumSq[i] += double(acc.rgba()[i]) * acc.rgba()[i];
    }
  }
  return m;
}

/// z of the image-mean difference of each colour component between the
/// lower piece (in front: the camera looks up) and the whole volume with
/// the camera rays ending at the piece's far side, z = 12 (window depth
/// 0.4 of lookingUp's 40 units from z = -4), independent renders.
std::array<double, 3> lowerAgainstWhole(const SplitScene& s, int renders)
{
  const std::unique_ptr<Renderer> r = testRenderer();
  const Moments w = litMoments(*r, s.whole, lookingUp(0), renders, 1000, 0.4f);
  const Moments piece = litMoments(*r, s.lower, lookingUp(0), renders, 5000, 1.f);
  std::array<double, 3> z{};
  for (int c = 0; c < 3; ++c)
  {
    double D = 0, V = 0, M = 0;
    for (size_t i = size_t(c); i < w.size(); i += 4)
    {
      D += piece.mean(i) - w.mean(i);
      V += piece.var(i) / piece.n + w.var(i) / w.n;
      M += w.mean(i);
    }
    std::printf("component %d: image mean %.5f, difference %.5f +- %.5f\n", c, M / double(w.size() / 4),
      D / double(w.size() / 4), std::sqrt(V) / double(w.size() / 4));
    z[size_t(c)] = V > 0 ? D / std::sqrt(V) : 0.0;
  }
  return z;
}
} // namespace

// Lighting across pieces (Scene::setOutside): a volume split in two; the
// lower piece rendered alone with the whole volume as its stand-in equals
// the whole volume rendered with the camera rays ending where the piece
// ends (a window depth at its far side). The light shines down (+z is
// towards it) and the camera looks up: the faint lower slab is lit through
// the upper slab (optical depth 3; its shadow rays cross the upper piece)
// and, mostly, by the light that the upper slab scatters forward, down
// (albedo 0.99, anisotropy 0.8, up to 8 scattering events, no ambient
// light), which the lower slab's scattered rays reach only through the
// stand-in (without that continuation the image mean is 8 to 10 standard
// errors low). Both ways of using the stand-in are tested: the part of a
// path beyond the piece in the stand-in, and (an exact stand-in) the whole
// path in it from its first vertex. The image-mean difference of
// each colour component is tested (z, central limit over the pixels), 6
// checks; power: without the stand-in every component is off by more than
// 10 standard errors.
TEST(Lighting, StandInCarriesLightAcrossPieces)
{
  const double alpha = kAlpha / 6;
  LightingDesc ld;
  LightDesc sun;
  sun.vector[2] = 1;
  sun.intensity = 2;
  ld.lights = { sun };
  ld.albedo = { 0.99f };
  ld.anisotropy = { 0.8f };
  ld.maxDepth = 8;
  SplitScene split(ld);
  const std::array<double, 3> alone = lowerAgainstWhole(split, 64);
  split.linkStandIn(false);
  const std::array<double, 3> linked = lowerAgainstWhole(split, 64);
  split.linkStandIn(true);
  const std::array<double, 3> exact = lowerAgainstWhole(split, 64);
  for (int c = 0; c < 3; ++c)
  {
    std::printf("component %d: z = %.2f with the stand-in beyond the piece, %.2f exact, %.2f without\n", c,
      linked[size_t(c)], exact[size_t(c)], alone[size_t(c)]);
    EXPECT_GT(normalTwoSided(linked[size_t(c)]), alpha) << "component " << c;
    EXPECT_GT(normalTwoSided(exact[size_t(c)]), alpha) << "component " << c;
    EXPECT_GT(std::fabs(alone[size_t(c)]), 10.0) << "component " << c;
  }
}

// Which voxels each way reads: single scattering from the lower piece,
// with a stand-in that lies about the piece (an absorber of optical depth
// 3 between the faint slab and the piece's top face, where the piece is
// empty). Beyond the piece only: the stand-in's copy of the piece is never
// read, so the image is bit for bit the one with the true stand-in. Exact:
// every shadow ray crosses the absorber in the stand-in, so the image is
// less than half as bright (exp(-2.5) of it in expectation). And the
// exact path follows the stand-in's index map (an offset).
TEST(Lighting, ExactStandInCarriesTheWholePath)
{
  LightingDesc ld;
  LightDesc sun;
  sun.vector[2] = 1;
  sun.intensity = 2;
  ld.lights = { sun };
  ld.albedo = { 1.f }; // no emission: the image is the light through the shadow rays
  ld.maxDepth = 1;
  SplitScene split(ld);
  std::vector<float> lie = split.values;
  for (int z = 6; z <= 10; ++z)
  {
    std::fill_n(lie.begin() + ptrdiff_t(z) * SplitScene::kNx * SplitScene::kNy, SplitScene::kNx * SplitScene::kNy, 1.f);
  }
  Scene liar;
  SplitScene::build(liar, lie.data(), SplitScene::kNz, ld);

  const Camera cam = lookingUp(0);
  RenderSettings rs;
  rs.samplesPerPixel = 16;
  rs.seed = 7;
  const std::unique_ptr<Renderer> r = testRenderer();
  const size_t P = size_t(cam.width) * size_t(cam.height);
  auto render = [&](const Scene* standIn, bool exact, const double* offset = nullptr)
  {
    split.lower.setOutside(standIn, nullptr, offset, exact);
    Accumulator acc;
    r->render(split.lower, cam, rs, nullptr, acc);
    return std::vector<float>(acc.rgba(), acc.rgba() + 4 * P);
  };
  auto mean = [&](const std::vector<float>& image)
  {
    double m = 0;
    for (size_t i = 0; i < P; ++i)
    {
      m += image[4 * i];
    }
    return m / double(P);
  };
  EXPECT_EQ(render(&split.whole, false), render(&liar, false));
  const double truth = mean(render(&split.whole, true));
  const double lied = mean(render(&liar, true));

  // The map into the stand-in: the whole volume again, below 4 empty
  // planes (one macrocell, so its cells line up with the piece's), the
  // piece's point p at p + (0, 0, 4). The same random numbers give the same
  // image up to rounding; without the offset every path would start 4
  // voxels too low, in and below the faint slab.
  std::vector<float> padded(size_t(SplitScene::kNx) * SplitScene::kNy * 4, 0.f);
  padded.insert(padded.end(), split.values.begin(), split.values.end());
  Scene shifted;
  SplitScene::build(shifted, padded.data(), SplitScene::kNz + 4, ld);
  const double offset[3] = { 0, 0, 4 };
  const double moved = mean(render(&shifted, true, offset));
  std::printf("exact stand-in: red mean %.5f with the true stand-in, %.5f with the absorber, %.5f shifted\n", truth,
    lied, moved);
  EXPECT_GT(truth, 0.0);
  EXPECT_LT(lied, 0.5 * truth);
  EXPECT_NEAR(moved, truth, 0.02 * truth);

  // Under the visibility optimization, which acts on light rays inside the
  // piece, the piece's paths keep reading the piece: exact or not, the
  // same image.
  ImportanceDesc imp;
  imp.enabled = true;
  imp.tables = { std::vector<float>(64, 0.5f) };
  split.lower.setImportance(imp);
  split.lower.update();
  EXPECT_EQ(render(&liar, true), render(&liar, false));
}

// The stand-in is read only by lit renders, and bad stand-ins are errors:
// an unlit piece renders bit for bit the same with and without one; a
// Scene cannot stand in for itself; the map must be finite and positive;
// a stand-in with another number of channels, or not updated, is refused
// by the render.
TEST(Lighting, StandInIsUnlitFreeAndChecked)
{
  LightingDesc dark;
  SplitScene split(dark);
  const Camera cam = lookingUp(0);
  RenderSettings rs;
  rs.samplesPerPixel = 4;
  const std::unique_ptr<Renderer> r = testRenderer();
  Accumulator before, after;
  r->render(split.lower, cam, rs, nullptr, before);
  split.linkStandIn();
  r->render(split.lower, cam, rs, nullptr, after);
  EXPECT_EQ(0, std::memcmp(before.rgba(), after.rgba(), sizeof(float) * 4 * size_t(cam.width) * cam.height));

  EXPECT_THROW(split.whole.setOutside(&split.whole), std::invalid_argument);
  const double bad[3] = { 1, 0, 1 };
  EXPECT_THROW(split.lower.setOutside(&split.whole, bad), std::invalid_argument);
  const double nan[3] = { 0, std::nan(""), 0 };
  EXPECT_THROW(split.lower.setOutside(&split.whole, nullptr, nan), std::invalid_argument);

  LightingDesc ld;
  ld.ambient[0] = ld.ambient[1] = ld.ambient[2] = 0.5;
  split.lower.setLighting(ld);
  split.lower.update();
  Scene empty; // never updated
  split.lower.setOutside(&empty);
  Accumulator acc;
  EXPECT_THROW(r->render(split.lower, cam, rs, nullptr, acc), std::invalid_argument);
  std::vector<float> two(size_t(SplitScene::kNx) * SplitScene::kNy * SplitScene::kNz * 2, 0.f);
  const ChannelSource pair[2] = { { two.data(), ScalarType::Float32, 2, 0.0 }, { two.data() + 1, ScalarType::Float32, 2, 0.0 } };
  const int dims[3] = { SplitScene::kNx, SplitScene::kNy, SplitScene::kNz };
  Scene other;
  other.setVolume(dims, 2, pair);
  other.setTransferFunction(0, flatTF(0.5f, 1, 1, 1));
  other.setTransferFunction(1, flatTF(0.5f, 1, 1, 1));
  other.update();
  split.lower.setOutside(&other);
  EXPECT_THROW(r->render(split.lower, cam, rs, nullptr, acc), std::invalid_argument);
}

// The expected-value estimator of lit camera rays (traceLitExpected():
// expected-value emission, the scattered part at one tentative collision
// picked by its weight, with roulette below LightingDesc::scatterRoulette)
// has the collision estimator's expectation: density, max and mix blending
// (per-channel albedo and anisotropy) under one sun and one point light
// with ratio shadows, the same with delta shadows and ambient 0.3,
// multiple scattering (depth 8, ambient 0.2, gradient shading), and without
// shadows, where the scattered light is scored in closed form
// (closedFormScattering(): max and mix with per-channel anisotropy, all
// three with one anisotropy, under both lights with one chosen per vertex
// and ambient 0.3, and under the sun alone). Each pair: 160 one-sample
// renders per estimator, independent seeds, expectSameMean (image mean,
// 4 x 4 blocks, sparse blocks pooled; per component): 18 pairs x 12
// checks. And with scatterRoulette 1 it spends the collision estimator's
// shadow rays: in single scattering its scattering events (0 or 1 a
// sample) in 16 samples per pixel equal the collision estimator's (z-test,
// variance bounded by the counts, 6 checks).
TEST(Lighting, ExpectedValueEqualsTheCollisionEstimator)
{
  const double alpha = kAlpha / (18 * 12 + 6);
  const DemoVolume v = makeDemo("cosmology", { 16, 16, 16 });
  const Camera cam = orbitCamera(v.dims, v.spacing, 12, 12, 30, 20);
  const LightDesc sun = testSun(1.5);
  const LightDesc lamp = testLamp(300);
  const std::unique_ptr<Renderer> rp = testRenderer();
  for (BlendMode mode : { BlendMode::Density, BlendMode::Max, BlendMode::Mix })
  {
    Scene scene;
    configureDemo(scene, v, 4, 128, 0.5, mode);
    for (int config = 0; config < 6; ++config)
    {
      LightingDesc ld;
      ld.lights = { sun, lamp };
      ld.albedo = { 0.9f, 0.6f, 0.8f, 0.3f };
      ld.anisotropy = { 0.4f, -0.2f, 0.f, 0.7f };
      const char* name = "shadows";
      if (config >= 3)
      {
        ld.shadows = false;
        ld.ambient[0] = ld.ambient[1] = ld.ambient[2] = 0.3;
        name = "no shadows";
      }
      if (config == 4)
      {
        name = "no shadows, one anisotropy, one light a vertex";
        ld.anisotropy.assign(4, 0.5f);
        ld.sampleOneLight = true;
      }
      else if (config == 5)
      {
        name = "no shadows, one anisotropy, the sun alone";
        ld.lights = { sun };
        ld.anisotropy.assign(4, -0.3f);
        ld.ambient[0] = ld.ambient[1] = ld.ambient[2] = 0.0;
      }
      if (config == 1)
      {
        name = "delta shadows, ambient";
        ld.deltaShadows = true;
        ld.ambient[0] = ld.ambient[1] = ld.ambient[2] = 0.3;
      }
      else if (config == 2)
      {
        name = "multiple scattering";
        ld.ambient[0] = ld.ambient[1] = ld.ambient[2] = 0.2;
        ld.maxDepth = 8;
        ld.gradientShading = true;
      }
      scene.setLighting(ld);
      ASSERT_TRUE(scene.lit());
      RenderSettings ev;
      ev.estimator = Estimator::ExpectedValue;
      RenderSettings col = ev;
      col.estimator = Estimator::Collision;
      if (config < 2)
      {
        LightingDesc counted = ld;
        counted.scatterRoulette = 1.f;
        scene.setLighting(counted);
        RenderCounters cEV, cCol;
        RenderSettings many = ev;
        many.samplesPerPixel = 16;
        Accumulator probe;
        rp->render(scene, cam, many, nullptr, probe, &cEV);
        probe.reset();
        many.estimator = Estimator::Collision;
        rp->render(scene, cam, many, nullptr, probe, &cCol);
        const double a = double(cEV.scatteringEvents), b = double(cCol.scatteringEvents);
        std::printf("%s, %s: scattering events %.0f (expected value), %.0f (collision)\n", toString(mode), name, a, b);
        EXPECT_GT(a, 0.0);
        EXPECT_GT(normalTwoSided((a - b) / std::sqrt(a + b)), alpha)
          << toString(mode) << ", " << name << ": scattering events " << a << " against " << b;
        scene.setLighting(ld);
      }
      const Moments A = renderMoments(*rp, scene, cam, ev, 160, 1000);
      const Moments B = renderMoments(*rp, scene, cam, col, 160, 5000);
      expectSameMean(A, B, alpha, std::string(toString(mode)) + ", " + name + ": expected value against collision");
    }
  }
}

// A light without shadows costs the expected-value estimator the unlit
// traversal: with one anisotropy and no gradient shading the scattered light
// is scored in closed form at every tentative collision
// (closedFormScattering()), so the lit render draws the unlit render's
// random numbers and visits its cells and collisions, count for count, with
// no scattering vertex and no shadow ray. With gradient shading it scatters
// at picked vertices, as before.
TEST(Lighting, LightWithoutShadowsCostsTheUnlitTraversal)
{
  const DemoVolume v = makeDemo("cosmology", { 16, 16, 16 });
  const Camera cam = orbitCamera(v.dims, v.spacing, 12, 12, 30, 20);
  const std::unique_ptr<Renderer> rp = testRenderer();
  RenderSettings rs;
  rs.estimator = Estimator::ExpectedValue;
  rs.samplesPerPixel = 4;
  for (BlendMode mode : { BlendMode::Density, BlendMode::Max, BlendMode::Mix })
  {
    Scene scene;
    configureDemo(scene, v, 4, 128, 0.5, mode);
    Accumulator acc;
    RenderCounters unlit, lit, shaded;
    rp->render(scene, cam, rs, nullptr, acc, &unlit);
    LightingDesc ld;
    ld.lights = { testSun(1.5), testLamp(300) };
    ld.albedo = { 0.9f, 0.6f, 0.8f, 0.3f };
    ld.anisotropy.assign(4, 0.4f);
    ld.shadows = false;
    ld.ambient[0] = ld.ambient[1] = ld.ambient[2] = 0.3;
    scene.setLighting(ld);
    ASSERT_TRUE(scene.lit());
    acc.reset();
    rp->render(scene, cam, rs, nullptr, acc, &lit);
    double total = 0;
    for (int i = 0; i < 12 * 12 * 4; ++i)
    {
      total += acc.sums()[i];
    }
    EXPECT_TRUE(std::isfinite(total) && total > 0) << toString(mode) << ": " << total;
    ld.gradientShading = true;
    scene.setLighting(ld);
    acc.reset();
    rp->render(scene, cam, rs, nullptr, acc, &shaded);
    const char* m = toString(mode);
    EXPECT_GT(unlit.tentativeCollisions, 0u) << m;
    EXPECT_EQ(lit.ddaSteps, unlit.ddaSteps) << m;
    EXPECT_EQ(lit.tentativeCollisions, unlit.tentativeCollisions) << m;
    EXPECT_EQ(lit.channelSamples, unlit.channelSamples) << m;
    EXPECT_EQ(lit.realCollisions, 0u) << m;
    EXPECT_EQ(lit.scatteringEvents, 0u) << m;
    EXPECT_EQ(lit.shadowRays, 0u) << m;
    EXPECT_EQ(lit.gradientEvaluations, 0u) << m;
    EXPECT_GT(shaded.scatteringEvents, 0u) << m;
    EXPECT_GT(shaded.gradientEvaluations, 0u) << m;
  }
}

namespace
{
/// The scene and view of the lit path tests: the four-channel 16^3 cosmology
/// demo, seen by 12x12 pixels.
struct LitPathView
{
  DemoVolume v = makeDemo("cosmology", { 16, 16, 16 });
  Camera camera = orbitCamera(v.dims, v.spacing, 12, 12, 30, 20);
  CameraView cam = toView(camera);
  void configure(Scene& scene, BlendMode mode) const { configureDemo(scene, v, 4, 128, 0.5, mode); }
};

/// Lights for the four-channel demo of the lit path tests, with a different
/// albedo and anisotropy per channel.
LightingDesc fourChannelLighting(std::vector<LightDesc> lights)
{
  LightingDesc ld;
  ld.lights = std::move(lights);
  ld.albedo = { 0.9f, 0.6f, 0.8f, 0.3f };
  ld.anisotropy = { 0.4f, -0.2f, 0.f, 0.7f };
  return ld;
}
} // namespace

// Where no ray follows the camera ray's collision (no shadows, one
// scattering vertex), the lit kernels compile the light path without the
// code of those rays (litPathFrom()'s Local), and the expected-value
// estimator's kernels its closed form alone (localKernels()). It must be
// the same path: on every pixel, both estimators, three blends, two lights
// (both, or one chosen), ambient light, per-channel or one anisotropy and
// gradient shading, the Local code gives the pixel's sum bit for bit
// wherever localKernels() picks it; where it does not (the expected-value
// estimator with gradient shading, or density blending with per-channel
// anisotropy), the render runs the full kernel.
namespace
{
/// Pixel (x, y) lit by the full light path and by its Local code, with the
/// lit estimator `code` (0 or 1).
template <BlendMode Mode>
void fullAndLocal(int code, const SceneView& s, const CameraView& cam, const FrameParams& fp, int x, int y,
  RayCounters& cFull, Vec4d& full, RayCounters& cLocal, Vec4d& local)
{
  if (code == 1)
  {
    renderPixel<Mode, true, false, 1>(s, s, cam, fp, x, y, 1.f, cFull, full);
    renderPixel<Mode, true, false, 1 + kLocalLight>(s, s, cam, fp, x, y, 1.f, cLocal, local);
  }
  else
  {
    renderPixel<Mode, true, false, 0>(s, s, cam, fp, x, y, 1.f, cFull, full);
    renderPixel<Mode, true, false, kLocalLight>(s, s, cam, fp, x, y, 1.f, cLocal, local);
  }
}
} // namespace

TEST(Lighting, LocalLightPathIsTheFullPath)
{
  const LitPathView view;
  const CameraView& cam = view.cam;
  for (BlendMode mode : { BlendMode::Density, BlendMode::Max, BlendMode::Mix })
  {
    Scene scene;
    view.configure(scene, mode);
    for (int config = 0; config < 3; ++config)
    {
      LightingDesc ld = fourChannelLighting({ testSun(1.5), testLamp(300) });
      ld.shadows = false;
      ld.ambient[0] = ld.ambient[1] = ld.ambient[2] = 0.3;
      ld.gradientShading = config == 1;
      ld.sampleOneLight = config >= 1;
      if (config == 2)
      {
        ld.anisotropy.assign(4, 0.4f);
      }
      scene.setLighting(ld);
      ASSERT_TRUE(scene.lit());
      SceneView s = scene.view();
      ASSERT_TRUE(localLighting(s.lighting));
      s.sigmaLimit = extinctionLimit(cam);
      setLightingFrame(s, view.camera);
      for (Estimator e : { Estimator::Collision, Estimator::ExpectedValue })
      {
        RenderSettings rs;
        rs.estimator = e;
        rs.samplesPerPixel = 8;
        const FrameParams fp = frameParams(rs, 0);
        const int code = unlitEstimator(e, mode, true, false);
        const bool closedForm = e == Estimator::ExpectedValue && closedFormScattering(s, mode);
        const bool expectLocal = e == Estimator::Collision || (config != 1 && (config == 2 || mode != BlendMode::Density));
        EXPECT_EQ(localKernels(s, mode, e), expectLocal) << toString(mode) << ", config " << config;
        if (!localKernels(s, mode, e))
        {
          continue;
        }
        ASSERT_EQ(unlitEstimator(e, mode, true, false, false, true), code + kLocalLight);
        double total = 0;
        uint64_t differ = 0;
        RayCounters cFull, cLocal;
        for (int y = 0; y < cam.height; ++y)
        {
          for (int x = 0; x < cam.width; ++x)
          {
            Vec4d full, local;
            switch (mode)
            {
              case BlendMode::Max:
                fullAndLocal<BlendMode::Max>(code, s, cam, fp, x, y, cFull, full, cLocal, local);
                break;
              case BlendMode::Mix:
                fullAndLocal<BlendMode::Mix>(code, s, cam, fp, x, y, cFull, full, cLocal, local);
                break;
              default:
                fullAndLocal<BlendMode::Density>(code, s, cam, fp, x, y, cFull, full, cLocal, local);
                break;
            }
            differ += (full.r != local.r || full.g != local.g || full.b != local.b || full.a != local.a) ? 1u : 0u;
            total += full.r + full.g + full.b;
          }
        }
        const char* lights[3] = { ", two lights", ", one light, gradients", ", one light, one anisotropy" };
        const std::string what = std::string(toString(mode)) + lights[config] + (code ? ", expected value" : ", collision");
        EXPECT_EQ(differ, 0u) << what;
        EXPECT_GT(total, 0.0) << what;
        if (closedForm)
        {
          EXPECT_EQ(cFull.scattering, 0u) << what;
        }
        else
        {
          EXPECT_GT(cFull.scattering, 0u) << what;
        }
        EXPECT_EQ(cFull.scattering, cLocal.scattering) << what;
        EXPECT_EQ(cLocal.shadowRays, 0u) << what;
      }
    }
  }
  LightingView L;
  L.enabled = true;
  L.shadows = false;
  EXPECT_TRUE(localLighting(L));
  L.maxDepth = 2;
  EXPECT_FALSE(localLighting(L)) << "scattered rays";
  L.maxDepth = 1;
  L.shadows = true;
  EXPECT_FALSE(localLighting(L)) << "shadow rays";
  L.shadows = false;
  L.enabled = false;
  EXPECT_FALSE(localLighting(L)) << "unlit";
}

// Where the shadow rays are deferred (deferrableShadows(): the GPU traces
// them in a kernel of their own), the recorded rays, finished afterwards,
// must give the traced path's sample bit for bit: on every pixel and sample,
// both estimators, three blends, one light with ratio-tracking shadows, and
// two lights of which one is chosen per vertex with ambient light, gradient
// shading and delta-tracking shadows (two rays per vertex).
namespace
{
/// Sample `index` of pixel (x, y) traced, and deferred then finished, with
/// the lit estimator `code` (0 or 1); `rays` gets the deferred ray count.
template <BlendMode Mode, int Code>
void tracedAndDeferred(const SceneView& s, const CameraView& cam, const FrameParams& fp, int x, int y, uint32_t index,
  Vec4f& traced, Vec4f& deferred, int& rays)
{
  RayCounters c;
  ShadowCounters sc;
  traced = Vec4f();
  deferred = Vec4f();
  renderSample<Mode, true, false, Code>(s, s, cam, fp, x, y, 1.f, index, c, sc, nullptr, traced);
  DeferredShadows d;
  RayCounters cd;
  ShadowCounters scd;
  renderSample<Mode, true, false, Code + kDeferredShadows>(
    s, s, cam, fp, x, y, 1.f, index, cd, scd, nullptr, deferred, &d);
  rays = d.count;
  if (d.count > 0)
  {
    d.sample = deferred;
    deferred = finishDeferredSample<Mode>(s, d);
  }
}

template <BlendMode Mode>
void tracedAndDeferred(int code, const SceneView& s, const CameraView& cam, const FrameParams& fp, int x, int y,
  uint32_t index, Vec4f& traced, Vec4f& deferred, int& rays)
{
  if (code == 1)
  {
    tracedAndDeferred<Mode, 1>(s, cam, fp, x, y, index, traced, deferred, rays);
  }
  else
  {
    tracedAndDeferred<Mode, 0>(s, cam, fp, x, y, index, traced, deferred, rays);
  }
}
} // namespace

TEST(Lighting, DeferredShadowRaysAreTheTracedOnes)
{
  const LitPathView view;
  const CameraView& cam = view.cam;
  for (BlendMode mode : { BlendMode::Density, BlendMode::Max, BlendMode::Mix })
  {
    Scene scene;
    view.configure(scene, mode);
    for (int config = 0; config < 2; ++config)
    {
      LightingDesc ld = fourChannelLighting({ testSun(1.5) });
      if (config == 1)
      {
        ld.lights.push_back(testLamp(300));
        ld.sampleOneLight = true;
        ld.ambient[0] = ld.ambient[1] = ld.ambient[2] = 0.3;
        ld.gradientShading = true;
        ld.deltaShadows = true;
      }
      scene.setLighting(ld);
      SceneView s = scene.view();
      s.sigmaLimit = extinctionLimit(cam);
      setLightingFrame(s, view.camera);
      ASSERT_TRUE(deferrableShadows(s, Sampler::Sobol));
      for (Estimator e : { Estimator::Collision, Estimator::ExpectedValue })
      {
        RenderSettings rs;
        rs.estimator = e;
        const FrameParams fp = frameParams(rs, 0);
        const int code = unlitEstimator(e, mode, true, false);
        uint64_t differ = 0, deferredSamples = 0, twoRays = 0;
        double total = 0, shadowed = 0;
        for (int y = 0; y < cam.height; ++y)
        {
          for (int x = 0; x < cam.width; ++x)
          {
            for (uint32_t index = 0; index < 8; ++index)
            {
              Vec4f traced, deferred;
              int rays = 0;
              switch (mode)
              {
                case BlendMode::Max:
                  tracedAndDeferred<BlendMode::Max>(code, s, cam, fp, x, y, index, traced, deferred, rays);
                  break;
                case BlendMode::Mix:
                  tracedAndDeferred<BlendMode::Mix>(code, s, cam, fp, x, y, index, traced, deferred, rays);
                  break;
                default:
                  tracedAndDeferred<BlendMode::Density>(code, s, cam, fp, x, y, index, traced, deferred, rays);
                  break;
              }
              differ +=
                (traced.r != deferred.r || traced.g != deferred.g || traced.b != deferred.b || traced.a != deferred.a)
                ? 1u
                : 0u;
              deferredSamples += rays > 0 ? 1u : 0u;
              twoRays += rays == 2 ? 1u : 0u;
              total += traced.r + traced.g + traced.b;
              shadowed += rays > 0 ? traced.r + traced.g + traced.b : 0.0;
            }
          }
        }
        const std::string what = std::string(toString(mode)) + (config ? ", two lights, ambient" : ", one light") +
          (code ? ", expected value" : ", collision");
        EXPECT_EQ(differ, 0u) << what;
        EXPECT_GT(deferredSamples, 50u) << what;
        EXPECT_GT(shadowed, 0.0) << what;
        EXPECT_GT(total, shadowed) << what; // some emission without shadow rays
        if (config == 1)
        {
          EXPECT_GT(twoRays, 0u) << what;
        }
      }
    }
  }
  // Where a path's shadow rays cannot wait.
  Scene scene;
  view.configure(scene, BlendMode::Density);
  LightingDesc ld;
  ld.lights = { testSun(1.5) };
  scene.setLighting(ld);
  SceneView s = scene.view();
  EXPECT_TRUE(deferrableShadows(s, Sampler::Independent));
  s.lighting.ambient = Vec3f(0.2f, 0.2f, 0.2f);
  EXPECT_TRUE(deferrableShadows(s, Sampler::Sobol));
  EXPECT_FALSE(deferrableShadows(s, Sampler::Independent)) << "the ambient direction drawn between two shadow rays";
  s.lighting.numLights = 2;
  EXPECT_FALSE(deferrableShadows(s, Sampler::Sobol)) << "three rays per vertex";
  s.lighting.sampleOneLight = true;
  EXPECT_TRUE(deferrableShadows(s, Sampler::Sobol));
  s.lighting.maxDepth = 2;
  EXPECT_FALSE(deferrableShadows(s, Sampler::Sobol)) << "scattered rays follow the shadow rays";
  s.lighting.maxDepth = 1;
  s.lighting.shadows = false;
  EXPECT_FALSE(deferrableShadows(s, Sampler::Sobol)) << "no shadow rays";
  s.lighting.shadows = true;
  SceneView other = s;
  s.outside = &other;
  EXPECT_FALSE(deferrableShadows(s, Sampler::Sobol)) << "a stand-in of other pieces";
  s.outside = nullptr;
  s.lighting.enabled = false;
  EXPECT_FALSE(deferrableShadows(s, Sampler::Sobol)) << "unlit";
}

// Which estimator a lit camera ray runs: the expected-value one where asked
// for (the default), the collision estimator where asked for, under the
// visibility optimization and under post-render compositing, and for the
// unbiased march (unlit only).
TEST(Lighting, LitEstimatorCodes)
{
  EXPECT_EQ(unlitEstimator(Estimator::ExpectedValue, BlendMode::Density, true, false), 1);
  EXPECT_EQ(unlitEstimator(Estimator::ExpectedValue, BlendMode::Max, true, false), 1);
  EXPECT_EQ(unlitEstimator(Estimator::Collision, BlendMode::Density, true, false), 0);
  EXPECT_EQ(unlitEstimator(Estimator::UnbiasedMarch, BlendMode::Density, true, false), 0);
  EXPECT_EQ(unlitEstimator(Estimator::ExpectedValue, BlendMode::Density, true, true), 0);
  EXPECT_EQ(unlitEstimator(Estimator::ExpectedValue, BlendMode::Composite, true, false), 0);
  EXPECT_EQ(unlitEstimator(Estimator::ExpectedValue, BlendMode::Density, true, false, false, true), 1 + kLocalLight);
  EXPECT_EQ(unlitEstimator(Estimator::Collision, BlendMode::Mix, true, false, false, true), kLocalLight);
  EXPECT_EQ(unlitEstimator(Estimator::ExpectedValue, BlendMode::Density, true, true, false, true), 0);
  EXPECT_EQ(unlitEstimator(Estimator::ExpectedValue, BlendMode::Composite, true, false, false, true), 0);
  EXPECT_EQ(RenderSettings().estimator, Estimator::ExpectedValue);
}
