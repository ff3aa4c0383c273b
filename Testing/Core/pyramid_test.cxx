// SPDX-License-Identifier: BSD-3-Clause
// Pre-classified extinction channels and extinction-based pyramids
// (Documentation/user-guide/levels-of-detail.md; Kraus and Buerger,
// "Interpolating and Downsampling RGBA Volume Data", Sections 3.3 and 4):
// extinction-weighted interpolation, analytic
// transmittance through classified data (Monte Carlo and ray marcher), the
// paper's 8-voxel and one-voxel-wall examples, the filters, agreement with
// scalar + transfer-function rendering, Monte Carlo against the ray marcher,
// majorants, and bad input.
//
// Significance: SlabTransmittanceMonteCarlo makes 2 binomial checks at
// kAlpha / 2; MonteCarloMatchesRayMarch 2 modes x 4 components x 4 statistics
// = 32 checks at kAlpha / 32 (Bonferroni). Seeds are fixed.
#include "TestUtil.h"

#include "mcvol/ray/Acceleration.h"
#include "mcvol/DeviceRenderer.h"
#include "mcvol/Pyramid.h"
#include "mcvol/RayMarcher.h"

#include <atomic>
#ifdef _OPENMP
#include <omp.h>
#endif
#include <cstdio>
#include <functional>
#include <limits>
#include <stdexcept>

using namespace mcvol;
using namespace mcvol::test;

namespace
{
constexpr double kAlpha = 1e-3;

/// A pre-classified volume owned by the test: 4 floats per voxel.
struct ClassifiedData
{
  int dims[3] = { 0, 0, 0 };
  std::vector<float> v;

  ClassifiedData(int nx, int ny, int nz)
  {
    this->dims[0] = nx;
    this->dims[1] = ny;
    this->dims[2] = nz;
    this->v.assign(size_t(nx) * size_t(ny) * size_t(nz) * 4, 0.f);
  }
  size_t index(int i, int j, int k) const
  {
    return (size_t(k) * size_t(this->dims[1]) + size_t(j)) * size_t(this->dims[0]) + size_t(i);
  }
  /// Sets voxel (i, j, k) to extinction sigma and colour c.
  void set(int i, int j, int k, float sigma, float r, float g, float b)
  {
    float* x = this->v.data() + this->index(i, j, k) * 4;
    x[0] = sigma;
    x[1] = sigma * r;
    x[2] = sigma * g;
    x[3] = sigma * b;
  }
  ChannelSource source() const
  {
    ChannelSource s;
    s.data = this->v.data();
    s.type = ScalarType::Float32;
    s.stride = 4;
    s.format = ChannelFormat::Extinction;
    return s;
  }
  ClassifiedVolumeView view() const
  {
    ClassifiedVolumeView w;
    w.voxels = this->v.data();
    std::copy(this->dims, this->dims + 3, w.dims);
    return w;
  }
};

void setClassified(Scene& scene, const int dims[3], const std::vector<ChannelSource>& src, int macrocell = 4,
  BlendMode mode = BlendMode::Density)
{
  scene.setVolume(dims, int(src.size()), src.data());
  scene.setMacrocellSize(macrocell);
  scene.setBlendMode(mode);
  scene.update();
}

std::vector<float> march(const Scene& scene, const Camera& cam, const MarchSettings& ms)
{
  RayMarcher r;
  Accumulator acc;
  r.render(scene, cam, ms, nullptr, acc);
  return std::vector<float>(acc.rgba(), acc.rgba() + size_t(cam.width) * cam.height * 4);
}

double maxAbsDiff(const std::vector<float>& a, const std::vector<float>& b)
{
  double m = 0;
  for (size_t i = 0; i < a.size(); ++i)
  {
    m = std::max(m, std::fabs(double(a[i]) - double(b[i])));
  }
  return m;
}

/**
 * Channel 0's sigma at `count` random points of the scene's box is finite,
 * not negative and at most its macrocell's majorant; `extra(p, sigma)`, if
 * given, checks each sample further. The first failure is returned.
 */
::testing::AssertionResult majorantsBoundChannel0(const Scene& scene, TestRand& r, int count,
  const std::function<::testing::AssertionResult(Vec3f, float)>& extra = nullptr)
{
  const SceneView& s = scene.view();
  const GridView& g = s.grid;
  const int N = s.volume.numChannels;
  for (float m : scene.majorants())
  {
    if (!(std::isfinite(m) && m >= 0.f))
    {
      return ::testing::AssertionFailure() << "majorant " << m;
    }
  }
  for (int i = 0; i < count; ++i)
  {
    Vec3f p;
    for (int a = 0; a < 3; ++a)
    {
      p[a] = float(r.uniform(s.volume.boxLo[a], s.volume.boxHi[a]));
    }
    const float sigma = channelOptics(s, 0, p).sigma;
    int cell[3];
    for (int a = 0; a < 3; ++a)
    {
      cell[a] = clampi(int((p[a] - g.lo[a]) * g.invCellSize[a]), 0, g.dims[a] - 1);
    }
    const size_t c = size_t(cell[0] + g.dims[0] * (cell[1] + g.dims[1] * cell[2]));
    if (!(std::isfinite(sigma) && sigma >= 0.f && sigma <= g.majorants[c * size_t(N)]))
    {
      return ::testing::AssertionFailure() << "sigma " << sigma << " against majorant " << g.majorants[c * size_t(N)]
                                           << " at (" << p.x << ", " << p.y << ", " << p.z << ")";
    }
    if (extra)
    {
      const ::testing::AssertionResult more = extra(p, sigma);
      if (!more)
      {
        return more;
      }
    }
  }
  return ::testing::AssertionSuccess();
}

/// Random transfer function: K texels, opacities in [0, 0.6], colours in [0, 1].
TransferFunctionDesc randomTF(TestRand& r, int K, float unit)
{
  TransferFunctionDesc tf = flatTF(0.f, 0, 0, 0, unit, K, 0.f, 1.f);
  for (int i = 0; i < K; ++i)
  {
    tf.opacity[size_t(i)] = float(r.uniform(0.0, 0.6));
    for (int c = 0; c < 3; ++c)
    {
      tf.rgb[size_t(i) * 3 + size_t(c)] = float(r.uniform());
    }
  }
  return tf;
}

/// Extinction linear in the scalar over [0, 1] (sigma = tau s), constant colour.
TransferFunctionDesc linearExtinctionTF(double tau, float r, float g, float b, int K = 1025)
{
  TransferFunctionDesc tf = flatTF(0.f, r, g, b, 1.f, K, 0.f, 1.f);
  for (int i = 0; i < K; ++i)
  {
    tf.opacity[size_t(i)] = float(-std::expm1(-tau * double(i) / double(K - 1)));
  }
  return tf;
}

/// Smooth random field in [0, 1] (a few sines), for scalar channels.
std::vector<float> smoothField(const int d[3], TestRand& r)
{
  const double f[3] = { r.uniform(0.2, 0.6), r.uniform(0.2, 0.6), r.uniform(0.2, 0.6) };
  const double ph[3] = { r.uniform(0, 6), r.uniform(0, 6), r.uniform(0, 6) };
  std::vector<float> out(size_t(d[0]) * size_t(d[1]) * size_t(d[2]));
  for (int k = 0; k < d[2]; ++k)
    for (int j = 0; j < d[1]; ++j)
      for (int i = 0; i < d[0]; ++i)
      {
        const double s = std::sin(f[0] * i + ph[0]) * std::sin(f[1] * j + ph[1]) * std::sin(f[2] * k + ph[2]);
        out[(size_t(k) * size_t(d[1]) + size_t(j)) * size_t(d[0]) + size_t(i)] = float(0.5 + 0.5 * s);
      }
  return out;
}

ChannelSource scalarSource(const std::vector<float>& data)
{
  ChannelSource s;
  s.data = data.data();
  s.type = ScalarType::Float32;
  s.stride = 1;
  return s;
}

/// Camera along -z over world x, y in [x0, x1] x [y0, y1] of a grid with the
/// given spacing and origin.
Camera gridCameraAlongZ(int W, int H, double x0, double x1, double y0, double y1, double zStart, double length,
  const double spacing[3], const double origin[3])
{
  Camera c = orthoAlongZ(W, H, x0, x1, y0, y1, zStart, length);
  setWorldToIndex(c, spacing, origin);
  return c;
}

/// The opacity along a ray perpendicular to a wall of a level through the
/// ray marcher (extinction model), and the voxel sum of sigma * spacing
/// along the column through the middle.
struct WallOpacity
{
  double marched = 0;
  double opticalDepth = 0;
};

WallOpacity wallOpacity(const PyramidLevel& L)
{
  WallOpacity w;
  Scene scene;
  const ChannelSource src = L.source();
  setClassified(scene, L.dims, { src }, 2);
  double cx[2];
  for (int a = 0; a < 2; ++a)
  {
    cx[a] = L.origin[a] + L.spacing[a] * 0.5 * double(L.dims[a] - 1);
  }
  const double top = L.origin[2] + L.spacing[2] * double(L.dims[2]) + 5.0;
  const Camera cam =
    gridCameraAlongZ(2, 2, cx[0] - 0.1, cx[0] + 0.1, cx[1] - 0.1, cx[1] + 0.1, top, top + 10.0, L.spacing, L.origin);
  MarchSettings ms;
  ms.step = 1.0 / 32.0;
  ms.terminateTransmittance = 0.f;
  const std::vector<float> img = march(scene, cam, ms);
  w.marched = img[3];
  const int i = L.dims[0] / 2, j = L.dims[1] / 2;
  for (int k = 0; k < L.dims[2]; ++k)
  {
    const size_t v = (size_t(k) * size_t(L.dims[1]) + size_t(j)) * size_t(L.dims[0]) + size_t(i);
    w.opticalDepth += double(L.voxels[v * 4]) * L.spacing[2];
  }
  return w;
}
} // namespace

// ------------------------------------------------------------- sampling

