// SPDX-License-Identifier: BSD-3-Clause
// View-dependent visibility optimization (Lerzer and Dachsbacher): the
// per-ray segment structure (Algorithm 1, Sec. 5.1-5.2) and the optimized
// extinction (Eq. 7-8) in Monte Carlo tracking and in the ray-marched
// baseline.
#include "TestUtil.h"

#include "mcvol/CPURenderer.h"
#include "mcvol/DemoData.h"
#include "mcvol/ray/Importance.h"
#include "mcvol/RayMarcher.h"

#include <cmath>
#include <cstdio>
#include <functional>
#include <vector>

using namespace mcvol;
using namespace mcvol::test;

namespace
{
constexpr double kAlpha = 1e-3;

Camera demoCam(const DemoVolume& v, int W, int H)
{
  return orbitCamera(v.dims, v.spacing, W, H, 30, 20);
}

ImportanceSegment sample(float t, float k)
{
  ImportanceSegment s;
  s.t = t;
  s.k = k;
  return s;
}

ImportanceSegment segment(float t, float length, float k)
{
  ImportanceSegment s = sample(t, k);
  s.length = length;
  return s;
}

/// Refines a list for `passes` passes of N samples of the step function k.
int refine(std::vector<ImportanceSegment>& seg, float T, int N, int passes, float d,
  const std::function<float(float)>& k, float& total, uint32_t seed = 1)
{
  seg.assign(kImportanceCapacity, ImportanceSegment());
  int count = 0;
  total = 0.f;
  for (int pass = 0; pass < passes; ++pass)
  {
    Rng rng(7, uint32_t(pass), seed);
    float pos[kMaxImportanceSamples];
    const int n = importanceSamplePositions(seg.data(), count, T, N, pass, rng, pos);
    std::vector<ImportanceSegment> samples;
    for (int i = 0; i < n; ++i)
    {
      samples.push_back(sample(pos[i], k(pos[i])));
    }
    const int merged =
      importanceMerge(seg.data(), count, kImportanceCapacity, samples.data(), int(samples.size()), d, T, total);
    EXPECT_GE(merged, 0) << "pass " << pass << " overflowed";
    if (merged >= 0)
    {
      count = merged;
    }
  }
  return count;
}

/// Two channels on a 16 x 16 x 32 grid along z: channel 0 (red) fills the
/// front half z < 16 (first met by a camera looking down -z from above), channel 1
/// (green) the back half; both with extinction `sigma`.
TestVolume occluderVolume()
{
  TestVolume v(16, 16, 32, 2, 0.f);
  for (int k = 0; k < 32; ++k)
  {
    for (int j = 0; j < 16; ++j)
    {
      for (int i = 0; i < 16; ++i)
      {
        const bool front = k >= 16; // the camera looks along -z from z > 31
        v.channels[0][v.index(i, j, k)] = front ? 1.f : 0.f;
        v.channels[1][v.index(i, j, k)] = front ? 0.f : 1.f;
      }
    }
  }
  return v;
}

/// Importance table of K texels over [0, 1]: `low` below 0.5, `high` above.
std::vector<float> stepTable(int K, float low, float high)
{
  std::vector<float> t(static_cast<size_t>(K));
  for (int i = 0; i < K; ++i)
  {
    t[size_t(i)] = float(i) / float(K - 1) < 0.5f ? low : high;
  }
  return t;
}

void setupOccluder(Scene& scene, const TestVolume& v, double sigma)
{
  const int K = 64;
  std::vector<TransferFunctionDesc> tfs;
  // Opacity ramps with the value: 0 at 0, full at 1 (unit distance 1).
  for (int n = 0; n < 2; ++n)
  {
    TransferFunctionDesc tf = flatTF(opacityFor(sigma, 1.0), n == 0 ? 1.f : 0.f, n == 1 ? 1.f : 0.f, 0.f, 1.f, K);
    for (int i = 0; i < K; ++i)
    {
      tf.opacity[size_t(i)] = opacityFor(sigma * double(i) / double(K - 1), 1.0);
    }
    tfs.push_back(tf);
  }
  configure(scene, v, tfs, 4);
}

Camera occluderCamera()
{
  return orthoAlongZ(16, 16, 0.5, 14.5, 0.5, 14.5, 40.0, 80.0);
}

/// Green share G / (R + G) of an image.
double greenShare(const Accumulator& acc)
{
  double r = 0, g = 0;
  const size_t P = size_t(acc.width()) * size_t(acc.height());
  for (size_t p = 0; p < P; ++p)
  {
    r += acc.rgba()[4 * p + 0];
    g += acc.rgba()[4 * p + 1];
  }
  return g / (r + g);
}
} // namespace

