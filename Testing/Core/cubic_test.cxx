// SPDX-License-Identifier: BSD-3-Clause
// Cubic B-spline sampling (Interpolation::Cubic; Documentation/user-guide/
// channels-and-blending.md): the
// weights, the 64-tap sample against a reference written here in double,
// pre-classified channels, the wider macrocell ranges that keep majorants
// valid, the scene's rebuild on a switch, the ray marcher's refusal of the
// opacity model, and Monte Carlo converging to the cubic ray march.
//
// Significance: CubicMonteCarloConvergesToRayMarch makes 2 datasets x 2
// modes x 2 estimators x 4 components x 4 statistics = 128 checks at
// family-wise level kAlpha = 0.001 (Bonferroni). Everything else is
// deterministic (fixed seeds).
#include "TestUtil.h"

#include "mcvol/ray/Acceleration.h"
#include "mcvol/ray/Blend.h"
#include "mcvol/RayMarcher.h"
#include "mcvol/ray/Sampling.h"

#include <cfloat>
#include <limits>

using namespace mcvol;
using namespace mcvol::test;

namespace
{
constexpr double kAlpha = 1e-3;

/// The uniform cubic B-spline kernel B(d) at distance d from a voxel centre,
/// written from its piecewise definition (not from bsplineWeights()).
double bspline(double d)
{
  d = std::fabs(d);
  if (d < 1.0)
  {
    return (4.0 - 6.0 * d * d + 3.0 * d * d * d) / 6.0;
  }
  if (d < 2.0)
  {
    return (2.0 - d) * (2.0 - d) * (2.0 - d) / 6.0;
  }
  return 0.0;
}

/// Reference cubic sample of a voxel function at continuous index p: the
/// point clamped to the grid, the kernel summed over every voxel within
/// reach (indices past the edges read the edge voxel), in double.
template <class Voxel>
double referenceCubic(const int dims[3], const double p[3], Voxel voxel)
{
  double x[3];
  int lo[3];
  for (int a = 0; a < 3; ++a)
  {
    x[a] = std::min(std::max(p[a], 0.0), double(dims[a] - 1));
    lo[a] = int(std::floor(x[a])) - 1;
  }
  double sum = 0.0;
  for (int k = lo[2]; k < lo[2] + 4; ++k)
    for (int j = lo[1]; j < lo[1] + 4; ++j)
      for (int i = lo[0]; i < lo[0] + 4; ++i)
      {
        const double w = bspline(x[0] - i) * bspline(x[1] - j) * bspline(x[2] - k);
        sum += w * voxel(clampi(i, 0, dims[0] - 1), clampi(j, 0, dims[1] - 1), clampi(k, 0, dims[2] - 1));
      }
  return sum;
}

std::vector<float> marchImage(const Scene& scene, const Camera& cam, const MarchSettings& ms)
{
  RayMarcher r;
  Accumulator acc;
  r.render(scene, cam, ms, nullptr, acc);
  return std::vector<float>(acc.rgba(), acc.rgba() + size_t(cam.width) * cam.height * 4);
}

Vec3f randomPoint(TestRand& r, const VolumeView& v, double margin)
{
  Vec3f p;
  for (int a = 0; a < 3; ++a)
  {
    p[a] = float(r.uniform(v.boxLo[a] - margin, v.boxHi[a] + margin));
  }
  return p;
}
} // namespace

