// SPDX-License-Identifier: BSD-3-Clause
// The numerical hard cases (Documentation/design.md, "Numerical rules";
// Documentation/user-guide/numerical-limits.md), each asserting a finite and
// correct result. (The generator's u never being 1 is tested in
// sampling_test.cxx, Rng.NeverReturnsOne.)
// Significance: each TEST has a family-wise level kAlpha = 0.001, split evenly
// (Bonferroni) over its statistical checks; seeds are fixed.
#include "TestUtil.h"

#include "mcvol/ray/Acceleration.h"

#include "mcvol/ray/Sampling.h"

#include <cstring>
#include <limits>

using namespace mcvol;
using namespace mcvol::test;

namespace
{
constexpr double kAlpha = 1e-3;

struct Image
{
  int width = 0, height = 0;
  std::vector<float> px;
  const float* at(int x, int y) const { return this->px.data() + 4 * (size_t(y) * size_t(this->width) + size_t(x)); }
};

Image render(const Scene& scene, const Camera& cam, Tracker t, int spp, uint32_t seed,
  RenderCounters* counters = nullptr, bool jitter = true, Estimator estimator = RenderSettings().estimator)
{
  std::unique_ptr<Renderer> r = testRenderer();
  Accumulator acc;
  RenderSettings rs;
  rs.samplesPerPixel = spp;
  rs.seed = seed;
  rs.tracker = t;
  rs.estimator = estimator;
  rs.jitterPixels = jitter;
  r->render(scene, cam, rs, nullptr, acc, counters);
  Image img;
  img.width = cam.width;
  img.height = cam.height;
  img.px.assign(acc.rgba(), acc.rgba() + size_t(cam.width) * cam.height * 4);
  return img;
}

/// Every value finite, alpha in [0, 1], colour in [0, max]. Returns the mean alpha.
double expectFinite(const Image& img, const std::string& what, float maxColour = 1.f)
{
  double sum = 0;
  int bad = 0;
  for (size_t i = 0; i < img.px.size(); ++i)
  {
    const float v = img.px[i];
    const float hi = i % 4 == 3 ? 1.f : maxColour;
    if (!(std::isfinite(v) && v >= 0.f && v <= hi + 1e-6f) && bad++ < 3)
    {
      ADD_FAILURE() << what << ": pixel value " << v << " at " << i;
    }
    if (i % 4 == 3)
    {
      sum += v;
    }
  }
  return sum / (img.px.size() / 4);
}

/// Sum over the given pixels of alpha * spp (= collided samples).
double hitCount(const Image& img, int spp, int x0, int x1, int y0, int y1)
{
  double h = 0;
  for (int y = y0; y < y1; ++y)
    for (int x = x0; x < x1; ++x)
      h += double(img.at(x, y)[3]) * spp;
  return std::round(h);
}

/// Orthographic camera looking along -axis at a volume of `dims` and
/// `spacing` (origin 0), film covering index coordinates [lo, hi] on the two
/// other axes (in index units), rays starting outside the volume.
Camera axisCamera(int axis, const int dims[3], const double spacing[3], double lo, double hi, int W, int H)
{
  const int a1 = (axis + 1) % 3, a2 = (axis + 2) % 3;
  double center[3] = { 0, 0, 0 }, right[3] = { 0, 0, 0 }, up[3] = { 0, 0, 0 }, dir[3] = { 0, 0, 0 };
  center[a1] = 0.5 * (lo + hi) * spacing[a1];
  center[a2] = 0.5 * (lo + hi) * spacing[a2];
  right[a1] = 0.5 * (hi - lo) * spacing[a1];
  up[a2] = 0.5 * (hi - lo) * spacing[a2];
  const double extent = (dims[axis] + 2) * spacing[axis];
  center[axis] = extent;
  dir[axis] = -1;
  Camera c = orthoCamera(W, H, center, right, up, dir, 0.0, 3 * extent);
  const double origin[3] = { 0, 0, 0 };
  setWorldToIndex(c, spacing, origin);
  return c;
}
} // namespace

// Opacity exactly 1: clamped to kMaxOpacity, extinction -ln(2^-20)/u =
// 13.86/u, finite majorants, and alpha exactly 1 through a thick volume.
TEST(HardCases, OpacityOne)
{
  EXPECT_NEAR(opacityToExtinction(1.f, 1.f), 20.0 * std::log(2.0), 1e-5);
  EXPECT_EQ(opacityToExtinction(1.f, 2.f), opacityToExtinction(kMaxOpacity, 2.f));
  EXPECT_TRUE(std::isfinite(opacityToExtinction(2.f, 1e-30f)));
  TestVolume v(8, 8, 17, 1, 0.5f);
  Scene scene;
  configure(scene, v, { flatTF(1.f, 0.2f, 0.4f, 0.6f, 2.f) }, 4);
  EXPECT_NEAR(scene.tables()[3], 13.8629436 / 2.0, 1e-5);
  for (float m : scene.majorants())
  {
    EXPECT_TRUE(std::isfinite(m) && m > 0.f);
  }
  const double spacing[3] = { 1, 1, 1 };
  const Camera cam = axisCamera(2, v.dims, spacing, 0.5, 6.5, 12, 12);
  // Collision: the first tentative collision is real, colour exact. Expected
  // value: it scores w = sigma / majorant = 1 / kMajorantInflation and
  // leaves T = 1 - w (about 1e-5), which the roulette ends (T = 0, alpha
  // exactly 1) unless a survivor (probability T / kRouletteThreshold, none
  // with this seed) goes on; the colour is short by at most c (1 - w).
  for (Estimator e : { Estimator::Collision, Estimator::ExpectedValue })
    for (Tracker t : { Tracker::OneDDA, Tracker::NDDA })
    {
      const Image img = render(scene, cam, t, 16, 3, nullptr, true, e);
      expectFinite(img, "opacity 1");
      const double tol = e == Estimator::Collision ? 1e-6 : 1e-6 + (1.0 - 1.0 / kMajorantInflation);
      for (int p = 0; p < cam.width * cam.height; ++p)
      {
        const float* px = img.px.data() + 4 * p;
        EXPECT_EQ(px[3], 1.f) << toString(t) << " " << toString(e) << " pixel " << p;
        EXPECT_NEAR(px[0], 0.2f, 0.2 * tol) << toString(e);
        EXPECT_NEAR(px[1], 0.4f, 0.4 * tol) << toString(e);
        EXPECT_NEAR(px[2], 0.6f, 0.6 * tol) << toString(e);
      }
    }
}