// Algorithm 1's cases, each on its own: merge, discard, split, insert, and a
// full list.
TEST(ImportanceSegments, Algorithm1Cases)
{
  ImportanceSegment list[4];
  ImportanceSegment later;
  bool hasLater = false;
  // Insert into an empty list (lines 1-4).
  int n = importanceInsert(list, 0, 4, sample(1.f, 1.f), 0.5f, later, hasLater);
  ASSERT_EQ(n, 1);
  EXPECT_FALSE(hasLater);
  // Merge: same importance within d of the end (lines 7-10).
  n = importanceInsert(list, n, 4, sample(1.4f, 1.f), 0.5f, later, hasLater);
  ASSERT_EQ(n, 1);
  EXPECT_FLOAT_EQ(list[0].t, 1.f);
  EXPECT_FLOAT_EQ(list[0].length, 0.4f);
  // Discard: same importance inside the segment (lines 11-13), nothing moves.
  n = importanceInsert(list, n, 4, sample(1.2f, 1.f), 0.5f, later, hasLater);
  ASSERT_EQ(n, 1);
  EXPECT_FLOAT_EQ(list[0].length, 0.4f);
  // Split: other importance inside (lines 15-20): the segment becomes its left
  // end, the candidate follows, the right end comes back for later.
  n = importanceInsert(list, n, 4, sample(1.3f, 0.25f), 0.5f, later, hasLater);
  ASSERT_EQ(n, 2);
  ASSERT_TRUE(hasLater);
  EXPECT_FLOAT_EQ(list[0].length, 0.f);
  EXPECT_FLOAT_EQ(list[1].t, 1.3f);
  EXPECT_FLOAT_EQ(list[1].k, 0.25f);
  EXPECT_FLOAT_EQ(later.t, 1.4f);
  EXPECT_FLOAT_EQ(later.k, 1.f);
  // Insert: same importance but farther than d (line 22).
  n = importanceInsert(list, n, 4, sample(2.f, 0.25f), 0.5f, later, hasLater);
  ASSERT_EQ(n, 3);
  EXPECT_FALSE(hasLater);
  // Full: no room, -1, and the list is untouched.
  n = importanceInsert(list, n, 4, sample(3.f, 1.f), 0.5f, later, hasLater);
  ASSERT_EQ(n, 4);
  EXPECT_EQ(importanceInsert(list, n, 4, sample(5.f, 0.f), 0.5f, later, hasLater), -1);
  EXPECT_FLOAT_EQ(list[3].t, 3.f);
}