// Eq. 18-23: sigma and sigma*colour are interpolated, the colour is their
// ratio (not the average of the colours, nor opacity-weighted). NaN blanks
// the channel where the voxel is read; negative sigma is clamped to 0; an
// infinite sigma is clamped to the render's limit.
TEST(Classified, SamplingIsExtinctionWeighted)
{
  ClassifiedData d(2, 1, 1);
  d.set(0, 0, 0, 1.f, 1.f, 0.f, 0.f); // red, sigma 1
  d.set(1, 0, 0, 3.f, 0.f, 0.f, 1.f); // blue, sigma 3
  Scene scene;
  const ChannelSource src = d.source();
  setClassified(scene, d.dims, { src }, 1);
  const SceneView& s = scene.view();
  const TFSample mid = channelOptics(s, 0, Vec3f(0.5f, 0.f, 0.f));
  EXPECT_NEAR(mid.sigma, 2.0, 1e-6);
  EXPECT_NEAR(mid.rgb.x, 0.25, 1e-6); // (0.5 * 1) / 2
  EXPECT_NEAR(mid.rgb.y, 0.0, 1e-6);
  EXPECT_NEAR(mid.rgb.z, 0.75, 1e-6); // (0.5 * 3) / 2
  const TFSample q = channelOptics(s, 0, Vec3f(0.25f, 0.f, 0.f));
  EXPECT_NEAR(q.sigma, 1.5, 1e-6);
  EXPECT_NEAR(q.rgb.x, 0.75 / 1.5, 1e-6);
  EXPECT_NEAR(q.rgb.z, 0.75 / 1.5, 1e-6);
  // Nearest: a voxel's own values.
  scene.setNearestInterpolation(true);
  scene.update();
  const TFSample n1 = channelOptics(scene.view(), 0, Vec3f(0.7f, 0.f, 0.f));
  EXPECT_FLOAT_EQ(n1.sigma, 3.f);
  EXPECT_FLOAT_EQ(n1.rgb.z, 1.f);
  scene.setNearestInterpolation(false);

  // NaN in one component of voxel 1: transparent wherever it is read.
  d.v[4 + 2] = std::numeric_limits<float>::quiet_NaN();
  scene.dataModified();
  scene.update();
  EXPECT_EQ(channelOptics(scene.view(), 0, Vec3f(0.5f, 0.f, 0.f)).sigma, 0.f);
  EXPECT_EQ(channelOptics(scene.view(), 0, Vec3f(0.f, 0.f, 0.f)).sigma, 0.f); // footprint reads voxel 1
  // Negative sigma: clamped to 0, its colour ignored.
  d.set(1, 0, 0, -3.f, 0.f, 0.f, 1.f);
  scene.dataModified();
  scene.update();
  const TFSample neg = channelOptics(scene.view(), 0, Vec3f(0.5f, 0.f, 0.f));
  EXPECT_NEAR(neg.sigma, 0.5, 1e-6);
  EXPECT_NEAR(neg.rgb.x, 1.0, 1e-6);
  EXPECT_NEAR(neg.rgb.z, 0.0, 1e-6);
  // Infinite sigma: finite, clamped by the render's extinction limit.
  d.v[4] = std::numeric_limits<float>::infinity();
  d.v[5] = d.v[6] = d.v[7] = std::numeric_limits<float>::infinity();
  scene.dataModified();
  scene.update();
  SceneView lim = scene.view();
  lim.sigmaLimit = 100.f;
  const TFSample inf = channelOptics(lim, 0, Vec3f(0.5f, 0.f, 0.f));
  EXPECT_TRUE(std::isfinite(inf.sigma));
  EXPECT_EQ(inf.sigma, 100.f);
  EXPECT_TRUE(std::isfinite(inf.rgb.x) && inf.rgb.x <= 1.f && inf.rgb.z <= 1.f);
  const float maj = scene.majorants()[0];
  EXPECT_TRUE(std::isfinite(maj) && maj >= kMaxClassifiedSigma);
}

/// sigma(z) = a + b z over a 7 x 6 x 25 grid of spacing 1, colour (0.2, 0.5, 0.9).
ClassifiedData rampVolume(double a, double b)
{
  ClassifiedData d(7, 6, 25);
  for (int k = 0; k < 25; ++k)
    for (int j = 0; j < 6; ++j)
      for (int i = 0; i < 7; ++i)
        d.set(i, j, k, float(a + b * k), 0.2f, 0.5f, 0.9f);
  return d;
}

// Woodcock tracking (both trackers) through a classified ramp, trilinear
// (exact for a linear field): the fraction of rays that pass matches
// exp(-integral of sigma) along each random ray.
TEST(Classified, SlabTransmittanceMonteCarlo)
{
  const double a = 0.01, b = 0.004;
  const ClassifiedData d = rampVolume(a, b);
  Scene scene;
  const ChannelSource src = d.source();
  setClassified(scene, d.dims, { src }, 5);
  const SceneView& s = scene.view();
  uint32_t seed = 900;
  for (Tracker tracker : { Tracker::OneDDA, Tracker::NDDA })
  {
    TestRand r(++seed);
    RayCounters c;
    const int rays = 20000;
    double through = 0, expected = 0, var = 0;
    for (int i = 0; i < rays; ++i)
    {
      const BoxRay ray = randomBoxRay(s.volume, r);
      Rng rng(uint32_t(i), 1u, seed);
      const Hit h = trackDensity(s, tracker, ray.o, ray.d, ray.tmax, rng, c);
      const double z0 = ray.o.z, z1 = ray.o.z + ray.d.z * ray.tmax;
      const double tau = ray.tmax * (a + b * 0.5 * (z0 + z1));
      const double p = std::exp(-tau);
      expected += p;
      var += p * (1 - p);
      through += h.found() ? 0 : 1;
    }
    const double z = (through - expected) / std::sqrt(var);
    EXPECT_GT(normalTwoSided(z), kAlpha / 2)
      << toString(tracker) << ": " << through << " rays passed, expected " << expected << " (z = " << z << ")";
  }
}

// The ray marcher (extinction model) through the same ramp along z: the
// midpoint rule integrates a linear extinction exactly, so alpha is
// 1 - exp(-(a L + b L^2 / 2)) and the colour c alpha, for each step dividing L.
TEST(Classified, RayMarchRampIsAnalytic)
{
  const double a = 0.01, b = 0.004;
  const ClassifiedData d = rampVolume(a, b);
  Scene scene;
  const ChannelSource src = d.source();
  setClassified(scene, d.dims, { src }, 4);
  const double L = 24.0;
  const double expected = -std::expm1(-(a * L + 0.5 * b * L * L));
  const Camera cam = orthoAlongZ(4, 4, 2, 4, 2, 3, 30, 40);
  for (double step : { 1.0, 0.5, 0.125, 3.0 })
  {
    MarchSettings ms;
    ms.step = step;
    ms.terminateTransmittance = 0.f;
    const std::vector<float> img = march(scene, cam, ms);
    for (size_t p = 0; p < img.size() / 4; ++p)
    {
      ASSERT_NEAR(img[4 * p + 3], expected, 2e-6) << "step " << step;
      ASSERT_NEAR(img[4 * p + 0], 0.2 * expected, 2e-6);
      ASSERT_NEAR(img[4 * p + 1], 0.5 * expected, 2e-6);
      ASSERT_NEAR(img[4 * p + 2], 0.9 * expected, 2e-6);
    }
  }
}

// ------------------------------------------------------------- pyramids

// Section 4.1, Figures 2 and 3: 2x2x2 voxels, four of tau = 4 and four of 0.
// Extinction averaging gives tau' = 2, i.e. opacity 1 - exp(-2 x 2) = 0.98
// for the coarse voxel's size d' = 2, the same as through one opaque and one
// transparent finer voxel (Eq. 25). Averaging the opacities (0.98 and 0 for
// d = 1) gives 0.49, and 1 - (1 - 0.49)^2 = 0.74 after the opacity
// correction to d' = 2: opacity is lost.
TEST(Pyramid, PaperEightVoxelExample)
{
  ClassifiedData d(2, 2, 2);
  for (int k = 0; k < 2; ++k)
    for (int j = 0; j < 2; ++j)
      for (int i = 0; i < 2; ++i)
        d.set(i, j, k, k == 0 ? 4.f : 0.f, 1.f, 1.f, 1.f);
  for (DownsampleFilter f : { DownsampleFilter::Box2, DownsampleFilter::Box4, DownsampleFilter::BSpline })
  {
    // With 2 voxels per axis every filter (clamped) averages them equally.
    const PyramidLevel ext = downsampleExtinction(d.view(), f);
    ASSERT_EQ(ext.numVoxels(), 1u);
    EXPECT_NEAR(ext.voxels[0], 2.0, 1e-6) << toString(f);
    EXPECT_NEAR(ext.voxels[1] / ext.voxels[0], 1.0, 1e-6); // colour stays white
    const double alphaExt = -std::expm1(-double(ext.voxels[0]) * 2.0);
    EXPECT_NEAR(alphaExt, 0.98, 0.005);
    EXPECT_NEAR(alphaExt, -std::expm1(-4.0 * 1.0) /* one opaque + one clear fine voxel */, 1e-6);

    const PyramidLevel opa = downsampleOpacity(d.view(), 1.0, f);
    ASSERT_EQ(opa.numVoxels(), 1u);
    const double avg = -std::expm1(-double(opa.voxels[0]) * 1.0); // averaged opacity for d = 1
    EXPECT_NEAR(avg, 0.5 * -std::expm1(-4.0), 1e-6);
    EXPECT_NEAR(avg, 0.49, 0.005);
    const double alphaOpa = -std::expm1(-double(opa.voxels[0]) * 2.0); // for d' = 2
    EXPECT_NEAR(alphaOpa, 0.74, 0.005) << toString(f);
    EXPECT_NEAR(alphaOpa, 1.0 - (1.0 - avg) * (1.0 - avg), 1e-6);
    EXPECT_NEAR(opa.voxels[1] / opa.voxels[0], 1.0, 1e-6);
    EXPECT_LT(alphaOpa, alphaExt - 0.2);
  }
}

// Section 3.6 / 4.1: a one-voxel-thick wall (tau = 4) keeps its opacity at
// levels 1 and 2 with extinction downsampling, for every filter: the marched
// opacity through the level is within 2e-3 of 1 - exp(-4) (the march's
// step is 1/32; the discrete optical depth is 4 to float rounding). With
// opacity averaging the same wall loses opacity: below 0.80 at level 1 and
// 0.70 at level 2 (about 0.74 and 0.60 with the 2-tap box; the values are
// printed).
TEST(Pyramid, OneVoxelWallKeepsItsOpacity)
{
  ClassifiedData d(4, 4, 32);
  const double tau = 4.0;
  for (int j = 0; j < 4; ++j)
    for (int i = 0; i < 4; ++i)
      d.set(i, j, 13, float(tau), 1.f, 0.6f, 0.2f);
  const double truth = -std::expm1(-tau);
  {
    PyramidLevel L0;
    std::copy(d.dims, d.dims + 3, L0.dims);
    L0.voxels = d.v;
    const WallOpacity w = wallOpacity(L0);
    EXPECT_NEAR(w.marched, truth, 2e-3) << "level 0";
  }
  for (DownsampleFilter f : { DownsampleFilter::Box2, DownsampleFilter::Box4, DownsampleFilter::BSpline })
  {
    const std::vector<PyramidLevel> ext = buildExtinctionPyramid(d.view(), 2, f);
    const std::vector<PyramidLevel> opa = buildOpacityPyramid(d.view(), 2, 1.0, f);
    ASSERT_EQ(ext.size(), 2u);
    ASSERT_EQ(opa.size(), 2u);
    for (int l = 0; l < 2; ++l)
    {
      const WallOpacity e = wallOpacity(ext[size_t(l)]);
      const WallOpacity o = wallOpacity(opa[size_t(l)]);
      std::printf("wall tau 4, %s level %d: extinction-downsampled opacity %.4f (depth %.4f), opacity-averaged "
                  "%.4f (depth %.4f), truth %.4f\n",
        toString(f), l + 1, e.marched, e.opticalDepth, o.marched, o.opticalDepth, truth);
      EXPECT_NEAR(e.opticalDepth, tau, 1e-5) << toString(f) << " level " << l + 1;
      EXPECT_NEAR(e.marched, truth, 2e-3) << toString(f) << " level " << l + 1;
      EXPECT_LT(o.marched, l == 0 ? 0.80 : 0.70) << toString(f) << " level " << l + 1;
      EXPECT_LT(o.marched, truth - 0.15);
      // The colour survives too: emission / alpha is the wall's colour.
      // (Checked on the voxel with the most extinction.)
      const PyramidLevel& L = ext[size_t(l)];
      size_t best = 0;
      for (size_t v = 0; v < L.numVoxels(); ++v)
      {
        best = L.voxels[v * 4] > L.voxels[best * 4] ? v : best;
      }
      EXPECT_NEAR(L.voxels[best * 4 + 2] / L.voxels[best * 4], 0.6, 1e-5);
    }
  }
}