// All-zero opacity: no channel active, nothing traversed, nothing sampled,
// a transparent image.
TEST(HardCases, AllZeroOpacity)
{
  TestVolume v(8, 8, 17, 3, 0.5f);
  Scene scene;
  configure(scene, v, { flatTF(0.f, 1, 0, 0), flatTF(0.f, 0, 1, 0), flatTF(0.f, 0, 0, 1) }, 4);
  EXPECT_EQ(scene.view().numActive, 0);
  for (float m : scene.majorants())
  {
    EXPECT_EQ(m, 0.f);
  }
  const double spacing[3] = { 1, 1, 1 };
  const Camera cam = axisCamera(2, v.dims, spacing, -1, 8, 10, 10);
  for (BlendMode mode : { BlendMode::Density, BlendMode::Max, BlendMode::Mix, BlendMode::Composite })
  {
    scene.setBlendMode(mode);
    scene.update();
    for (Tracker t : { Tracker::OneDDA, Tracker::NDDA })
    {
      RenderCounters c;
      const Image img = render(scene, cam, t, 4, 1, &c);
      const std::string what = std::string(toString(mode)) + " " + toString(t);
      for (float x : img.px)
      {
        EXPECT_EQ(x, 0.f) << what;
      }
      EXPECT_GT(c.rays, 0u);
      EXPECT_EQ(c.tentativeCollisions, 0u) << what;
      EXPECT_EQ(c.realCollisions, 0u) << what;
      EXPECT_EQ(c.channelSamples, 0u) << what;
      EXPECT_EQ(c.ddaSteps, 0u) << what << ": macrocells were traversed with no active channel";
    }
  }
}

// NaN voxels are transparent (and cost nothing: their cells' majorants are
// 0); Inf voxels give finite output; the rest of the volume is unaffected
// (binomial test, 2 checks).
TEST(HardCases, NaNAndInfVoxels)
{
  const float nan = std::numeric_limits<float>::quiet_NaN(), inf = std::numeric_limits<float>::infinity();
  TestVolume v(16, 16, 16, 1, 1.f);
  std::vector<float>& d = v.channels[0];
  for (int k = 0; k < 16; ++k)
    for (int j = 0; j < 16; ++j)
      for (int i = 0; i < 16; ++i)
      {
        if (i <= 6)
          d[v.index(i, j, k)] = nan;
        else if (i >= 9 && j == 12)
          d[v.index(i, j, k)] = inf;
        else if (i >= 9 && j == 13)
          d[v.index(i, j, k)] = -inf;
      }
  const double sigma = 0.1;
  Scene scene;
  configure(scene, v, { flatTF(opacityFor(sigma, 1.0), 0.3f, 0.6f, 0.9f, 1.f, 2, 0.f, 2.f) }, 4);
  EXPECT_EQ(scene.majorants()[0], 0.f) << "a macrocell of NaN voxels must have majorant 0";
  for (float m : scene.majorants())
  {
    EXPECT_TRUE(std::isfinite(m));
  }
  const double spacing[3] = { 1, 1, 1 };
  const Camera cam = axisCamera(2, v.dims, spacing, 0, 15, 15, 15);
  const int spp = 64;
  for (Tracker t : { Tracker::OneDDA, Tracker::NDDA })
  {
    const Image img = render(scene, cam, t, spp, 9);
    expectFinite(img, "NaN/Inf volume");
    // Pixels 0..6 (x in [0, 7]) see NaN in every interpolation: transparent.
    for (int y = 0; y < 15; ++y)
      for (int x = 0; x <= 6; ++x)
        EXPECT_EQ(img.at(x, y)[3], 0.f) << toString(t) << " NaN pixel " << x << "," << y;
    // Pixels x >= 7 away from the Inf rows (y in [11, 14)) see value 1.
    double hits = hitCount(img, spp, 7, 15, 0, 11) + hitCount(img, spp, 7, 15, 14, 15);
    const double n = 8.0 * 12.0 * spp;
    expectBinomial(hits, n, -std::expm1(-sigma * 15.0), kAlpha / 2, std::string("valid region ") + toString(t));
  }
  // An all-NaN volume: nothing active, transparent.
  TestVolume allNaN(6, 6, 6, 1, nan);
  Scene s2;
  configure(s2, allNaN, { flatTF(0.5f, 1, 1, 1) }, 2);
  EXPECT_EQ(s2.view().numActive, 0);
  const Image img = render(s2, axisCamera(2, allNaN.dims, spacing, 0, 5, 5, 5), Tracker::OneDDA, 4, 1);
  EXPECT_EQ(expectFinite(img, "all NaN"), 0.0);
}

