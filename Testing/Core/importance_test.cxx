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

// Which end of a light ray Eq. 7 starts from (ImportanceDesc::
// lightRaysFromLight). In the occluder scene the important target (green)
// is lit through the unimportant occluder (red): from the scattering
// vertex, the target's importance lies before each occluder point and
// weighs it by r (30); read from the light, it lies behind and weighs it by
// q (70), so the target gets more light. With q = r the two readings are
// the same formula (h = q K(z)) and give the same image bit for bit.
TEST(Visibility, LightRayOrigin)
{
  const TestVolume v = occluderVolume();
  const Camera cam = occluderCamera();
  auto render = [&](bool fromLight, double q, double r)
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
    imp.q = q;
    imp.r = r;
    imp.lightRaySamples = 64;
    imp.lightRaysFromLight = fromLight;
    scene.setImportance(imp);
    scene.update();
    std::unique_ptr<Renderer> rr = testRenderer();
    Accumulator acc;
    RenderSettings rs;
    rs.samplesPerPixel = 128;
    rs.seed = 23;
    rr->render(scene, cam, rs, nullptr, acc);
    return std::vector<float>(acc.rgba(), acc.rgba() + 16 * 16 * 4);
  };
  auto green = [](const std::vector<float>& img)
  {
    double g = 0;
    for (size_t p = 0; p < img.size() / 4; ++p)
    {
      g += img[4 * p + 1];
    }
    return g;
  };
  const std::vector<float> vertex = render(false, 70.0, 30.0);
  const std::vector<float> light = render(true, 70.0, 30.0);
  std::printf("target radiance, light-ray list from the scattering vertex %.3f, from the light %.3f (%.2fx)\n",
    green(vertex), green(light), green(light) / green(vertex));
  EXPECT_GT(green(light), 1.1 * green(vertex));
  EXPECT_EQ(render(false, 50.0, 50.0), render(true, 50.0, 50.0)) << "q = r: the readings agree";
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

// The occluder scene with a striped target: channel 1 (green, the back half
// z < 16) is 1 on z in [0, 4) and [8, 12) and 0.3 on [4, 8) and [12, 16),
// and its importance a step (1 above half its range, 0 below): along every
// camera ray the importance steps 0 -> 1 -> 0 -> 1 -> 0 (the red occluder in
// front has none), so a pixel's segment list must find four steps (Algorithm
// 1 with the adaptive passes of Sec. 5.2) for Monte Carlo to reach the
// optimized march, which samples the importance at every lattice point.
namespace
{
TestVolume stripedOccluderVolume()
{
  TestVolume v = occluderVolume();
  for (int k = 0; k < 16; ++k)
    for (int j = 0; j < 16; ++j)
      for (int i = 0; i < 16; ++i)
        v.channels[1][v.index(i, j, k)] = (k / 4) % 2 == 0 ? 1.f : 0.3f;
  return v;
}

ImportanceDesc stripedImportance()
{
  ImportanceDesc imp;
  imp.enabled = true;
  imp.tables = { {}, stepTable(64, 0.f, 1.f) };
  return imp;
}

LightingDesc occluderSun()
{
  LightingDesc ld;
  LightDesc sun;
  sun.vector[0] = 0.2;
  sun.vector[1] = 0.1;
  sun.vector[2] = 1.0; // towards +z: through the occluder
  sun.intensity = 3.0;
  ld.lights = { sun };
  ld.albedo = { 1.f, 1.f };
  return ld;
}
} // namespace