// The filters: weights as published, normalised; a constant volume stays
// constant at every level, the boundary included, for odd dims and axes of
// 1; dims halve with ceil, spacing doubles and the origin moves half a finer
// spacing on halved axes only; byte sizes.
TEST(Pyramid, FiltersAndConstantVolumes)
{
  const FilterTaps b2 = filterTaps(DownsampleFilter::Box2);
  const FilterTaps b4 = filterTaps(DownsampleFilter::Box4);
  const FilterTaps bs = filterTaps(DownsampleFilter::BSpline);
  EXPECT_EQ(b2.count, 2);
  EXPECT_EQ(b4.count, 4);
  EXPECT_EQ(bs.count, 4);
  EXPECT_DOUBLE_EQ(b2.w[0], 0.5);
  EXPECT_DOUBLE_EQ(b4.w[0], 0.25);
  EXPECT_DOUBLE_EQ(b4.w[1], 0.25);
  EXPECT_DOUBLE_EQ(bs.w[0], 13.0 / 64.0);
  EXPECT_DOUBLE_EQ(bs.w[1], 19.0 / 64.0);
  EXPECT_DOUBLE_EQ(bs.w[2], 19.0 / 64.0);
  EXPECT_DOUBLE_EQ(bs.w[3], 13.0 / 64.0);
  for (const FilterTaps& t : { b2, b4, bs })
  {
    double sum = 0;
    for (int k = 0; k < t.count; ++k)
    {
      sum += t.w[k];
      EXPECT_DOUBLE_EQ(t.w[k], t.w[t.count - 1 - k]); // symmetric
    }
    EXPECT_DOUBLE_EQ(sum, 1.0);
  }
  const int shapes[][3] = { { 7, 5, 3 }, { 1, 1, 1 }, { 1, 6, 1 }, { 8, 3, 2 }, { 2, 1, 9 }, { 33, 1, 17 } };
  for (const auto& sh : shapes)
  {
    ClassifiedData d(sh[0], sh[1], sh[2]);
    for (int k = 0; k < sh[2]; ++k)
      for (int j = 0; j < sh[1]; ++j)
        for (int i = 0; i < sh[0]; ++i)
          d.set(i, j, k, 0.7f, 0.1f, 0.2f, 0.3f);
    ClassifiedVolumeView v = d.view();
    v.spacing[0] = 0.5;
    v.spacing[1] = 2.0;
    v.spacing[2] = 1.25;
    v.origin[0] = -3.0;
    v.origin[1] = 10.0;
    v.origin[2] = 0.5;
    const int levels = maxPyramidLevels(sh);
    for (DownsampleFilter f : { DownsampleFilter::Box2, DownsampleFilter::Box4, DownsampleFilter::BSpline })
    {
      for (bool opacity : { false, true })
      {
        const std::vector<PyramidLevel> P =
          opacity ? buildOpacityPyramid(v, levels, 0.8, f) : buildExtinctionPyramid(v, levels, f);
        ASSERT_EQ(int(P.size()), levels);
        int dims[3] = { sh[0], sh[1], sh[2] };
        double spacing[3] = { v.spacing[0], v.spacing[1], v.spacing[2] };
        double origin[3] = { v.origin[0], v.origin[1], v.origin[2] };
        for (const PyramidLevel& L : P)
        {
          const std::string what = std::string(toString(f)) + (opacity ? " opacity" : " extinction") + " level " +
            std::to_string(L.level) + " of " + std::to_string(sh[0]) + "x" + std::to_string(sh[1]) + "x" +
            std::to_string(sh[2]);
          for (int a = 0; a < 3; ++a)
          {
            if (dims[a] > 1)
            {
              origin[a] += 0.5 * spacing[a];
              spacing[a] *= 2.0;
              dims[a] = (dims[a] + 1) / 2;
            }
            EXPECT_EQ(L.dims[a], dims[a]) << what;
            EXPECT_DOUBLE_EQ(L.spacing[a], spacing[a]) << what;
            EXPECT_DOUBLE_EQ(L.origin[a], origin[a]) << what;
          }
          ASSERT_EQ(L.voxels.size(), L.numVoxels() * 4) << what;
          EXPECT_EQ(L.bytes(), L.numVoxels() * 4 * sizeof(float)) << what;
          for (size_t i = 0; i < L.numVoxels(); ++i)
          {
            // The opacity baseline keeps a constant volume constant too
            // (through exp and log: a little more rounding).
            const double tol = opacity ? 1e-5 : 1e-6;
            ASSERT_NEAR(L.voxels[i * 4 + 0], 0.7, tol * 0.7) << what << " voxel " << i;
            ASSERT_NEAR(L.voxels[i * 4 + 1] / L.voxels[i * 4], 0.1, 1e-6) << what;
            ASSERT_NEAR(L.voxels[i * 4 + 2] / L.voxels[i * 4], 0.2, 1e-6) << what;
            ASSERT_NEAR(L.voxels[i * 4 + 3] / L.voxels[i * 4], 0.3, 1e-6) << what;
          }
        }
        if (levels > 0)
        {
          EXPECT_EQ(P.back().numVoxels(), 1u);
        }
      }
    }
  }
}

// Filter taps and clamping by hand on a 5-voxel ramp sigma = 1..5 (odd: the
// last coarse voxel reads past the end, clamped to voxel 4).
TEST(Pyramid, OddDimsByHand)
{
  ClassifiedData d(5, 1, 1);
  for (int i = 0; i < 5; ++i)
  {
    d.set(i, 0, 0, float(i + 1), 0.5f, 0.5f, 0.5f);
  }
  const std::vector<double> box2 = { 1.5, 3.5, 5.0 };
  const std::vector<double> box4 = { (1 + 1 + 2 + 3) / 4.0, (2 + 3 + 4 + 5) / 4.0, (4 + 5 + 5 + 5) / 4.0 };
  const std::vector<double> bspl = { (13 * 1 + 19 * 1 + 19 * 2 + 13 * 3) / 64.0,
    (13 * 2 + 19 * 3 + 19 * 4 + 13 * 5) / 64.0, (13 * 4 + 19 * 5 + 19 * 5 + 13 * 5) / 64.0 };
  const std::pair<DownsampleFilter, const std::vector<double>*> cases[] = { { DownsampleFilter::Box2, &box2 },
    { DownsampleFilter::Box4, &box4 }, { DownsampleFilter::BSpline, &bspl } };
  for (const auto& c : cases)
  {
    const PyramidLevel L = downsampleExtinction(d.view(), c.first);
    ASSERT_EQ(L.dims[0], 3);
    ASSERT_EQ(L.dims[1], 1);
    ASSERT_EQ(L.dims[2], 1);
    for (int i = 0; i < 3; ++i)
    {
      EXPECT_NEAR(L.voxels[size_t(i) * 4], (*c.second)[size_t(i)], 1e-6) << toString(c.first) << " voxel " << i;
      EXPECT_NEAR(L.voxels[size_t(i) * 4 + 1], 0.5 * (*c.second)[size_t(i)], 1e-6);
    }
  }
}

// ------------------------------------------- classified vs scalar + TF

// When the classification is exact the two renderings agree: nearest
// interpolation with any transfer function (every voxel is its own sample),
// and trilinear interpolation with extinction linear in the scalar and a
// constant colour. Ray marcher, both compositing models, blend modes, two
// channels, lit and unlit; and the density blend of two scalar channels
// equals one channel classified by accumulation.
TEST(Classified, EqualsScalarPlusTransferFunction)
{
  TestRand r(77);
  const int dims[3] = { 12, 10, 9 };
  const std::vector<float> s0 = smoothField(dims, r);
  const std::vector<float> s1 = smoothField(dims, r);
  const size_t V = s0.size();
  for (bool nearest : { true, false })
  {
    std::vector<TransferFunctionDesc> tfs;
    if (nearest)
    {
      tfs = { randomTF(r, 64, 1.5f), randomTF(r, 48, 1.5f) };
      tfs[1].opacity.resize(64, 0.3f); // same size as channel 0's table
      tfs[1].rgb.resize(64 * 3, 0.5f);
    }
    else
    {
      tfs = { linearExtinctionTF(0.4, 0.9f, 0.3f, 0.1f), linearExtinctionTF(0.25, 0.1f, 0.4f, 0.8f) };
    }
    Scene scalar;
    const std::vector<ChannelSource> ss = { scalarSource(s0), scalarSource(s1) };
    scalar.setVolume(dims, 2, ss.data());
    scalar.setTransferFunction(0, tfs[0]);
    scalar.setTransferFunction(1, tfs[1]);
    scalar.setMacrocellSize(3);
    scalar.setNearestInterpolation(nearest);
    std::vector<float> c0(V * 4), c1(V * 4), sum(V * 4);
    classifyScalars(ss[0], dims, tfs[0], c0.data());
    classifyScalars(ss[1], dims, tfs[1], c1.data());
    classifyScalars(ss[0], dims, tfs[0], sum.data());
    classifyScalars(ss[1], dims, tfs[1], sum.data(), 4, true);
    Scene classified;
    std::vector<ChannelSource> cs(2);
    cs[0].data = c0.data();
    cs[1].data = c1.data();
    for (ChannelSource& c : cs)
    {
      c.stride = 4;
      c.format = ChannelFormat::Extinction;
    }
    classified.setVolume(dims, 2, cs.data());
    classified.setMacrocellSize(3);
    classified.setNearestInterpolation(nearest);
    Scene one;
    ChannelSource os = cs[0];
    os.data = sum.data();
    one.setVolume(dims, 1, &os);
    one.setMacrocellSize(5);
    one.setNearestInterpolation(nearest);
    const double sp[3] = { 1, 1, 1 };
    const Camera cam = orbitCamera(dims, sp, 20, 16, 35, 25);
    for (bool lit : { false, true })
    {
      LightingDesc ld;
      if (lit)
      {
        LightDesc l;
        l.vector[0] = 0.3;
        l.vector[1] = 0.5;
        l.vector[2] = 0.8;
        ld.lights.push_back(l);
        ld.albedo = { 0.7f, 0.4f };
      }
      scalar.setLighting(ld);
      classified.setLighting(ld);
      for (BlendMode mode : { BlendMode::Density, BlendMode::Max, BlendMode::Mix, BlendMode::Composite })
      {
        if (lit && mode == BlendMode::Composite)
        {
          continue; // not supported lit
        }
        for (Compositing model : { Compositing::Extinction, Compositing::Opacity })
        {
          if (model == Compositing::Opacity && (lit || !nearest))
          {
            continue; // opacity compositing interpolates voxel opacities: exact only for nearest
          }
          scalar.setBlendMode(mode);
          classified.setBlendMode(mode);
          scalar.update();
          classified.update();
          MarchSettings ms;
          ms.step = 0.5;
          ms.compositing = model;
          const std::vector<float> a = march(scalar, cam, ms);
          const std::vector<float> b = march(classified, cam, ms);
          double peak = 0;
          for (float x : a)
            peak = std::max(peak, double(x));
          EXPECT_GT(peak, 0.2) << "the image must show something";
          EXPECT_LT(maxAbsDiff(a, b), 2e-5) << (nearest ? "nearest " : "trilinear ") << toString(mode) << " model "
                                            << int(model) << (lit ? " lit" : "");
          if (mode == BlendMode::Density && !lit)
          {
            one.update();
            const std::vector<float> c = march(one, cam, ms);
            if (model == Compositing::Extinction)
            {
              EXPECT_LT(maxAbsDiff(a, c), 2e-5) << "density blend of 2 channels vs one accumulated channel";
            }
          }
        }
      }
    }
  }
}