// A single voxel: one spacing of thickness, visible, alpha 1 - exp(-sigma s)
// (binomial tests, 4 checks) for spacing 1 and 2.
TEST(HardCases, SingleVoxel)
{
  TestVolume v(1, 1, 1, 1, 0.5f);
  int check = 0;
  for (double s : { 1.0, 2.0 })
  {
    Scene scene;
    // Opacity 0.5 over one spacing: alpha 0.5 through the voxel.
    configure(scene, v, { flatTF(0.5f, 1, 1, 1, float(s)) }, 8);
    const double spacing[3] = { s, s, s };
    Camera cam = axisCamera(2, v.dims, spacing, -0.4, 0.4, 16, 16);
    for (Tracker t : { Tracker::OneDDA, Tracker::NDDA })
    {
      const int spp = 64;
      const Image img = render(scene, cam, t, spp, uint32_t(++check));
      expectFinite(img, "single voxel");
      expectBinomial(hitCount(img, spp, 0, 16, 0, 16), 16.0 * 16.0 * spp, 0.5, kAlpha / 4,
        "single voxel, spacing " + std::to_string(s) + " " + toString(t));
    }
    // Seen from an oblique perspective camera: finite and visible.
    const Camera orbit = orbitCamera(v.dims, spacing, 24, 24, 35, 25);
    const Image img = render(scene, orbit, Tracker::OneDDA, 8, 1);
    EXPECT_GT(expectFinite(img, "single voxel orbit"), 0.01);
  }
}

// A slab one voxel thick along each axis in turn, spacing 3 along it and
// opacity 0.4 over unit distance 3: alpha = 1 - exp(-sigma * spacing) = 0.4
// (binomial tests, 6 checks).
TEST(HardCases, OneVoxelThickSlab)
{
  int check = 0;
  for (int axis = 0; axis < 3; ++axis)
  {
    int dims[3] = { 12, 12, 12 };
    dims[axis] = 1;
    TestVolume v(dims[0], dims[1], dims[2], 1, 0.5f);
    double spacing[3] = { 1, 1, 1 };
    spacing[axis] = 3;
    Scene scene;
    configure(scene, v, { flatTF(0.4f, 1, 1, 1, 3.f) }, 4);
    const Camera cam = axisCamera(axis, dims, spacing, 0.5, 10.5, 16, 16);
    for (Tracker t : { Tracker::OneDDA, Tracker::NDDA })
    {
      const int spp = 64;
      const Image img = render(scene, cam, t, spp, uint32_t(100 + ++check));
      expectFinite(img, "slab");
      expectBinomial(hitCount(img, spp, 0, 16, 0, 16), 16.0 * 16.0 * spp, 0.4, kAlpha / 6,
        "1-voxel slab along axis " + std::to_string(axis) + " " + toString(t));
    }
  }
}

namespace
{
/// The comparison scene: a small cosmology volume.
const DemoVolume& cosmology()
{
  static const DemoVolume v = makeDemo("cosmology", { 20, 20, 20 });
  return v;
}
} // namespace

// Anisotropic spacing, views along z and along x, unit distance scaled by the
// spacing along the view: the same image as spacing 1 (pooled two-sample
// comparison, 2 views x 12 checks).
TEST(HardCases, AnisotropicSpacing)
{
  const DemoVolume& v = cosmology();
  const double one[3] = { 1, 1, 1 }, aniso[3] = { 2, 0.5, 3 };
  RenderSettings rs;
  int view = 0;
  for (int axis : { 2, 0 })
  {
    Scene ref, test;
    configureDemo(ref, v, 4, 64, 1.0);
    configureDemo(test, v, 4, 64, aniso[axis]);
    const Moments A = renderMoments(ref, axisCamera(axis, v.dims, one, 1, 18, 24, 24), rs, 48, 10);
    const Moments B = renderMoments(test, axisCamera(axis, v.dims, aniso, 1, 18, 24, 24), rs, 48, 500);
    expectSameImage(A, B, kAlpha / 24, "anisotropic spacing, view " + std::to_string(view++));
  }
}

// Tiny (1e-6) and huge (1e6) uniform spacing with the unit distance scaled:
// the same image as spacing 1 from an oblique perspective camera
// (2 x 12 checks).
TEST(HardCases, TinyAndHugeSpacing)
{
  const DemoVolume& v = cosmology();
  RenderSettings rs;
  const double one[3] = { 1, 1, 1 };
  Scene ref;
  configureDemo(ref, v, 4, 64, 1.0);
  const Moments A = renderMoments(ref, orbitCamera(v.dims, one, 24, 24, 40, 25), rs, 48, 10);
  for (double s : { 1e-6, 1e6 })
  {
    Scene test;
    configureDemo(test, v, 4, 64, s);
    const double sp[3] = { s, s, s };
    const Moments B = renderMoments(test, orbitCamera(v.dims, sp, 24, 24, 40, 25), rs, 48, 700);
    expectSameImage(A, B, kAlpha / 24, "spacing " + std::to_string(s));
  }
}

namespace
{
/// The same camera and volume moved by `T` in world space.
Camera translated(Camera c, const double T[3])
{
  double m[16];
  std::memcpy(m, c.invViewProj, sizeof(m));
  for (int r = 0; r < 3; ++r)
    for (int k = 0; k < 4; ++k)
      c.invViewProj[r * 4 + k] = m[r * 4 + k] + T[r] * m[12 + k];
  for (int r = 0; r < 3; ++r)
    c.worldToIndex[r * 4 + 3] -=
      c.worldToIndex[r * 4 + 0] * T[0] + c.worldToIndex[r * 4 + 1] * T[1] + c.worldToIndex[r * 4 + 2] * T[2];
  return c;
}
} // namespace