// Unlit: the first 4 renders, of one sample each, refine the lists (4 of the
// image's N + 4 samples); then N samples. Per-pixel comparison as
// MonteCarloConvergesToTheOptimizedRayMarch, alpha kAlpha.
TEST(Visibility, StepImportanceMonteCarloConvergesToTheOptimizedRayMarch)
{
  const int N = 2048;
  const TestVolume v = stripedOccluderVolume();
  const Camera cam = occluderCamera();
  Scene scene;
  setupOccluder(scene, v, 0.3);
  scene.setImportance(stripedImportance());
  scene.update();
  ASSERT_TRUE(scene.optimized());
  MarchSettings ms;
  // 1/128 voxel: the march's lattice sums of K converge slowly across the
  // stripes' sharp edges (at 1/16 its image still moves by 2e-3).
  ms.step = 1.0 / 128.0;
  ms.terminateTransmittance = 0.f;
  RayMarcher marcher;
  Accumulator refAcc;
  marcher.render(scene, cam, ms, nullptr, refAcc);
  const std::vector<float> ref(refAcc.rgba(), refAcc.rgba() + 4 * 16 * 16);
  Scene plainScene;
  setupOccluder(plainScene, v, 0.3);
  Accumulator plainAcc;
  marcher.render(plainScene, cam, ms, nullptr, plainAcc);
  double redRef = 0, redPlain = 0;
  for (size_t i = 0; i < ref.size(); i += 4)
  {
    redRef += ref[i];
    redPlain += plainAcc.rgba()[i];
  }
  std::printf("striped target: occluder red %.2f optimized, %.2f unoptimized (march)\n", redRef, redPlain);
  EXPECT_LT(redRef, 0.5 * redPlain) << "the optimization should thin the occluder";

  std::unique_ptr<Renderer> mc = testRenderer();
  Accumulator acc;
  RenderSettings rs;
  rs.jitterPixels = false;
  rs.seed = 78;
  uint64_t refined[4] = {};
  for (int pass = 0; pass < 4; ++pass)
  {
    RenderCounters counters;
    rs.samplesPerPixel = 1;
    mc->render(scene, cam, rs, nullptr, acc, &counters);
    refined[pass] = counters.importanceSamples;
  }
  for (int pass = 0; pass < 4; ++pass)
  {
    EXPECT_GT(refined[pass], 0u) << "refinement pass " << pass << " drew importance samples";
  }
  rs.samplesPerPixel = N;
  mc->render(scene, cam, rs, nullptr, acc);
  ASSERT_EQ(acc.samples(), uint32_t(N + 4));
  std::vector<double> D, V;
  for (size_t i = 0; i < ref.size(); ++i)
  {
    const double mu = std::min(1.0, std::max(0.0, double(ref[i])));
    const bool enough = N * mu * (1.0 - mu) >= 100.0;
    D.push_back(enough ? double(acc.rgba()[i]) - double(ref[i]) : 0.0);
    V.push_back(enough ? mu * (1.0 - mu) / (N + 4) : 0.0);
  }

  expectZeroDifference(D, V, kAlpha, "striped step importance: MC vs optimized ray march");
}

// Lit, the same scene and importance, the sun through the occluder: every
// light ray's fresh list (1000 stratified samples) must find the target's
// steps for the transmittance to the light to reach the lit optimized march.
// (A light list resolves the steps to about its strata: with the default
// 200 samples the target comes out 3e-4 darker than the march, 2 to 5
// sigma of this test.) Image-mean z test per component over 24 independent
// images (each refining its own camera lists), alpha kAlpha / 4; the light
// rays' optimization must move the reference by more than 10 sigma.
TEST(Visibility, StepImportanceLitMonteCarloConvergesToTheOptimizedRayMarch)
{
  const double alpha = kAlpha / 4;
  const TestVolume v = stripedOccluderVolume();
  const Camera cam = occluderCamera();
  Scene scene;
  setupOccluder(scene, v, 0.3);
  scene.setLighting(occluderSun());
  ImportanceDesc imp = stripedImportance();
  imp.lightRaySamples = 1000;
  scene.setImportance(imp);
  scene.update();
  RayMarcher rm;
  Accumulator ref, plainRef;
  MarchSettings ms;
  ms.step = 1.0 / 16.0;
  ms.terminateTransmittance = 0.f;
  rm.render(scene, cam, ms, nullptr, ref);
  Scene camOnly;
  setupOccluder(camOnly, v, 0.3);
  camOnly.setLighting(occluderSun());
  ImportanceDesc noLight = stripedImportance();
  noLight.lightRays = false;
  camOnly.setImportance(noLight);
  camOnly.update();
  rm.render(camOnly, cam, ms, nullptr, plainRef);
  const std::unique_ptr<Renderer> r = testRenderer();
  const int K = 24;
  const size_t P = size_t(cam.width) * cam.height * 4;
  std::vector<double> sum(P, 0.0), sumSq(P, 0.0);
  RenderCounters counters;
  for (int k = 0; k < K; ++k)
  {
    Accumulator acc;
    RenderSettings rs;
    rs.jitterPixels = false;
    rs.seed = uint32_t(1900 + k);
    for (int pass = 0; pass < 4; ++pass)
    {
      rs.samplesPerPixel = 1;
      r->render(scene, cam, rs, nullptr, acc, &counters);
    }
    rs.samplesPerPixel = 32;
    r->render(scene, cam, rs, nullptr, acc, &counters);
    for (size_t i = 0; i < P; ++i)
    {
      sum[i] += acc.rgba()[i];
      sumSq[i] += double(acc.rgba()[i]) * acc.rgba()[i];
    }
  }
  EXPECT_GT(counters.importanceSamples, 0u);
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
    std::printf("striped step importance, lit, component %d: image-mean difference %.5f, z = %.2f; light-ray "
                "optimization moved the reference's mean by %.4f (%.0f sigma)\n",
      c, D / (P / 4), z, shift / (P / 4), V > 0 ? std::fabs(shift) / std::sqrt(V) : 0.0);
    EXPECT_GT(normalTwoSided(z), alpha) << "component " << c;
    if (c == 1)
    {
      EXPECT_GT(std::fabs(shift), 10.0 * std::sqrt(V)) << "the test has power: light-ray optimization moves the target";
    }
  }
}