// Partition of unity, non-negativity, agreement with the kernel's piecewise
// definition, linear precision (the first moment is t: a B-spline reproduces
// linear functions), and continuity across voxels (the weights at t -> 1 are
// those at t = 0 shifted by one tap).
TEST(CubicWeights, ConvexExactAndContinuous)
{
  for (int s = 0; s <= 1000; ++s)
  {
    const float t = s == 1000 ? std::nextafter(1.f, 0.f) : float(s) / 1000.f;
    float w[4];
    bsplineWeights(t, w);
    double sum = 0.0, moment = 0.0;
    for (int k = 0; k < 4; ++k)
    {
      EXPECT_GE(w[k], 0.f) << "t " << t << " tap " << k;
      EXPECT_NEAR(w[k], bspline(double(t) - (k - 1)), 1e-6) << "t " << t << " tap " << k;
      sum += w[k];
      moment += w[k] * (k - 1);
    }
    EXPECT_NEAR(sum, 1.0, 1e-6) << "t " << t;
    EXPECT_NEAR(moment, double(t), 1e-6) << "t " << t;
  }
  float w0[4], w1[4];
  bsplineWeights(0.f, w0);
  bsplineWeights(std::nextafter(1.f, 0.f), w1);
  EXPECT_NEAR(w1[0], 0.f, 1e-6);
  for (int k = 0; k < 3; ++k)
  {
    EXPECT_NEAR(w1[k + 1], w0[k], 1e-6) << "tap " << k;
  }
}

// sampleChannelCubic() equals the double-precision
// reference at random points (inside, on the faces and outside the box,
// which clamp) for float32, uint8 and float64 (with an offset) channels,
// odd sizes and one-voxel axes. Tolerance: float rounding of a 64-term
// convex sum, relative to the data's magnitude.
TEST(CubicSampling, MatchesReference)
{
  TestRand r(2024);
  for (int sc = 0; sc < 24; ++sc)
  {
    int dims[3];
    for (int& d : dims)
    {
      d = r.chance(0.15) ? 1 : r.integer(2, 11);
    }
    const size_t voxels = size_t(dims[0]) * dims[1] * dims[2];
    std::vector<float> f32(voxels);
    std::vector<uint8_t> u8(voxels);
    std::vector<double> f64(voxels);
    for (size_t v = 0; v < voxels; ++v)
    {
      f32[v] = float(r.uniform(-5.0, 5.0));
      u8[v] = uint8_t(r.integer(0, 255));
      f64[v] = 1e9 + r.uniform(0.0, 500.0);
    }
    ChannelSource src[3];
    src[0].data = f32.data();
    src[1].data = u8.data();
    src[1].type = ScalarType::UInt8;
    src[2].data = f64.data();
    src[2].type = ScalarType::Float64;
    src[2].offset = 1e9;
    Scene scene;
    scene.setVolume(dims, 3, src);
    const float range[3][2] = { { -5.f, 5.f }, { 0.f, 255.f }, { 0.f, 500.f } };
    for (int n = 0; n < 3; ++n)
    {
      // Extinction rising with the value, so that the optics show which sample was taken.
      TransferFunctionDesc tf = flatTF(0.1f, 1, 1, 1, 1.f, 2, range[n][0], range[n][1]);
      tf.opacity[1] = 0.9f;
      scene.setTransferFunction(n, tf);
    }
    scene.setInterpolation(Interpolation::Cubic);
    EXPECT_EQ(scene.interpolation(), Interpolation::Cubic);
    scene.update();
    const VolumeView& vol = scene.view().volume;
    ASSERT_TRUE(vol.cubic);
    ASSERT_FALSE(vol.nearest);
    auto at = [&](size_t n, int i, int j, int k) -> double
    {
      const size_t v = (size_t(k) * dims[1] + j) * dims[0] + i;
      return n == 0 ? double(f32[v]) : (n == 1 ? double(u8[v]) : f64[v] - 1e9);
    };
    const double scale[3] = { 5.0, 255.0, 500.0 };
    for (int s = 0; s < 400; ++s)
    {
      const Vec3f p = randomPoint(r, vol, 0.7);
      const double pd[3] = { p.x, p.y, p.z };
      for (int n = 0; n < 3; ++n)
      {
        const double ref = referenceCubic(dims, pd, [&](int i, int j, int k) { return at(size_t(n), i, j, k); });
        // float64: the voxel itself is rounded to float after the offset.
        const double tol = (n == 2 ? 1e-4 : 5e-6) * scale[n];
        const float v = sampleChannelCubic(vol, n, p);
        ASSERT_NEAR(v, ref, tol) << "scene " << sc << " dims " << dims[0] << "x" << dims[1] << "x" << dims[2]
                                 << " channel " << n << " at (" << p.x << ", " << p.y << ", " << p.z << ")";
        // The render path (channelOptics) takes the cubic sample.
        ASSERT_EQ(channelOptics(scene.view(), n, p).sigma, lookupTF(scene.view().tables, n, v).sigma);
      }
    }
  }
}