// An origin 1e6 away from zero (volume and camera moved together): with the
// same seed nearly every pixel is bit-identical (ray set-up in double); with
// other seeds the image agrees statistically (12 checks).
TEST(HardCases, OriginFarFromZero)
{
  const DemoVolume& v = cosmology();
  Scene scene;
  configureDemo(scene, v, 4, 64, 1.0);
  const double one[3] = { 1, 1, 1 };
  const Camera cam = orbitCamera(v.dims, one, 24, 24, 20, 30);
  const double T[3] = { 1e6, -1e6, 1e6 };
  const Camera far = translated(cam, T);
  for (Tracker t : { Tracker::OneDDA, Tracker::NDDA })
  {
    const Image a = render(scene, cam, t, 8, 42), b = render(scene, far, t, 8, 42);
    expectFinite(b, "far origin");
    int differ = 0;
    for (size_t i = 0; i < a.px.size(); i += 4)
      differ += std::memcmp(&a.px[i], &b.px[i], 4 * sizeof(float)) != 0 ? 1 : 0;
    EXPECT_LE(differ, int(a.px.size() / 4 / 100)) << toString(t) << ": " << differ << " pixels changed";
  }
  RenderSettings rs;
  const Moments A = renderMoments(scene, cam, rs, 48, 10);
  const Moments B = renderMoments(scene, far, rs, 48, 900);
  expectSameImage(A, B, kAlpha / 12, "origin at 1e6");
}

namespace
{
/// Expected collided samples for a homogeneous box of extinction sigma,
/// with rays through pixel centres (no jitter) computed in world space here.
void expectHomogeneousImage(const Image& img, const Camera& cam, int spp, double sigma, const double lo[3],
  const double hi[3], double alpha, const std::string& what, int* visible = nullptr)
{
  double hits = 0, expected = 0, var = 0;
  int vis = 0;
  for (int y = 0; y < cam.height; ++y)
    for (int x = 0; x < cam.width; ++x)
    {
      const WorldRay r = pixelRay(cam, x + 0.5, y + 0.5);
      const double L = lengthInBox(r, lo, hi);
      const double p = -std::expm1(-sigma * L);
      vis += L > 0 ? 1 : 0;
      expected += spp * p;
      var += spp * p * (1 - p);
      hits += double(img.at(x, y)[3]) * spp;
      if (L == 0)
      {
        EXPECT_EQ(img.at(x, y)[3], 0.f) << what << ": pixel " << x << "," << y << " misses the box";
      }
    }
  hits = std::round(hits);
  const double z = (hits - expected) / std::sqrt(var);
  EXPECT_GT(normalTwoSided(z), alpha) << what << ": " << hits << " collisions, expected " << expected << " (z = " << z
                                      << ")";
  if (visible)
    *visible = vis;
}
} // namespace

// Camera inside a homogeneous volume, looking obliquely: per-pixel alpha
// 1 - exp(-sigma L) with L from the near plane to the box exit (computed
// independently in world space); Poisson-binomial count, 2 checks.
TEST(HardCases, CameraInsideVolume)
{
  TestVolume v(33, 33, 33, 1, 0.5f);
  const double sigma = 0.05;
  Scene scene;
  configure(scene, v, { flatTF(opacityFor(sigma, 1.0), 1, 1, 1) }, 8);
  const double eye[3] = { 16, 15, 17 }, target[3] = { 40, 30, 25 }, up[3] = { 0, 1, 0 };
  const auto vp = viewProjection(eye, target, up, 60.0, 1.0, 0.05, 200.0, false, 1.0);
  Camera cam;
  cam.width = cam.height = 24;
  ASSERT_TRUE(invert4x4(vp.data(), cam.invViewProj));
  const double lo[3] = { 0, 0, 0 }, hi[3] = { 32, 32, 32 };
  for (Tracker t : { Tracker::OneDDA, Tracker::NDDA })
  {
    const Image img = render(scene, cam, t, 32, 17, nullptr, false);
    expectFinite(img, "camera inside");
    expectHomogeneousImage(img, cam, 32, sigma, lo, hi, kAlpha / 2, std::string("camera inside ") + toString(t));
  }
  // Inside a structured volume: finite.
  Scene demo;
  configureDemo(demo, cosmology(), 4, 64, 1.0);
  const double e2[3] = { 9, 10, 8 }, t2[3] = { 0, 3, 19 };
  const auto vp2 = viewProjection(e2, t2, up, 70.0, 1.0, 0.01, 100.0, false, 1.0);
  ASSERT_TRUE(invert4x4(vp2.data(), cam.invViewProj));
  EXPECT_GT(expectFinite(render(demo, cam, Tracker::OneDDA, 4, 1), "inside cosmology"), 0.0);
}

