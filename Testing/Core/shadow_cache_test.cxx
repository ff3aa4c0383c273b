// SPDX-License-Identifier: BSD-3-Clause
// Cached shadows (LightingDesc::cacheShadows, mcvol/ray/ShadowCache.h): the
// grid against the analytic transmittance of homogeneous slabs, its hard
// cases, Monte Carlo with the cache against the ray marcher with the same
// cache, the rays it saves, and when it is rebuilt.
//
// Significance: each TEST has a family-wise level kAlpha = 0.001, split
// evenly (Bonferroni) over its statistical checks; seeds are fixed.
#include "TestUtil.h"

#include "mcvol/HostShadowCache.h"
#include "mcvol/RayMarcher.h"
#include "mcvol/RenderSetup.h"
#include "mcvol/ray/Lighting.h"

#include <cmath>

using namespace mcvol;
using namespace mcvol::test;

namespace
{
constexpr double kAlpha = 1e-3;

/// A directional light towards (x, y, z).
LightDesc sunTowards(double x, double y, double z, double intensity = 1.0)
{
  LightDesc l;
  l.vector[0] = x;
  l.vector[1] = y;
  l.vector[2] = z;
  l.intensity = intensity;
  return l;
}

/// A camera whose worldToIndex has voxel spacing `spacing` (origin 0): the
/// lighting frame of the cache's tests.
Camera cameraWithSpacing(const double spacing[3])
{
  Camera cam = orthoAlongZ(4, 4, 0, 1, 0, 1, 100, 200);
  const double origin[3] = { 0, 0, 0 };
  setWorldToIndex(cam, spacing, origin);
  return cam;
}

/// The view of `scene` lit by `light` with cached shadows at `spacing`
/// voxels, its grid filled by `cache`.
SceneView cachedView(
  Scene& scene, const Camera& cam, const LightDesc& light, float spacing, HostShadowCache& cache)
{
  LightingDesc ld;
  ld.lights = { light };
  ld.cacheShadows = true;
  ld.cacheSpacing = spacing;
  scene.setLighting(ld);
  SceneView s = scene.view();
  setLightingFrame(s, cam);
  cache.prepare(scene, s, 0);
  return s;
}

/// exp(-sigma t), t the world length of the ray from index point x towards
/// the light (index direction dl) inside the box: the exact transmittance
/// of a homogeneous box of extinction sigma per world unit.
double exactSlab(const SceneView& s, Vec3f x, Vec3f dl, double sigma)
{
  float t0 = 0.f, t1 = 3.4e38f;
  if (!intersectBox(s.volume.boxLo, s.volume.boxHi, x, dl, t0, t1))
  {
    return 1.0;
  }
  return std::exp(-sigma * double(t1 - t0));
}

/// Largest and mean absolute difference between the cached transmittance and
/// the exact one (exactSlab), over `points` random points of the box, or
/// (`nodes`) at every node of the grid.
struct SlabError
{
  double largest = 0, mean = 0;
  bool finite = true;
};

SlabError slabError(const SceneView& s, double sigma, int points, uint64_t seed, bool nodes = false)
{
  const LightingView& L = s.lighting;
  const Vec3f dl = shadowCacheDirection(L, 0);
  const ShadowCacheFrame f = ShadowCacheFrame::of(s.volume, dl, L.cacheSpacing);
  TestRand r(seed);
  SlabError e;
  const int count = nodes ? int(f.nodes()) : points;
  for (int i = 0; i < count; ++i)
  {
    Vec3f x;
    if (nodes)
    {
      const int a = i % f.dims[0], b = (i / f.dims[0]) % f.dims[1], c = i / (f.dims[0] * f.dims[1]);
      x = f.origin + f.axis[0] * (float(a) * f.step[0]) + f.axis[1] * (float(b) * f.step[1]) +
        f.axis[2] * (float(c) * f.step[2]);
    }
    else
    {
      for (int a = 0; a < 3; ++a)
      {
        x[a] = float(s.volume.boxLo[a] + r.uniform() * (s.volume.boxHi[a] - s.volume.boxLo[a]));
      }
    }
    const double T = cachedTransmittance(L, 0, x);
    e.finite = e.finite && std::isfinite(T) && T >= 0.0 && T <= 1.0;
    const double d = std::fabs(T - exactSlab(s, x, dl, sigma));
    e.largest = std::max(e.largest, d);
    e.mean += d / count;
  }
  return e;
}
} // namespace