// A linear ramp is reproduced exactly where the footprint lies inside the
// grid (floor(x) in [1, dim - 3] on every axis), a constant volume stays
// constant everywhere (edges and outside the box included), an axis with
// one voxel is constant along it, and a NaN voxel poisons exactly the
// samples that read it.
TEST(CubicSampling, RampsConstantsOneVoxelAxesAndNaN)
{
  const int dims[3] = { 9, 7, 8 };
  TestVolume ramp(dims[0], dims[1], dims[2], 2, 0.75f);
  for (int k = 0; k < dims[2]; ++k)
    for (int j = 0; j < dims[1]; ++j)
      for (int i = 0; i < dims[0]; ++i)
      {
        ramp.channels[0][ramp.index(i, j, k)] = 0.5f + 0.25f * i - 0.5f * j + 0.125f * k;
      }
  Scene scene;
  configure(scene, ramp, { flatTF(0.5f, 1, 1, 1), flatTF(0.5f, 1, 1, 1) }, 4);
  scene.setInterpolation(Interpolation::Cubic);
  scene.update();
  const VolumeView& vol = scene.view().volume;
  TestRand r(7);
  for (int s = 0; s < 2000; ++s)
  {
    Vec3f p;
    for (int a = 0; a < 3; ++a)
    {
      p[a] = float(r.uniform(1.0, double(dims[a] - 2))); // floor(p) in [1, dim - 3]
    }
    const double expect = 0.5 + 0.25 * p.x - 0.5 * p.y + 0.125 * p.z;
    ASSERT_NEAR(sampleChannelCubic(vol, 0, p), expect, 1e-5) << "ramp at (" << p.x << ", " << p.y << ", " << p.z << ")";
    const Vec3f q = randomPoint(r, vol, 1.5);
    ASSERT_NEAR(sampleChannelCubic(vol, 1, q), 0.75f, 1e-6f)
      << "constant at (" << q.x << ", " << q.y << ", " << q.z << ")";
  }
  // Near the edges the clamped B-spline is no longer exact for a ramp (it
  // repeats the edge voxel): that is the documented boundary rule, checked
  // against the reference, not the ramp.
  {
    const Vec3f p(0.f, 3.f, 3.f);
    EXPECT_NEAR(sampleChannelCubic(vol, 0, p), 0.5 + 0.25 * (1.0 / 6.0) - 0.5 * 3 + 0.125 * 3, 1e-5)
      << "at x = 0 the taps are (v0, v0, v1, v2) with weights (1/6, 4/6, 1/6, 0)";
  }

  // One-voxel axes: a 1 x 6 x 1 line sampled anywhere in x and z equals the
  // 1D sample along y.
  const int lineDims[3] = { 1, 6, 1 };
  TestVolume line(1, 6, 1, 1, 0.f);
  const float values[6] = { 0.f, 1.f, 4.f, 2.f, 7.f, 3.f };
  std::copy(values, values + 6, line.channels[0].begin());
  Scene ls;
  configure(ls, line, { flatTF(0.5f, 1, 1, 1) }, 2);
  ls.setInterpolation(Interpolation::Cubic);
  ls.update();
  for (int s = 0; s < 500; ++s)
  {
    const Vec3f p(float(r.uniform(-0.5, 0.5)), float(r.uniform(-1.0, 6.0)), float(r.uniform(-0.5, 0.5)));
    const double pd[3] = { p.x, p.y, p.z };
    const double ref = referenceCubic(lineDims, pd, [&](int, int j, int) { return double(values[j]); });
    ASSERT_NEAR(sampleChannelCubic(ls.view().volume, 0, p), ref, 1e-5) << "y " << p.y;
    const Vec3f q(0.f, p.y, 0.f);
    ASSERT_EQ(sampleChannelCubic(ls.view().volume, 0, p), sampleChannelCubic(ls.view().volume, 0, q)) << "y " << p.y;
  }

  // NaN at (4, 3, 4): samples whose 4x4x4 footprint holds it are NaN (and
  // transparent through the table), others are not.
  ramp.channels[1][ramp.index(4, 3, 4)] = std::numeric_limits<float>::quiet_NaN();
  scene.dataModified();
  scene.update();
  for (int s = 0; s < 2000; ++s)
  {
    const Vec3f p = randomPoint(r, vol, 0.0);
    bool reads = true;
    const int nan[3] = { 4, 3, 4 };
    for (int a = 0; a < 3; ++a)
    {
      const int i = int(std::floor(p[a]));
      reads = reads && nan[a] >= i - 1 && nan[a] <= i + 2;
    }
    const float v = sampleChannelCubic(vol, 1, p);
    ASSERT_EQ(std::isnan(v), reads) << "at (" << p.x << ", " << p.y << ", " << p.z << ")";
    if (reads)
    {
      ASSERT_EQ(channelOptics(scene.view(), 1, p).sigma, 0.f);
    }
  }
}