// Axis-parallel rays exactly on faces and edges of the box (and a
// face-diagonal ray), tracked directly: inside the closed box, alpha
// 1 - exp(-sigma L) (binomial, 5 rays x 2 trackers = 10 checks). Rendered
// axis-parallel views with pixel centres on the faces: finite.
TEST(HardCases, GrazingAndAxisParallelRays)
{
  TestVolume v(9, 9, 9, 1, 0.5f);
  const double sigma = 0.1;
  Scene scene;
  configure(scene, v, { flatTF(opacityFor(sigma, 1.0), 1, 1, 1) }, 4);
  const SceneView& s = scene.view();
  struct Case
  {
    Vec3f o, d;
    const char* name;
  };
  const Case cases[] = {
    { Vec3f(0.f, 4.f, 0.f), Vec3f(0.f, 0.f, 1.f), "on face x = 0" },
    { Vec3f(8.f, 4.f, 0.f), Vec3f(0.f, 0.f, 1.f), "on face x = 8" },
    { Vec3f(0.f, 0.f, 0.f), Vec3f(0.f, 0.f, 1.f), "along edge" },
    { Vec3f(0.f, 0.f, 0.f), Vec3f(0.f, 0.6f, 0.8f), "face diagonal" },
    { Vec3f(8.f, 8.f, 8.f), Vec3f(-1.f, 0.f, 0.f), "edge, negative direction" },
  };
  uint32_t seed = 0;
  for (const Case& c : cases)
  {
    float t0 = 0.f, t1 = FLT_MAX;
    ASSERT_TRUE(intersectBox(s.volume.boxLo, s.volume.boxHi, c.o, c.d, t0, t1)) << c.name;
    EXPECT_EQ(t0, 0.f) << c.name;
    const double L = t1;
    EXPECT_NEAR(L, c.d.y > 0.f ? 10.0 : 8.0, 1e-5) << c.name;
    for (Tracker t : { Tracker::OneDDA, Tracker::NDDA })
    {
      ++seed;
      const int rays = 20000;
      double hits = 0;
      RayCounters rc;
      for (int i = 0; i < rays; ++i)
      {
        Rng rng(uint32_t(i), 0u, seed);
        const Hit h = trackDensity(s, t, c.o, c.d, t1, rng, rc);
        if (h.found())
        {
          ASSERT_TRUE(std::isfinite(h.t) && h.t >= 0.f && h.t <= t1) << c.name;
          hits += 1;
        }
      }
      expectBinomial(hits, rays, -std::expm1(-sigma * L), kAlpha / 10, std::string(c.name) + " " + toString(t));
    }
  }
  // Rendered: pixel centres on x = 0, 1, ..., 8 (faces at both ends), all
  // three axes.
  const double one[3] = { 1, 1, 1 };
  for (int axis = 0; axis < 3; ++axis)
  {
    const Camera cam = axisCamera(axis, v.dims, one, -0.5, 8.5, 9, 9);
    for (Tracker t : { Tracker::OneDDA, Tracker::NDDA })
    {
      EXPECT_GT(expectFinite(render(scene, cam, t, 4, 3, nullptr, false), "grazing view"), 0.3);
    }
  }
}

// Very long rays: a perspective camera 1e5 units away with a narrow field of
// view sees the same image as an orthographic camera (12 checks), and a
// homogeneous volume gives alpha 1 - exp(-sigma L) (2 checks).
TEST(HardCases, VeryLongRays)
{
  const double D = 1e5;
  auto farCamera = [&](const double c[3], double halfWindow, int W)
  {
    const double eye[3] = { c[0], c[1], c[2] + D }, up[3] = { 0, 1, 0 };
    const double fovy = 2.0 * std::atan(halfWindow / D) * 180.0 / M_PI;
    const auto vp = viewProjection(eye, c, up, fovy, 1.0, 1.0, 2 * D, false, 1.0);
    Camera cam;
    cam.width = cam.height = W;
    EXPECT_TRUE(invert4x4(vp.data(), cam.invViewProj));
    return cam;
  };
  const DemoVolume& v = cosmology();
  Scene scene;
  configureDemo(scene, v, 4, 64, 1.0);
  const double one[3] = { 1, 1, 1 };
  const double centre[3] = { 9.5, 9.5, 9.5 };
  RenderSettings rs;
  const Moments A = renderMoments(scene, axisCamera(2, v.dims, one, 1, 18, 24, 24), rs, 48, 10);
  const Moments B = renderMoments(scene, farCamera(centre, 8.5, 24), rs, 48, 300);
  expectSameImage(A, B, kAlpha / 12, "camera 1e5 away");

  TestVolume h(17, 17, 17, 1, 0.5f);
  const double sigma = 0.08;
  Scene hs;
  configure(hs, h, { flatTF(opacityFor(sigma, 1.0), 1, 1, 1) }, 4);
  const double c2[3] = { 8, 8, 8 }, lo[3] = { 0, 0, 0 }, hi[3] = { 16, 16, 16 };
  const Camera cam = farCamera(c2, 10.0, 20);
  for (Tracker t : { Tracker::OneDDA, Tracker::NDDA })
  {
    const Image img = render(hs, cam, t, 32, 5, nullptr, false);
    expectFinite(img, "long rays");
    int visible = 0;
    expectHomogeneousImage(img, cam, 32, sigma, lo, hi, kAlpha / 2, std::string("long rays ") + toString(t), &visible);
    EXPECT_GT(visible, 200);
  }
}

