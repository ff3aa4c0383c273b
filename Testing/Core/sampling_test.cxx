// SPDX-License-Identifier: BSD-3-Clause
// The sampling primitives of Woodcock tracking:
// - free-flight distances and the random generator;
// - multi-density channel selection (Eq. 7, Sahistan et al.) for both trackers;
// - homogeneous slab transmittance for both trackers.
// Significance: each TEST has a family-wise level kAlpha = 0.001; its k
// statistical checks (two-sided z tests or upper-tail chi-square tests) each
// use kAlpha / k (Bonferroni). Seeds are fixed, so a run is deterministic.
#include "TestUtil.h"

#include "mcvol/ray/Tracking.h"

#include <cfloat>

using namespace mcvol;
using namespace mcvol::test;

namespace
{
constexpr double kAlpha = 1e-3;

Hit track(const SceneView& s, Tracker tracker, const BoxRay& ray, Rng& rng, RayCounters& c)
{
  return trackDensity(s, tracker, ray.o, ray.d, ray.tmax, rng, c);
}
} // namespace

// ------------------------------------------- free flights and the generator

// Chi-square goodness of fit of the free flight sampleOpticalDepth / m to Exp(m) over 64 equiprobable
// bins (63 dof) and a z test of the mean, for several majorants.
TEST(FreeFlight, ExponentialDistribution)
{
  const int bins = 64;
  const int draws = 256000;
  const double alpha = kAlpha / 8; // 4 majorants x 2 checks
  for (const float m : { 0.01f, 1.f, 37.5f, 1e5f })
  {
    Rng rng(12345u, 0u, 99u);
    std::vector<double> counts(size_t(bins), 0.0);
    double sum = 0.0;
    for (int i = 0; i < draws; ++i)
    {
      const float t = sampleOpticalDepth(rng) / m;
      ASSERT_TRUE(std::isfinite(t) && t >= 0.f);
      sum += t;
      // Bin of the exponential CDF value 1 - exp(-m t).
      const double F = -std::expm1(-double(m) * double(t));
      counts[size_t(std::min(bins - 1, int(F * bins)))] += 1.0;
    }
    double stat = 0;
    const double p = chiSquarePValue(counts, std::vector<double>(size_t(bins), 1.0 / bins), &stat);
    EXPECT_GT(p, alpha) << "majorant " << m << ": chi-square " << stat;
    // Mean 1/m: z test with sd 1/(m sqrt(n)).
    const double z = (sum / draws - 1.0 / m) / (1.0 / m / std::sqrt(double(draws)));
    EXPECT_GT(normalTwoSided(z), alpha) << "majorant " << m << ": mean free path z = " << z;
  }
}

// The generator's largest value is 1 - 2^-24: never 1, so -log(1 - u) is
// finite. 2^27 draws (the top value is expected 8 times).
TEST(Rng, NeverReturnsOne)
{
  Rng rng(7u, 3u, 11u);
  float mx = 0.f, mn = 1.f;
  for (uint32_t i = 0; i < (1u << 27); ++i)
  {
    const float u = rng.next();
    mx = u > mx ? u : mx;
    mn = u < mn ? u : mn;
  }
  EXPECT_LT(mx, 1.f);
  EXPECT_GE(mn, 0.f);
  EXPECT_EQ(mx, 1.f - 0x1p-24f) << "expected to see the largest value";
  // The free-flight distance at the extremes is finite.
  EXPECT_TRUE(std::isfinite(-logf(1.f - mx)));
  EXPECT_EQ(-logf(1.f - 0.f), 0.f);
}

// Mean and variance of U[0,1): z tests (sd of the mean
// sqrt(1/12/n); sd of the sample variance sqrt((1/80 - 1/144)/n)). Also the
// first value of 2^16 pixel streams is uniform (chi-square, 32 bins) and
// uncorrelated with the neighbouring pixel's.
TEST(Rng, UniformMoments)
{
  const double alpha = kAlpha / 4; // 4 checks
  const int n = 1 << 22;
  Rng rng(1u, 2u, 3u);
  double s = 0, s2 = 0;
  for (int i = 0; i < n; ++i)
  {
    const double u = rng.next();
    s += u;
    s2 += u * u;
  }
  const double mean = s / n;
  const double var = s2 / n - mean * mean;
  const double zm = (mean - (0.5 - 0x1p-25)) / std::sqrt(1.0 / 12.0 / n);
  const double zv = (var - 1.0 / 12.0) / std::sqrt((1.0 / 80.0 - 1.0 / 144.0) / n);
  EXPECT_GT(normalTwoSided(zm), alpha) << "mean " << mean;
  EXPECT_GT(normalTwoSided(zv), alpha) << "variance " << var;

  std::vector<double> counts(32, 0.0);
  double sxy = 0, sx = 0;
  float prev = 0.f;
  const int P = 1 << 16;
  for (int p = 0; p < P; ++p)
  {
    const float u = Rng(uint32_t(p), 0u, 5u).next();
    counts[size_t(u * 32)] += 1;
    if (p > 0)
    {
      sxy += (u - 0.5) * (prev - 0.5);
    }
    sx += u;
    prev = u;
  }
  EXPECT_GT(chiSquarePValue(counts, std::vector<double>(32, 1.0 / 32)), alpha);
  // Lag-1 correlation across pixel streams: z = r sqrt(n).
  const double corr = sxy / (P - 1) * 12.0;
  EXPECT_GT(normalTwoSided(corr * std::sqrt(double(P - 1))), alpha) << "correlation " << corr;
  // Same key gives the same stream; another sample index another stream.
  Rng a(9u, 4u, 2u), b(9u, 4u, 2u), c(9u, 5u, 2u);
  const uint32_t x = a.nextU32();
  EXPECT_EQ(x, b.nextU32());
  EXPECT_NE(x, c.nextU32());
}

