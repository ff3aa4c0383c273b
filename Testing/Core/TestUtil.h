// SPDX-License-Identifier: BSD-3-Clause
// Helpers shared by the core tests: a platform-independent random source,
// statistics (chi-square, normal tails), scene and camera builders, and a
// Monte Carlo image comparison.
#pragma once

#include "mcvol/CPURenderer.h"
#include "mcvol/CameraMath.h"
#include "mcvol/DemoData.h"
#include "mcvol/Renderer.h"
#include "mcvol/Scene.h"
#include "mcvol/ray/Tracking.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cfloat>
#include <cmath>
#include <cstdint>
#include <cstdlib>
#include <memory>
#include <string>
#include <vector>

namespace mcvol
{
namespace test
{
/// Deterministic generator for test inputs (SplitMix64; no std:: distributions,
/// whose output is implementation-defined).
class TestRand
{
public:
  explicit TestRand(uint64_t seed)
    : S(seed)
  {
  }
  uint64_t u64()
  {
    uint64_t z = (this->S += 0x9E3779B97F4A7C15ull);
    z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ull;
    z = (z ^ (z >> 27)) * 0x94D049BB133111EBull;
    return z ^ (z >> 31);
  }
  /// Uniform in [0, 1).
  double uniform() { return double(this->u64() >> 11) * 0x1p-53; }
  double uniform(double lo, double hi) { return lo + (hi - lo) * this->uniform(); }
  /// Uniform integer in [lo, hi].
  int integer(int lo, int hi) { return lo + int(this->u64() % uint64_t(hi - lo + 1)); }
  bool chance(double p) { return this->uniform() < p; }

private:
  uint64_t S;
};

/// The lit test scenes' directional light, from (1, 2, 0.5).
inline LightDesc testSun(double intensity)
{
  LightDesc sun;
  sun.vector[0] = 1;
  sun.vector[1] = 2;
  sun.vector[2] = 0.5;
  sun.intensity = intensity;
  return sun;
}

/// The lit test scenes' bluish point light at (25, -5, 10) (index space).
inline LightDesc testLamp(double intensity)
{
  LightDesc lamp;
  lamp.point = true;
  lamp.vector[0] = 25;
  lamp.vector[1] = -5;
  lamp.vector[2] = 10;
  lamp.intensity = intensity;
  lamp.color[2] = 0.5;
  return lamp;
}

/// One directional light (testSun) with shadows, and a grey sky of
/// radiance `ambient`: the lit test scenes' light.
inline LightingDesc sunAndSky(double intensity, double ambient)
{
  LightingDesc ld;
  ld.lights = { testSun(intensity) };
  ld.ambient[0] = ld.ambient[1] = ld.ambient[2] = ambient;
  return ld;
}

// ---------------------------------------------------------------- statistics

/// Regularised upper incomplete gamma Q(a, x).
inline double gammaQ(double a, double x)
{
  if (!(x > 0.0))
  {
    return 1.0;
  }
  const double lnPre = -x + a * std::log(x) - std::lgamma(a);
  if (x < a + 1.0)
  {
    double ap = a, term = 1.0 / a, sum = term;
    for (int n = 0; n < 100000; ++n)
    {
      ap += 1.0;
      term *= x / ap;
      sum += term;
      if (std::fabs(term) < std::fabs(sum) * 1e-16)
      {
        break;
      }
    }
    return std::max(0.0, 1.0 - sum * std::exp(lnPre));
  }
  const double tiny = 1e-300;
  double b = x + 1.0 - a, c = 1.0 / tiny, d = 1.0 / b, h = d;
  for (int i = 1; i < 100000; ++i)
  {
    const double an = -double(i) * (double(i) - a);
    b += 2.0;
    d = an * d + b;
    d = std::fabs(d) < tiny ? tiny : d;
    c = b + an / c;
    c = std::fabs(c) < tiny ? tiny : c;
    d = 1.0 / d;
    const double del = d * c;
    h *= del;
    if (std::fabs(del - 1.0) < 1e-16)
    {
      break;
    }
  }
  return std::exp(lnPre) * h;
}

/// P(X >= x) for X ~ chi-square with k degrees of freedom.
inline double chi2Sf(double x, double k)
{
  return gammaQ(0.5 * k, 0.5 * x);
}

/// Two-sided normal tail P(|Z| >= |z|).
inline double normalTwoSided(double z)
{
  return std::erfc(std::fabs(z) / std::sqrt(2.0));
}

/// Pearson chi-square of observed counts against expected probabilities;
/// returns the p-value (dof = number of cells - 1). Cells of probability 0
/// must have count 0 (asserted).
inline double chiSquarePValue(
  const std::vector<double>& counts, const std::vector<double>& probs, double* statOut = nullptr)
{
  double total = 0.0;
  for (double c : counts)
  {
    total += c;
  }
  double stat = 0.0;
  int cells = 0;
  for (size_t i = 0; i < counts.size(); ++i)
  {
    if (probs[i] <= 0.0)
    {
      EXPECT_EQ(counts[i], 0.0) << "cell " << i << " has probability 0";
      continue;
    }
    const double e = total * probs[i];
    stat += (counts[i] - e) * (counts[i] - e) / e;
    ++cells;
  }
  if (statOut)
  {
    *statOut = stat;
  }
  return chi2Sf(stat, double(cells - 1));
}

// ---------------------------------------------------------------- backends

/// The backend the backend-generic tests render with: MCVOL_TEST_BACKEND=cuda
/// runs them on the CUDA backend (TestMain.cxx skips with 125 when no device
/// is usable); anything else, or unset, the CPU.
inline Backend testBackend()
{
  const char* e = std::getenv("MCVOL_TEST_BACKEND");
  return e && std::string(e) == "cuda" ? Backend::CUDA : Backend::CPU;
}

/// A renderer of testBackend(); `threads` applies to the CPU backend (0 = default).
inline std::unique_ptr<Renderer> testRenderer(int threads = 0)
{
  if (testBackend() == Backend::CUDA)
  {
    return Renderer::create(Backend::CUDA);
  }
  std::unique_ptr<CPURenderer> r(new CPURenderer());
  r->setThreads(threads);
  return std::unique_ptr<Renderer>(r.release());
}

// ------------------------------------------------------------------ scenes

/// Float channels owned by the test (planar, x fastest).
struct TestVolume
{
  int dims[3] = { 0, 0, 0 };
  std::vector<std::vector<float>> channels;