// Monte Carlo converges to the ray marcher (extinction model, fine step) on
// classified channels, density and max blends.
TEST(Classified, MonteCarloMatchesRayMarch)
{
  TestRand r(5);
  const int dims[3] = { 14, 12, 10 };
  const std::vector<float> s0 = smoothField(dims, r);
  const std::vector<float> s1 = smoothField(dims, r);
  std::vector<float> c0(s0.size() * 4), c1(s1.size() * 4);
  classifyScalars(scalarSource(s0), dims, randomTF(r, 32, 4.f), c0.data());
  classifyScalars(scalarSource(s1), dims, randomTF(r, 32, 4.f), c1.data());
  std::vector<ChannelSource> cs(2);
  cs[0].data = c0.data();
  cs[1].data = c1.data();
  for (ChannelSource& c : cs)
  {
    c.stride = 4;
    c.format = ChannelFormat::Extinction;
  }
  const double sp[3] = { 1, 1, 1 };
  const Camera cam = orbitCamera(dims, sp, 16, 16, 30, 20);
  const int N = 1024;
  const double alpha = kAlpha / 32;
  for (BlendMode mode : { BlendMode::Density, BlendMode::Max })
  {
    Scene scene;
    setClassified(scene, dims, cs, 4, mode);
    MarchSettings ms;
    ms.step = 1.0 / 16.0;
    ms.terminateTransmittance = 0.f;
    const std::vector<float> ref = march(scene, cam, ms);
    CPURenderer mc;
    Accumulator acc;
    RenderSettings rs;
    rs.jitterPixels = false;
    rs.samplesPerPixel = N;
    rs.seed = 41;
    mc.render(scene, cam, rs, nullptr, acc);
    std::vector<double> D, V;
    double poolD[4] = { 0, 0, 0, 0 }, poolV[4] = { 0, 0, 0, 0 };
    double peak = 0;
    for (size_t i = 0; i < ref.size(); ++i)
    {
      const double mu = std::min(1.0, std::max(0.0, double(ref[i])));
      peak = std::max(peak, mu);
      const double d = double(acc.rgba()[i]) - double(ref[i]);
      const double var = mu * (1 - mu) / N;
      if (N * mu * (1 - mu) >= 100.0)
      {
        D.push_back(d);
        V.push_back(var);
      }
      else
      {
        D.push_back(0.0);
        V.push_back(0.0);
        poolD[i % 4] += d;
        poolV[i % 4] += var;
      }
    }
    EXPECT_GT(peak, 0.3) << "the image must show something";
    const std::string what = std::string("classified ") + toString(mode) + " MC vs ray march";
    expectZeroDifference(D, V, alpha, what);
    for (int c = 0; c < 4; ++c)
    {
      if (poolV[c] > 0)
      {
        const double z = poolD[c] / std::sqrt(poolV[c]);
        EXPECT_GT(normalTwoSided(z), alpha) << what << " component " << c << ": pooled rare pixels z = " << z;
      }
    }
  }
}

// Majorants (max sigma over each macrocell's footprint) bound every sampled
// sigma of a classified channel, with NaN, negative, infinite and huge
// voxels present, trilinear and nearest, several macrocell sizes.
TEST(Classified, MajorantsBoundSampledSigma)
{
  TestRand r(123);
  for (int sc = 0; sc < 12; ++sc)
  {
    const int dims[3] = { r.integer(1, 19), r.integer(1, 13), r.integer(1, 11) };
    ClassifiedData d(dims[0], dims[1], dims[2]);
    for (size_t v = 0; v < d.v.size() / 4; ++v)
    {
      const double u = r.uniform();
      float s = float(r.uniform(0.0, 2.0) * (r.chance(0.2) ? 50.0 : 1.0));
      if (u < 0.03)
        s = std::numeric_limits<float>::quiet_NaN();
      else if (u < 0.06)
        s = -1.f;
      else if (u < 0.07)
        s = std::numeric_limits<float>::infinity();
      else if (u < 0.3)
        s = 0.f;
      d.v[v * 4] = s;
      for (int c = 1; c < 4; ++c)
        d.v[v * 4 + size_t(c)] = float(r.uniform()) * (std::isfinite(s) && s > 0 ? s : 1.f);
    }
    // A second, scalar channel keeps the scene mixed.
    TestVolume tv(dims[0], dims[1], dims[2], 1, 0.5f);
    std::vector<ChannelSource> src = { d.source(), tv.sources()[0] };
    Scene scene;
    scene.setVolume(dims, 2, src.data());
    scene.setTransferFunction(1, flatTF(0.3f, 1, 1, 1));
    scene.setMacrocellSize(r.integer(1, 6));
    const bool nearest = r.chance(0.3);
    scene.setNearestInterpolation(nearest);
    scene.update();
    ASSERT_TRUE(majorantsBoundChannel0(scene, r, 4000)) << "scene " << sc << (nearest ? " nearest" : " trilinear");
  }
}

// ------------------------------------------------------------ bad input

TEST(Classified, BadInputErrors)
{
  ClassifiedData d(4, 4, 4);
  d.set(1, 1, 1, 1.f, 1, 1, 1);
  Scene scene;
  ChannelSource src = d.source();
  // Wrong element type, stride too small, unknown format.
  ChannelSource bad = src;
  bad.type = ScalarType::UInt8;
  EXPECT_THROW(scene.setVolume(d.dims, 1, &bad), std::invalid_argument);
  bad = src;
  bad.stride = 3;
  EXPECT_THROW(scene.setVolume(d.dims, 1, &bad), std::invalid_argument);
  bad = src;
  bad.format = ChannelFormat(7);
  EXPECT_THROW(scene.setVolume(d.dims, 1, &bad), std::invalid_argument);
  bad = src;
  bad.type = ScalarType::Float64;
  bad.offset = 1.0;
  EXPECT_THROW(scene.setVolume(d.dims, 1, &bad), std::invalid_argument);
  // Good: no transfer function needed; a stride above 4 (interleaved) works.
  scene.setVolume(d.dims, 1, &src);
  EXPECT_NO_THROW(scene.update());
  EXPECT_EQ(scene.memory().dataBytes, size_t(64) * 16);
  EXPECT_GT(scene.view().numActive, 0);
  // Importance on a classified channel: refused at setImportance and at update.
  ImportanceDesc imp;
  imp.enabled = true;
  imp.tables = { std::vector<float>(2, 1.f) };
  EXPECT_THROW(scene.setImportance(imp), std::invalid_argument);
  {
    // Set while the channel was scalar, then the channel becomes classified.
    Scene s2;
    TestVolume tv(4, 4, 4, 1, 0.5f);
    const std::vector<ChannelSource> ts = tv.sources();
    s2.setVolume(tv.dims, 1, ts.data());
    s2.setTransferFunction(0, flatTF(0.3f, 1, 1, 1));
    s2.setImportance(imp);
    s2.setVolume(d.dims, 1, &src);
    EXPECT_THROW(s2.update(), std::invalid_argument);
  }
  // A scalar channel beside it still needs its transfer function.
  TestVolume tv(4, 4, 4, 1, 0.5f);
  std::vector<ChannelSource> mixed = { src, tv.sources()[0] };
  Scene s3;
  s3.setVolume(d.dims, 2, mixed.data());
  EXPECT_THROW(s3.update(), std::invalid_argument);
  s3.setTransferFunction(1, flatTF(0.3f, 1, 1, 1));
  EXPECT_NO_THROW(s3.update());

  // Pyramids.
  ClassifiedVolumeView v = d.view();
  EXPECT_NO_THROW(buildExtinctionPyramid(v, 2));
  EXPECT_THROW(buildExtinctionPyramid(v, 3), std::invalid_argument); // 4^3 has 2 levels
  EXPECT_THROW(buildExtinctionPyramid(v, -1), std::invalid_argument);
  ClassifiedVolumeView b = v;
  b.voxels = nullptr;
  EXPECT_THROW(downsampleExtinction(b, DownsampleFilter::Box2), std::invalid_argument);
  b = v;
  b.stride = 2;
  EXPECT_THROW(downsampleExtinction(b, DownsampleFilter::Box2), std::invalid_argument);
  b = v;
  b.dims[1] = 0;
  EXPECT_THROW(downsampleExtinction(b, DownsampleFilter::Box2), std::invalid_argument);
  b = v;
  b.spacing[2] = 0.0;
  EXPECT_THROW(downsampleExtinction(b, DownsampleFilter::Box2), std::invalid_argument);
  EXPECT_THROW(downsampleExtinction(v, DownsampleFilter(9)), std::invalid_argument);
  EXPECT_THROW(downsampleOpacity(v, 0.0, DownsampleFilter::Box2), std::invalid_argument);
  for (float x : { -1.f, std::numeric_limits<float>::quiet_NaN(), std::numeric_limits<float>::infinity() })
  {
    ClassifiedData e = d;
    e.v[8] = x; // sigma of voxel 2
    EXPECT_THROW(downsampleExtinction(e.view(), DownsampleFilter::Box4), std::invalid_argument) << x;
    e = d;
    e.v[9] = x; // a weighted colour
    EXPECT_THROW(downsampleExtinction(e.view(), DownsampleFilter::Box4), std::invalid_argument) << x;
  }
  // Classification.
  std::vector<float> out(64 * 4);
  TransferFunctionDesc tf = flatTF(0.3f, 1, 1, 1);
  EXPECT_THROW(classifyScalars(src, d.dims, tf, out.data()), std::invalid_argument); // already classified
  const ChannelSource ts = tv.sources()[0];
  EXPECT_THROW(classifyScalars(ts, d.dims, tf, nullptr), std::invalid_argument);
  EXPECT_THROW(classifyScalars(ts, d.dims, tf, out.data(), 3), std::invalid_argument);
  tf.opacity.resize(1);
  EXPECT_THROW(classifyScalars(ts, d.dims, tf, out.data()), std::invalid_argument);
}

// ---------------------------------------------------------- streamed levels