// The merge of a stored list with new samples processes the split's right
// end in its turn, and a full result leaves the list as it was.
TEST(ImportanceSegments, MergeAndOverflow)
{
  std::vector<ImportanceSegment> seg(kImportanceCapacity);
  seg[0] = segment(0.f, 1.f, 1.f);
  float total = 0.f;
  const ImportanceSegment news[] = { sample(0.5f, 0.f) };
  const int n = importanceMerge(seg.data(), 1, kImportanceCapacity, news, 1, 0.01f, 2.f, total);
  ASSERT_EQ(n, 3);
  EXPECT_FLOAT_EQ(seg[0].t, 0.f);
  EXPECT_FLOAT_EQ(seg[0].length, 0.f);
  EXPECT_FLOAT_EQ(seg[1].t, 0.5f);
  EXPECT_FLOAT_EQ(seg[2].t, 1.f);
  EXPECT_FLOAT_EQ(seg[2].k, 1.f);
  // Integral: gaps take the mean of their neighbours, the last gap to T
  // half the last importance: [0,0.5]: 0.5^2*0.5, [0.5,1]: 0.5^2*0.5,
  // [1,2]: 0.5^2*1.
  EXPECT_NEAR(total, 0.125f + 0.125f + 0.25f, 1e-6);

  // A list at capacity whose merge needs one more entry: -1, unchanged.
  std::vector<ImportanceSegment> full(kImportanceCapacity);
  for (int i = 0; i < kImportanceCapacity; ++i)
  {
    full[size_t(i)] = sample(float(i), (i % 2) ? 1.f : 0.f);
  }
  const std::vector<ImportanceSegment> before = full;
  const ImportanceSegment extra[] = { sample(100.f, 1.f) };
  float t2 = -1.f;
  EXPECT_EQ(importanceMerge(full.data(), kImportanceCapacity, kImportanceCapacity, extra, 1, 0.01f, 200.f, t2), -1);
  for (int i = 0; i < kImportanceCapacity; ++i)
  {
    EXPECT_EQ(full[size_t(i)].t, before[size_t(i)].t);
  }
  EXPECT_EQ(t2, -1.f);
}

// K(t) by binary search: inside a segment its value plus k^2 times the way in;
// in a gap the linear interpolation between its ends; before the first and
// after the last segment half the neighbour's importance.
TEST(ImportanceSegments, IntegralInSegmentsAndGaps)
{
  std::vector<ImportanceSegment> seg = { segment(1.f, 1.f, 1.f), segment(3.f, 1.f, 0.5f) };
  const float total = importanceIntegrals(seg.data(), 2, 6.f);
  // [0,1] gap k=0.5: 0.25; [1,2] k=1: 1; [2,3] gap k=0.75: 0.5625; [3,4] k=0.5:
  // 0.25; [4,6] gap k=0.25: 0.125.
  EXPECT_NEAR(seg[0].K, 0.25f, 1e-6);
  EXPECT_NEAR(seg[1].K, 0.25f + 1.f + 0.5625f, 1e-6);
  EXPECT_NEAR(total, 0.25f + 1.f + 0.5625f + 0.25f + 0.125f, 1e-6);
  EXPECT_NEAR(importanceIntegral(seg.data(), 2, 0.5f), 0.125f, 1e-6);
  EXPECT_NEAR(importanceIntegral(seg.data(), 2, 1.5f), 0.25f + 0.5f, 1e-6);
  EXPECT_NEAR(importanceIntegral(seg.data(), 2, 2.5f), 1.25f + 0.5f * 0.5625f, 1e-6);
  EXPECT_NEAR(importanceIntegral(seg.data(), 2, 3.5f), 1.8125f + 0.125f, 1e-6);
  EXPECT_NEAR(importanceIntegral(seg.data(), 2, 5.f), 2.0625f + 0.0625f, 1e-6);
  EXPECT_EQ(importanceIntegral(seg.data(), 0, 5.f), 0.f);
}

// Paper Fig. 7: a step function with narrow peaks (widths 0.01 to 0.05 on a
// ray of length 10). One uniform pass misses or blurs them; adaptive passes
// find their edges, and the error of the whole-ray integral falls to float
// precision, as does K at t = 5.
TEST(ImportanceSegments, NarrowPeaksConvergeToTheIntegral)
{
  const float T = 10.f;
  struct Peak
  {
    float a, b, k;
  };
  const Peak peaks[] = { { 2.f, 2.01f, 1.f }, { 4.5f, 4.55f, 0.5f }, { 7.3f, 7.33f, 1.f } };
  auto k = [&](float t)
  {
    for (const Peak& p : peaks)
    {
      if (t >= p.a && t <= p.b)
      {
        return p.k;
      }
    }
    return 0.f;
  };
  double exact = 0.0, exactAt5 = 0.0;
  for (const Peak& p : peaks)
  {
    exact += double(p.k) * p.k * (p.b - p.a);
    exactAt5 += p.b <= 5.f ? double(p.k) * p.k * (p.b - p.a) : 0.0;
  }
  std::vector<double> errors;
  for (int passes : { 1, 4, 16, 32, 64, 128 })
  {
    std::vector<ImportanceSegment> seg;
    float total = 0.f;
    const int n = refine(seg, T, 64, passes, 2.f * T / 62.f, k, total);
    const double err = std::fabs(double(total) - exact);
    errors.push_back(err);
    std::printf("passes %d: segments %d, |error| %.3g\n", passes, n, err);
    if (passes == 32)
    {
      EXPECT_LT(err, 2e-5 * exact) << "whole-ray integral after 32 passes";
      EXPECT_NEAR(importanceIntegral(seg.data(), n, 5.f), exactAt5, 2e-5 * exact) << "K(5)";
    }
  }
  EXPECT_GT(errors.front(), 100.0 * errors.back()) << "the error falls with refinement";
}