// Pre-classified channels: sigma is the reference B-spline sample of the
// voxels' sanitised sigma; on a volume of one colour (sigma varying, zeros
// included) the colour is that colour wherever sigma > 0; a NaN voxel makes
// the samples that read it transparent.
TEST(CubicSampling, ClassifiedKeepsAConstantColour)
{
  TestRand r(99);
  const int dims[3] = { 7, 6, 5 };
  const size_t voxels = size_t(dims[0]) * dims[1] * dims[2];
  const float colour[3] = { 0.2f, 0.5f, 0.9f };
  std::vector<float> data(voxels * 4);
  for (size_t v = 0; v < voxels; ++v)
  {
    const float s = r.chance(0.3) ? 0.f : float(r.uniform(0.0, 3.0));
    data[v * 4] = s;
    for (int c = 0; c < 3; ++c)
    {
      data[v * 4 + 1 + size_t(c)] = s * colour[c];
    }
  }
  ChannelSource src;
  src.data = data.data();
  src.stride = 4;
  src.format = ChannelFormat::Extinction;
  Scene scene;
  scene.setVolume(dims, 1, &src);
  scene.setInterpolation(Interpolation::Cubic);
  scene.update();
  const SceneView& s = scene.view();
  int coloured = 0;
  for (int i = 0; i < 3000; ++i)
  {
    const Vec3f p = randomPoint(r, s.volume, 0.5);
    const double pd[3] = { p.x, p.y, p.z };
    const TFSample t = channelOptics(s, 0, p);
    const double ref = referenceCubic(
      dims, pd, [&](int a, int b, int c) { return double(data[((size_t(c) * dims[1] + b) * dims[0] + a) * 4]); });
    ASSERT_NEAR(t.sigma, ref, 1e-5) << "at (" << p.x << ", " << p.y << ", " << p.z << ")";
    if (t.sigma > 0.f)
    {
      ++coloured;
      for (int c = 0; c < 3; ++c)
      {
        ASSERT_NEAR(t.rgb[c], colour[c], 1e-5) << "component " << c;
      }
    }
  }
  EXPECT_GT(coloured, 2500);
  // The trilinear sample differs (the filters differ), so the cubic path was taken.
  const Vec3f p(2.3f, 3.6f, 1.2f);
  const float cubicSigma = channelOptics(s, 0, p).sigma;
  scene.setInterpolation(Interpolation::Linear);
  scene.update();
  EXPECT_GT(std::fabs(channelOptics(scene.view(), 0, p).sigma - cubicSigma), 1e-3f);
  scene.setInterpolation(Interpolation::Cubic);
  data[((size_t(2) * dims[1] + 3) * dims[0] + 3) * 4 + 2] = std::numeric_limits<float>::quiet_NaN();
  scene.dataModified();
  scene.update();
  EXPECT_EQ(channelOptics(scene.view(), 0, Vec3f(3.5f, 2.5f, 1.5f)).sigma, 0.f) << "footprint holds the NaN";
  EXPECT_GT(channelOptics(scene.view(), 0, Vec3f(0.2f, 0.2f, 4.f)).sigma, 0.f) << "footprint misses it";
}