// A homogeneous box of extinction sigma per voxel, lit along an axis,
// obliquely, and grazing (2 degrees off its faces), at node spacings h of
// 0.5 to 5 voxels and voxel spacings of 1, anisotropic (1, 2, 0.5), tiny
// (1e-4) and huge (1e4) world units (the transfer function's unit distance
// scaled with them).
// - At the grid's nodes, on rays towards the light, the value is exact up
//   to the midpoint rule where the ray crosses the box's faces: within
//   sigma dt, dt the rule's step (a wrong axis, direction, origin or scale
//   is off by tens of percent).
// - Between nodes a light along an axis changes only along the rays: within
//   (sigma h)^2 / 8 + sigma dt. An oblique light's exit distance bends where
//   the face it leaves through changes, with a jump in its lateral slope of
//   up to 1 / sin(theta) (theta the least angle between the light and a face
//   it crosses): linear interpolation across rays is then off by at most a
//   quarter of sigma h / sin(theta), the blur of a shadow edge.
TEST(ShadowCache, SlabTransmittanceIsAnalytic)
{
  const double sigma = 0.12; // per voxel along x
  const std::vector<std::array<double, 3>> voxelSpacings = { { 1, 1, 1 }, { 1, 2, 0.5 }, { 1e-4, 1e-4, 1e-4 },
    { 1e4, 1e4, 1e4 } };
  const std::vector<LightDesc> lights = { sunTowards(0, 0, 1), sunTowards(0, 0, -1), sunTowards(1, 2, 0.5),
    sunTowards(-1, 0.3, -0.2), sunTowards(1, 0, std::tan(2.0 * M_PI / 180.0)) };
  for (const std::array<double, 3>& sp : voxelSpacings)
  {
    TestVolume v(23, 17, 11, 1, 1.f);
    Scene scene;
    const double unit = sp[0];
    configure(scene, v, { flatTF(opacityFor(sigma, 1.0), 1, 1, 1, float(unit)) }, 4);
    const Camera cam = cameraWithSpacing(sp.data());
    const double sigmaWorld = sigma / unit;
    for (float spacing : { 0.5f, 2.f, 5.f })
    {
      for (size_t l = 0; l < lights.size(); ++l)
      {
        HostShadowCache cache;
        const SceneView s = cachedView(scene, cam, lights[l], spacing, cache);
        ASSERT_NE(s.lighting.shadowCache[0], nullptr);
        ASSERT_EQ(cache.lastRebuilt(), 1);
        const Vec3f dl = shadowCacheDirection(s.lighting, 0);
        const ShadowCacheFrame f = ShadowCacheFrame::of(s.volume, dl, spacing);
        // The rule's step in world units and the optical depths it spans.
        const double dlLength = std::sqrt(double(dot(dl, dl)));
        const double dtWorld = f.step[2] / std::ceil(f.step[2] * kShadowCacheSamplesPerVoxel) / dlLength;
        const double rule = sigmaWorld * dtWorld + 1e-4;
        double hWorld = 0, sinTheta = 1;
        for (int a = 0; a < 3; ++a)
        {
          hWorld = std::max(hWorld, double(f.step[a]) / dlLength);
          // The light's unit world direction against face a's normal (world = index * spacing).
          const double c = std::fabs(double(dl[a]) * sp[size_t(a)]);
          if (c > 1e-6)
          {
            sinTheta = std::min(sinTheta, c);
          }
        }
        const bool axial = (lights[l].vector[0] == 0) + (lights[l].vector[1] == 0) + (lights[l].vector[2] == 0) == 2;
        const double across = axial ? 0.0 : sigmaWorld * hWorld / (4 * sinTheta);
        const double along = sigmaWorld * hWorld * sigmaWorld * hWorld / 8;
        const SlabError atNodes = slabError(s, sigmaWorld, 0, 0, true);
        const SlabError between = slabError(s, sigmaWorld, 2000, 17 + l);
        std::printf("voxel spacing (%g, %g, %g), node spacing %.1f, light %zu: at nodes %.5f (bound %.5f); "
                    "between, largest %.5f, mean %.5f (bound %.5f)\n",
          sp[0], sp[1], sp[2], spacing, l, atNodes.largest, rule, between.largest, between.mean,
          rule + along + across);
        EXPECT_TRUE(atNodes.finite && between.finite);
        EXPECT_LT(atNodes.largest, rule) << "light " << l << ", node spacing " << spacing;
        EXPECT_LT(between.largest, rule + along + across) << "light " << l << ", node spacing " << spacing;
      }
    }
  }
}