  TestVolume() = default;
  TestVolume(int nx, int ny, int nz, int numChannels, float value)
  {
    this->dims[0] = nx;
    this->dims[1] = ny;
    this->dims[2] = nz;
    this->channels.assign(size_t(numChannels), std::vector<float>(this->voxels(), value));
  }
  size_t voxels() const { return size_t(this->dims[0]) * size_t(this->dims[1]) * size_t(this->dims[2]); }
  size_t index(int i, int j, int k) const
  {
    return (size_t(k) * size_t(this->dims[1]) + size_t(j)) * size_t(this->dims[0]) + size_t(i);
  }
  std::vector<ChannelSource> sources() const
  {
    std::vector<ChannelSource> s(this->channels.size());
    for (size_t n = 0; n < s.size(); ++n)
    {
      s[n].data = this->channels[n].data();
      s[n].type = ScalarType::Float32;
      s[n].stride = 1;
    }
    return s;
  }
};

/// Opacity giving extinction `sigma` over `unit` (inverse of opacityToExtinction).
inline float opacityFor(double sigma, double unit)
{
  return float(-std::expm1(-sigma * unit));
}

/// Extinction of opacity a over unit distance u, in double.
inline double extinctionOf(double a, double u)
{
  return -std::log1p(-a) / u;
}

/// Constant opacity and colour over the scalar range [lo, hi] with K texels.
inline TransferFunctionDesc flatTF(
  float opacity, float r, float g, float b, float unit = 1.f, int K = 2, float lo = 0.f, float hi = 1.f)
{
  TransferFunctionDesc tf;
  tf.scalarMin = lo;
  tf.scalarMax = hi;
  tf.unitDistance = unit;
  tf.opacity.assign(size_t(K), opacity);
  tf.rgb.resize(size_t(K) * 3);
  for (int i = 0; i < K; ++i)
  {
    tf.rgb[size_t(i) * 3 + 0] = r;
    tf.rgb[size_t(i) * 3 + 1] = g;
    tf.rgb[size_t(i) * 3 + 2] = b;
  }
  return tf;
}

inline void configure(Scene& scene, const TestVolume& v, const std::vector<TransferFunctionDesc>& tfs,
  int macrocell = 8, BlendMode mode = BlendMode::Density)
{
  const std::vector<ChannelSource> src = v.sources();
  scene.setVolume(v.dims, int(src.size()), src.data());
  for (size_t n = 0; n < tfs.size(); ++n)
  {
    scene.setTransferFunction(int(n), tfs[n]);
  }
  scene.setMacrocellSize(macrocell);
  scene.setBlendMode(mode);
  scene.update();
}

/// Sets up a Scene for a generated demo dataset with its suggested transfer
/// functions (K texels over each channel's finite range, unit distance scaled
/// by `unitScale`).
inline void configureDemo(Scene& scene, const DemoVolume& v, int macrocell = 8, int K = 128, double unitScale = 1.0,
  BlendMode mode = BlendMode::Density)
{
  std::vector<ChannelSource> src;
  for (int n = 0; n < v.numChannels(); ++n)
  {
    src.push_back(v.source(n));
  }
  scene.setVolume(v.dims, v.numChannels(), src.data());
  for (int n = 0; n < v.numChannels(); ++n)
  {
    const std::array<float, 2> range = v.range(n);
    scene.setTransferFunction(
      n, sampleTransferFunction(v.transferFunctions[size_t(n)], range[0], range[1], K, unitScale));
  }
  scene.setMacrocellSize(macrocell);
  scene.setBlendMode(mode);
  scene.update();
}

/// Rays through the volume box: origin uniform on the box face z = lo (or
/// inside), direction random in the +z hemisphere; clipped to the box.
struct BoxRay
{
  Vec3f o, d;
  float tmax;
};

inline BoxRay randomBoxRay(const VolumeView& vol, TestRand& r)
{
  while (true)
  {
    BoxRay ray;
    for (int a = 0; a < 2; ++a)
    {
      ray.o[a] = float(r.uniform(vol.boxLo[a], vol.boxHi[a]));
    }
    ray.o.z = vol.boxLo.z;
    double u[3], n2 = 0;
    u[0] = r.uniform(-1, 1);
    u[1] = r.uniform(-1, 1);
    u[2] = r.uniform(0.2, 1);
    for (double x : u)
      n2 += x * x;
    const double s = 1.0 / std::sqrt(n2);
    ray.d = Vec3f(float(u[0] * s), float(u[1] * s), float(u[2] * s));
    float t0 = 0.f, t1 = FLT_MAX;
    if (intersectBox(vol.boxLo, vol.boxHi, ray.o, ray.d, t0, t1) && t1 > t0)
    {
      ray.o = ray.o + ray.d * t0;
      ray.tmax = t1 - t0;
      return ray;
    }
  }
}

/// One Density-mode tracking of a ray with the chosen tracker.
inline Hit trackDensity(const SceneView& s, Tracker tracker, Vec3f o, Vec3f d, float tmax, Rng& rng, RayCounters& c)
{
  return tracker == Tracker::OneDDA ? track1DDA<BlendMode::Density>(s, o, d, 0.f, tmax, rng, c)
                                    : trackNDDA<BlendMode::Density>(s, o, d, 0.f, tmax, rng, c);
}

// ----------------------------------------------------------------- cameras

/**
 * Orthographic camera: the film spans center +- right (x) and +- up (y); rays
 * go along the unit vector `dir` from center + dir * nearT to
 * center + dir * farT. The affine NDC-to-world map is written directly, so
 * pixel rays are exact.
 */
inline Camera orthoCamera(int W, int H, const double center[3], const double right[3], const double up[3],
  const double dir[3], double nearT, double farT)
{
  Camera c;
  c.width = W;
  c.height = H;
  const double half = 0.5 * (farT - nearT);
  const double mid = nearT + half;
  for (int r = 0; r < 3; ++r)
  {
    c.invViewProj[r * 4 + 0] = right[r];
    c.invViewProj[r * 4 + 1] = up[r];
    c.invViewProj[r * 4 + 2] = dir[r] * half;
    c.invViewProj[r * 4 + 3] = center[r] + dir[r] * mid;
  }
  c.invViewProj[12] = 0;
  c.invViewProj[13] = 0;
  c.invViewProj[14] = 0;
  c.invViewProj[15] = 1;
  return c;
}

/// Orthographic view along -z covering world x in [x0, x1], y in [y0, y1];
/// rays start at z = zStart and travel towards -z.
inline Camera orthoAlongZ(int W, int H, double x0, double x1, double y0, double y1, double zStart, double length)
{
  const double center[3] = { 0.5 * (x0 + x1), 0.5 * (y0 + y1), zStart };
  const double right[3] = { 0.5 * (x1 - x0), 0, 0 };
  const double up[3] = { 0, 0.5 * (y1 - y0), 0 };
  const double dir[3] = { 0, 0, -1 };
  return orthoCamera(W, H, center, right, up, dir, 0.0, length);
}

/// Diagonal worldToIndex for spacing s and origin o (world = o + s * index).
inline void setWorldToIndex(Camera& c, const double spacing[3], const double origin[3])
{
  for (double& x : c.worldToIndex)
  {
    x = 0.0;
  }
  for (int a = 0; a < 3; ++a)
  {
    c.worldToIndex[a * 4 + a] = 1.0 / spacing[a];
    c.worldToIndex[a * 4 + 3] = -origin[a] / spacing[a];
  }
}

/// Ray through the centre of pixel (x, y) in world space, as a double check
/// independent of RayGen: origin on the near plane, unit direction, and the
/// largest parameter (far plane).
struct WorldRay
{
  double o[3];
  double d[3];
  double tFar;
};

inline WorldRay pixelRay(const Camera& c, double px, double py)
{
  auto un = [&](double x, double y, double z, double out[3])
  {
    const double* m = c.invViewProj;
    const double X = m[0] * x + m[1] * y + m[2] * z + m[3];
    const double Y = m[4] * x + m[5] * y + m[6] * z + m[7];
    const double Z = m[8] * x + m[9] * y + m[10] * z + m[11];
    const double Wh = m[12] * x + m[13] * y + m[14] * z + m[15];
    out[0] = X / Wh;
    out[1] = Y / Wh;
    out[2] = Z / Wh;
  };
  const double x = 2.0 * px / c.width - 1.0, y = 2.0 * py / c.height - 1.0;
  WorldRay r;
  double f[3];
  un(x, y, -1.0, r.o);
  un(x, y, 1.0, f);
  double len = 0;
  for (int a = 0; a < 3; ++a)
  {
    r.d[a] = f[a] - r.o[a];
    len += r.d[a] * r.d[a];
  }
  len = std::sqrt(len);
  for (double& v : r.d)
  {
    v /= len;
  }
  r.tFar = len;
  return r;
}

/// Length of the part of [0, tFar] of a world ray inside the world box [lo, hi].
inline double lengthInBox(const WorldRay& r, const double lo[3], const double hi[3])
{
  double t0 = 0.0, t1 = r.tFar;
  for (int a = 0; a < 3; ++a)
  {
    if (r.d[a] == 0.0)
    {
      if (r.o[a] < lo[a] || r.o[a] > hi[a])
      {
        return 0.0;
      }
      continue;
    }
    double ta = (lo[a] - r.o[a]) / r.d[a], tb = (hi[a] - r.o[a]) / r.d[a];
    if (ta > tb)
    {
      std::swap(ta, tb);
    }
    t0 = std::max(t0, ta);
    t1 = std::min(t1, tb);
  }
  return t1 > t0 ? t1 - t0 : 0.0;
}

// ------------------------------------------------------ image comparisons

/// Per-pixel sums of n independent one-sample renders (sum and sum of squares
/// of each of R, G, B, A), for variance estimates.
struct Moments
{
  int width = 0, height = 0, n = 0;
  std::vector<double> sum, sumSq; ///< [pixel * 4 + component]
  double mean(size_t i) const { return this->sum[i] / this->n; }
  /// Unbiased sample variance of one sample.
  double var(size_t i) const
  {
    const double m = this->mean(i);
    return std::max(0.0, (this->sumSq[i] - this->n * m * m) / (this->n - 1));
  }
  size_t size() const { return this->sum.size(); }
};

/// n renders of one sample each, seeds seedBase, seedBase + 1, ... (each
/// seed gives independent random streams).
inline Moments renderMoments(
  Renderer& r, const Scene& scene, const Camera& cam, RenderSettings settings, int n, uint32_t seedBase)
{
  Moments m;
  m.width = cam.width;
  m.height = cam.height;
  m.n = n;
  const size_t P = size_t(cam.width) * size_t(cam.height) * 4;
  m.sum.assign(P, 0.0);
  m.sumSq.assign(P, 0.0);
  settings.samplesPerPixel = 1;
  Accumulator acc;
  for (int k = 0; k < n; ++k)
  {
    acc.resize(cam.width, cam.height);
    acc.reset();
    settings.seed = seedBase + uint32_t(k);
    r.render(scene, cam, settings, nullptr, acc);
    const float* px = acc.rgba();
    for (size_t i = 0; i < P; ++i)
    {
      const double v = px[i];
      EXPECT_TRUE(std::isfinite(v)) << "non-finite pixel value";
      m.sum[i] += v;
      m.sumSq[i] += v * v;
    }
  }
  return m;
}

/// renderMoments on testBackend().
inline Moments renderMoments(
  const Scene& scene, const Camera& cam, RenderSettings settings, int n, uint32_t seedBase, int threads = 0)
{
  std::unique_ptr<Renderer> r = testRenderer(threads);
  return renderMoments(*r, scene, cam, settings, n, seedBase);
}

/**
 * Per RGBA component, the image-mean z statistic of K renders against a
 * reference image: `sum` and `sumSq` hold each pixel value's sum and sum of
 * squares over the renders; z = sum_p (mean_p - ref_p) / sqrt(sum_p
 * var(mean_p)), about standard normal when the renders converge to the
 * reference (pixels independent). `meanDiff` (optional) gets the mean of
 * mean_p - ref_p.
 */
inline std::array<double, 4> imageMeanZ(const std::vector<double>& sum, const std::vector<double>& sumSq, int K,
  const float* ref, std::array<double, 4>* meanDiff = nullptr)
{
  std::array<double, 4> z{};
  const size_t P = sum.size();
  for (int c = 0; c < 4; ++c)
  {
    double D = 0, V = 0;
    for (size_t i = size_t(c); i < P; i += 4)
    {
      const double m = sum[i] / K;
      D += m - ref[i];
      V += std::max(0.0, (sumSq[i] - K * m * m) / (K - 1)) / K;
    }
    z[size_t(c)] = V > 0 ? D / std::sqrt(V) : 0.0;
    if (meanDiff)
    {
      (*meanDiff)[size_t(c)] = D / double(P / 4);
    }
  }
  return z;
}

/**
 * Tests that per-pixel differences D_p with estimated variances V_p (of D_p)
 * are consistent with zero mean, per component (R, G, B, A), three ways, each
 * at significance `alpha`:
 *  1. image mean: sum_p D_p / sqrt(sum_p V_p) is standard normal (pixels are
 *     independent: each draws from its own random streams);
 *  2. sum_p D_p^2 / V_p is chi-square with (pixels with V_p > 0) degrees of
 *     freedom (upper tail);
 *  3. max_p |D_p| / sqrt(V_p), Bonferroni-corrected over the pixels.
 * Pixels with V_p == 0 must have D_p == 0 (every sample was identical).
 */
inline void expectZeroDifference(
  const std::vector<double>& D, const std::vector<double>& V, double alpha, const std::string& what)
{
  const char* names[4] = { "R", "G", "B", "A" };
  const size_t P = D.size() / 4;
  for (int c = 0; c < 4; ++c)
  {
    double sumD = 0, sumV = 0, chi = 0, maxZ = 0;
    int dof = 0;
    for (size_t p = 0; p < P; ++p)
    {
      const double d = D[p * 4 + c], v = V[p * 4 + c];
      if (!(v > 1e-14))
      {
        EXPECT_LE(std::fabs(d), 1e-6) << what << " " << names[c] << ": pixel " << p
                                      << " differs although no sample varied";
        continue;
      }
      sumD += d;
      sumV += v;
      const double z = d / std::sqrt(v);
      chi += z * z;
      maxZ = std::max(maxZ, std::fabs(z));
      ++dof;
    }
    if (dof == 0)
    {
      continue;
    }
    const double zMean = sumD / std::sqrt(sumV);
    EXPECT_GT(normalTwoSided(zMean), alpha) << what << " " << names[c] << ": image-mean difference z = " << zMean;
    EXPECT_GT(chi2Sf(chi, dof), alpha) << what << " " << names[c] << ": sum of z^2 = " << chi << " over " << dof
                                       << " pixels";
    EXPECT_GT(std::min(1.0, normalTwoSided(maxZ) * dof), alpha)
      << what << " " << names[c] << ": largest |z| = " << maxZ << " over " << dof << " pixels";
  }
}

/// The long-accumulation check: images a and b of `preset` samples each
/// (a of mean 0.5, b of mean 0; presetLongImages()) then the same `renders`
/// one-sample renders. a must equal 0.5 x preset / N + b (N = preset +
/// renders) to within the rounding of a (under one float spacing at 0.5,
/// 6e-8), on enough pixels that a stalled float mean (0.5, 9.5e-7 off where
/// the samples are 0 or 1) is caught.
inline void expectLongMean(const Accumulator& a, const Accumulator& b, uint32_t preset, int renders)
{
  const size_t n = size_t(a.width()) * size_t(a.height()) * 4;
  const double N = double(preset) + renders;
  const double base = 0.5 * double(preset) / N;
  double worst = 0;
  size_t moved = 0;
  for (size_t i = 0; i < n; ++i)
  {
    const double want = base + double(b.rgba()[i]);
    worst = std::max(worst, std::fabs(double(a.rgba()[i]) - want));
    moved += std::fabs(want - 0.5) > 2e-7 ? 1u : 0u; // more than 3 float spacings from 0.5
  }
  EXPECT_LE(worst, 0x1p-24) << "the mean of " << preset << " + " << renders
                            << " samples is off by more than its rounding";
  EXPECT_GT(moved, n / 4) << "too few pixels whose mean must move";
}

/// Sets a and b up as images of `preset` samples of the camera's size
/// without rendering them (a mean written through rgbaForOverwrite(), the
/// count through addSamples()): a of mean 0.5, b of mean 0; with or
/// without the error estimate's even half.
inline void presetLongImages(
  Accumulator& a, Accumulator& b, const Camera& cam, uint32_t preset, bool errorEstimation = true)
{
  const size_t n = size_t(cam.width) * size_t(cam.height) * 4;
  for (Accumulator* acc : { &a, &b })
  {
    acc->resize(cam.width, cam.height);
    if (!errorEstimation)
    {
      acc->setErrorEstimation(false);
    }
    float* mean = acc->rgbaForOverwrite();
    std::fill(mean, mean + n, acc == &a ? 0.5f : 0.f);
    acc->addSamples(preset);
  }
}

// Asserts that a Monte Carlo image of N samples per pixel, each of whose
// colour components lies in [0, top] and alpha in [0, 1], has the reference
// as its mean, at significance level alpha: components with
// N mu (top - mu) >= 100 one by one (expectZeroDifference's image-mean z,
// sum of z^2 and largest |z|, whose normal tail needs that many expected
// hits), the others pooled per component into one z-score of their summed
// differences. The variance bound mu (top - mu) / N holds for any variable
// in [0, top] with mean mu.
inline void expectMeanOfSamples(
  const Accumulator& acc, const std::vector<float>& ref, int N, double top, double alpha, const std::string& what)
{
  std::vector<double> D, V;
  double poolD[4] = { 0, 0, 0, 0 }, poolV[4] = { 0, 0, 0, 0 };
  for (size_t i = 0; i < ref.size(); ++i)
  {
    const double M = i % 4 == 3 ? 1.0 : top;
    const double mu = std::min(M, std::max(0.0, double(ref[i])));
    const double d = double(acc.rgba()[i]) - double(ref[i]);
    const double var = mu * (M - mu) / N;
    if (N * mu * (M - mu) >= 100.0)
    {
      D.push_back(d);
      V.push_back(var);
    }
    else
    {
      D.push_back(0.0); // keeps the layout; skipped by expectZeroDifference
      V.push_back(0.0);
      poolD[i % 4] += d;
      poolV[i % 4] += var;
    }
  }
  expectZeroDifference(D, V, alpha, what);
  for (int c = 0; c < 4; ++c)
  {
    if (poolV[c] > 0)
    {
      const double z = poolD[c] / std::sqrt(poolV[c]);
      EXPECT_GT(normalTwoSided(z), alpha) << what << " component " << c << ": pooled rare pixels z = " << z;
    }
    else
    {
      EXPECT_LE(std::fabs(poolD[c]), 1e-5) << what << " component " << c;
    }
  }
}
/// Two renders of the same expectation (pooled variance under the null).
inline void expectSameImage(const Moments& A, const Moments& B, double alpha, const std::string& what)
{
  ASSERT_EQ(A.size(), B.size());
  std::vector<double> D(A.size()), V(A.size());
  for (size_t i = 0; i < A.size(); ++i)
  {
    const double nA = A.n, nB = B.n, N = nA + nB;
    const double m = (A.sum[i] + B.sum[i]) / N;
    const double s2 = std::max(0.0, (A.sumSq[i] + B.sumSq[i] - N * m * m) / (N - 1));
    D[i] = A.mean(i) - B.mean(i);
    V[i] = s2 * (1.0 / nA + 1.0 / nB);
  }
  expectZeroDifference(D, V, alpha, what);
}

/**
 * Two renders of the same expectation by estimators whose per-sample
 * distributions differ (e.g. the collision estimator's rare bright samples
 * against the expected-value estimator's small steady ones), at
 * significance `alpha`, per component: the image-mean z (the pixels'
 * differences summed, over the summed variances of the difference), then
 * the z of each `tile` x `tile` block of pixels, Bonferroni-corrected over
 * the blocks. A per-pixel test would not do: where one estimator has only a
 * few non-zero samples in a pixel, its mean is far from normal. A block
 * takes part only where each render holds at least 30 effective non-zero
 * samples in it (sum^2 / sum of squares, at most the count of non-zero
 * samples); the other blocks are pooled into one more z-test.
 */
inline void expectSameMean(const Moments& A, const Moments& B, double alpha, const std::string& what, int tile = 4)
{
  ASSERT_EQ(A.size(), B.size());
  const char* names[4] = { "R", "G", "B", "A" };
  const int tx = (A.width + tile - 1) / tile, ty = (A.height + tile - 1) / tile;
  for (int c = 0; c < 4; ++c)
  {
    double allD = 0, allV = 0, rareD = 0, rareV = 0, maxZ = 0;
    int blocks = 0;
    for (int by = 0; by < ty; ++by)
    {
      for (int bx = 0; bx < tx; ++bx)
      {
        double D = 0, V = 0, sA = 0, qA = 0, sB = 0, qB = 0;
        for (int y = by * tile; y < std::min(A.height, (by + 1) * tile); ++y)
        {
          for (int x = bx * tile; x < std::min(A.width, (bx + 1) * tile); ++x)
          {
            const size_t i = (size_t(y) * size_t(A.width) + size_t(x)) * 4 + size_t(c);
            D += A.mean(i) - B.mean(i);
            V += A.var(i) / A.n + B.var(i) / B.n;
            sA += A.sum[i];
            qA += A.sumSq[i];
            sB += B.sum[i];
            qB += B.sumSq[i];
          }
        }
        allD += D;
        allV += V;
        const bool enough = qA > 0 && qB > 0 && sA * sA / qA >= 30.0 && sB * sB / qB >= 30.0;
        if (!enough)
        {
          rareD += D;
          rareV += V;
          continue;
        }
        maxZ = std::max(maxZ, std::fabs(D) / std::sqrt(V));
        ++blocks;
      }
    }
    if (allV > 0)
    {
      const double z = allD / std::sqrt(allV);
      EXPECT_GT(normalTwoSided(z), alpha) << what << " " << names[c] << ": image-mean difference z = " << z;
    }
    else
    {
      EXPECT_LE(std::fabs(allD), 1e-6) << what << " " << names[c] << ": differs although no sample varied";
    }
    if (blocks > 0)
    {
      EXPECT_GT(std::min(1.0, normalTwoSided(maxZ) * blocks), alpha)
        << what << " " << names[c] << ": largest block |z| = " << maxZ << " over " << blocks << " blocks";
    }
    if (rareV > 0)
    {
      const double z = rareD / std::sqrt(rareV);
      EXPECT_GT(normalTwoSided(z), alpha) << what << " " << names[c] << ": pooled sparse blocks z = " << z;
    }
  }
}

/// Binomial test: `hits` successes in `n` trials of probability p, two-sided,
/// normal approximation (n p (1 - p) is large in every use here).
inline void expectBinomial(double hits, double n, double p, double alpha, const std::string& what)
{
  const double sd = std::sqrt(n * p * (1.0 - p));
  const double z = (hits - n * p) / sd;
  EXPECT_GT(normalTwoSided(z), alpha) << what << ": " << hits << " of " << n << " (expected " << n * p << ", z = " << z
                                      << ")";
}
} // namespace test
} // namespace mcvol