// ------------------------------------------------------- channel selection

namespace
{
/// Homogeneous channels whose constant value sits halfway between two texels
/// of differing opacity, so the majorant exceeds the extinction and null
/// collisions occur. Returns the extinctions computed independently.
std::vector<double> buildSelectionScene(
  Scene& scene, TestVolume& v, const std::vector<std::array<float, 3>>& opac, int macrocell, float unit)
{
  const int N = int(opac.size());
  v = TestVolume(9, 10, 11, N, 0.25f); // texel coordinate 0.5 with K = 3 over [0,1]
  std::vector<TransferFunctionDesc> tfs;
  std::vector<double> sigma;
  for (int n = 0; n < N; ++n)
  {
    TransferFunctionDesc tf = flatTF(0.f, float(n % 3 == 0), float(n % 3 == 1), float(n % 3 == 2), unit, 3);
    for (int i = 0; i < 3; ++i)
      tf.opacity[size_t(i)] = opac[size_t(n)][size_t(i)];
    tfs.push_back(tf);
    // Extinction (not opacity) is interpolated between texels 0 and 1.
    sigma.push_back(0.5 * (extinctionOf(opac[size_t(n)][0], unit) + extinctionOf(opac[size_t(n)][1], unit)));
  }
  configure(scene, v, tfs, macrocell);
  for (int n = 0; n < N; ++n)
  {
    const float got = lookupTF(scene.view().tables, n, 0.25f).sigma;
    EXPECT_NEAR(got, sigma[size_t(n)], 1e-5 * sigma[size_t(n)] + 1e-7) << "channel " << n << " extinction";
  }
  return sigma;
}

/// Frequencies of the channel hit, over rays that collided, against
/// sigma_n / sum sigma: chi-square at `alpha`. Also the collision fraction
/// against 1 - exp(-sum sigma L) (normal approximation of the
/// Poisson-binomial count, two-sided at `alpha`).
void checkSelection(const Scene& scene, const std::vector<double>& sigma, Tracker tracker, int rays, uint32_t seed,
  double alpha, const std::string& what)
{
  const SceneView& s = scene.view();
  const int N = int(sigma.size());
  double total = 0;
  for (double x : sigma)
    total += x;
  std::vector<double> counts(size_t(N), 0.0);
  std::vector<double> probs(size_t(N), 0.0);
  for (int n = 0; n < N; ++n)
    probs[size_t(n)] = sigma[size_t(n)] / total;
  TestRand r(seed);
  RayCounters c;
  double hits = 0, expHits = 0, varHits = 0;
  for (int i = 0; i < rays; ++i)
  {
    const BoxRay ray = randomBoxRay(s.volume, r);
    Rng rng(uint32_t(i), 0u, seed);
    const Hit h = track(s, tracker, ray, rng, c);
    const double p = -std::expm1(-total * ray.tmax);
    expHits += p;
    varHits += p * (1 - p);
    if (h.found())
    {
      ASSERT_GE(h.channel, 0);
      ASSERT_LT(h.channel, N);
      ASSERT_TRUE(h.t >= 0.f && h.t <= ray.tmax);
      counts[size_t(h.channel)] += 1;
      hits += 1;
    }
  }
  double stat = 0;
  const double p = chiSquarePValue(counts, probs, &stat);
  EXPECT_GT(p, alpha) << what << " (" << toString(tracker) << "): channel frequencies chi-square " << stat;
  const double z = (hits - expHits) / std::sqrt(varHits);
  EXPECT_GT(normalTwoSided(z), alpha) << what << " (" << toString(tracker) << "): " << hits << " collisions, expected "
                                      << expHits;
  EXPECT_GT(c.tentative, c.real) << "null collisions were expected (majorant above the extinction)";
}
} // namespace