// The streamed builder gives exactly the level that buildExtinctionPyramid
// builds from the whole level 0: every filter, every level, odd and
// even extents, a flat axis, with geometry.
TEST(StreamedPyramid, EqualsWholeVolumePyramid)
{
  TestRand r(2024);
  const int shapes[][3] = { { 17, 12, 9 }, { 8, 8, 8 }, { 5, 1, 7 }, { 1, 1, 6 }, { 9, 6, 1 } };
  for (const auto& shape : shapes)
  {
    ClassifiedData d(shape[0], shape[1], shape[2]);
    for (float& x : d.v)
    {
      x = float(r.uniform(0.0, 3.0));
    }
    ClassifiedVolumeView v = d.view();
    const double spacing[3] = { 0.5, 1.25, 2.0 };
    const double origin[3] = { -3.0, 10.0, 0.25 };
    std::copy(spacing, spacing + 3, v.spacing);
    std::copy(origin, origin + 3, v.origin);
    const int most = maxPyramidLevels(d.dims);
    for (DownsampleFilter f : { DownsampleFilter::Box2, DownsampleFilter::Box4, DownsampleFilter::BSpline })
    {
      const std::vector<PyramidLevel> whole = buildExtinctionPyramid(v, most, f);
      for (int level = 1; level <= most; ++level)
      {
        // Slices may come from several threads (one z-range each, in order
        // within it, halo slices read twice): count them atomically.
        std::vector<std::atomic<int>> calls(size_t(d.dims[2]));
        auto slice = [&](int z, float* out)
        {
          ++calls[size_t(z)];
          const size_t n = size_t(d.dims[0]) * size_t(d.dims[1]) * 4;
          std::copy(d.v.begin() + long(size_t(z) * n), d.v.begin() + long(size_t(z + 1) * n), out);
        };
        size_t peak = 0;
        const PyramidLevel s = streamExtinctionLevel(d.dims, spacing, origin, level, f, slice, &peak);
        const PyramidLevel& w = whole[size_t(level - 1)];
        const std::string what = std::string(toString(f)) + " level " + std::to_string(level) + " of " +
          std::to_string(d.dims[0]) + "x" + std::to_string(d.dims[1]) + "x" + std::to_string(d.dims[2]);
        int total = 0;
        for (int z = 0; z < d.dims[2]; ++z)
        {
          EXPECT_GE(calls[size_t(z)].load(), 1) << what << ": slice " << z << " never read";
          total += calls[size_t(z)].load();
        }
        // Halos: a few slices per chunk and stage, never the volume twice.
        EXPECT_LE(total, 2 * d.dims[2] + 16) << what;
        EXPECT_EQ(s.level, level) << what;
        for (int a = 0; a < 3; ++a)
        {
          EXPECT_EQ(s.dims[a], w.dims[a]) << what;
          EXPECT_DOUBLE_EQ(s.spacing[a], w.spacing[a]) << what;
          EXPECT_DOUBLE_EQ(s.origin[a], w.origin[a]) << what;
        }
        int ld[3];
        levelDims(d.dims, level, ld);
        EXPECT_TRUE(ld[0] == w.dims[0] && ld[1] == w.dims[1] && ld[2] == w.dims[2]) << what;
        EXPECT_EQ(levelBytes(d.dims, level, 3), 3 * w.bytes()) << what;
        ASSERT_EQ(s.voxels.size(), w.voxels.size()) << what;
        // The same taps in the same order: bit for bit.
        EXPECT_EQ(maxAbsDiff(s.voxels, w.voxels), 0.0) << what;
        EXPECT_GT(peak, 0u) << what;
      }
    }
  }
}

// Scalar channels classified slice by slice and summed equal the density
// blend classified whole and then downsampled, and the working memory stays
// a small fraction of the full-resolution classified volume that is never
// built.
TEST(StreamedPyramid, ClassifiesWithoutTheFullVolume)
{
  TestRand r(99);
  // Tall, so that a few slices are a small part of the volume; two threads
  // (chunks run at once, each holding its own slices).
#ifdef _OPENMP
  const int threads = omp_get_max_threads();
  omp_set_num_threads(2);
#endif
  const int dims[3] = { 48, 40, 256 };
  const std::vector<float> s0 = smoothField(dims, r);
  const std::vector<float> s1 = smoothField(dims, r);
  const TransferFunctionDesc tf0 = randomTF(r, 64, 2.f);
  const TransferFunctionDesc tf1 = randomTF(r, 32, 0.5f);
  const size_t V = s0.size();
  std::vector<float> sum(V * 4);
  classifyScalars(scalarSource(s0), dims, tf0, sum.data());
  classifyScalars(scalarSource(s1), dims, tf1, sum.data(), 4, true);
  ClassifiedVolumeView v;
  v.voxels = sum.data();
  std::copy(dims, dims + 3, v.dims);
  const ClassifyInput inputs[2] = { { scalarSource(s0), &tf0 }, { scalarSource(s1), &tf1 } };
  const double spacing[3] = { 1, 1, 1 }, origin[3] = { 0, 0, 0 };
  for (int level : { 1, 2, 3 })
  {
    const PyramidLevel whole = buildExtinctionPyramid(v, level, DownsampleFilter::Box4).back();
    size_t peak = 0;
    const PyramidLevel s =
      classifyExtinctionLevel(inputs, 2, dims, spacing, origin, level, DownsampleFilter::Box4, &peak);
    ASSERT_EQ(s.voxels.size(), whole.voxels.size());
    EXPECT_EQ(maxAbsDiff(s.voxels, whole.voxels), 0.0) << "level " << level;
    // Per thread one level-0 slice (30 KiB here) and a few filtered slices
    // per stage: far below the 7.5 MiB classified level 0.
    const size_t full = V * 4 * sizeof(float);
    EXPECT_LT(peak, full / 8) << "level " << level << ": " << peak << " bytes of work against " << full;
    std::printf("level %d: streamed work %zu bytes, full-resolution classified volume %zu bytes\n", level, peak, full);
  }
  // One channel gives its own pre-classified level.
  std::vector<float> c1(V * 4);
  classifyScalars(scalarSource(s1), dims, tf1, c1.data());
  v.voxels = c1.data();
  const PyramidLevel one = classifyExtinctionLevel(inputs + 1, 1, dims, spacing, origin, 1, DownsampleFilter::BSpline);
  EXPECT_EQ(maxAbsDiff(one.voxels, downsampleExtinction(v, DownsampleFilter::BSpline).voxels), 0.0);
#ifdef _OPENMP
  omp_set_num_threads(threads);
#endif
}

TEST(StreamedPyramid, BadInputErrors)
{
  const int dims[3] = { 4, 4, 4 };
  const double spacing[3] = { 1, 1, 1 }, origin[3] = { 0, 0, 0 };
  auto zeros = [](int, float*) {};
  EXPECT_THROW(streamExtinctionLevel(dims, spacing, origin, 0, DownsampleFilter::Box4, zeros), std::invalid_argument);
  EXPECT_THROW(streamExtinctionLevel(dims, spacing, origin, 3, DownsampleFilter::Box4, zeros), std::invalid_argument);
  EXPECT_NO_THROW(streamExtinctionLevel(dims, spacing, origin, 2, DownsampleFilter::Box4, zeros));
  const double badSpacing[3] = { 1, 0, 1 };
  EXPECT_THROW(
    streamExtinctionLevel(dims, badSpacing, origin, 1, DownsampleFilter::Box4, zeros), std::invalid_argument);
  EXPECT_THROW(streamExtinctionLevel(dims, spacing, origin, 1, DownsampleFilter::Box4, nullptr), std::invalid_argument);
  auto negative = [](int z, float* out)
  {
    if (z == 2)
    {
      out[5 * 4] = -1.f;
    }
  };
  EXPECT_THROW(
    streamExtinctionLevel(dims, spacing, origin, 1, DownsampleFilter::Box4, negative), std::invalid_argument);
  auto nan = [](int, float* out) { out[1] = std::numeric_limits<float>::quiet_NaN(); };
  EXPECT_THROW(streamExtinctionLevel(dims, spacing, origin, 1, DownsampleFilter::Box2, nan), std::invalid_argument);
  EXPECT_THROW(
    classifyExtinctionLevel(nullptr, 0, dims, spacing, origin, 1, DownsampleFilter::Box4), std::invalid_argument);
  const ClassifyInput noTable[1] = { { ChannelSource{}, nullptr } };
  EXPECT_THROW(
    classifyExtinctionLevel(noTable, 1, dims, spacing, origin, 1, DownsampleFilter::Box4), std::invalid_argument);
}

// A backend without a device (the CPU) builds levels on the host:
// classifyLevel() on it is the host build itself.
TEST(StreamedPyramid, DefaultRendererClassifyLevel)
{
  std::unique_ptr<Renderer> cpu = Renderer::create(Backend::CPU);
  EXPECT_EQ(cpu->device(), nullptr);
  TestRand r(5);
  const int dims[3] = { 13, 6, 9 };
  const std::vector<float> s0 = smoothField(dims, r), s1 = smoothField(dims, r);
  const TransferFunctionDesc tf0 = randomTF(r, 16, 1.f), tf1 = randomTF(r, 8, 2.f);
  const ClassifyInput inputs[2] = { { scalarSource(s0), &tf0 }, { scalarSource(s1), &tf1 } };
  const double spacing[3] = { 1, 2, 0.5 }, origin[3] = { 1, 0, -1 };
  for (int level : { 1, 2 })
  {
    const PyramidLevel a = classifyLevel(*cpu, inputs, 2, dims, spacing, origin, level, DownsampleFilter::BSpline);
    const PyramidLevel b = classifyExtinctionLevel(inputs, 2, dims, spacing, origin, level, DownsampleFilter::BSpline);
    EXPECT_EQ(a.voxels, b.voxels) << "level " << level;
    for (int ax = 0; ax < 3; ++ax)
    {
      EXPECT_EQ(a.dims[ax], b.dims[ax]);
      EXPECT_EQ(a.spacing[ax], b.spacing[ax]);
      EXPECT_EQ(a.origin[ax], b.origin[ax]);
    }
    // The geometry alone, as the device backends take it.
    const PyramidLevel g = pyramidLevelGeometry(dims, spacing, origin, level);
    EXPECT_TRUE(g.voxels.empty());
    EXPECT_TRUE(g.level == b.level && g.dims[0] == b.dims[0] && g.dims[1] == b.dims[1] && g.dims[2] == b.dims[2]);
    EXPECT_TRUE(g.origin[0] == b.origin[0] && g.spacing[2] == b.spacing[2]);
  }
  EXPECT_THROW(classifyLevel(*cpu, inputs, 2, dims, spacing, origin, 5, DownsampleFilter::Box4), std::invalid_argument);
}

// The automatic level follows L = floor(log2(footprint / min spacing)),
// clamped to [0, levels].
TEST(LevelOfDetail, FootprintRule)
{
  const double spacing[3] = { 2.0, 0.5, 1.0 }; // the finest is 0.5
  EXPECT_EQ(chooseLevelOfDetail(0.0, spacing, 5), 0);
  EXPECT_EQ(chooseLevelOfDetail(0.25, spacing, 5), 0);  // pixel smaller than a voxel
  EXPECT_EQ(chooseLevelOfDetail(0.5, spacing, 5), 0);   // one voxel a pixel
  EXPECT_EQ(chooseLevelOfDetail(0.999, spacing, 5), 0); // just under two voxels
  EXPECT_EQ(chooseLevelOfDetail(1.0, spacing, 5), 1);   // two voxels a pixel: level 1's voxel is the pixel
  EXPECT_EQ(chooseLevelOfDetail(1.99, spacing, 5), 1);
  EXPECT_EQ(chooseLevelOfDetail(2.0, spacing, 5), 2);
  EXPECT_EQ(chooseLevelOfDetail(std::nextafter(4.0, 0.0), spacing, 5), 2);
  EXPECT_EQ(chooseLevelOfDetail(4.0, spacing, 5), 3);
  EXPECT_EQ(chooseLevelOfDetail(100.0, spacing, 5), 5); // 2^7.6: clamped
  EXPECT_EQ(chooseLevelOfDetail(100.0, spacing, 0), 0);
  EXPECT_EQ(chooseLevelOfDetail(std::numeric_limits<double>::infinity(), spacing, 4), 4);
  for (int k = 0; k < 12; ++k)
  {
    EXPECT_EQ(chooseLevelOfDetail(0.5 * std::ldexp(1.0, k), spacing, 20), k) << "2^" << k << " voxels a pixel";
  }
  EXPECT_THROW(chooseLevelOfDetail(-1.0, spacing, 3), std::invalid_argument);
  EXPECT_THROW(chooseLevelOfDetail(std::numeric_limits<double>::quiet_NaN(), spacing, 3), std::invalid_argument);
  EXPECT_THROW(chooseLevelOfDetail(1.0, spacing, -1), std::invalid_argument);
  const double zero[3] = { 1.0, 0.0, 1.0 };
  EXPECT_THROW(chooseLevelOfDetail(1.0, zero, 3), std::invalid_argument);
}