// Importance zero everywhere, or the optimization off: bit for bit the
// unoptimized image, with no importance sample taken.
TEST(Visibility, OffOrZeroImportanceIsTheUnoptimizedImage)
{
  const TestVolume v = occluderVolume();
  const Camera cam = occluderCamera();
  RenderSettings rs;
  rs.samplesPerPixel = 8;
  rs.seed = 11;
  auto renderWith = [&](const ImportanceDesc* imp, RenderCounters& counters)
  {
    Scene scene;
    setupOccluder(scene, v, 0.3);
    if (imp)
    {
      scene.setImportance(*imp);
      scene.update();
    }
    std::unique_ptr<Renderer> r = testRenderer();
    Accumulator acc;
    r->render(scene, cam, rs, nullptr, acc, &counters);
    r->render(scene, cam, rs, nullptr, acc, &counters);
    return std::vector<float>(acc.rgba(), acc.rgba() + 4 * 16 * 16);
  };
  RenderCounters c0, c1, c2;
  const std::vector<float> plain = renderWith(nullptr, c0);
  ImportanceDesc off;
  off.enabled = false;
  off.tables = { {}, stepTable(64, 0.f, 1.f) };
  const std::vector<float> offImage = renderWith(&off, c1);
  ImportanceDesc zero;
  zero.enabled = true;
  zero.tables = { stepTable(64, 0.f, 0.f), stepTable(64, 0.f, 0.1f) }; // 0.1 snaps to 0
  const std::vector<float> zeroImage = renderWith(&zero, c2);
  EXPECT_EQ(plain, offImage);
  EXPECT_EQ(plain, zeroImage);
  EXPECT_EQ(c0.importanceSamples, 0u);
  EXPECT_EQ(c1.importanceSamples, 0u);
  EXPECT_EQ(c2.importanceSamples, 0u);
  EXPECT_EQ(c0.tentativeCollisions, c2.tentativeCollisions);
}

// The important (green) back slab behind the red occluder: the optimization
// raises its share of the image by at least 10x (measured 0.0095 -> 0.90), and a
// deviation weight p -> infinity gives the unoptimized image back.
TEST(Visibility, ImportantChannelShowsThroughTheOccluder)
{
  const TestVolume v = occluderVolume();
  const Camera cam = occluderCamera();
  RenderSettings rs;
  rs.samplesPerPixel = 256;
  rs.seed = 5;
  auto share = [&](const ImportanceDesc* imp, std::vector<float>* image)
  {
    Scene scene;
    setupOccluder(scene, v, 0.3);
    if (imp)
    {
      scene.setImportance(*imp);
      scene.update();
    }
    std::unique_ptr<Renderer> r = testRenderer();
    Accumulator acc;
    r->render(scene, cam, rs, nullptr, acc);
    if (image)
    {
      image->assign(acc.rgba(), acc.rgba() + 4 * 16 * 16);
    }
    return greenShare(acc);
  };
  std::vector<float> plainImage, hugePImage;
  const double plain = share(nullptr, &plainImage);
  ImportanceDesc imp;
  imp.enabled = true;
  imp.tables = { {}, stepTable(64, 0.f, 1.f) };
  const double optimized = share(&imp, nullptr);
  std::printf("green share: unoptimized %.4f, optimized %.4f (%.2fx)\n", plain, optimized, optimized / plain);
  EXPECT_GT(optimized, 10.0 * plain) << "green share " << plain << " -> " << optimized;
  imp.p = 1e7;
  share(&imp, &hugePImage);
  double maxDiff = 0.0;
  for (size_t i = 0; i < plainImage.size(); ++i)
  {
    maxDiff = std::max(maxDiff, std::fabs(double(plainImage[i]) - double(hugePImage[i])));
  }
  // p = 1e7 moves mu' from mu by about 1e-5 relative; with 256 samples a
  // pixel changes only if one decision flips (probability ~1e-5 each).
  EXPECT_LT(maxDiff, 2.0 / 256.0);
}