// 16 channels (more than VTK's 4): channel frequencies proportional to the
// extinctions (chi-square, 15 dof) and the collision count (binomial-type),
// for both trackers (4 checks); a 16-channel demo renders finite.
TEST(HardCases, SixteenChannels)
{
  const int N = 16;
  TestVolume v(9, 9, 13, N, 0.5f);
  std::vector<TransferFunctionDesc> tfs;
  std::vector<double> sigma;
  double total = 0;
  for (int n = 0; n < N; ++n)
  {
    const double s = 0.004 * (1 + n % 5) * (n % 2 ? 1.5 : 1.0);
    tfs.push_back(flatTF(opacityFor(s, 1.0), 1, 1, 1));
    sigma.push_back(extinctionOf(tfs.back().opacity[0], 1.0));
    total += sigma.back();
  }
  Scene scene;
  configure(scene, v, tfs, 4);
  ASSERT_EQ(scene.view().numActive, N);
  std::vector<double> probs;
  for (double s : sigma)
    probs.push_back(s / total);
  uint32_t seed = 60;
  for (Tracker t : { Tracker::OneDDA, Tracker::NDDA })
  {
    TestRand r(++seed);
    std::vector<double> counts(N, 0.0);
    RayCounters rc;
    double hits = 0, expected = 0, var = 0;
    for (int i = 0; i < 60000; ++i)
    {
      const BoxRay ray = randomBoxRay(scene.view().volume, r);
      Rng rng(uint32_t(i), 0u, seed);
      const Hit h = trackDensity(scene.view(), t, ray.o, ray.d, ray.tmax, rng, rc);
      const double p = -std::expm1(-total * ray.tmax);
      expected += p;
      var += p * (1 - p);
      if (h.found())
      {
        ASSERT_GE(h.channel, 0);
        ASSERT_LT(h.channel, N);
        counts[size_t(h.channel)] += 1;
        hits += 1;
      }
    }
    double stat = 0;
    EXPECT_GT(chiSquarePValue(counts, probs, &stat), kAlpha / 4) << toString(t) << ": chi-square " << stat;
    const double z = (hits - expected) / std::sqrt(var);
    EXPECT_GT(normalTwoSided(z), kAlpha / 4) << toString(t) << ": collisions z = " << z;
  }
  const DemoVolume d = makeDemo("cosmology", { 16, 16, 16 }, 16);
  Scene ds;
  configureDemo(ds, d, 4, 32, 1.0);
  EXPECT_EQ(ds.numChannels(), 16);
  EXPECT_EQ(ds.view().numActive, 16);
  const double one[3] = { 1, 1, 1 };
  for (Tracker t : { Tracker::OneDDA, Tracker::NDDA })
  {
    EXPECT_GT(expectFinite(render(ds, orbitCamera(d.dims, one, 16, 16, 30, 20), t, 4, 2), "16 channels"), 0.05);
  }
}

// A channel whose majorant is 0 costs nothing: with a zero-opacity channel
// added, images and work counters are identical to the scene without it;
// rays through cells where an active channel's majorant is 0 take no
// tentative collisions.
TEST(HardCases, ZeroMajorantChannelCostsNothing)
{
  TestVolume one(10, 10, 10, 1, 0.5f), two(10, 10, 10, 2, 0.5f);
  const TransferFunctionDesc visible = flatTF(opacityFor(0.1, 1.0), 1, 0.5f, 0);
  Scene a, b;
  configure(a, one, { visible }, 4);
  configure(b, two, { visible, flatTF(0.f, 0, 1, 0) }, 4);
  const float weights[2] = { 1.f, 0.f }; // Mix: the same normalised weight for channel 0
  b.setMixWeights(weights, 2);
  EXPECT_EQ(b.view().numActive, 1);
  const double sp[3] = { 1, 1, 1 };
  const Camera cam = orbitCamera(one.dims, sp, 16, 16, 30, 20);
  for (BlendMode mode : { BlendMode::Density, BlendMode::Max, BlendMode::Mix, BlendMode::Composite })
  {
    a.setBlendMode(mode);
    a.update();
    b.setBlendMode(mode);
    b.update();
    for (Tracker t : { Tracker::OneDDA, Tracker::NDDA })
    {
      RenderCounters ca, cb;
      const Image ia = render(a, cam, t, 4, 8, &ca), ib = render(b, cam, t, 4, 8, &cb);
      const std::string what = std::string(toString(mode)) + " " + toString(t);
      EXPECT_EQ(0, std::memcmp(ia.px.data(), ib.px.data(), ia.px.size() * sizeof(float))) << what;
      EXPECT_EQ(ca.tentativeCollisions, cb.tentativeCollisions) << what;
      EXPECT_EQ(ca.ddaSteps, cb.ddaSteps) << what;
      EXPECT_EQ(ca.channelSamples, cb.channelSamples) << what;
      EXPECT_GT(ca.tentativeCollisions, 0u);
    }
  }
  // Channel 0 is 0 (transparent) for x < 12, 1 (opaque-ish) beyond.
  TestVolume half(24, 8, 8, 1, 0.f);
  for (int k = 0; k < 8; ++k)
    for (int j = 0; j < 8; ++j)
      for (int i = 12; i < 24; ++i)
        half.channels[0][half.index(i, j, k)] = 1.f;
  TransferFunctionDesc ramp = flatTF(0.f, 1, 1, 1);
  ramp.opacity[1] = 0.5f;
  Scene hs;
  configure(hs, half, { ramp }, 4);
  for (Tracker t : { Tracker::OneDDA, Tracker::NDDA })
  {
    RayCounters empty, full;
    for (int i = 0; i < 1000; ++i)
    {
      Rng rng(uint32_t(i), 0u, 1u);
      const float y = 0.5f + 6.f * float(i % 10) / 10.f;
      const Hit h =
        trackDensity(hs.view(), t, Vec3f(1.5f + float(i % 7) * 0.1f, y, 0.f), Vec3f(0, 0, 1), 7.f, rng, empty);
      EXPECT_FALSE(h.found());
      trackDensity(hs.view(), t, Vec3f(18.f, y, 0.f), Vec3f(0, 0, 1), 7.f, rng, full);
    }
    EXPECT_EQ(empty.tentative, 0u) << toString(t);
    EXPECT_EQ(empty.samples, 0u) << toString(t);
    EXPECT_GT(empty.ddaSteps, 0u) << toString(t);
    EXPECT_GT(full.tentative, 0u) << toString(t);
  }
}