// A light ray's list is built afresh from its samples; where the importance
// along the ray changes more often than kImportanceCapacity segments hold, the
// build fails and optimizedShadow() tracks that ray unoptimized and counts it
// (Documentation/user-guide/visibility.md, "Overflows"). A 64-voxel line whose
// importance alternates every 2 voxels (32 runs) overflows with 200 samples; the
// same line with one step (2 runs) does not.
TEST(Visibility, LightRayListOverflowIsCounted)
{
  for (int runs : { 32, 2 })
  {
    TestVolume v(64, 1, 1, 1, 0.f);
    for (int i = 0; i < 64; ++i)
    {
      v.channels[0][v.index(i, 0, 0)] = (i / (64 / runs)) % 2 == 0 ? 1.f : 0.f;
    }
    Scene scene;
    TransferFunctionDesc tf = flatTF(0.3f, 1, 1, 1, 1.f, 64);
    configure(scene, v, { tf }, 4);
    LightingDesc ld;
    ld.lights = { LightDesc() };
    ld.albedo = { 1.f };
    scene.setLighting(ld);
    ImportanceDesc imp;
    imp.enabled = true;
    imp.tables = { stepTable(64, 0.f, 1.f) };
    scene.setImportance(imp);
    scene.update();
    const SceneView& s = scene.view();
    ASSERT_EQ(s.importance.lightRaySamples, 200);
    ImportanceSegment seg[kImportanceCapacity];
    RayImportance ri;
    uint32_t samples = 0;
    Rng rng(3, 0, 1);
    const bool fits = buildLightRayImportance(s, Vec3f(0.f, 0.f, 0.f), Vec3f(1.f, 0.f, 0.f), 63.f, rng, seg, ri, samples);
    EXPECT_EQ(fits, runs <= kImportanceCapacity) << runs << " runs";
    EXPECT_GT(samples, 0u);
    ShadowCounters sc;
    Rng rng2(3, 0, 1);
    const float T = optimizedShadow<BlendMode::Density>(
      s, Vec3f(0.f, 0.f, 0.f), Vec3f(1.f, 0.f, 0.f), 63.f, ShadowEstimator::Ratio, rng2, sc);
    EXPECT_TRUE(T >= 0.f && T <= 1.f);
    EXPECT_EQ(sc.importanceOverflows, runs <= kImportanceCapacity ? 0u : 1u) << runs << " runs";
    EXPECT_EQ(sc.rays, 1u);
  }
}