// The majorant of a point's macrocell bounds every channel's cubic sample,
// for points anywhere in the cell and up to 0.75 voxel outside it: the
// trilinear ranges' apron leaves one voxel of margin for points the DDA
// places off their cell by rounding, and the cubic ranges keep that margin
// (footprintApron). Random sparse data (zeros next to large values, so a tap
// outside the ranges shows), scalar channels with random tables and a
// pre-classified channel, random macrocell sizes; trilinear is held to the
// same contract. With the cubic apron set to 1 this test fails (checked when
// it was written): the B-spline reaches one voxel further than trilinear.
TEST(CubicMajorants, BoundEverySampleWithMargin)
{
  TestRand r(31337);
  for (int sc = 0; sc < 16; ++sc)
  {
    int dims[3];
    for (int& d : dims)
    {
      d = r.chance(0.15) ? 1 : r.integer(2, 20);
    }
    const size_t voxels = size_t(dims[0]) * dims[1] * dims[2];
    std::vector<float> a(voxels), b(voxels), cl(voxels * 4);
    for (size_t v = 0; v < voxels; ++v)
    {
      a[v] = r.chance(0.85) ? 0.f : float(r.uniform(0.0, 10.0));
      b[v] = r.chance(0.05) ? std::numeric_limits<float>::quiet_NaN() : float(r.uniform(-3.0, 7.0));
      const float s = r.chance(0.85) ? 0.f : float(r.uniform(0.0, 5.0));
      cl[v * 4] = s;
      cl[v * 4 + 1] = cl[v * 4 + 2] = cl[v * 4 + 3] = 0.5f * s;
    }
    ChannelSource src[3];
    src[0].data = a.data();
    src[1].data = b.data();
    src[2].data = cl.data();
    src[2].stride = 4;
    src[2].format = ChannelFormat::Extinction;
    Scene scene;
    scene.setVolume(dims, 3, src);
    // Channel 0: extinction rises from 0 at scalar 0, so any leak is visible.
    TransferFunctionDesc ramp = flatTF(0.f, 1, 1, 1, 1.f, 64, 0.f, 10.f);
    for (int i = 0; i < 64; ++i)
    {
      ramp.opacity[size_t(i)] = 0.9f * float(i) / 63.f;
    }
    scene.setTransferFunction(0, ramp);
    TransferFunctionDesc bumpy = flatTF(0.f, 1, 1, 1, 1.f, 64, -3.f, 7.f); // one table size for all channels
    for (float& o : bumpy.opacity)
    {
      o = r.chance(0.4) ? 0.f : float(r.uniform());
    }
    scene.setTransferFunction(1, bumpy);
    scene.setMacrocellSize(r.integer(1, 6));
    for (Interpolation interp : { Interpolation::Cubic, Interpolation::Linear })
    {
      scene.setInterpolation(interp);
      scene.update();
      const SceneView& s = scene.view();
      const GridView& g = s.grid;
      int failures = 0;
      for (int i = 0; i < 3000 && failures < 5; ++i)
      {
        int cell[3];
        Vec3f p;
        for (int ax = 0; ax < 3; ++ax)
        {
          cell[ax] = r.integer(0, g.dims[ax] - 1);
          const double lo = g.lo[ax] + cell[ax] * g.cellSize[ax];
          p[ax] = float(r.uniform(lo - 0.75, lo + g.cellSize[ax] + 0.75));
        }
        const size_t c = size_t(cell[0] + g.dims[0] * (cell[1] + g.dims[1] * cell[2]));
        for (int n = 0; n < 3; ++n)
        {
          const float sigma = channelOptics(s, n, p).sigma;
          ASSERT_TRUE(std::isfinite(sigma) && sigma >= 0.f);
          if (!(sigma <= g.majorants[c * 3 + size_t(n)]))
          {
            ++failures;
            ADD_FAILURE() << toString(interp) << " scene " << sc << " macrocell " << scene.macrocellSize()
                          << " channel " << n << " at (" << p.x << ", " << p.y << ", " << p.z << ") in cell ("
                          << cell[0] << ", " << cell[1] << ", " << cell[2] << "): sigma " << sigma << " > majorant "
                          << g.majorants[c * 3 + size_t(n)];
          }
        }
      }
    }
  }
}