// Monte Carlo with the optimized extinction converges to the ray-marched
// optimization. The importance is constant along every ray (a channel of
// constant value mapped to 0.5), so the pixel's segment list is exact after
// its first pass and the only differences are noise and the march's step.
// Each blend mode at family-wise significance kAlpha.
TEST(Visibility, MonteCarloConvergesToTheOptimizedRayMarch)
{
  const double alpha = kAlpha / (4 * 4 * 3);
  const int N = 2048;
  const DemoVolume v = makeDemo("figure3", { 24, 24, 24 });
  const Camera cam = demoCam(v, 32, 32);
  for (BlendMode mode : { BlendMode::Density, BlendMode::Max, BlendMode::Mix, BlendMode::Composite })
  {
    Scene scene;
    configureDemo(scene, v, 4, 128, 1.0, mode);
    ImportanceDesc imp;
    imp.enabled = true;
    imp.tables.assign(size_t(v.numChannels()), std::vector<float>());
    imp.tables[0].assign(128, 0.5f);
    scene.setImportance(imp);
    scene.update();
    ASSERT_TRUE(scene.optimized());
    MarchSettings ms;
    ms.step = 1.0 / 16.0;
    ms.terminateTransmittance = 0.f;
    RayMarcher marcher;
    Accumulator refAcc;
    marcher.render(scene, cam, ms, nullptr, refAcc);
    const std::vector<float> ref(refAcc.rgba(), refAcc.rgba() + 4 * 32 * 32);
    // Without the optimization the image is brighter: the test has power.
    Scene plainScene;
    configureDemo(plainScene, v, 4, 128, 1.0, mode);
    Accumulator plainAcc;
    marcher.render(plainScene, cam, ms, nullptr, plainAcc);
    double sumRef = 0, sumPlain = 0;
    for (size_t i = 3; i < ref.size(); i += 4)
    {
      sumRef += ref[i];
      sumPlain += plainAcc.rgba()[i];
    }
    EXPECT_LT(sumRef, 0.8 * sumPlain) << toString(mode) << ": the optimization should thin the occluders";

    std::unique_ptr<Renderer> mc = testRenderer();
    Accumulator acc;
    RenderSettings rs;
    rs.jitterPixels = false;
    rs.samplesPerPixel = N;
    rs.seed = 77;
    RenderCounters counters;
    mc->render(scene, cam, rs, nullptr, acc, &counters);
    EXPECT_GT(counters.importanceSamples, 0u);
    const std::string what = std::string(toString(mode)) + " optimized MC vs optimized ray march";
    const double top = mode == BlendMode::Composite ? double(scene.view().numActive) : 1.0;
    std::vector<double> D, V;
    for (size_t i = 0; i < ref.size(); ++i)
    {
      const double M = i % 4 == 3 ? 1.0 : top;
      const double mu = std::min(M, std::max(0.0, double(ref[i])));
      const double var = mu * (M - mu) / N;
      const bool enough = N * mu * (M - mu) >= 100.0;
      D.push_back(enough ? double(acc.rgba()[i]) - double(ref[i]) : 0.0);
      V.push_back(enough ? var : 0.0);
    }
    expectZeroDifference(D, V, alpha, what);
  }
}