// The hard cases: opacity 1 (transmittance 0 a voxel inside, finite
// everywhere), opacity 0 (exactly 1), NaN and infinite voxels (finite, in
// [0, 1]; NaN counts as empty as it does for the trackers), and a volume of
// one voxel (a grid of 2 x 2 x 2 nodes over its box, the slab's value).
TEST(ShadowCache, HardCasesStayFinite)
{
  const double spacing[3] = { 1, 1, 1 };
  const Camera cam = cameraWithSpacing(spacing);
  const LightDesc sun = sunTowards(1, 2, 0.5);
  {
    TestVolume v(12, 12, 12, 1, 1.f);
    Scene scene;
    configure(scene, v, { flatTF(1.f, 1, 1, 1) }, 4);
    HostShadowCache cache;
    const SceneView s = cachedView(scene, cam, sun, 2.f, cache);
    // The node one voxel inside the far corner's faces, whose way to the light
    // runs through at least a voxel: no light.
    const float T = cachedTransmittance(s.lighting, 0, Vec3f(2.f, 2.f, 2.f));
    EXPECT_EQ(T, 0.f) << "opacity 1";
    const SlabError e = slabError(s, 0.0, 500, 3);
    EXPECT_TRUE(e.finite) << "opacity 1";
  }
  {
    TestVolume v(12, 12, 12, 1, 1.f);
    Scene scene;
    configure(scene, v, { flatTF(0.f, 1, 1, 1) }, 4);
    HostShadowCache cache;
    const SceneView s = cachedView(scene, cam, sun, 2.f, cache);
    const SlabError e = slabError(s, 0.0, 500, 4);
    EXPECT_TRUE(e.finite);
    EXPECT_EQ(e.largest, 0.0) << "opacity 0: exactly 1 everywhere";
  }
  {
    TestVolume v(12, 12, 12, 1, 1.f);
    for (size_t i = 0; i < v.voxels(); i += 3)
    {
      v.channels[0][i] = i % 2 ? std::numeric_limits<float>::quiet_NaN() : std::numeric_limits<float>::infinity();
    }
    Scene scene;
    configure(scene, v, { flatTF(opacityFor(0.2, 1.0), 1, 1, 1) }, 4);
    HostShadowCache cache;
    const SceneView s = cachedView(scene, cam, sun, 2.f, cache);
    const SlabError e = slabError(s, 0.0, 500, 5);
    EXPECT_TRUE(e.finite) << "NaN and infinite voxels";
  }
  {
    TestVolume v(1, 1, 1, 1, 1.f);
    Scene scene;
    configure(scene, v, { flatTF(opacityFor(0.3, 1.0), 1, 1, 1) }, 4);
    HostShadowCache cache;
    const SceneView s = cachedView(scene, cam, sunTowards(0, 0, 1), 2.f, cache);
    EXPECT_EQ(s.lighting.cacheDims[0][0], 2);
    EXPECT_EQ(s.lighting.cacheDims[0][1], 2);
    EXPECT_EQ(s.lighting.cacheDims[0][2], 2);
    // Exact at the nodes (the light along z), linear between them.
    EXPECT_NEAR(cachedTransmittance(s.lighting, 0, Vec3f(0.5f, -0.5f, -0.5f)), std::exp(-0.3), 1e-5);
    EXPECT_EQ(cachedTransmittance(s.lighting, 0, Vec3f(-0.5f, 0.5f, 0.5f)), 1.f);
    const SlabError e = slabError(s, 0.3, 500, 6);
    EXPECT_TRUE(e.finite);
    EXPECT_LT(e.largest, 0.3 * 0.3 / 8 + 1e-4) << "one voxel";
  }
}