// ------------------------------------------------- Eq. 7-8 by value
//
// The factor mu'/mu = p / (p + (1 - g)^(2 lambda) h), h = (r - q) K + q K(z)
// (Lerzer and Dachsbacher, Eq. 7-8), against hand-computed numbers, through
// the view a Scene publishes (so that a weight lost between ImportanceDesc
// and the per-ray code shows too).
namespace
{
/// The importance view of a Scene with one channel and importance on.
ImportanceView viewWith(const ImportanceDesc& d)
{
  Scene scene;
  TestVolume v(4, 4, 4, 1, 0.5f);
  configure(scene, v, { flatTF(0.5f, 1, 1, 1, 1.f, 8) }, 4);
  ImportanceDesc imp = d;
  imp.enabled = true;
  imp.tables = { std::vector<float>(8, 0.5f) };
  scene.setImportance(imp);
  scene.update();
  return scene.view().importance;
}
} // namespace

// K = 0.2 before the point and K(z) = 0.5 over the ray, so with the defaults
// (p 1, q 70, r 30, lambda 1) h = (30 - 70) 0.2 + 70 0.5 = 27:
//   g = 0:   1 / (1 + 27)          = 0.0357143
//   g = 0.5: 1 / (1 + 0.25 * 27)   = 0.1290323
//   g = 1:   1                       (important points keep their extinction)
// lambda 2: (1 - 0.5)^4 = 0.0625 -> 1 / (1 + 1.6875) = 0.3720930;
// lambda 0.5: 0.5 -> 1 / 14.5 = 0.0689655; lambda 0: 1 / 28 for every g < 1;
// p 2: 2 / (2 + 27) = 0.0689655. With q and r swapped h would be 23 (1/24);
// with lambda ignored, lambda 2 would give 0.129.
TEST(OptimizedExtinction, FactorByValue)
{
  const ImportanceView def = viewWith(ImportanceDesc());
  const float K = 0.2f, Kz = 0.5f;
  EXPECT_NEAR(optimizedExtinctionFactor(def, 0.f, K, Kz), 1.0 / 28.0, 1e-6);
  EXPECT_NEAR(optimizedExtinctionFactor(def, 0.5f, K, Kz), 1.0 / 7.75, 1e-6);
  EXPECT_EQ(optimizedExtinctionFactor(def, 1.f, K, Kz), 1.f);
  // Before any importance (K = K(z) = 0) nothing changes.
  EXPECT_EQ(optimizedExtinctionFactor(def, 0.f, 0.f, 0.f), 1.f);
  // All importance behind the point (K = 0): h = q K(z), the occlusion term.
  EXPECT_NEAR(optimizedExtinctionFactor(def, 0.f, 0.f, 0.5f), 1.0 / 36.0, 1e-6);
  // All of it in front (K = K(z)): h = r K(z), the clutter term.
  EXPECT_NEAR(optimizedExtinctionFactor(def, 0.f, 0.5f, 0.5f), 1.0 / 16.0, 1e-6);
  struct Case
  {
    double lambda, p;
    float g;
    double expected;
  };
  for (const Case& c : { Case{ 2.0, 1.0, 0.5f, 1.0 / 2.6875 }, Case{ 0.5, 1.0, 0.5f, 1.0 / 14.5 },
         Case{ 0.0, 1.0, 0.5f, 1.0 / 28.0 }, Case{ 0.0, 1.0, 0.9f, 1.0 / 28.0 }, Case{ 1.0, 2.0, 0.f, 2.0 / 29.0 } })
  {
    ImportanceDesc d;
    d.lambda = c.lambda;
    d.p = c.p;
    EXPECT_NEAR(optimizedExtinctionFactor(viewWith(d), c.g, K, Kz), c.expected, 1e-6)
      << "lambda " << c.lambda << ", p " << c.p << ", g " << c.g;
  }
  // Other weights: q 10, r 50: h = 40 * 0.2 + 10 * 0.5 = 13.
  ImportanceDesc w;
  w.q = 10.0;
  w.r = 50.0;
  EXPECT_NEAR(optimizedExtinctionFactor(viewWith(w), 0.f, K, Kz), 1.0 / 14.0, 1e-6);
}