// Switching to or from cubic rebuilds the ranges (the footprint widens),
// with and without the host build (the CUDA backend follows dataVersion());
// nearest <-> linear does not. The cubic ranges contain the trilinear ones.
TEST(CubicMajorants, SwitchRebuildsRanges)
{
  TestVolume v(12, 10, 9, 1, 0.f);
  TestRand r(5);
  for (float& x : v.channels[0])
  {
    x = r.chance(0.8) ? 0.f : float(r.uniform(0.0, 1.0));
  }
  for (bool host : { true, false })
  {
    Scene scene;
    scene.setHostAcceleration(host);
    configure(scene, v, { flatTF(0.5f, 1, 1, 1) }, 4);
    const std::vector<float> linear = scene.macrocellRanges();
    uint64_t version = scene.dataVersion();
    scene.setNearestInterpolation(true);
    EXPECT_FALSE(scene.update()) << "nearest reads within the trilinear ranges";
    EXPECT_EQ(scene.dataVersion(), version);
    scene.setInterpolation(Interpolation::Cubic);
    EXPECT_TRUE(scene.update());
    EXPECT_GT(scene.dataVersion(), version);
    version = scene.dataVersion();
    if (host)
    {
      const std::vector<float>& cubic = scene.macrocellRanges();
      ASSERT_EQ(cubic.size(), linear.size());
      int wider = 0;
      for (size_t i = 0; i < cubic.size(); i += 2)
      {
        EXPECT_LE(cubic[i], linear[i]);
        EXPECT_GE(cubic[i + 1], linear[i + 1]);
        wider += cubic[i] < linear[i] || cubic[i + 1] > linear[i + 1] ? 1 : 0;
      }
      EXPECT_GT(wider, 0) << "sparse data: some cell's range must widen";
    }
    scene.setInterpolation(Interpolation::Cubic);
    EXPECT_FALSE(scene.update()) << "no change, no rebuild";
    scene.setNearestInterpolation(false);
    EXPECT_EQ(scene.interpolation(), Interpolation::Linear);
    EXPECT_TRUE(scene.update());
    EXPECT_GT(scene.dataVersion(), version);
    if (host)
    {
      EXPECT_EQ(scene.macrocellRanges(), linear);
    }
  }
  Scene scene;
  EXPECT_THROW(scene.setInterpolation(Interpolation(7)), std::invalid_argument);
  EXPECT_STREQ(toString(Interpolation::Cubic), "cubic");
  EXPECT_STREQ(toString(Interpolation::Nearest), "nearest");
  EXPECT_STREQ(toString(Interpolation::Linear), "linear");
}