// ------------------------------------------------ half-precision levels

// binary16 conversion: every one of the 65536 patterns decodes to its exact
// value and encodes back to itself (NaN to a NaN); rounding to nearest, ties
// to even, at normals, subnormals and the overflow threshold.
TEST(HalfPrecision, ConversionIsExactAndRoundsToNearestEven)
{
  for (uint32_t h = 0; h < 0x10000u; ++h)
  {
    const float f = halfToFloat(uint16_t(h));
    const bool nan = (h & 0x7c00u) == 0x7c00u && (h & 0x03ffu) != 0u;
    if (nan)
    {
      ASSERT_TRUE(std::isnan(f)) << std::hex << h;
      ASSERT_TRUE(std::isnan(halfToFloat(floatToHalf(f))));
      continue;
    }
    // The value from the definition: (-1)^s 2^(e-15) (1 + m/1024), or
    // 2^-14 m/1024 for e = 0, infinity for e = 31.
    const int e = int((h >> 10) & 0x1fu), m = int(h & 0x3ffu);
    double want = e == 0 ? std::ldexp(double(m), -24)
      : e == 31          ? std::numeric_limits<double>::infinity()
                         : std::ldexp(1.0 + m / 1024.0, e - 15);
    if (h & 0x8000u)
    {
      want = -want;
    }
    ASSERT_EQ(double(f), want) << std::hex << h;
    ASSERT_EQ(floatToHalf(f), uint16_t(h)) << std::hex << h;
  }
  // The per-ray reader of float16 voxels (classifiedVoxelAt: a fast decode
  // for finite, non-negative values, the exact one otherwise) against the
  // definition, every finite non-negative pattern, at two scales.
  for (const double scale : { 1.0, 0x1p-40 })
  {
    for (uint32_t h = 0; h < 0x7c00u; ++h)
    {
      const uint16_t v[4] = { uint16_t(h), uint16_t(h >> 1), uint16_t(h >> 2), 0 };
      float out[4];
      ASSERT_TRUE(classifiedVoxelAt(v, ScalarType::Float16, scale, 4, 0, out));
      ASSERT_EQ(out[0], float(double(halfToFloat(uint16_t(h))) * scale)) << std::hex << h;
      ASSERT_EQ(out[1], std::min(out[0], float(double(halfToFloat(uint16_t(h >> 1))) * scale))) << std::hex << h;
    }
  }
  {
    float out[4];
    const uint16_t negative[4] = { 0xbc00, 0x3c00, 0x3c00, 0x3c00 }; // sigma -1: transparent
    ASSERT_TRUE(classifiedVoxelAt(negative, ScalarType::Float16, 1.0, 4, 0, out));
    EXPECT_EQ(out[0], 0.f);
    EXPECT_EQ(out[1], 0.f);
    const uint16_t nan[4] = { 0x3c00, 0x7e00, 0x3c00, 0x3c00 }; // a NaN: the voxel blanks the channel
    EXPECT_FALSE(classifiedVoxelAt(nan, ScalarType::Float16, 1.0, 4, 0, out));
    const uint16_t inf[4] = { 0x7c00, 0x3c00, 0x3c00, 0x3c00 }; // infinite sigma: clamped
    ASSERT_TRUE(classifiedVoxelAt(inf, ScalarType::Float16, 1.0, 4, 0, out));
    EXPECT_EQ(out[0], kMaxClassifiedSigma);
  }
  EXPECT_EQ(halfToFloat(0x3c00), 1.f);
  EXPECT_EQ(halfToFloat(0x7bff), 65504.f);
  EXPECT_EQ(floatToHalf(65519.f), 0x7bff) << "below the midpoint to 2^16";
  EXPECT_EQ(floatToHalf(65520.f), 0x7c00) << "the midpoint rounds to even: infinity";
  EXPECT_EQ(floatToHalf(1e30f), 0x7c00);
  EXPECT_EQ(floatToHalf(0x1p-25f), 0x0000) << "half the smallest subnormal: ties to even, 0";
  EXPECT_EQ(floatToHalf(0x1.8p-24f), 0x0002) << "1.5 subnormal units: ties to even, 2";
  EXPECT_EQ(floatToHalf(1.f + 0x1p-11f), 0x3c00) << "midpoint above 1 rounds to even";
  EXPECT_EQ(floatToHalf(1.f + 0x1.8p-10f), 0x3c02) << "midpoint between 1+2^-10 and 1+2^-9: even";
  EXPECT_EQ(floatToHalf(-2.f), 0xc000);
  // Random floats: the result is the nearest binary16 (or one of two equally
  // near), within 2^-11 relative for normals.
  TestRand r(77);
  for (int i = 0; i < 200000; ++i)
  {
    const float x = float(std::ldexp(r.uniform(1.0, 2.0), r.integer(-30, 14))); // below 2^15
    const uint16_t h = floatToHalf(x);
    const double got = halfToFloat(h);
    const double err = std::fabs(got - double(x));
    ASSERT_LE(err, std::fabs(double(halfToFloat(uint16_t(h + 1))) - double(x))) << x;
    if (h > 0)
    {
      ASSERT_LE(err, std::fabs(double(halfToFloat(uint16_t(h - 1))) - double(x))) << x;
    }
    if (x >= 0x1p-14f)
    {
      ASSERT_LE(err, std::ldexp(double(x), -11)) << x;
    }
  }
}

namespace
{
/// A streamed, classified level 1 of two random channels summed (what the
/// mapper builds), float32.
PyramidLevel randomLevel(int seed, const int dims[3])
{
  TestRand r(seed);
  const std::vector<float> s0 = smoothField(dims, r);
  const std::vector<float> s1 = smoothField(dims, r);
  const TransferFunctionDesc t0 = randomTF(r, 32, 0.5f);
  const TransferFunctionDesc t1 = randomTF(r, 32, 0.5f);
  ClassifyInput in[2];
  in[0].source = scalarSource(s0);
  in[0].tf = &t0;
  in[1].source = scalarSource(s1);
  in[1].tf = &t1;
  const double sp[3] = { 1, 1, 1 };
  const double org[3] = { 0, 0, 0 };
  return classifyExtinctionLevel(in, 2, dims, sp, org, 1, DownsampleFilter::Box4);
}
} // namespace

// A level converted to half precision: a power-of-two scale, half the bytes,
// every value within binary16's rounding of the float32 one, a float16
// channel source, no float view, idempotent; bad values throw.
TEST(HalfPrecision, LevelConversion)
{
  const int dims[3] = { 30, 26, 22 };
  const PyramidLevel f32 = randomLevel(3, dims);
  PyramidLevel h = f32;
  h.toHalfPrecision();
  ASSERT_TRUE(h.halfPrecision());
  EXPECT_TRUE(h.voxels.empty()) << "the float32 voxels are freed";
  EXPECT_EQ(h.bytes() * 2, f32.bytes());
  EXPECT_EQ(levelBytes(dims, 1, 1, true) * 2, levelBytes(dims, 1, 1, false));
  EXPECT_EQ(levelBytes(dims, 1, 1, false), f32.bytes());
  int e = 0;
  EXPECT_EQ(std::frexp(h.halfScale, &e), 0.5) << "a power of two";
  float largest = 0.f;
  for (float v : f32.voxels)
  {
    largest = std::max(largest, v);
  }
  ASSERT_GT(largest, 0.f);
  const ChannelSource s = h.source();
  EXPECT_EQ(s.type, ScalarType::Float16);
  EXPECT_EQ(s.stride, 4);
  EXPECT_EQ(s.scale, h.halfScale);
  double largestStored = 0.0;
  for (size_t i = 0; i < f32.voxels.size(); ++i)
  {
    const double stored = halfToFloat(h.halfVoxels[i]);
    largestStored = std::max(largestStored, stored);
    const double back = stored * h.halfScale;
    const double want = f32.voxels[i];
    ASSERT_LE(std::fabs(back - want), std::max(std::ldexp(want, -11), std::ldexp(double(largest), -38)))
      << "value " << i;
  }
  EXPECT_GE(largestStored, 8192.0);
  EXPECT_LT(largestStored, 16384.0 + 8.0);
  EXPECT_THROW(h.view(), std::logic_error);
  const std::vector<uint16_t> once = h.halfVoxels;
  h.toHalfPrecision();
  EXPECT_EQ(h.halfVoxels, once) << "idempotent";
  PyramidLevel bad = f32;
  bad.voxels[5] = -1.f;
  EXPECT_THROW(bad.toHalfPrecision(), std::invalid_argument);
  bad.voxels[5] = std::numeric_limits<float>::infinity();
  EXPECT_THROW(bad.toHalfPrecision(), std::invalid_argument);
  PyramidLevel withNaN = f32;
  withNaN.voxels[8] = std::numeric_limits<float>::quiet_NaN();
  withNaN.toHalfPrecision();
  EXPECT_TRUE(std::isnan(halfToFloat(withNaN.halfVoxels[8]))) << "NaN stays NaN (the channel's NaN rule)";
  PyramidLevel zero = f32;
  std::fill(zero.voxels.begin(), zero.voxels.end(), 0.f);
  zero.toHalfPrecision();
  EXPECT_EQ(zero.halfScale, std::ldexp(1.0, -13)) << "an empty level: scale of largest 1";
  for (uint16_t v : zero.halfVoxels)
  {
    ASSERT_EQ(v, 0u);
  }
  // Tiny units (extreme spacing): the scale follows the values, no overflow
  // or flush to zero.
  for (double unit : { 1e-30, 1e-38, 1e25 })
  {
    PyramidLevel scaled = f32;
    for (float& v : scaled.voxels)
    {
      v = float(double(v) * unit);
    }
    const PyramidLevel ref = scaled;
    scaled.toHalfPrecision();
    const double top = double(largest) * unit; // about: float rounding aside
    for (size_t i = 0; i < ref.voxels.size(); i += 7)
    {
      const double back = halfToFloat(scaled.halfVoxels[i]) * scaled.halfScale;
      ASSERT_TRUE(std::isfinite(back)) << "unit " << unit << " value " << i;
      ASSERT_LE(std::fabs(back - ref.voxels[i]), std::max(std::ldexp(double(ref.voxels[i]), -11), std::ldexp(top, -37)))
        << "unit " << unit << " value " << i;
    }
  }
}