// Monte Carlo with cached shadows converges to the ray marcher with the same
// cache (both look up one grid): density, max and mix, the collision and the
// expected-value estimators, a directional light alone (every shadow cached:
// no shadow ray at all, the local kernels) and with a point light (whose
// shadow rays are tracked, one per scattering event). Per mode, estimator
// and light set, a z-test per RGBA component on the image-mean difference:
// 3 x 2 x 2 x 4 = 48 tests.
TEST(ShadowCache, MonteCarloMatchesTheMarchWithTheSameCache)
{
  const double alpha = kAlpha / 48;
  const DemoVolume v = makeDemo("cosmology", { 20, 20, 20 });
  const Camera cam = orbitCamera(v.dims, v.spacing, 16, 16, 30, 20);
  for (BlendMode mode : { BlendMode::Density, BlendMode::Max, BlendMode::Mix })
  {
    for (bool lamp : { false, true })
    {
      Scene scene;
      configureDemo(scene, v, 4, 128, 0.5, mode);
      LightingDesc ld;
      ld.lights = { testSun(1.5) };
      if (lamp)
      {
        ld.lights.push_back(testLamp(400));
      }
      ld.albedo = { 0.9f, 0.6f, 0.8f, 0.3f };
      ld.anisotropy = { 0.4f, 0.4f, 0.4f, 0.4f };
      ld.maxDepth = 1;
      ld.cacheShadows = true;
      ld.cacheSpacing = 1.5f;
      scene.setLighting(ld);
      RayMarcher rm;
      Accumulator ref;
      MarchSettings ms;
      ms.step = 0.125;
      ms.terminateTransmittance = 0.f;
      rm.render(scene, cam, ms, nullptr, ref);
      // The tracked shadows differ from the cached ones by the grid's bias:
      // the march without the cache, for scale.
      LightingDesc tracked = ld;
      tracked.cacheShadows = false;
      const std::unique_ptr<Renderer> r = testRenderer();
      for (Estimator est : { Estimator::Collision, Estimator::ExpectedValue })
      {
        const int K = 48;
        const size_t P = size_t(cam.width) * cam.height * 4;
        std::vector<double> sum(P, 0.0), sumSq(P, 0.0);
        RenderCounters c;
        for (int k = 0; k < K; ++k)
        {
          Accumulator acc;
          RenderSettings rs;
          rs.samplesPerPixel = 32;
          rs.jitterPixels = false;
          rs.estimator = est;
          rs.seed = uint32_t(900 + k);
          r->render(scene, cam, rs, nullptr, acc, &c);
          for (size_t i = 0; i < P; ++i)
          {
            sum[i] += acc.rgba()[i];
            sumSq[i] += double(acc.rgba()[i]) * acc.rgba()[i];
          }
        }
        const char* what = est == Estimator::Collision ? "collision" : "expected value";
        if (lamp)
        {
          // The lamp's shadow rays alone (every light sampled).
          EXPECT_GT(c.shadowRays, 0u) << what;
          EXPECT_LE(c.shadowRays, c.scatteringEvents) << what << ": one ray per vertex, for the lamp";
        }
        else
        {
          EXPECT_EQ(c.shadowRays, 0u) << what << ": every shadow cached";
        }
        std::array<double, 4> diff{};
        const std::array<double, 4> z = imageMeanZ(sum, sumSq, K, ref.rgba(), &diff);
        for (int ch = 0; ch < 4; ++ch)
        {
          std::printf("%s, %s, %s: component %d, image-mean difference %.5f, z = %.2f\n", toString(mode),
            lamp ? "sun and lamp" : "sun", what, ch, diff[size_t(ch)], z[size_t(ch)]);
          EXPECT_GT(normalTwoSided(z[size_t(ch)]), alpha) << toString(mode) << " " << what << " component " << ch;
        }
      }
    }
  }
}