TEST(ChannelSelection, ProportionalToExtinction)
{
  Scene scene;
  TestVolume v;
  // Channel 3 has zero opacity: never active, never hit.
  const std::vector<double> sigma = buildSelectionScene(scene, v,
    { { { 0.05f, 0.15f, 0.9f } }, { { 0.3f, 0.1f, 0.f } }, { { 0.02f, 0.02f, 0.02f } }, { { 0.f, 0.f, 0.f } } }, 4,
    1.5f);
  EXPECT_EQ(scene.view().numActive, 3);
  for (Tracker t : { Tracker::OneDDA, Tracker::NDDA })
  {
    checkSelection(scene, sigma, t, 100000, 31, kAlpha / 4, "4 channels"); // 2 trackers x 2 checks
  }
}

// ------------------------------------------------------ slab transmittance

namespace
{
/// Fraction of rays through a homogeneous slab (thickness 24 along z, rays
/// of random obliquity) with no collision against exp(-sigma L): the count
/// of uncollided rays is Poisson-binomial, tested two-sided at `alpha` by its
/// normal approximation (variance sum p(1-p), several hundred at least).
void checkSlab(const std::vector<double>& sigmaWanted, int macrocell, Tracker tracker, uint32_t seed,
  bool nullCollisions, double alpha)
{
  const int N = int(sigmaWanted.size());
  TestVolume v(7, 6, 25, N, nullCollisions ? 0.25f : 0.5f);
  const float unit = 2.f;
  std::vector<TransferFunctionDesc> tfs;
  double total = 0;
  for (int n = 0; n < N; ++n)
  {
    TransferFunctionDesc tf = flatTF(opacityFor(sigmaWanted[size_t(n)], unit), 1, 1, 1, unit, 3);
    if (nullCollisions)
    {
      // Value at texel 0.5: extinction halfway between texels 0 and 1, and a
      // majorant twice the extinction from texel 1.
      tf.opacity[0] = 0.f;
      tf.opacity[1] = opacityFor(2 * sigmaWanted[size_t(n)], unit);
      tf.opacity[2] = 0.f;
    }
    tfs.push_back(tf);
  }
  Scene scene;
  configure(scene, v, tfs, macrocell);
  for (int n = 0; n < N; ++n)
  {
    const double expect = nullCollisions ? 0.5 * extinctionOf(tfs[size_t(n)].opacity[1], unit)
                                         : extinctionOf(tfs[size_t(n)].opacity[0], unit);
    EXPECT_NEAR(lookupTF(scene.view().tables, n, nullCollisions ? 0.25f : 0.5f).sigma, expect, 1e-5 * expect);
    total += expect;
  }
  const SceneView& s = scene.view();
  TestRand r(seed);
  RayCounters c;
  const int rays = 20000;
  double through = 0, expected = 0, var = 0;
  for (int i = 0; i < rays; ++i)
  {
    const BoxRay ray = randomBoxRay(s.volume, r);
    Rng rng(uint32_t(i), 1u, seed);
    const Hit h = track(s, tracker, ray, rng, c);
    const double p = std::exp(-total * ray.tmax);
    expected += p;
    var += p * (1 - p);
    through += h.found() ? 0 : 1;
  }
  const double z = (through - expected) / std::sqrt(var);
  EXPECT_GT(normalTwoSided(z), alpha) << toString(tracker) << ", " << N << " channel(s), total sigma " << total
                                      << ", macrocell " << macrocell << (nullCollisions ? ", null collisions" : "")
                                      << ": " << through << " rays passed, expected " << expected << " (z = " << z
                                      << ")";
}
} // namespace

TEST(SlabTransmittance, OneChannel)
{
  uint32_t seed = 100;
  for (Tracker t : { Tracker::OneDDA, Tracker::NDDA })
    for (double sigma : { 0.0125, 0.0625, 0.17 })
      for (int mc : { 1, 3, 8, 32 })
        checkSlab({ sigma }, mc, t, ++seed, false, kAlpha / 24); // 24 checks
}

TEST(SlabTransmittance, NullCollisionsAndSeveralChannels)
{
  uint32_t seed = 200;
  for (Tracker t : { Tracker::OneDDA, Tracker::NDDA })
    for (int mc : { 2, 5, 16 })
    {
      checkSlab({ 0.05 }, mc, t, ++seed, true, kAlpha / 18); // 18 checks
      checkSlab({ 0.01, 0.03, 0.02 }, mc, t, ++seed, false, kAlpha / 18);
      checkSlab({ 0.01, 0.04 }, mc, t, ++seed, true, kAlpha / 18);
    }
}