// Eq. 7 integrates the squared importance. A list with the levels 0.25, 0.5,
// 1 and 0.75 (squares 0.0625, 0.25, 1, 0.5625) on [0.5, 1], [1, 1.5],
// [2, 3] and [3, 4] of a ray of length 5 (gaps take the mean importance of
// their neighbours, 0 at the ends):
//   [0, 0.5] 0.125^2 0.5 = 0.0078125   [0.5, 1] 0.0625 0.5 = 0.03125
//   [1, 1.5] 0.25 0.5 = 0.125           [1.5, 2] 0.75^2 0.5 = 0.28125
//   [2, 3] 1                            [3, 4] 0.5625
//   [4, 5] 0.375^2 = 0.140625           K(z) = 2.1484375
// At t = 3.5 (g = 0.75): K = 1.4453125 + 0.5625 0.5 = 1.7265625,
// h = -40 K + 70 K(z) = 81.328125, and the factor 1 / (1 + 0.0625 h) =
// 0.1643924. With g instead of g^2 every integral grows (K(z) = 2.9375).
TEST(OptimizedExtinction, SquaredImportanceIntegral)
{
  std::vector<ImportanceSegment> seg = { segment(0.5f, 0.5f, 0.25f), segment(1.f, 0.5f, 0.5f),
    segment(2.f, 1.f, 1.f), segment(3.f, 1.f, 0.75f) };
  const float total = importanceIntegrals(seg.data(), 4, 5.f);
  EXPECT_NEAR(seg[0].K, 0.0078125, 1e-7);
  EXPECT_NEAR(seg[1].K, 0.0390625, 1e-7);
  EXPECT_NEAR(seg[2].K, 0.4453125, 1e-7);
  EXPECT_NEAR(seg[3].K, 1.4453125, 1e-7);
  EXPECT_NEAR(total, 2.1484375, 1e-6);
  EXPECT_NEAR(importanceIntegral(seg.data(), 4, 0.75f), 0.0078125 + 0.0625 * 0.25, 1e-7);
  EXPECT_NEAR(importanceIntegral(seg.data(), 4, 1.75f), 0.1640625 + 0.5 * 0.28125, 1e-7);
  EXPECT_NEAR(importanceIntegral(seg.data(), 4, 3.5f), 1.7265625, 1e-6);
  EXPECT_NEAR(importanceIntegral(seg.data(), 4, 4.5f), 2.0078125 + 0.5 * 0.140625, 1e-6);
  // The factor at t = 3.5 through the ray's list (normalised units = world).
  ImportanceView iv = viewWith(ImportanceDesc());
  iv.invLengthUnit = 1.f;
  RayImportance ray;
  ray.segments = seg.data();
  ray.count = 4;
  ray.total = total;
  EXPECT_NEAR(importanceFactor(iv, ray, 3.5f, 0.75f), 0.16439236, 1e-6);
  EXPECT_EQ(importanceFactor(iv, ray, 2.5f, 1.f), 1.f);
}

// The defaults are the paper's (Sec. 6: p = 1, q = 70, r = 30, lambda = 1,
// 200 samples per light ray), in the description, in the view a Scene
// publishes, and in the per-ray view's own defaults.
TEST(OptimizedExtinction, PaperDefaults)
{
  const ImportanceDesc d;
  EXPECT_EQ(d.p, 1.0);
  EXPECT_EQ(d.q, 70.0);
  EXPECT_EQ(d.r, 30.0);
  EXPECT_EQ(d.lambda, 1.0);
  EXPECT_EQ(d.lightRaySamples, 200);
  EXPECT_TRUE(d.lightRays);
  const ImportanceView v = viewWith(d);
  EXPECT_EQ(v.p, 1.f);
  EXPECT_EQ(v.q, 70.f);
  EXPECT_EQ(v.r, 30.f);
  EXPECT_EQ(v.twoLambda, 2.f);
  EXPECT_EQ(v.lightRaySamples, 200);
  EXPECT_TRUE(v.lightRays);
  const ImportanceView raw{};
  EXPECT_EQ(raw.p, 1.f);
  EXPECT_EQ(raw.q, 70.f);
  EXPECT_EQ(raw.r, 30.f);
  EXPECT_EQ(raw.twoLambda, 2.f);
  EXPECT_EQ(raw.lightRaySamples, 200);
}