// The cached image is close to the tracked one: the march with the cache at
// node spacing 1 against the march without it, on the lit cosmology scene
// whose shadows cover most of the image. The RMS difference is a small part
// of the shadows' own effect (the march without shadows against with).
TEST(ShadowCache, CachedShadowsAreCloseToTrackedOnes)
{
  const DemoVolume v = makeDemo("cosmology", { 24, 24, 24 });
  const Camera cam = orbitCamera(v.dims, v.spacing, 24, 24, 30, 20);
  Scene scene;
  configureDemo(scene, v, 4, 128, 0.5, BlendMode::Density);
  auto march = [&](bool shadows, bool cached) {
    LightingDesc ld;
    ld.lights = { testSun(1.5) };
    ld.albedo = { 0.9f, 0.6f, 0.8f, 0.3f };
    ld.shadows = shadows;
    ld.cacheShadows = cached;
    ld.cacheSpacing = 1.f;
    scene.setLighting(ld);
    RayMarcher rm;
    Accumulator out;
    MarchSettings ms;
    ms.step = 0.125;
    ms.terminateTransmittance = 0.f;
    rm.render(scene, cam, ms, nullptr, out);
    return std::vector<float>(out.rgba(), out.rgba() + size_t(cam.width) * cam.height * 4);
  };
  const std::vector<float> tracked = march(true, false);
  const std::vector<float> cached = march(true, true);
  const std::vector<float> unshadowed = march(false, false);
  auto rms = [](const std::vector<float>& a, const std::vector<float>& b) {
    double s = 0;
    for (size_t i = 0; i < a.size(); ++i)
    {
      s += (double(a[i]) - b[i]) * (double(a[i]) - b[i]);
    }
    return std::sqrt(s / double(a.size()));
  };
  const double bias = rms(cached, tracked);
  const double effect = rms(unshadowed, tracked);
  std::printf("RMS: cached against tracked %.5f, unshadowed against tracked %.5f\n", bias, effect);
  EXPECT_GT(effect, 0.01) << "the scene's shadows must matter for the test to mean anything";
  EXPECT_LT(bias, 0.1 * effect);
}