// A fixed seed gives the same optimized image whatever the thread count
// (the refinement samples draw from per-pixel streams); on the CUDA backend
// the same image run after run.
TEST(Visibility, SameSeedSameImageAnyThreadCount)
{
  const TestVolume v = occluderVolume();
  const Camera cam = occluderCamera();
  Scene scene;
  setupOccluder(scene, v, 0.3);
  ImportanceDesc imp;
  imp.enabled = true;
  imp.tables = { {}, stepTable(64, 0.f, 1.f) };
  scene.setImportance(imp);
  scene.update();
  RenderSettings rs;
  rs.samplesPerPixel = 4;
  rs.seed = 3;
  std::vector<std::vector<float>> images;
  for (int threads : { 1, 2, 3 })
  {
    std::unique_ptr<Renderer> r = testRenderer(threads);
    Accumulator acc;
    for (int k = 0; k < 5; ++k)
    {
      r->render(scene, cam, rs, nullptr, acc);
    }
    images.emplace_back(acc.rgba(), acc.rgba() + 4 * 16 * 16);
    EXPECT_EQ(acc.importancePoolIfAny().passes, 4) << "one uniform and three adaptive passes";
    EXPECT_GT(acc.importancePoolIfAny().bytes(), size_t(16 * 16 * kImportanceCapacity * 16));
  }
  EXPECT_EQ(images[0], images[1]);
  EXPECT_EQ(images[0], images[2]);
}

// Bad weights are clear errors; a table of the wrong size too.
TEST(Visibility, BadSettingsAreErrors)
{
  Scene scene;
  ImportanceDesc bad;
  bad.p = 0.0;
  EXPECT_THROW(scene.setImportance(bad), std::invalid_argument);
  bad = ImportanceDesc();
  bad.q = std::nan("");
  EXPECT_THROW(scene.setImportance(bad), std::invalid_argument);
  bad = ImportanceDesc();
  bad.samplesPerPass = kMaxImportanceSamples + 1;
  EXPECT_THROW(scene.setImportance(bad), std::invalid_argument);
  const TestVolume v = occluderVolume();
  setupOccluder(scene, v, 0.3);
  ImportanceDesc wrongSize;
  wrongSize.enabled = true;
  wrongSize.tables = { std::vector<float>(10, 1.f) };
  scene.setImportance(wrongSize);
  EXPECT_THROW(scene.update(), std::invalid_argument);
  EXPECT_EQ(snapImportance(0.1f), 0.f);
  EXPECT_EQ(snapImportance(0.6f), 0.5f);
  EXPECT_EQ(snapImportance(0.9f), 1.f);
  EXPECT_EQ(snapImportance(std::nanf("")), 0.f);
}

// Light rays (Sec. 5.3): the green target lies in the shadow of the red
// occluder (light from the camera's side). With the light rays optimized
// the light reaches it through the occluder: its radiance rises by at
// least 1.5x; the camera rays are optimized in both images.
TEST(Visibility, LightRaysBrightenTheShadowedTarget)
{
  const TestVolume v = occluderVolume();
  const Camera cam = occluderCamera();
  auto green = [&](bool lightRays, RenderCounters& counters)
  {
    Scene scene;
    setupOccluder(scene, v, 0.3);
    LightingDesc ld;
    LightDesc sun;
    sun.vector[0] = 0.2;
    sun.vector[1] = 0.1;
    sun.vector[2] = 1.0; // towards +z: through the occluder
    sun.intensity = 3.0;
    ld.lights = { sun };
    ld.albedo = { 1.f, 1.f };
    scene.setLighting(ld);
    ImportanceDesc imp;
    imp.enabled = true;
    imp.tables = { {}, stepTable(64, 0.f, 1.f) };
    imp.lightRays = lightRays;
    imp.lightRaySamples = 64;
    scene.setImportance(imp);
    scene.update();
    std::unique_ptr<Renderer> r = testRenderer();
    Accumulator acc;
    RenderSettings rs;
    rs.samplesPerPixel = 128;
    rs.seed = 21;
    r->render(scene, cam, rs, nullptr, acc, &counters);
    double g = 0;
    for (int p = 0; p < 16 * 16; ++p)
    {
      g += acc.rgba()[4 * p + 1];
    }
    return g;
  };
  RenderCounters off, on;
  const double g0 = green(false, off);
  const double g1 = green(true, on);
  std::printf("target radiance: light rays unoptimized %.3f, optimized %.3f (%.2fx)\n", g0, g1, g1 / g0);
  EXPECT_GT(g1, 1.5 * g0);
  EXPECT_GT(on.importanceSamples, off.importanceSamples) << "light-ray lists sample importance";
}