// The ray marcher's opacity model interpolates voxel opacities trilinearly:
// with cubic interpolation it is refused with a message saying why; the
// extinction model renders, and its image differs from the trilinear one
// (the cubic filter is taken).
TEST(CubicRayMarch, OpacityModelRefusedExtinctionRenders)
{
  const DemoVolume v = makeDemo("cosmology", { 16, 16, 16 });
  const Camera cam = orbitCamera(v.dims, v.spacing, 24, 24, 30, 20);
  Scene scene;
  configureDemo(scene, v, 4, 128, 1.0, BlendMode::Density);
  MarchSettings ms;
  ms.step = 0.25;
  const std::vector<float> linear = marchImage(scene, cam, ms);
  scene.setInterpolation(Interpolation::Cubic);
  scene.update();
  const std::vector<float> cubic = marchImage(scene, cam, ms);
  double diff = 0.0, sum = 0.0;
  for (size_t i = 0; i < cubic.size(); ++i)
  {
    ASSERT_TRUE(std::isfinite(cubic[i]));
    diff += std::fabs(double(cubic[i]) - double(linear[i]));
    sum += cubic[i];
  }
  EXPECT_GT(sum, 1.0) << "the scene is visible";
  EXPECT_GT(diff, 1e-3 * sum) << "cubic and trilinear images differ";
  ms.compositing = Compositing::Opacity;
  try
  {
    marchImage(scene, cam, ms);
    ADD_FAILURE() << "the opacity model with cubic interpolation must throw";
  }
  catch (const std::invalid_argument& e)
  {
    EXPECT_NE(std::string(e.what()).find("cubic"), std::string::npos) << e.what();
  }
  scene.setInterpolation(Interpolation::Linear);
  scene.update();
  EXPECT_NO_THROW(marchImage(scene, cam, ms));
}

// Monte Carlo with cubic interpolation converges to the cubic ray march
// (extinction model, fine step), the pattern of RayMarch.MonteCarloConverges
// ToRayMarch (raymarch_test.cxx): N = 2048 samples per pixel at pixel
// centres, independent samples, per-component variance bounded by
// mu (top - mu) / N, components with N mu (top - mu) >= 100 tested one by
// one (expectZeroDifference: image-mean z, sum of z^2, largest |z|), the rest
// pooled. Density and max, collision and expected-value estimators, two
// datasets: 4 checks x 4 components x 8 = 128 at family-wise kAlpha.
TEST(CubicRayMarch, MonteCarloConvergesToRayMarch)
{
  const double alpha = kAlpha / (4 * 4 * 2 * 2 * 2);
  const int N = 2048;
  for (const char* name : { "figure3", "cosmology" })
  {
    const DemoVolume v = makeDemo(name, { 20, 20, 20 });
    const Camera cam = orbitCamera(v.dims, v.spacing, 24, 24, 30, 20);
    for (BlendMode mode : { BlendMode::Density, BlendMode::Max })
    {
      Scene scene;
      configureDemo(scene, v, 4, 128, 1.0, mode);
      scene.setInterpolation(Interpolation::Cubic);
      scene.update();
      MarchSettings ms;
      ms.step = 1.0 / 16.0;
      ms.terminateTransmittance = 0.f;
      const std::vector<float> ref = marchImage(scene, cam, ms);
      for (Estimator estimator : { Estimator::Collision, Estimator::ExpectedValue })
      {
        CPURenderer mc;
        Accumulator acc;
        RenderSettings rs;
        rs.jitterPixels = false;
        rs.samplesPerPixel = N;
        rs.seed = 411;
        rs.sampler = Sampler::Independent;
        rs.estimator = estimator;
        mc.render(scene, cam, rs, nullptr, acc);
        const std::string what =
          std::string(name) + " " + toString(mode) + " " + toString(estimator) + " cubic MC vs cubic ray march";
        const double top = estimator == Estimator::ExpectedValue ? 1.0 + kRouletteThreshold : 1.0;
        expectMeanOfSamples(acc, ref, N, top, alpha, what);
      }
    }
  }
}