// Rendering a half-precision level: the exact ray march differs from the
// float32 level's by far less than an 8-bit step; majorants still bound
// every sampled sigma (trilinear, nearest, cubic); Monte Carlo on it
// converges to its own ray march (z-test, kAlpha / 8 per component and mode
// pair, 8 checks); the nearest sample decodes the voxel exactly.
TEST(HalfPrecision, RendersLikeFloat32)
{
  const int dims[3] = { 36, 30, 26 };
  const PyramidLevel f32 = randomLevel(11, dims);
  PyramidLevel h = f32;
  h.toHalfPrecision();
  const ChannelSource sf = f32.source(), sh = h.source();
  const double sp[3] = { 1, 1, 1 };
  const Camera cam = orbitCamera(f32.dims, sp, 40, 40, 30, 20);
  MarchSettings ms;
  ms.step = 0.25;
  ms.terminateTransmittance = 0.f;
  for (Interpolation interp : { Interpolation::Linear, Interpolation::Nearest, Interpolation::Cubic })
  {
    Scene a, b;
    setClassified(a, f32.dims, { sf });
    setClassified(b, f32.dims, { sh });
    a.setInterpolation(interp);
    b.setInterpolation(interp);
    a.update();
    b.update();
    const std::vector<float> ia = march(a, cam, ms), ib = march(b, cam, ms);
    double sum = 0.0;
    for (float v : ia)
    {
      sum += v;
    }
    EXPECT_GT(sum, 50.0) << "the image must show something";
    EXPECT_LT(maxAbsDiff(ia, ib), 2e-3) << toString(interp) << ": far below an 8-bit step (3.9e-3)";
    // Majorants from the decoded voxels bound the decoded samples; the
    // nearest sample is the voxel's decoded value exactly.
    TestRand r(5);
    const VolumeView& vol = b.view().volume;
    EXPECT_TRUE(majorantsBoundChannel0(b, r, 5000,
      [&](Vec3f p, float sigma)
      {
        if (interp != Interpolation::Nearest)
        {
          return ::testing::AssertionSuccess();
        }
        const float want = halfToFloat(h.halfVoxels[size_t(nearestVoxel(vol, p)) * 4]) * float(h.halfScale);
        return sigma == want ? ::testing::AssertionSuccess()
                             : ::testing::AssertionFailure() << "nearest: " << sigma << " against " << want;
      }))
      << toString(interp);
  }
  // Monte Carlo on the half level against its ray march.
  Scene b;
  setClassified(b, f32.dims, { sh });
  MarchSettings fine;
  fine.step = 1.0 / 16.0;
  fine.terminateTransmittance = 0.f;
  const std::vector<float> ref = march(b, cam, fine);
  CPURenderer mc;
  Accumulator acc;
  RenderSettings rs;
  rs.jitterPixels = false;
  rs.samplesPerPixel = 256;
  rs.seed = 17;
  mc.render(b, cam, rs, nullptr, acc);
  // Per component, the pooled difference over all pixels against the
  // sample variance of the image: the expected-value estimator's variance is
  // unknown, so the check uses the pixels' spread from a second seed.
  Accumulator acc2;
  rs.seed = 18;
  mc.render(b, cam, rs, nullptr, acc2);
  for (int c = 0; c < 4; ++c)
  {
    double d = 0.0, v = 0.0;
    size_t n = 0;
    for (size_t i = size_t(c); i < ref.size(); i += 4)
    {
      const double x1 = acc.rgba()[i], x2 = acc2.rgba()[i];
      d += 0.5 * (x1 + x2) - ref[i];
      v += 0.25 * (x1 - x2) * (x1 - x2); // unbiased variance of the mean of two
      ++n;
    }
    ASSERT_GT(n, 0u);
    const double z = d / std::sqrt(std::max(v, 1e-30));
    EXPECT_GT(normalTwoSided(z), kAlpha / 4) << "component " << c << ": z = " << z;
  }
}

namespace
{
/// f() throws std::invalid_argument whose message contains `words`.
template <typename F>
void expectInvalidArgument(F f, const std::string& words)
{
  try
  {
    f();
    ADD_FAILURE() << "no exception; expected one saying \"" << words << "\"";
  }
  catch (const std::invalid_argument& e)
  {
    EXPECT_NE(std::string(e.what()).find(words), std::string::npos) << e.what();
  }
}
} // namespace

// Float16 is for pre-classified channels only, and only they are scaled.
TEST(HalfPrecision, BadInputErrors)
{
  const int dims[3] = { 4, 4, 4 };
  std::vector<uint16_t> halves(64 * 4, 0);
  ChannelSource s;
  s.data = halves.data();
  s.type = ScalarType::Float16;
  s.stride = 1;
  Scene scene;
  expectInvalidArgument([&] { scene.setVolume(dims, 1, &s); }, "only pre-classified");
  s.format = ChannelFormat::Extinction;
  s.stride = 4;
  s.scale = 0.0;
  expectInvalidArgument([&] { scene.setVolume(dims, 1, &s); }, "scale");
  s.scale = std::numeric_limits<double>::infinity();
  expectInvalidArgument([&] { scene.setVolume(dims, 1, &s); }, "scale");
  s.scale = 0.5;
  EXPECT_NO_THROW(scene.setVolume(dims, 1, &s));
  std::vector<float> floats(64 * 4, 0.f);
  ChannelSource f;
  f.data = floats.data();
  f.stride = 4;
  f.format = ChannelFormat::Extinction;
  f.scale = 2.0;
  expectInvalidArgument([&] { scene.setVolume(dims, 1, &f); }, "only float16 pre-classified channels are scaled");
}

// ------------------------------------------------------------- level bounds
//
// Every level covers level 0's world box (PyramidLevel::indexBounds,
// Scene::setIndexBounds; Documentation/user-guide/levels-of-detail.md): a
// level's outer voxels sit inside that box, and the rays are clipped to the
// box, not to them. Rendered by testBackend() (its march and its Monte
// Carlo), levels 1 and 2 built by the backend (classifyLevel: on the device
// for CUDA), for every filter and interpolation.
//
// Significance: LevelBounds.WallKeepsItsWholeImageAlpha makes 3 filters x 3
// interpolations x 3 levels = 27 z-tests of Monte Carlo against the march at
// kAlpha / 27 (Bonferroni). The march checks are deterministic. Seeds are
// fixed.
namespace
{
constexpr DownsampleFilter kFilters[3] = { DownsampleFilter::Box2, DownsampleFilter::Box4, DownsampleFilter::BSpline };
constexpr Interpolation kInterpolations[3] = { Interpolation::Linear, Interpolation::Nearest, Interpolation::Cubic };

const char* interpolationName(Interpolation i)
{
  return i == Interpolation::Linear ? "linear" : (i == Interpolation::Nearest ? "nearest" : "cubic");
}

/// A scalar volume in level 0's index space (world = index) with a
/// transfer function whose extinction is linear in the scalar (0 at 0,
/// `sigma1` at 1, white), and a level of it rendered over level 0's box.
struct LevelScene
{
  PyramidLevel data; ///< level > 0: the pre-classified level the scene reads
  Scene scene;
  double spacing[3] = { 1, 1, 1 };
  double origin[3] = { 0, 0, 0 };
};

TransferFunctionDesc linearSigmaTF(double sigma1)
{
  TransferFunctionDesc tf = flatTF(0.f, 1.f, 1.f, 1.f, 1.f, 2, 0.f, 1.f);
  tf.opacity[0] = 0.f;
  tf.opacity[1] = float(-std::expm1(-sigma1));
  return tf;
}

/// Level `level` of the scalar volume `values` (0: the volume itself), built
/// by `r` (classifyLevel) with `filter` and sampled with `interp`.
std::unique_ptr<LevelScene> levelScene(Renderer& r, const TestVolume& values, const TransferFunctionDesc& tf,
  int level, DownsampleFilter filter, Interpolation interp)
{
  std::unique_ptr<LevelScene> L(new LevelScene());
  if (level == 0)
  {
    configure(L->scene, values, { tf }, 4);
  }
  else
  {
    const std::vector<ChannelSource> src = values.sources();
    ClassifyInput in;
    in.source = src[0];
    in.tf = &tf;
    L->data = classifyLevel(r, &in, 1, values.dims, L->spacing, L->origin, level, filter);
    const ChannelSource s = L->data.source();
    L->scene.setVolume(L->data.dims, 1, &s);
    L->scene.setMacrocellSize(4);
    double lo[3], hi[3];
    L->data.indexBounds(lo, hi);
    L->scene.setIndexBounds(lo, hi);
    std::copy(L->data.spacing, L->data.spacing + 3, L->spacing);
    std::copy(L->data.origin, L->data.origin + 3, L->origin);
  }
  L->scene.setInterpolation(interp);
  L->scene.update();
  return L;
}

/// Orthographic camera along -z over world [x0, x1] x [y0, y1] into the
/// level's index space.
Camera levelCamera(const LevelScene& L, int W, int H, double x0, double x1, double y0, double y1)
{
  Camera c = orthoAlongZ(W, H, x0, x1, y0, y1, 40.0, 80.0);
  setWorldToIndex(c, L.spacing, L.origin);
  return c;
}

std::vector<float> marchImage(Renderer& r, const LevelScene& L, const Camera& cam)
{
  MarchSettings ms;
  ms.step = 1.0 / 16.0;
  ms.terminateTransmittance = 0.f;
  Accumulator acc;
  acc.resize(cam.width, cam.height);
  r.march(L.scene, cam, ms, nullptr, acc);
  return std::vector<float>(acc.rgba(), acc.rgba() + size_t(cam.width) * size_t(cam.height) * 4);
}

double meanAlpha(const std::vector<float>& rgba)
{
  double s = 0;
  for (size_t p = 0; p * 4 < rgba.size(); ++p)
  {
    s += rgba[p * 4 + 3];
  }
  return s / double(rgba.size() / 4);
}

/// Where a row of alpha values crosses 1/2 first from the left and last from
/// the right, in pixels of the row (linear interpolation between samples at
/// pixel centres i + 0.5).
void halfCrossings(const std::vector<float>& rgba, double& left, double& right)
{
  const size_t n = rgba.size() / 4;
  auto a = [&](size_t i) { return double(rgba[i * 4 + 3]); };
  left = right = -1.0;
  for (size_t i = 1; i < n && left < 0.0; ++i)
  {
    if (a(i - 1) < 0.5 && a(i) >= 0.5)
    {
      left = double(i) - 0.5 + (0.5 - a(i - 1)) / (a(i) - a(i - 1));
    }
  }
  for (size_t i = n - 1; i > 0 && right < 0.0; --i)
  {
    if (a(i) < 0.5 && a(i - 1) >= 0.5)
    {
      right = double(i) - 0.5 + (a(i - 1) - 0.5) / (a(i - 1) - a(i));
    }
  }
}
} // namespace