// Opacity 1 over a unit distance of 1e-4 voxel (extinction 1.4e5 per voxel)
// inside mostly empty macrocells: without the per-render extinction limit a
// ray takes ~1e5 null collisions per macrocell (the mapper test of such a box
// ran for hours). With it: the opaque box is still exactly opaque and
// uniformly coloured, the surroundings transparent, and the work per ray is
// bounded (kMaxOpticalDepthPerVoxel per voxel crossed, at most).
TEST(HardCases, HugeExtinctionStaysBounded)
{
  TestVolume v(24, 24, 24, 1, 0.f);
  for (int k = 8; k <= 15; ++k)
    for (int j = 8; j <= 15; ++j)
      for (int i = 8; i <= 15; ++i)
        v.channels[0][v.index(i, j, k)] = 1.f;
  // Opacity 0 below 0.5, 1 above (K = 3 texels over [0, 1]: 0, 1, 1).
  TransferFunctionDesc tf = flatTF(1.f, 0.9f, 0.5f, 0.1f, 1e-4f, 3);
  tf.opacity[0] = 0.f;
  Scene scene;
  configure(scene, v, { tf }, 16);
  EXPECT_GT(scene.tables()[7], 1e5f); // the table itself is not clamped
  const double spacing[3] = { 1, 1, 1 };
  // Film over index [0, 23] on x and y, looking down -z: the box covers the
  // film's middle third.
  const Camera cam = axisCamera(2, v.dims, spacing, 0.0, 23.0, 23, 23);
  for (Tracker t : { Tracker::OneDDA, Tracker::NDDA })
  {
    RenderCounters c;
    const Image img = render(scene, cam, t, 8, 5, &c, false);
    expectFinite(img, "huge extinction");
    // Rays cross at most 24 voxels (sqrt(3) per voxel along a diagonal): the
    // expected null collisions per ray are bounded by 24 * 16 * sqrt(3) * 2.
    EXPECT_LT(double(c.tentativeCollisions) / double(c.rays), 24 * 16 * 1.8 * 2) << toString(t);
    // Pixel centres x + 0.5 in film index units [0, 23]: 23 pixels of one
    // index unit. Pixels whose rays pass through voxels 9..14 (away from the
    // 0.5 iso-surface at 7.5 and 15.5 by more than a voxel) are opaque.
    for (int y = 0; y < 23; ++y)
      for (int x = 0; x < 23; ++x)
      {
        const float* px = img.at(x, y);
        const bool inside = x >= 9 && x <= 14 && y >= 9 && y <= 14;
        const bool outside = x <= 5 || x >= 18 || y <= 5 || y >= 18;
        if (inside)
        {
          EXPECT_EQ(px[3], 1.f) << toString(t) << " at " << x << "," << y;
          EXPECT_NEAR(px[0], 0.9f, 1e-6);
        }
        if (outside)
        {
          EXPECT_EQ(px[3], 0.f) << toString(t) << " at " << x << "," << y;
        }
      }
  }
}

// A transfer-function range of zero width at 1e8 (a constant channel) or of
// 1e-37 (narrower than float resolution) would give an infinite table scale,
// NaN texel coordinates and an out-of-bounds read in the majorant build if
// taken as is. The majorants stay finite, and the voxels render with the
// table's opacity (alpha > 0), for both cases.
TEST(HardCases, DegenerateTransferFunctionRange)
{
  struct Case
  {
    const char* name;
    float value;
    double lo, hi;
  };
  for (const Case& k : { Case{ "constant 1e8", 1e8f, 1e8, 1e8 }, Case{ "width 1e-37", 1e-37f, 0.0, 1e-37 } })
  {
    TestVolume v(8, 8, 8, 1, k.value);
    TransferFunctionDesc tf = flatTF(0.5f, 1.f, 1.f, 1.f, 1.f, 16);
    tf.scalarMin = k.lo;
    tf.scalarMax = k.hi;
    Scene scene;
    configure(scene, v, { tf }, 4);
    for (float m : scene.majorants())
    {
      ASSERT_TRUE(std::isfinite(m) && m > 0.f) << k.name;
    }
    EXPECT_TRUE(std::isfinite(scene.view().tables.scale[0])) << k.name;
    const double spacing[3] = { 1, 1, 1 };
    const Camera cam = axisCamera(2, v.dims, spacing, 1.0, 6.0, 4, 4);
    const Image img = render(scene, cam, Tracker::OneDDA, 16, 1);
    EXPECT_GT(expectFinite(img, k.name), 0.5) << k.name; // 8 voxels at opacity 0.5 each
  }
}

// Float64 data far from zero: 1e9 + i along x. With the channel's offset set
// to 1e9 the per-ray code sees i (float would quantise 1e9 + i to steps of
// 64), and a transfer function that is transparent below 1e9 + 20 leaves the
// macrocells there empty.
TEST(HardCases, Float64FarFromZeroKeepsResolution)
{
  const int dims[3] = { 40, 4, 4 };
  std::vector<double> data(size_t(dims[0]) * dims[1] * dims[2]);
  for (size_t p = 0; p < data.size(); ++p)
  {
    data[p] = 1e9 + double(p % size_t(dims[0]));
  }
  ChannelSource src;
  src.data = data.data();
  src.type = ScalarType::Float64;
  src.offset = 1e9;
  Scene scene;
  scene.setVolume(dims, 1, &src);
  TransferFunctionDesc tf = flatTF(0.f, 1.f, 1.f, 1.f, 1.f, 40);
  tf.scalarMin = 1e9;
  tf.scalarMax = 1e9 + 39;
  for (int i = 20; i < 40; ++i)
  {
    tf.opacity[size_t(i)] = 0.9f;
  }
  scene.setTransferFunction(0, tf);
  scene.setMacrocellSize(4);
  scene.update();
  for (int i = 0; i < dims[0] - 1; i += 3)
  {
    EXPECT_NEAR(sampleChannel(scene.view().volume, 0, Vec3f(float(i) + 0.25f, 1.f, 1.f)), i + 0.25, 1e-4);
  }
  // Cells over x in [0, 16] (voxels up to 17 with padding) are empty.
  const GridView& g = scene.view().grid;
  for (int cx = 0; cx < 4; ++cx)
  {
    EXPECT_EQ(g.majorants[size_t(cx)], 0.f) << "cell " << cx;
  }
  EXPECT_GT(g.majorants[size_t(g.dims[0] - 1)], 0.f);
  // An offset on a non-double channel is refused.
  ChannelSource bad = src;
  bad.type = ScalarType::Float32;
  EXPECT_THROW(scene.setVolume(dims, 1, &bad), std::invalid_argument);
}