// Lit: Monte Carlo with camera and light rays optimized converges to the
// ray march with the same optimization (sums for the integrals). Constant
// importance (exact lists), image-mean z test per component as the lighting
// tests (the march's step biases single pixels), alpha kAlpha / 8.
TEST(Visibility, LitMonteCarloConvergesToTheOptimizedRayMarch)
{
  const double alpha = kAlpha / 8;
  const DemoVolume v = makeDemo("cosmology", { 20, 20, 20 });
  const Camera cam = orbitCamera(v.dims, v.spacing, 16, 16, 30, 20);
  for (BlendMode mode : { BlendMode::Density, BlendMode::Max })
  {
    Scene scene;
    configureDemo(scene, v, 4, 128, 0.5, mode);
    LightingDesc ld;
    LightDesc sun;
    sun.vector[0] = 1;
    sun.vector[1] = 2;
    sun.vector[2] = 0.5;
    sun.intensity = 1.5;
    ld.lights = { sun };
    ld.albedo = { 0.9f, 0.6f, 0.8f, 0.3f };
    scene.setLighting(ld);
    ImportanceDesc imp;
    imp.enabled = true;
    imp.tables.assign(size_t(v.numChannels()), std::vector<float>());
    imp.tables[0].assign(128, 0.5f);
    imp.lightRaySamples = 16;
    scene.setImportance(imp);
    scene.update();
    RayMarcher rm;
    Accumulator ref, plainRef;
    MarchSettings ms;
    ms.step = 0.125;
    ms.terminateTransmittance = 0.f;
    rm.render(scene, cam, ms, nullptr, ref);
    Scene plain;
    configureDemo(plain, v, 4, 128, 0.5, mode);
    plain.setLighting(ld);
    plain.update();
    rm.render(plain, cam, ms, nullptr, plainRef);
    const std::unique_ptr<Renderer> r = testRenderer();
    const int K = 48;
    const size_t P = size_t(cam.width) * cam.height * 4;
    std::vector<double> sum(P, 0.0), sumSq(P, 0.0);
    for (int k = 0; k < K; ++k)
    {
      Accumulator acc;
      RenderSettings rs;
      rs.samplesPerPixel = 32;
      rs.jitterPixels = false;
      rs.seed = uint32_t(900 + k);
      r->render(scene, cam, rs, nullptr, acc);
      for (size_t i = 0; i < P; ++i)
      {
        sum[i] += acc.rgba()[i];
        sumSq[i] += double(acc.rgba()[i]) * acc.rgba()[i];
      }
    }
    for (int c = 0; c < 4; ++c)
    {
      double D = 0, V = 0, shift = 0;
      for (size_t i = size_t(c); i < P; i += 4)
      {
        const double m = sum[i] / K;
        D += m - ref.rgba()[i];
        V += std::max(0.0, (sumSq[i] - K * m * m) / (K - 1)) / K;
        shift += double(ref.rgba()[i]) - plainRef.rgba()[i];
      }
      const double z = V > 0 ? D / std::sqrt(V) : 0.0;
      std::printf("%s component %d: image-mean difference %.5f, z = %.2f; the optimization moved the reference's "
                  "mean by %.4f (%.0f sigma)\n",
        toString(mode), c, D / (P / 4), z, shift / (P / 4), std::fabs(shift) / std::sqrt(V));
      EXPECT_GT(normalTwoSided(z), alpha) << toString(mode) << " component " << c;
      EXPECT_GT(std::fabs(shift), 10.0 * std::sqrt(V)) << "the test has power: the optimized reference differs";
    }
  }
}