// A 32^3 volume with a one-voxel wall (scalar 1 at z = 15, 0 elsewhere,
// extinction sigma = 1.15 at 1: opacity 0.683) across its whole x-y extent,
// seen along -z at 32x32 pixels over exactly the volume's x-y box. Every
// pixel sees the wall, so the whole-image alpha is the wall's at every
// level: the march at levels 1 and 2 within 2% of level 0 (a level clipped
// to its own outer voxels loses a one-pixel border at level 1 and two at
// level 2: 12% and 23% less alpha). The backend's Monte Carlo image agrees
// with its march at every level (z-test of the image mean).
TEST(LevelBounds, WallKeepsItsWholeImageAlpha)
{
  std::unique_ptr<Renderer> r = testRenderer();
  TestVolume v(32, 32, 32, 1, 0.f);
  for (int j = 0; j < 32; ++j)
    for (int i = 0; i < 32; ++i)
      v.channels[0][v.index(i, j, 15)] = 1.f;
  const TransferFunctionDesc tf = linearSigmaTF(1.15);
  // |z| above which a two-sided normal tail is below kAlpha / 27.
  double zLo = 0.0, zCrit = 10.0;
  for (int k = 0; k < 100; ++k)
  {
    const double m = 0.5 * (zLo + zCrit);
    (normalTwoSided(m) > kAlpha / 27.0 ? zLo : zCrit) = m;
  }
  for (Interpolation interp : kInterpolations)
  {
    double alpha0 = 0.0;
    for (DownsampleFilter f : kFilters)
    {
      for (int level = 0; level <= 2; ++level)
      {
        const std::unique_ptr<LevelScene> L = levelScene(*r, v, tf, level, f, interp);
        const Camera cam = levelCamera(*L, 32, 32, 0.0, 31.0, 0.0, 31.0);
        const std::vector<float> march = marchImage(*r, *L, cam);
        const double marched = meanAlpha(march);
        if (level == 0)
        {
          alpha0 = marched;
        }
        RenderSettings rs;
        const Moments m = renderMoments(*r, L->scene, cam, rs, 16, 900u + uint32_t(level));
        double sumD = 0.0, sumV = 0.0, mc = 0.0;
        for (size_t p = 0; p < size_t(32 * 32); ++p)
        {
          sumD += m.mean(p * 4 + 3) - double(march[p * 4 + 3]);
          sumV += m.var(p * 4 + 3) / m.n;
          mc += m.mean(p * 4 + 3);
        }
        mc /= 1024.0;
        std::printf("wall, %s, %s, level %d: whole-image alpha %.4f (march), %.4f (Monte Carlo)\n",
          interpolationName(interp), toString(f), level, marched, mc);
        EXPECT_NEAR(marched, 0.683, 0.01) << interpolationName(interp) << " " << toString(f) << " level " << level;
        EXPECT_LE(std::fabs(marched / alpha0 - 1.0), 0.02)
          << interpolationName(interp) << " " << toString(f) << " level " << level;
        EXPECT_LE(std::fabs(sumD) / std::sqrt(std::max(sumV, 1e-30)), zCrit)
          << interpolationName(interp) << " " << toString(f) << " level " << level << ": Monte Carlo " << mc
          << " against the march " << marched;
      }
    }
  }
}

// The silhouette of an opaque box does not move across levels by more than
// half a pixel (64 pixels across 35 voxels, marched along a row and a column
// at 8 samples a pixel, crossings of alpha 1/2):
// - the whole volume opaque (the box is the volume's own): each of its four
//   edges stays within half a pixel of level 0's;
// - an opaque box inside it (voxels 10..21 in x, 12..19 in y, centred on
//   the volume, about which every level's grid is symmetric): the centre of
//   its silhouette stays within half a pixel (its edges blur outwards with
//   the filter, symmetrically; a level shifted against level 0 moves it).
TEST(LevelBounds, OpaqueBoxSilhouetteStays)
{
  std::unique_ptr<Renderer> r = testRenderer();
  TestVolume full(32, 32, 32, 1, 1.f);
  TestVolume inner(32, 32, 32, 1, 0.f);
  for (int k = 8; k < 24; ++k)
    for (int j = 12; j <= 19; ++j)
      for (int i = 10; i <= 21; ++i)
        inner.channels[0][inner.index(i, j, k)] = 1.f;
  const TransferFunctionDesc tf = linearSigmaTF(8.0);
  const int S = 8;                   // samples a pixel along the line
  const int W = 64;                  // pixels across the view
  const double lo = -2.0, hi = 33.0; // the view: W pixels over [lo, hi]
  const double px = (hi - lo) / W;
  for (Interpolation interp : kInterpolations)
  {
    for (DownsampleFilter f : kFilters)
    {
      double edges0[2][4] = {}; // [volume][x left, x right, y low, y high], level 0, in pixels
      for (int level = 0; level <= 2; ++level)
      {
        for (int which = 0; which < 2; ++which)
        {
          const TestVolume& v = which == 0 ? full : inner;
          const std::unique_ptr<LevelScene> L = levelScene(*r, v, tf, level, f, interp);
          const double mid = 15.5;
          const Camera row = levelCamera(*L, W * S, 1, lo, hi, mid - 0.01, mid + 0.01);
          const Camera col = levelCamera(*L, 1, W * S, mid - 0.01, mid + 0.01, lo, hi);
          double e[4];
          halfCrossings(marchImage(*r, *L, row), e[0], e[1]);
          halfCrossings(marchImage(*r, *L, col), e[2], e[3]);
          for (double& x : e)
          {
            x /= S; // in pixels
          }
          const std::string what = std::string(which == 0 ? "opaque volume" : "opaque inner box") + ", " +
            interpolationName(interp) + ", " + toString(f) + ", level " + std::to_string(level);
          std::printf("%s: silhouette x [%.3f, %.3f] y [%.3f, %.3f] pixels\n", what.c_str(), e[0], e[1], e[2], e[3]);
          for (double x : e)
          {
            ASSERT_GE(x, 0.0) << what << ": no silhouette edge";
          }
          if (level == 0)
          {
            std::copy(e, e + 4, edges0[which]);
            if (which == 0)
            {
              // The volume's box [0, 31] is at (0 - lo) / px .. (31 - lo) / px.
              EXPECT_NEAR(e[0], (0.0 - lo) / px, 0.25) << what;
              EXPECT_NEAR(e[1], (31.0 - lo) / px, 0.25) << what;
            }
            continue;
          }
          const double* e0 = edges0[which];
          if (which == 0)
          {
            for (int k = 0; k < 4; ++k)
            {
              EXPECT_LE(std::fabs(e[k] - e0[k]), 0.5) << what << ", edge " << k;
            }
          }
          else
          {
            EXPECT_LE(std::fabs(0.5 * (e[0] + e[1]) - 0.5 * (e0[0] + e0[1])), 0.5) << what << ", x centre";
            EXPECT_LE(std::fabs(0.5 * (e[2] + e[3]) - 0.5 * (e0[2] + e0[3])), 0.5) << what << ", y centre";
          }
        }
      }
    }
  }
}

// Scene::setIndexBounds: the default box, a level's box, and bad boxes
// refused with a message; setVolume restores the default.
TEST(LevelBounds, IndexBoundsOfLevels)
{
  const int dims[3] = { 32, 2, 1 };
  const double spacing[3] = { 0.5, 2.0, 3.0 }, origin[3] = { -4.0, 1.0, 7.0 };
  const PyramidLevel g1 = pyramidLevelGeometry(dims, spacing, origin, 1);
  const PyramidLevel g2 = pyramidLevelGeometry(dims, spacing, origin, 2);
  double lo[3], hi[3];
  g1.indexBounds(lo, hi);
  // x: 16 voxels at -4 + 0.25 + 1.0 i; level 0's box [-4, 11.5] -> [-0.25, 15.25].
  EXPECT_DOUBLE_EQ(lo[0], -0.25);
  EXPECT_DOUBLE_EQ(hi[0], 15.25);
  // y: 2 voxels -> 1 at 2.0 (spacing 4); level 0's box [1, 3] -> [-0.25, 0.25].
  EXPECT_DOUBLE_EQ(lo[1], -0.25);
  EXPECT_DOUBLE_EQ(hi[1], 0.25);
  // z: one voxel, never halved: [-0.5, 0.5] as level 0.
  EXPECT_DOUBLE_EQ(lo[2], -0.5);
  EXPECT_DOUBLE_EQ(hi[2], 0.5);
  g2.indexBounds(lo, hi);
  EXPECT_DOUBLE_EQ(lo[0], -0.375); // 8 voxels at -4 + 0.75 + 2 i
  EXPECT_DOUBLE_EQ(hi[0], 7.375);
  for (int a = 0; a < 3; ++a)
  {
    EXPECT_DOUBLE_EQ(g2.boundsLo[a], g1.boundsLo[a]);
    EXPECT_DOUBLE_EQ(g2.boundsHi[a], g1.boundsHi[a]);
  }
  // The whole-volume builders keep level 0's box at every level too.
  ClassifiedData d(32, 2, 1);
  ClassifiedVolumeView view = d.view();
  std::copy(spacing, spacing + 3, view.spacing);
  std::copy(origin, origin + 3, view.origin);
  const std::vector<PyramidLevel> ext = buildExtinctionPyramid(view, 2);
  const std::vector<PyramidLevel> opa = buildOpacityPyramid(view, 2, 1.0);
  for (int a = 0; a < 3; ++a)
  {
    EXPECT_DOUBLE_EQ(ext[1].boundsLo[a], g2.boundsLo[a]);
    EXPECT_DOUBLE_EQ(ext[1].boundsHi[a], g2.boundsHi[a]);
    EXPECT_DOUBLE_EQ(opa[1].boundsLo[a], g2.boundsLo[a]);
    EXPECT_DOUBLE_EQ(opa[1].boundsHi[a], g2.boundsHi[a]);
  }
  // A level made by hand has its own box.
  PyramidLevel byHand;
  byHand.dims[0] = 5;
  byHand.dims[1] = 1;
  byHand.dims[2] = 3;
  byHand.indexBounds(lo, hi);
  EXPECT_EQ(lo[0], 0.0);
  EXPECT_EQ(hi[0], 4.0);
  EXPECT_EQ(lo[1], -0.5);
  EXPECT_EQ(hi[1], 0.5);

  Scene scene;
  const double good[2][3] = { { -0.25, -0.25, -0.5 }, { 15.25, 0.25, 0.5 } };
  EXPECT_THROW(scene.setIndexBounds(good[0], good[1]), std::invalid_argument); // no volume yet
  ClassifiedData c(16, 1, 1);
  const ChannelSource src = c.source();
  scene.setVolume(c.dims, 1, &src);
  scene.update();
  EXPECT_EQ(scene.view().volume.boxLo[0], 0.f);
  EXPECT_EQ(scene.view().volume.boxHi[0], 15.f);
  scene.setIndexBounds(good[0], good[1]);
  EXPECT_EQ(scene.view().volume.boxLo[0], -0.25f);
  EXPECT_EQ(scene.view().volume.boxHi[1], 0.25f);
  scene.update();
  EXPECT_EQ(scene.view().volume.boxHi[0], 15.25f);
  const double nan = std::numeric_limits<double>::quiet_NaN();
  const double bad[4][2][3] = {
    { { -0.6, 0, -0.5 }, { 15, 0.5, 0.5 } },  // more than half a voxel below
    { { 0, -0.5, -0.5 }, { 15.6, 0.5, 0.5 } }, // more than half a voxel above
    { { 3, -0.5, -0.5 }, { 3, 0.5, 0.5 } },    // empty
    { { nan, -0.5, -0.5 }, { 15, 0.5, 0.5 } }, // not finite
  };
  for (const auto& b : bad)
  {
    try
    {
      scene.setIndexBounds(b[0], b[1]);
      ADD_FAILURE() << "bad bounds accepted";
    }
    catch (const std::invalid_argument& e)
    {
      EXPECT_NE(std::string(e.what()).find("index bounds"), std::string::npos) << e.what();
    }
  }
  EXPECT_EQ(scene.view().volume.boxLo[0], -0.25f); // a refused box changes nothing
  scene.setVolume(c.dims, 1, &src);
  scene.update();
  EXPECT_EQ(scene.view().volume.boxLo[0], 0.f);
  EXPECT_EQ(scene.view().volume.boxHi[0], 15.f);
}