// The lit estimators on the hard cases: one light with ratio shadows and
// ambient 0.3, albedo 0.7. Opacity 1 (every first tentative collision real),
// a volume with NaN and Inf voxels, and a single voxel: the expected-value
// estimator of lit camera rays (traceLitExpected()) and the collision
// estimator give the same image (expectSameMean, 3 scenes x 12 checks;
// 128 one-sample renders each, independent seeds); every value finite.
// All-zero opacity: both give a transparent image with no work at all.
TEST(HardCases, LitEstimatorsAgree)
{
  const double alpha = kAlpha / 36;
  const float nan = std::numeric_limits<float>::quiet_NaN(), inf = std::numeric_limits<float>::infinity();
  LightingDesc ld;
  LightDesc sun;
  sun.vector[0] = 0.3;
  sun.vector[1] = 0.5;
  sun.vector[2] = 1;
  sun.intensity = 2;
  ld.lights = { sun };
  ld.ambient[0] = ld.ambient[1] = ld.ambient[2] = 0.3;
  ld.albedo = { 0.7f };
  ld.anisotropy = { 0.3f };
  const double spacing[3] = { 1, 1, 1 };
  std::unique_ptr<Renderer> r = testRenderer();
  RenderSettings ev;
  ev.estimator = Estimator::ExpectedValue;
  RenderSettings col = ev;
  col.estimator = Estimator::Collision;
  auto compare = [&](const Scene& scene, const Camera& cam, const std::string& what)
  {
    ASSERT_TRUE(scene.lit()) << what;
    const Moments A = renderMoments(*r, scene, cam, ev, 128, 300);
    const Moments B = renderMoments(*r, scene, cam, col, 128, 900);
    double lit = 0;
    for (size_t i = 0; i < A.size(); ++i)
    {
      EXPECT_TRUE(std::isfinite(A.mean(i)) && std::isfinite(B.mean(i))) << what;
      lit += i % 4 == 3 ? 0.0 : A.mean(i);
    }
    EXPECT_GT(lit, 0.0) << what << ": the scene is lit and visible";
    expectSameMean(A, B, alpha, what + ": lit expected value against collision");
  };
  {
    TestVolume v(8, 8, 17, 1, 0.5f);
    Scene scene;
    configure(scene, v, { flatTF(1.f, 0.2f, 0.4f, 0.6f, 2.f) }, 4);
    scene.setLighting(ld);
    compare(scene, axisCamera(2, v.dims, spacing, -1.5, 8.5, 10, 10), "opacity 1");
  }
  {
    TestVolume v(16, 16, 16, 1, 1.f);
    for (int k = 0; k < 16; ++k)
      for (int j = 0; j < 16; ++j)
        for (int i = 0; i < 16; ++i)
        {
          if (i <= 6)
            v.channels[0][v.index(i, j, k)] = nan;
          else if (i >= 9 && j == 12)
            v.channels[0][v.index(i, j, k)] = inf;
        }
    Scene scene;
    configure(scene, v, { flatTF(opacityFor(0.1, 1.0), 0.3f, 0.6f, 0.9f, 1.f, 2, 0.f, 2.f) }, 4);
    scene.setLighting(ld);
    compare(scene, axisCamera(2, v.dims, spacing, 0, 15, 12, 12), "NaN and Inf voxels");
  }
  {
    TestVolume v(1, 1, 1, 1, 0.5f);
    Scene scene;
    configure(scene, v, { flatTF(0.5f, 1, 1, 1) }, 8);
    scene.setLighting(ld);
    compare(scene, orbitCamera(v.dims, spacing, 12, 12, 35, 25), "single voxel");
  }
  {
    TestVolume v(8, 8, 17, 2, 0.5f);
    Scene scene;
    configure(scene, v, { flatTF(0.f, 1, 0, 0), flatTF(0.f, 0, 1, 0) }, 4);
    LightingDesc two = ld;
    two.albedo = { 0.7f, 0.7f };
    two.anisotropy = { 0.3f, 0.3f };
    scene.setLighting(two);
    const Camera cam = axisCamera(2, v.dims, spacing, -1, 8, 10, 10);
    for (Estimator e : { Estimator::ExpectedValue, Estimator::Collision })
    {
      RenderCounters c;
      const Image img = render(scene, cam, Tracker::OneDDA, 4, 1, &c, true, e);
      for (float x : img.px)
      {
        EXPECT_EQ(x, 0.f) << "zero opacity, " << toString(e);
      }
      EXPECT_EQ(c.tentativeCollisions + c.channelSamples + c.scatteringEvents + c.shadowRays, 0u) << toString(e);
    }
  }
}