// The grid is filled once and kept: a second render rebuilds nothing; a new
// light direction, transfer function or node spacing rebuilds it, and the
// image then equals a fresh renderer's (bit for bit, same seed); turned
// off, it is freed. A point
// light and cacheShadows off build no grid (no memory), and so do
// post-render composite blending and a stand-in of other pieces.
TEST(ShadowCache, RebuiltWhenItsInputsChange)
{
  const DemoVolume v = makeDemo("cosmology", { 16, 16, 16 });
  const Camera cam = orbitCamera(v.dims, v.spacing, 12, 12, 30, 20);
  Scene scene;
  configureDemo(scene, v, 4, 128, 0.5, BlendMode::Density);
  LightingDesc ld;
  ld.lights = { testSun(1.5) };
  ld.cacheShadows = true;
  CPURenderer r;
  RenderSettings rs;
  rs.seed = 5;
  auto render = [&](CPURenderer& renderer) {
    Accumulator acc;
    renderer.render(scene, cam, rs, nullptr, acc);
    return std::vector<float>(acc.rgba(), acc.rgba() + size_t(cam.width) * cam.height * 4);
  };
  auto fresh = [&]() {
    CPURenderer other;
    return render(other);
  };
  scene.setLighting(ld);
  render(r);
  EXPECT_EQ(r.shadowCache().lastRebuilt(), 1);
  EXPECT_GT(r.shadowCache().bytes(), size_t(9 * 9 * 9) * sizeof(float)); // 15 voxels at spacing 2, turned
  render(r);
  EXPECT_EQ(r.shadowCache().lastRebuilt(), 0) << "nothing changed";
  ld.lights = { sunTowards(-1, 0.5, 2, 1.5) };
  scene.setLighting(ld);
  EXPECT_EQ(render(r), fresh()) << "new light direction";
  EXPECT_EQ(r.shadowCache().lastRebuilt(), 1) << "new light direction";
  TransferFunctionDesc tf = sampleTransferFunction(v.transferFunctions[0], v.range(0)[0], v.range(0)[1], 128, 0.25);
  scene.setTransferFunction(0, tf);
  scene.update();
  EXPECT_EQ(render(r), fresh()) << "new transfer function";
  EXPECT_EQ(r.shadowCache().lastRebuilt(), 1) << "new transfer function";
  ld.cacheSpacing = 4.f;
  scene.setLighting(ld);
  EXPECT_EQ(render(r), fresh()) << "new node spacing";
  EXPECT_EQ(r.shadowCache().lastRebuilt(), 1) << "new node spacing";
  // Turned off, the grid is freed; turned on again, filled again.
  LightingDesc tracked = ld;
  tracked.cacheShadows = false;
  scene.setLighting(tracked);
  render(r);
  EXPECT_EQ(r.shadowCache().bytes(), 0u) << "cached shadows turned off";
  scene.setLighting(ld);
  EXPECT_EQ(render(r), fresh()) << "cached shadows turned on again";
  EXPECT_EQ(r.shadowCache().lastRebuilt(), 1) << "cached shadows turned on again";

  // No grid where none is asked for or none applies.
  for (int variant = 0; variant < 3; ++variant)
  {
    CPURenderer other;
    LightingDesc l2 = ld;
    Scene* target = &scene;
    Scene composite;
    if (variant == 0)
    {
      l2.cacheShadows = false;
    }
    else if (variant == 1)
    {
      l2.lights = { testLamp(400) };
    }
    else
    {
      configureDemo(composite, v, 4, 128, 0.5, BlendMode::Composite);
      target = &composite;
    }
    target->setLighting(l2);
    Accumulator acc;
    RenderCounters c;
    other.render(*target, cam, rs, nullptr, acc, &c);
    EXPECT_EQ(other.shadowCache().bytes(), 0u) << "variant " << variant;
    EXPECT_EQ(c.shadowRays, c.scatteringEvents) << "variant " << variant << ": its shadow rays are tracked";
  }
  Scene lower, whole;
  configureDemo(lower, v, 4, 128, 0.5, BlendMode::Density);
  configureDemo(whole, v, 4, 128, 0.5, BlendMode::Density);
  lower.setLighting(ld);
  whole.setLighting(ld);
  lower.setOutside(&whole);
  CPURenderer other;
  Accumulator acc;
  RenderCounters c;
  other.render(lower, cam, rs, nullptr, acc, &c);
  EXPECT_EQ(other.shadowCache().bytes(), 0u) << "a piece with a stand-in";
  EXPECT_GT(c.shadowRays, 0u) << "a piece with a stand-in tracks its shadow rays";
}

// A node spacing outside [0.5, 64] voxels is an error that names it.
TEST(ShadowCache, BadSpacingIsAnError)
{
  Scene scene;
  for (float bad : { 0.f, 0.25f, 65.f, std::numeric_limits<float>::quiet_NaN() })
  {
    LightingDesc ld;
    ld.lights = { testSun(1) };
    ld.cacheShadows = true;
    ld.cacheSpacing = bad;
    try
    {
      scene.setLighting(ld);
      ADD_FAILURE() << "spacing " << bad << " accepted";
    }
    catch (const std::invalid_argument& e)
    {
      EXPECT_NE(std::string(e.what()).find("node spacing"), std::string::npos) << e.what();
    }
  }
}
