// SPDX-License-Identifier: BSD-3-Clause
// The CUDA backend against the CPU backend (needs a CUDA device; TestMain
// skips with 125 without one).
//
// Significance: CudaAgreement runs 2 samplings x 5 types x 5 channel counts
// x 4 blend modes x 2 trackers = 400 image comparisons, each of 12 checks
// (3 statistics x R, G, B, A); the family-wise level is kAlpha = 0.001, so
// each check runs at kAlpha / 4800 (Bonferroni). Seeds are fixed.
#include "TestUtil.h"

#include "mcvol/Pyramid.h"

#include "mcvol/CUDARenderer.h"
#include "mcvol/EstimatorChoice.h"
#include "mcvol/MarchSetup.h"
#include "mcvol/RenderSetup.h"

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <cstring>
#include <functional>
#include <limits>
#include <sstream>
#include <utility>
#include <vector>

using namespace mcvol;
using namespace mcvol::test;

namespace
{
constexpr double kAlpha = 1e-3;

/// N channels of smooth, different blobs, stored as T (planar), with a NaN
/// voxel in float data.
struct TypedVolume
{
  int dims[3] = { 0, 0, 0 };
  ScalarType type = ScalarType::Float32;
  std::vector<std::vector<uint8_t>> bytes;
  double minValue = 0.0;
  double maxValue = 1.0;
  double offset = 0.0; ///< float64: the data sit at 1e6 + [0, 1]

  TypedVolume(ScalarType t, int n, int nx, int ny, int nz)
  {
    this->dims[0] = nx;
    this->dims[1] = ny;
    this->dims[2] = nz;
    this->type = t;
    switch (t)
    {
      case ScalarType::UInt8:
        this->maxValue = 255;
        break;
      case ScalarType::UInt16:
        this->maxValue = 65535;
        break;
      case ScalarType::Int16: // the whole range, -32768 included (snorm's edge)
        this->minValue = -32768;
        this->maxValue = 32767;
        break;
      case ScalarType::Float64:
        this->offset = 1e6;
        this->minValue = 1e6;
        this->maxValue = 1e6 + 1;
        break;
      default:
        break;
    }
    const size_t voxels = size_t(nx) * ny * nz;
    const size_t es = size_t(scalarTypeSize(t));
    this->bytes.assign(size_t(n), std::vector<uint8_t>(voxels * es));
    for (int c = 0; c < n; ++c)
    {
      // Blob centre and radius differ per channel, so channels overlap partly.
      const double cx = nx * (0.3 + 0.4 * ((c * 37) % 11) / 10.0);
      const double cy = ny * (0.3 + 0.4 * ((c * 53) % 7) / 6.0);
      const double cz = nz * (0.3 + 0.4 * ((c * 29) % 5) / 4.0);
      const double r = 0.25 * nx * (0.7 + 0.3 * ((c * 17) % 3));
      for (int k = 0; k < nz; ++k)
        for (int j = 0; j < ny; ++j)
          for (int i = 0; i < nx; ++i)
          {
            const double d2 = ((i - cx) * (i - cx) + (j - cy) * (j - cy) + (k - cz) * (k - cz)) / (r * r);
            const double v = std::exp(-d2) * (0.8 + 0.2 * std::sin(0.7 * i + 0.3 * c));
            const size_t idx = (size_t(k) * ny + j) * nx + i;
            uint8_t* p = this->bytes[size_t(c)].data() + idx * es;
            if (t == ScalarType::UInt8)
            {
              *p = uint8_t(std::lround(std::min(1.0, std::max(0.0, v)) * 255));
            }
            else if (t == ScalarType::UInt16)
            {
              const uint16_t u = uint16_t(std::lround(std::min(1.0, std::max(0.0, v)) * 65535));
              std::memcpy(p, &u, 2);
            }
            else if (t == ScalarType::Int16)
            {
              const int16_t u = int16_t(std::lround(std::min(1.0, std::max(0.0, v)) * 65535 - 32768));
              std::memcpy(p, &u, 2);
            }
            else if (t == ScalarType::Float64)
            {
              const double f = 1e6 + v;
              std::memcpy(p, &f, 8);
            }
            else
            {
              float f = float(v);
              if (c == 0 && i == nx / 2 && j == ny / 2 && k == nz / 2)
              {
                f = std::numeric_limits<float>::quiet_NaN();
              }
              std::memcpy(p, &f, 4);
            }
          }
    }
  }

  void configure(Scene& scene, BlendMode mode, int macrocell = 4) const
  {
    std::vector<ChannelSource> src(this->bytes.size());
    for (size_t n = 0; n < src.size(); ++n)
    {
      src[n].data = this->bytes[n].data();
      src[n].type = this->type;
      src[n].offset = this->offset;
    }
    scene.setVolume(this->dims, int(src.size()), src.data());
    const float colours[6][3] = { { 1, 0.2f, 0.1f }, { 0.1f, 1, 0.2f }, { 0.2f, 0.3f, 1 }, { 1, 1, 0.1f },
      { 0.1f, 1, 1 }, { 1, 0.1f, 1 } };
    for (size_t n = 0; n < src.size(); ++n)
    {
      // Opacity ramps up over the upper part of the range, so every channel
      // has empty, thin and dense regions.
      TransferFunctionDesc tf;
      tf.scalarMin = this->minValue;
      tf.scalarMax = this->maxValue;
      tf.unitDistance = 1.f + 0.5f * float(n % 3);
      const int K = 64;
      for (int i = 0; i < K; ++i)
      {
        const float x = float(i) / float(K - 1);
        tf.opacity.push_back(x < 0.2f ? 0.f : std::min(1.f, (x - 0.2f) * 0.6f));
        const float* c = colours[n % 6];
        tf.rgb.push_back(c[0] * (0.5f + 0.5f * x));
        tf.rgb.push_back(c[1]);
        tf.rgb.push_back(c[2] * (1.f - 0.5f * x));
      }
      scene.setTransferFunction(int(n), tf);
    }
    scene.setMacrocellSize(macrocell);
    scene.setBlendMode(mode);
    std::vector<float> w(src.size());
    for (size_t n = 0; n < w.size(); ++n)
    {
      w[n] = 1.f + float(n % 3);
    }
    scene.setMixWeights(w.data(), int(w.size()));
    scene.update();
  }
};

std::unique_ptr<CUDARenderer> cudaRenderer(CudaSampling s)
{
  std::unique_ptr<CUDARenderer> r(new CUDARenderer());
  r->setSampling(s);
  return r;
}

std::vector<float> renderImage(Renderer& r, const Scene& scene, const Camera& cam, int spp, uint32_t seed,
  Tracker t = Tracker::OneDDA, RenderCounters* counters = nullptr)
{
  Accumulator acc;
  RenderSettings rs;
  rs.samplesPerPixel = spp;
  rs.seed = seed;
  rs.tracker = t;
  r.render(scene, cam, rs, nullptr, acc, counters);
  return std::vector<float>(acc.rgba(), acc.rgba() + size_t(cam.width) * cam.height * 4);
}
} // namespace

// Statistical agreement of CPU and CUDA images for every blend mode, both
// trackers, uint8/int16/uint16/float32/float64 data (float64 at 1e6 + [0, 1],
// read relative to its offset), N = 1, 3, 4, 12, 16, with texture and
// with global-memory sampling. Independent seeds on the two sides, so the
// per-pixel differences have mean zero exactly when both backends compute the
// same expectation (expectSameImage: image-mean z, sum of z^2, max |z|).
TEST(CudaAgreement, EveryModeTrackerTypeAndChannelCount)
{
  const int combos = 2 * 5 * 5 * 4 * 2;
  const double alpha = kAlpha / (combos * 12);
  CPURenderer cpu;
  const std::unique_ptr<CUDARenderer> tex = cudaRenderer(CudaSampling::Texture);
  const std::unique_ptr<CUDARenderer> glob = cudaRenderer(CudaSampling::Global);
  RenderSettings rs;
  const int renders = 24;
  uint32_t seed = 1;
  for (ScalarType type :
    { ScalarType::UInt8, ScalarType::Int16, ScalarType::UInt16, ScalarType::Float32, ScalarType::Float64 })
  {
    for (int N : { 1, 3, 4, 12, 16 })
    {
      const TypedVolume v(type, N, 24, 22, 20);
      const Camera cam = orbitCamera(v.dims, std::array<double, 3>{ 1, 1, 1 }.data(), 20, 20, 35, 25);
      for (BlendMode mode : { BlendMode::Density, BlendMode::Max, BlendMode::Mix, BlendMode::Composite })
      {
        Scene scene;
        v.configure(scene, mode);
        for (Tracker t : { Tracker::OneDDA, Tracker::NDDA })
        {
          rs.tracker = t;
          const Moments a = renderMoments(cpu, scene, cam, rs, renders, seed += 1000);
          std::ostringstream what;
          what << toString(type) << " N=" << N << " " << toString(mode) << " " << toString(t);
          double alphaSum = 0;
          for (size_t p = 3; p < a.size(); p += 4)
          {
            alphaSum += a.mean(p);
          }
          EXPECT_GT(alphaSum, 1.0) << what.str() << ": the CPU image is empty (a useless comparison)";
          for (CUDARenderer* g : { tex.get(), glob.get() })
          {
            const Moments b = renderMoments(*g, scene, cam, rs, renders, seed += 1000);
            expectSameImage(
              a, b, alpha, what.str() + (g->sampling() == CudaSampling::Texture ? " texture" : " global"));
          }
        }
      }
    }
  }
}

// With global-memory sampling the GPU runs the CPU's arithmetic on the same
// random numbers: with the same seed the images are equal up to float
// rounding (nvcc contracts a*b+c into FMAs, logf differs in the last bit), so
// nearly every pixel matches closely. A wrong channel, table or random stream
// would make most pixels differ.
TEST(CudaAgreement, SameSeedGlobalSamplingNearlyIdentical)
{
  CPURenderer cpu;
  const std::unique_ptr<CUDARenderer> g = cudaRenderer(CudaSampling::Global);
  const TypedVolume v(ScalarType::Float32, 4, 32, 30, 28);
  const Camera cam = orbitCamera(v.dims, std::array<double, 3>{ 1, 1, 1 }.data(), 48, 48, 35, 25);
  for (BlendMode mode : { BlendMode::Density, BlendMode::Max, BlendMode::Mix, BlendMode::Composite })
  {
    Scene scene;
    v.configure(scene, mode);
    for (Tracker t : { Tracker::OneDDA, Tracker::NDDA })
    {
      const std::vector<float> a = renderImage(cpu, scene, cam, 16, 77, t);
      const std::vector<float> b = renderImage(*g, scene, cam, 16, 77, t);
      size_t close = 0;
      for (size_t p = 0; p < a.size() / 4; ++p)
      {
        bool same = true;
        for (int c = 0; c < 4; ++c)
        {
          same = same && std::fabs(a[4 * p + c] - b[4 * p + c]) <= 1e-4f;
        }
        close += same ? 1 : 0;
      }
      const double frac = double(close) / double(a.size() / 4);
      std::printf("same seed, %s %s: %.4f of pixels within 1e-4\n", toString(mode), toString(t), frac);
      EXPECT_GE(frac, 0.99) << toString(mode) << " " << toString(t); // typically 1.0000
    }
  }
}

// The unbiased-march estimator runs the same per-ray code on the device: the
// same seed gives the same image as the CPU's, pixel by pixel within 1e-4
// for at least 99% of the pixels (global-memory sampling, as above; a
// roulette decision at a float rounding's distance may differ), every blend
// mode it serves, with jittered pixels (the plain strata) and at pixel
// centres (the control variates, their own kernel on the device).
TEST(CudaAgreement, UnbiasedMarchSameSeedAsCpu)
{
  CPURenderer cpu;
  const std::unique_ptr<CUDARenderer> g = cudaRenderer(CudaSampling::Global);
  const TypedVolume v(ScalarType::Float32, 4, 32, 30, 28);
  const Camera cam = orbitCamera(v.dims, std::array<double, 3>{ 1, 1, 1 }.data(), 48, 48, 35, 25);
  for (const bool jitter : { true, false })
  for (BlendMode mode : { BlendMode::Density, BlendMode::Max, BlendMode::Mix })
  {
    Scene scene;
    v.configure(scene, mode);
    std::vector<float> img[2];
    Renderer* rs[2] = { &cpu, g.get() };
    for (int k = 0; k < 2; ++k)
    {
      Accumulator acc;
      RenderSettings st;
      st.seed = 77;
      st.samplesPerPixel = 16;
      st.estimator = Estimator::UnbiasedMarch;
      st.jitterPixels = jitter;
      EXPECT_EQ(marchControlVariates(st, cam), !jitter);
      rs[k]->render(scene, cam, st, nullptr, acc);
      rs[k]->readBack(acc);
      img[k].assign(acc.rgba(), acc.rgba() + size_t(cam.width) * cam.height * 4);
    }
    size_t close = 0;
    double sum = 0.0;
    for (size_t p = 0; p < img[0].size() / 4; ++p)
    {
      bool same = true;
      for (int c = 0; c < 4; ++c)
      {
        same = same && std::fabs(img[0][4 * p + c] - img[1][4 * p + c]) <= 1e-4f;
        sum += img[0][4 * p + c];
      }
      close += same ? 1 : 0;
    }
    const double frac = double(close) / double(img[0].size() / 4);
    std::printf("unbiased march, same seed, %s, %s: %.4f of pixels within 1e-4\n", toString(mode),
      jitter ? "jittered" : "pixel centres", frac);
    EXPECT_GT(sum, 1.0) << toString(mode);
    EXPECT_GE(frac, 0.99) << toString(mode);
  }
}

// The GPU builds the same macrocell majorants as the host, bit for bit, for
// every voxel type (NaN and Inf voxels included), and the same active list.
TEST(CudaGrid, MajorantsEqualHostBuild)
{
  const int dims[3] = { 37, 21, 19 };
  const size_t voxels = size_t(dims[0]) * dims[1] * dims[2];
  TestRand rnd(5);
  std::vector<uint8_t> u8(voxels);
  std::vector<int16_t> i16(voxels);
  std::vector<uint16_t> u16(voxels);
  std::vector<float> f32(voxels);
  std::vector<double> f64(voxels);
  for (size_t i = 0; i < voxels; ++i)
  {
    const double x = rnd.uniform();
    u8[i] = uint8_t(x * 255);
    i16[i] = int16_t(x * 60000 - 30000);
    u16[i] = uint16_t(x * 65535);
    f32[i] = float(x * 10 - 3);
    f64[i] = 1e9 + x * 40;
  }
  f32[100] = std::numeric_limits<float>::quiet_NaN();
  f32[2000] = std::numeric_limits<float>::infinity();
  f64[300] = std::numeric_limits<double>::quiet_NaN();
  ChannelSource src[6];
  src[0] = { u8.data(), ScalarType::UInt8, 1, 0.0 };
  src[1] = { i16.data(), ScalarType::Int16, 1, 0.0 };
  src[2] = { u16.data(), ScalarType::UInt16, 1, 0.0 };
  src[3] = { f32.data(), ScalarType::Float32, 1, 0.0 };
  src[4] = { f64.data(), ScalarType::Float64, 1, 1e9 };
  std::vector<float> allZero(voxels, 0.5f);
  src[5] = { allZero.data(), ScalarType::Float32, 1, 0.0 };
  const double lo[6] = { 0, -30000, 0, -3, 1e9, 0 };
  const double hi[6] = { 255, 30000, 65535, 7, 1e9 + 40, 1 };
  for (int M : { 1, 3, 8 })
  {
    Scene scene;
    scene.setVolume(dims, 6, src);
    for (int n = 0; n < 6; ++n)
    {
      TransferFunctionDesc tf = flatTF(0.f, 1, 1, 1, 1.f, 256, float(lo[n]), float(hi[n]));
      tf.scalarMin = lo[n];
      tf.scalarMax = hi[n];
      for (int i = 0; i < 256; ++i)
      {
        // A bumpy opacity so that the covered texel range matters; channel 5 stays fully transparent.
        tf.opacity[size_t(i)] = n == 5 ? 0.f : float(0.5 + 0.5 * std::sin(i * 0.37 + n));
      }
      scene.setTransferFunction(n, tf);
    }
    scene.setMacrocellSize(M);
    scene.update();
    CUDARenderer g;
    const Camera cam = orbitCamera(dims, std::array<double, 3>{ 1, 1, 1 }.data(), 8, 8, 30, 20);
    renderImage(g, scene, cam, 1, 1);
    const int64_t cells = int64_t(scene.macrocellDims()[0]) * scene.macrocellDims()[1] * scene.macrocellDims()[2];
    for (int n = 0; n < 6; ++n)
    {
      const std::vector<float> dev = g.downloadMajorants(n);
      ASSERT_EQ(int64_t(dev.size()), cells);
      int64_t differ = 0;
      for (int64_t c = 0; c < cells; ++c)
      {
        differ += dev[size_t(c)] != scene.majorants()[size_t(c) * 6 + size_t(n)] ? 1 : 0;
      }
      EXPECT_EQ(differ, 0) << "macrocell " << M << ", channel " << n << " (" << toString(src[n].type) << ")";
    }
    const std::vector<int> active = g.activeChannels();
    EXPECT_EQ(active, std::vector<int>(scene.view().active, scene.view().active + scene.view().numActive));
    EXPECT_EQ(active.size(), 5u) << "the transparent channel must not be active";
  }
}

// Uploads happen once per data change, one channel's majorants are rebuilt
// when its transfer function changes, and the Scene can skip its host build.
TEST(CudaGrid, UploadsAndRebuildsFollowChanges)
{
  const TypedVolume v(ScalarType::Float32, 4, 30, 28, 26);
  Scene scene;
  scene.setHostAcceleration(false);
  v.configure(scene, BlendMode::Density);
  EXPECT_TRUE(scene.majorants().empty()) << "no host majorants when host acceleration is off";
  EXPECT_EQ(scene.memory().macrocellBytes, 0u);
  CUDARenderer g;
  const Camera cam = orbitCamera(v.dims, std::array<double, 3>{ 1, 1, 1 }.data(), 16, 16, 30, 20);
  Accumulator acc;
  RenderSettings rs;
  for (int i = 0; i < 5; ++i)
  {
    g.render(scene, cam, rs, nullptr, acc);
  }
  CudaUpdateCounters u = g.updateCounters();
  EXPECT_EQ(u.dataUploads, 4u) << "one upload per channel, not per frame";
  EXPECT_EQ(u.rangeBuilds, 1u);
  EXPECT_EQ(u.majorantChannelBuilds, 4u);
  EXPECT_EQ(u.imageDownloads, 5u) << "one image per render";

  // One transfer function changes: that channel's majorants only.
  TransferFunctionDesc tf = flatTF(0.3f, 1, 0, 0, 1.f, 64, 0.f, 1.f);
  scene.setTransferFunction(2, tf);
  scene.update();
  g.render(scene, cam, rs, nullptr, acc);
  u = g.updateCounters();
  EXPECT_EQ(u.dataUploads, 4u);
  EXPECT_EQ(u.rangeBuilds, 1u);
  EXPECT_EQ(u.majorantChannelBuilds, 5u);

  // A new macrocell size: ranges and all majorants, no upload.
  scene.setMacrocellSize(6);
  scene.update();
  g.render(scene, cam, rs, nullptr, acc);
  u = g.updateCounters();
  EXPECT_EQ(u.dataUploads, 4u);
  EXPECT_EQ(u.rangeBuilds, 2u);
  EXPECT_EQ(u.majorantChannelBuilds, 9u);

  // New voxel values: everything once.
  scene.dataModified();
  scene.update();
  g.render(scene, cam, rs, nullptr, acc);
  u = g.updateCounters();
  EXPECT_EQ(u.dataUploads, 8u);
  EXPECT_EQ(u.rangeBuilds, 3u);

  // The device-built grid renders what the host-built one does (same seed,
  // global sampling: nearly the same pixels).
  Scene hostScene;
  v.configure(hostScene, BlendMode::Density);
  hostScene.setTransferFunction(2, tf);
  hostScene.setMacrocellSize(6);
  hostScene.update();
  CPURenderer cpu;
  g.setSampling(CudaSampling::Global);
  const std::vector<float> a = renderImage(cpu, hostScene, cam, 64, 3);
  const std::vector<float> b = renderImage(g, scene, cam, 64, 3);
  double maxDiff = 0;
  double meanDiff = 0;
  for (size_t i = 0; i < a.size(); ++i)
  {
    maxDiff = std::max(maxDiff, double(std::fabs(a[i] - b[i])));
    meanDiff += std::fabs(a[i] - b[i]) / a.size();
  }
  EXPECT_LT(meanDiff, 2e-3) << "max difference " << maxDiff;
}

// Each channel is held once on the device (Documentation/user-guide/
// backends.md): as a texture
// with texture sampling, as an array with global sampling, and as an array
// when it holds NaN (the core's NaN rule needs unfiltered reads). Device
// bytes equal the data (float64 stored as float32), whatever the type, and
// a change of sampling moves the channels without a second copy.
TEST(CudaMemory, EachChannelHeldOnce)
{
  for (ScalarType t : { ScalarType::UInt8, ScalarType::Int16, ScalarType::UInt16, ScalarType::Float32,
         ScalarType::Float64 })
  {
    SCOPED_TRACE(toString(t));
    const int N = 3;
    const TypedVolume v(t, N, 20, 18, 16);
    Scene scene;
    v.configure(scene, BlendMode::Density);
    CUDARenderer g;
    const Camera cam = orbitCamera(v.dims, std::array<double, 3>{ 1, 1, 1 }.data(), 16, 16, 30, 20);
    Accumulator acc;
    RenderSettings rs;
    g.render(scene, cam, rs, nullptr, acc);
    const size_t voxels = size_t(20) * 18 * 16;
    const size_t es = t == ScalarType::Float64 ? 4 : size_t(scalarTypeSize(t));
    const size_t all = voxels * es * N;
    // Float32 channel 0 holds a NaN voxel (TypedVolume): it alone is an array.
    const size_t arrays = t == ScalarType::Float32 ? voxels * es : 0;
    CudaMemoryStats m = g.memory();
    EXPECT_EQ(m.textureBytes + m.dataBytes, all) << "each channel once";
    EXPECT_EQ(m.dataBytes, arrays);
    EXPECT_EQ(g.updateCounters().dataUploads, uint64_t(N));

    g.setSampling(CudaSampling::Global);
    g.render(scene, cam, rs, nullptr, acc);
    m = g.memory();
    EXPECT_EQ(m.textureBytes, 0u);
    EXPECT_EQ(m.dataBytes, all);
    g.setSampling(CudaSampling::Texture);
    g.render(scene, cam, rs, nullptr, acc);
    m = g.memory();
    EXPECT_EQ(m.textureBytes + m.dataBytes, all);
    EXPECT_EQ(m.dataBytes, arrays);
  }
}

// Pre-classified (extinction-format) channels on the device:
// uploaded packed from an interleaved array (stride 5); holding a NaN voxel,
// the channel stays an array even with CudaSampling::Texture (sampled in
// software), so a classified-only scene gives the CPU's pixels for the same
// seed; the device majorants (max sigma over
// each cell, NaN and negative voxels present) equal the host's bit for bit;
// and a scene mixing a classified and a scalar channel agrees statistically.
TEST(CudaClassified, MatchesCpuAndHostMajorants)
{
  const int dims[3] = { 26, 22, 19 };
  const size_t voxels = size_t(dims[0]) * dims[1] * dims[2];
  TestRand rnd(17);
  std::vector<float> inter(voxels * 5, 0.f);
  for (int k = 0; k < dims[2]; ++k)
    for (int j = 0; j < dims[1]; ++j)
      for (int i = 0; i < dims[0]; ++i)
      {
        const size_t v = (size_t(k) * dims[1] + j) * dims[0] + i;
        const double b = std::sin(0.3 * i) * std::sin(0.27 * j + 1) * std::sin(0.33 * k + 2);
        const float sigma = float(std::max(0.0, 0.25 * b));
        inter[v * 5 + 0] = sigma;
        inter[v * 5 + 1] = sigma * float(0.5 + 0.5 * b);
        inter[v * 5 + 2] = sigma * 0.3f;
        inter[v * 5 + 3] = sigma * float(rnd.uniform());
        inter[v * 5 + 4] = 12345.f; // another component of the interleaved array
      }
  inter[5 * 100] = std::numeric_limits<float>::quiet_NaN();
  inter[5 * 2000] = -2.f;
  ChannelSource cls;
  cls.data = inter.data();
  cls.stride = 5;
  cls.format = ChannelFormat::Extinction;
  const Camera cam = orbitCamera(dims, std::array<double, 3>{ 1, 1, 1 }.data(), 32, 32, 35, 25);
  CPURenderer cpu;
  for (CudaSampling sampling : { CudaSampling::Texture, CudaSampling::Global })
  {
    const std::unique_ptr<CUDARenderer> g = cudaRenderer(sampling);
    for (int M : { 1, 4 })
    {
      Scene scene;
      scene.setVolume(dims, 1, &cls);
      scene.setMacrocellSize(M);
      scene.update();
      const std::vector<float> a = renderImage(cpu, scene, cam, 16, 99);
      const std::vector<float> b = renderImage(*g, scene, cam, 16, 99);
      size_t close = 0;
      double alphaSum = 0;
      for (size_t p = 0; p < a.size() / 4; ++p)
      {
        bool same = true;
        for (int c = 0; c < 4; ++c)
        {
          same = same && std::fabs(a[4 * p + c] - b[4 * p + c]) <= 1e-4f;
        }
        close += same ? 1 : 0;
        alphaSum += a[4 * p + 3];
      }
      EXPECT_GT(alphaSum, 5.0) << "the image must show something";
      const double frac = double(close) / double(a.size() / 4);
      EXPECT_GE(frac, 0.99) << "classified, macrocell " << M
                            << (sampling == CudaSampling::Texture ? " texture" : " global");
      const std::vector<float> dev = g->downloadMajorants(0);
      ASSERT_EQ(dev.size(), scene.majorants().size());
      EXPECT_EQ(dev, scene.majorants()) << "macrocell " << M;
    }
  }
  // Mixed with a scalar channel: statistical agreement (texture sampling for
  // the scalar one).
  TestVolume tv(dims[0], dims[1], dims[2], 1, 0.f);
  for (size_t v = 0; v < voxels; ++v)
  {
    tv.channels[0][v] = float(rnd.uniform());
  }
  const std::vector<ChannelSource> src = { cls, tv.sources()[0] };
  const std::unique_ptr<CUDARenderer> tex = cudaRenderer(CudaSampling::Texture);
  for (BlendMode mode : { BlendMode::Density, BlendMode::Max })
  {
    Scene scene;
    scene.setVolume(dims, 2, src.data());
    scene.setTransferFunction(1, flatTF(0.05f, 0.2f, 0.9f, 0.3f, 1.f, 64, 0.f, 1.f));
    scene.setMacrocellSize(4);
    scene.setBlendMode(mode);
    scene.update();
    RenderSettings rs;
    const Moments ma = renderMoments(cpu, scene, cam, rs, 24, 5000);
    const Moments mb = renderMoments(*tex, scene, cam, rs, 24, 9000);
    expectSameImage(ma, mb, kAlpha / 24, std::string("classified + scalar ") + toString(mode));
  }
}

// Pre-classified channels without NaN are held as float4 textures under
// texture sampling (sanitised on upload: a negative voxel and a colour above
// sigma here), and only so: the hardware filter interpolates sigma and
// sigma*colour. The majorants equal the host's bit for bit (built from the
// texels), the Monte Carlo image agrees with the CPU's statistically (level
// kAlpha, as above), and the exact reference march (point reads of the
// texels) equals the CPU march to float rounding. Global sampling moves the
// channel back to an array.
namespace
{
/// The CudaClassified tests' volume: (sigma, sigma r, sigma g, sigma b) per
/// voxel, sigma a product of sines (0 where negative), b from `blue()`.
std::vector<float> sineClassified(const int dims[3], const std::function<float()>& blue)
{
  std::vector<float> packed(size_t(dims[0]) * dims[1] * dims[2] * 4, 0.f);
  for (int k = 0; k < dims[2]; ++k)
    for (int j = 0; j < dims[1]; ++j)
      for (int i = 0; i < dims[0]; ++i)
      {
        const size_t v = (size_t(k) * dims[1] + j) * dims[0] + i;
        const double b = std::sin(0.3 * i) * std::sin(0.27 * j + 1) * std::sin(0.33 * k + 2);
        const float sigma = float(std::max(0.0, 0.3 * b));
        packed[v * 4 + 0] = sigma;
        packed[v * 4 + 1] = sigma * float(0.5 + 0.5 * b);
        packed[v * 4 + 2] = sigma * 0.3f;
        packed[v * 4 + 3] = sigma * blue();
      }
  return packed;
}

/// The exact march (step 0.3, no termination decided on a rounding) on the
/// CPU and on `gpu`: their largest difference; `sum` receives the CPU
/// image's sum.
double marchDifference(CPURenderer& cpu, CUDARenderer& gpu, const Scene& scene, const Camera& cam, double& sum)
{
  MarchSettings ms;
  ms.step = 0.3;
  ms.terminateTransmittance = 0.f;
  Accumulator a, b;
  cpu.march(scene, cam, ms, nullptr, a);
  gpu.march(scene, cam, ms, nullptr, b);
  double worst = 0.0;
  sum = 0.0;
  for (size_t i = 0; i < size_t(cam.width) * cam.height * 4; ++i)
  {
    worst = std::max(worst, std::fabs(double(a.rgba()[i]) - double(b.rgba()[i])));
    sum += a.rgba()[i];
  }
  return worst;
}
} // namespace

TEST(CudaClassified, FloatTextureAgreesWithCpu)
{
  const int dims[3] = { 26, 22, 19 };
  const size_t voxels = size_t(dims[0]) * dims[1] * dims[2];
  TestRand rnd(23);
  std::vector<float> packed = sineClassified(dims, [&rnd] { return float(rnd.uniform()); });
  packed[4 * 2000] = -2.f;     // sanitised to a transparent voxel
  packed[4 * 3000 + 1] = 50.f; // colour above sigma: clamped to sigma
  ChannelSource cls;
  cls.data = packed.data();
  cls.stride = 4;
  cls.format = ChannelFormat::Extinction;
  const Camera cam = orbitCamera(dims, std::array<double, 3>{ 1, 1, 1 }.data(), 32, 32, 35, 25);
  CPURenderer cpu;
  const std::unique_ptr<CUDARenderer> tex = cudaRenderer(CudaSampling::Texture);
  Scene scene;
  scene.setVolume(dims, 1, &cls);
  scene.setMacrocellSize(4);
  scene.update();
  RenderSettings rs;
  const Moments ma = renderMoments(cpu, scene, cam, rs, 24, 5000);
  const Moments mb = renderMoments(*tex, scene, cam, rs, 24, 9000);
  expectSameImage(ma, mb, kAlpha / 24, "classified float4 texture");
  const CudaMemoryStats m = tex->memory();
  EXPECT_EQ(m.textureBytes, voxels * 16) << "held as a float4 texture";
  EXPECT_EQ(m.dataBytes, 0u) << "and only so";
  EXPECT_EQ(tex->downloadMajorants(0), scene.majorants());
  double sum = 0.0;
  const double worst = marchDifference(cpu, *tex, scene, cam, sum);
  EXPECT_GT(sum, 5.0) << "the image must show something";
  EXPECT_LE(worst, 1e-4) << "exact march through the point-sampled texels";
  tex->setSampling(CudaSampling::Global);
  Accumulator c;
  tex->render(scene, cam, rs, nullptr, c);
  EXPECT_EQ(tex->memory().textureBytes, 0u);
  EXPECT_EQ(tex->memory().dataBytes, voxels * 16);
}

// A half-precision level (PyramidLevel::toHalfPrecision) on the CUDA
// backend: widened to float32 on upload, the same values the CPU decodes, so
// the majorants are equal bit for bit, the exact march agrees within 1e-4
// and Monte Carlo images agree (family-wise kAlpha / 24), held as a float4
// texture of 16 bytes a voxel.
TEST(CudaClassified, HalfPrecisionAgreesWithCpu)
{
  PyramidLevel level;
  level.dims[0] = 26;
  level.dims[1] = 22;
  level.dims[2] = 19;
  const int* dims = level.dims;
  const size_t voxels = level.numVoxels();
  level.voxels = sineClassified(dims, [] { return 0.8f; });
  level.toHalfPrecision();
  const ChannelSource cls = level.source();
  ASSERT_EQ(cls.type, ScalarType::Float16);
  const Camera cam = orbitCamera(dims, std::array<double, 3>{ 1, 1, 1 }.data(), 32, 32, 35, 25);
  CPURenderer cpu;
  for (CudaSampling sampling : { CudaSampling::Texture, CudaSampling::Global })
  {
    const std::unique_ptr<CUDARenderer> gpu = cudaRenderer(sampling);
    Scene scene;
    scene.setVolume(dims, 1, &cls);
    scene.setMacrocellSize(4);
    scene.update();
    RenderSettings rs;
    const Moments ma = renderMoments(cpu, scene, cam, rs, 24, 5000);
    const Moments mb = renderMoments(*gpu, scene, cam, rs, 24, 9000);
    expectSameImage(ma, mb, kAlpha / 48, "classified float16 level");
    const CudaMemoryStats m = gpu->memory();
    EXPECT_EQ(m.textureBytes + m.dataBytes, voxels * 16) << "widened to float32, held once";
    EXPECT_EQ(gpu->downloadMajorants(0), scene.majorants());
    double sum = 0.0;
    const double worst = marchDifference(cpu, *gpu, scene, cam, sum);
    EXPECT_GT(sum, 5.0) << "the image must show something";
    EXPECT_LE(worst, 1e-4) << "exact march of the decoded voxels";
  }
}

// Progressive accumulation on the device: k renders of one sample with the
// image left on the device equal one render of k samples, bit for bit; a host reset
// restarts the device mean; the CPU's progressive mean matches too.
TEST(CudaAccumulation, ProgressiveDeviceMeanAndReset)
{
  const TypedVolume v(ScalarType::UInt8, 3, 30, 28, 26);
  Scene scene;
  v.configure(scene, BlendMode::Density);
  const Camera cam = orbitCamera(v.dims, std::array<double, 3>{ 1, 1, 1 }.data(), 24, 24, 30, 20);
  CUDARenderer g;
  Accumulator progressive;
  RenderSettings rs;
  rs.seed = 9;
  rs.readBack = false;
  for (int k = 0; k < 8; ++k)
  {
    g.render(scene, cam, rs, nullptr, progressive);
  }
  EXPECT_EQ(g.updateCounters().imageDownloads, 0u);
  g.readBack(progressive);
  EXPECT_EQ(progressive.samples(), 8u);
  const std::vector<float> once = renderImage(g, scene, cam, 8, 9);
  for (size_t i = 0; i < once.size(); ++i)
  {
    // Bit for bit: each sample joins the pixel's double sum in order.
    ASSERT_EQ(progressive.rgba()[i], once[i]) << "value " << i;
  }
  // An image left on the device is replaced by another Accumulator's render:
  // reading it back, or rendering on, is an error, not a stale image.
  {
    Accumulator a, b;
    RenderSettings lazy;
    lazy.readBack = false;
    g.render(scene, cam, lazy, nullptr, a);
    EXPECT_TRUE(a.pendingOnDevice());
    g.render(scene, cam, lazy, nullptr, b);
    EXPECT_THROW(g.readBack(a), std::logic_error);
    EXPECT_THROW(g.render(scene, cam, lazy, nullptr, a), std::logic_error);
    g.readBack(b);
    EXPECT_FALSE(b.pendingOnDevice());
    a.reset(); // a fresh start is fine
    EXPECT_NO_THROW(g.render(scene, cam, lazy, nullptr, a));
    g.finish();
  }
  // Reset on the host: the next render starts a new mean.
  progressive.reset();
  rs.readBack = true;
  rs.samplesPerPixel = 8;
  g.render(scene, cam, rs, nullptr, progressive);
  for (size_t i = 0; i < once.size(); ++i)
  {
    ASSERT_EQ(progressive.rgba()[i], once[i]) << "value " << i;
  }
}

// As render_test's Accumulation.KeepsConvergingPast2To24Samples, on the
// device: a 2^25-sample image set up on the host (its sums derived from the
// mean and uploaded), then 64 renders of one sample, read back each time
// for one image and left on the device until the last for the other. Image A (mean 0.5)
// must equal 0.5 x 2^25 / N + B (B: the same samples on a zero mean) within
// one float spacing at 0.5; a float running mean stalls at 0.5, 9.5e-7 off.
TEST(CudaAccumulation, KeepsConvergingPast2To24Samples)
{
  const TypedVolume v(ScalarType::UInt8, 3, 30, 28, 26);
  Scene scene;
  v.configure(scene, BlendMode::Density);
  const Camera cam = orbitCamera(v.dims, std::array<double, 3>{ 1, 1, 1 }.data(), 24, 24, 30, 20);
  const uint32_t preset = 1u << 25;
  const int renders = 64;
  CUDARenderer g;
  Accumulator a, b;
  presetLongImages(a, b, cam, preset);
  RenderSettings rs;
  rs.seed = 3;
  rs.samplesPerPixel = 1;
  for (int k = 0; k < renders; ++k)
  {
    g.render(scene, cam, rs, nullptr, a);
  }
  rs.readBack = false;
  for (int k = 0; k < renders; ++k)
  {
    g.render(scene, cam, rs, nullptr, b);
  }
  g.readBack(b);
  ASSERT_EQ(a.samples(), preset + uint32_t(renders));
  expectLongMean(a, b, preset, renders);
}

// The display image (what the VTK mapper draws from a device backend): the
// device mean as premultiplied RGBA8, each component clamped and rounded to
// nearest, copied without reading the float image back; a replaced image is
// an error, as for readBack().
TEST(CudaAccumulation, DisplayImageIsTheRoundedMean)
{
  const TypedVolume v(ScalarType::Float32, 3, 30, 28, 26);
  Scene scene;
  v.configure(scene, BlendMode::Density);
  const Camera cam = orbitCamera(v.dims, std::array<double, 3>{ 1, 1, 1 }.data(), 24, 24, 30, 20);
  CUDARenderer g;
  ASSERT_TRUE(g.hasDisplayImage());
  Accumulator acc;
  RenderSettings rs;
  rs.seed = 3;
  rs.readBack = false;
  rs.samplesPerPixel = 4;
  g.render(scene, cam, rs, nullptr, acc);
  const uint64_t downloads = g.updateCounters().imageDownloads;
  const uint8_t* display = g.displayImage(acc);
  ASSERT_NE(display, nullptr);
  EXPECT_TRUE(acc.pendingOnDevice()); // the float image stays on the device
  EXPECT_EQ(g.updateCounters().imageDownloads, downloads + 1);
  const std::vector<uint8_t> shown(display, display + size_t(cam.width) * cam.height * 4);
  g.readBack(acc);
  int visible = 0;
  for (size_t i = 0; i < shown.size(); ++i)
  {
    const float x = std::min(std::max(acc.rgba()[i], 0.f), 1.f);
    // Rounded to nearest: within half a level (plus float rounding).
    ASSERT_LE(std::abs(float(shown[i]) - 255.f * x), 0.5f + 1e-3f) << "component " << i;
    visible += (i % 4 == 3 && shown[i] > 0) ? 1 : 0;
  }
  EXPECT_GT(visible, int(cam.width) * cam.height / 10); // the volume covers the view
  // Still valid after the read-back (the device keeps the image).
  EXPECT_NE(g.displayImage(acc), nullptr);
  // Another Accumulator's render replaces the device image.
  Accumulator other;
  g.render(scene, cam, rs, nullptr, other);
  EXPECT_EQ(g.displayImage(acc), nullptr); // acc is on the host: draw its float image
  Accumulator lost, next;
  g.render(scene, cam, rs, nullptr, lost);
  g.render(scene, cam, rs, nullptr, next);
  EXPECT_THROW(g.displayImage(lost), std::logic_error);
  g.finish();
}

namespace
{
/// One render of `scene` by the plain or the general kernels.
std::vector<float> plainOrGeneral(const Scene& scene, const Camera& cam, bool plain, Estimator e)
{
  CUDARenderer g;
  g.setPlainKernels(plain);
  EXPECT_EQ(g.plainKernels(), plain);
  Accumulator acc;
  RenderSettings rs;
  rs.seed = 5;
  rs.samplesPerPixel = 4;
  rs.estimator = e;
  g.render(scene, cam, rs, nullptr, acc);
  return std::vector<float>(acc.rgba(), acc.rgba() + size_t(cam.width) * cam.height * 4);
}

/// The largest difference of two images, and the sum of the first.
std::pair<double, double> worstAndSum(const std::vector<float>& a, const std::vector<float>& b)
{
  double worst = 0.0, sum = 0.0;
  for (size_t i = 0; i < a.size(); ++i)
  {
    worst = std::max(worst, double(std::fabs(a[i] - b[i])));
    sum += a[i];
  }
  return { worst, sum };
}
} // namespace

// The plain kernels (CUDARenderer::setPlainKernels, the default) compute the
// same image as the general ones for a plain scene, for every estimator and
// every blend mode, unlit and lit, and are not taken for a cubic scene.
TEST(CudaRender, PlainKernelsEqualGeneral)
{
  EXPECT_TRUE(CUDARenderer().plainKernels()); // on by default
  const TypedVolume v(ScalarType::UInt16, 3, 30, 28, 26);
  const Camera cam = orbitCamera(v.dims, std::array<double, 3>{ 1, 1, 1 }.data(), 24, 24, 30, 20);
  for (BlendMode mode : { BlendMode::Density, BlendMode::Max, BlendMode::Mix, BlendMode::Composite })
  {
    for (Estimator e : { Estimator::Collision, Estimator::ExpectedValue, Estimator::UnbiasedMarch })
    {
      for (Interpolation interp : { Interpolation::Linear, Interpolation::Cubic })
      {
        Scene scene;
        v.configure(scene, mode);
        scene.setInterpolation(interp);
        scene.update();
        const auto [worst, sum] =
          worstAndSum(plainOrGeneral(scene, cam, false, e), plainOrGeneral(scene, cam, true, e));
        EXPECT_GT(sum, 1.0) << toString(mode);
        EXPECT_LE(worst, 1e-5) << toString(mode) << " " << toString(e) << " " << toString(interp);
      }
    }
  }
  // Lit: shadows and ambient, no shadows, two scattering events (composite
  // blending takes no lighting on this backend).
  for (BlendMode mode : { BlendMode::Density, BlendMode::Max, BlendMode::Mix })
  {
    for (int variant = 0; variant < 3; ++variant)
    {
      for (Interpolation interp : { Interpolation::Linear, Interpolation::Cubic })
      {
        Scene scene;
        v.configure(scene, mode);
        scene.setInterpolation(interp);
        LightingDesc ld = sunAndSky(2, 0.2);
        ld.shadows = variant != 1;
        ld.maxDepth = variant == 2 ? 2 : 1;
        scene.setLighting(ld);
        scene.update();
        const auto [worst, sum] = worstAndSum(
          plainOrGeneral(scene, cam, false, Estimator::Collision), plainOrGeneral(scene, cam, true, Estimator::Collision));
        EXPECT_GT(sum, 1.0) << "lit " << toString(mode);
        EXPECT_LE(worst, 1e-5) << "lit " << toString(mode) << " variant " << variant << " " << toString(interp);
      }
    }
  }
}

// Deferred shadow rays (CUDARenderer::setDeferredShadows, the default) give
// the image of the shadow rays traced in the camera rays' kernel: plain and
// general kernels, both lit estimators, three blends, one light with ratio
// tracking, and two lights of which one is chosen per vertex with ambient
// light, gradient shading and delta tracking. The queue is allocated only
// where the rays were deferred.
TEST(CudaRender, DeferredShadowsEqualTraced)
{
  EXPECT_TRUE(CUDARenderer().deferredShadows()); // on by default
  const TypedVolume v(ScalarType::UInt16, 3, 30, 28, 26);
  const Camera cam = orbitCamera(v.dims, std::array<double, 3>{ 1, 1, 1 }.data(), 24, 24, 30, 20);
  const size_t queueBytes = size_t(cam.width) * size_t(cam.height) * sizeof(DeferredShadows);
  for (BlendMode mode : { BlendMode::Density, BlendMode::Max, BlendMode::Mix })
  {
    for (int config = 0; config < 2; ++config)
    {
      Scene scene;
      v.configure(scene, mode);
      LightingDesc ld = sunAndSky(config == 0 ? 1 : 2, config == 0 ? 0.0 : 0.2);
      ld.sampleOneLight = config == 1;
      ld.gradientShading = config == 1;
      ld.deltaShadows = config == 1;
      scene.setLighting(ld);
      scene.update();
      for (Estimator e : { Estimator::Collision, Estimator::ExpectedValue })
      {
        for (bool plain : { true, false })
        {
          std::vector<float> image[2];
          size_t bytes[2] = { 0, 0 };
          for (int deferred = 0; deferred < 2; ++deferred)
          {
            CUDARenderer g;
            g.setPlainKernels(plain);
            g.setDeferredShadows(deferred == 1);
            Accumulator acc; // keeps the error estimate's even half (the default)
            RenderSettings rs;
            rs.seed = 9;
            rs.estimator = e;
            rs.samplesPerPixel = 3;
            g.render(scene, cam, rs, nullptr, acc);
            rs.samplesPerPixel = 2;
            g.render(scene, cam, rs, nullptr, acc);
            image[deferred].assign(acc.rgba(), acc.rgba() + size_t(cam.width) * cam.height * 4);
            ASSERT_NE(acc.evenRGBA(), nullptr);
            image[deferred].insert(
              image[deferred].end(), acc.evenRGBA(), acc.evenRGBA() + size_t(cam.width) * cam.height * 4);
            bytes[deferred] = g.memory().imageBytes;
          }
          const auto [worst, sum] = worstAndSum(image[0], image[1]);
          const std::string what = std::string(toString(mode)) + " config " + std::to_string(config) + " " +
            toString(e) + (plain ? " plain" : " general");
          EXPECT_GT(sum, 1.0) << what;
          EXPECT_LE(worst, 1e-6) << what;
          EXPECT_GE(bytes[1], bytes[0] + queueBytes) << what;
        }
      }
    }
  }
}

// A render of several samples traces a batch of them per pair of deferred
// launches (RenderLaunch::deferredBatch: CUDARenderer::setDeferredBatch()'s
// count, more where few pixels can have rays: a small image, or a depth mask
// that leaves one process's rows of a split image) and folds them in sample
// order: the image, even half included, is the one of the same samples
// rendered one per render, bit for bit, with and without ambient light.
// Cases: 1024^2 with batches of 3 and of the default 4; a 24x64 image
// (batch 8); 1024^2 masks that leave 1/2 and 1/8 of the rows (batches of 4
// and 8). 11 samples leave a remainder. The batch's slots and its longer
// queue count in imageBytes.
TEST(CudaRender, DeferredBatchesEqualOneSampleAtATime)
{
  EXPECT_EQ(CUDARenderer().deferredBatch(), 4); // the default
  EXPECT_THROW(CUDARenderer().setDeferredBatch(0), std::invalid_argument);
  EXPECT_THROW(CUDARenderer().setDeferredBatch(9), std::invalid_argument);
  const TypedVolume v(ScalarType::UInt16, 3, 30, 28, 26);
  struct Case
  {
    int width, height;
    int ranks;    ///< 1: no mask
    int batchSet; ///< setDeferredBatch(), 0 for the default
    size_t batch; ///< the batch expected
  };
  for (const Case& c : { Case{ 1024, 1024, 1, 3, 3 }, Case{ 1024, 1024, 1, 0, 4 }, Case{ 24, 64, 1, 0, 8 },
         Case{ 1024, 1024, 2, 0, 4 }, Case{ 1024, 1024, 8, 0, 8 } })
  {
    const Camera cam = orbitCamera(v.dims, std::array<double, 3>{ 1, 1, 1 }.data(), c.width, c.height, 30, 20);
    const size_t P = size_t(cam.width) * size_t(cam.height);
    // Process 0's stripes of 4 rows open, the others' at depth 0.
    std::vector<float> depth(P, 1.f);
    for (int y = 0; y < cam.height; ++y)
    {
      if ((y / 4) % c.ranks != 0)
      {
        std::fill_n(depth.begin() + std::ptrdiff_t(size_t(y) * size_t(cam.width)), cam.width, 0.f);
      }
    }
    const float* mask = c.ranks > 1 ? depth.data() : nullptr;
    for (double ambient : { 0.0, 0.2 })
    {
      Scene scene;
      v.configure(scene, BlendMode::Density);
      scene.setLighting(sunAndSky(1, ambient));
      scene.update();
      std::vector<float> image[2];
      size_t bytes[2] = { 0, 0 };
      for (int batched = 0; batched < 2; ++batched)
      {
        CUDARenderer g;
        if (c.batchSet > 0)
        {
          g.setDeferredBatch(c.batchSet);
        }
        Accumulator acc;
        RenderSettings rs;
        rs.seed = 5;
        if (batched == 1)
        {
          rs.samplesPerPixel = 11;
          g.render(scene, cam, rs, mask, acc);
        }
        else
        {
          for (int k = 0; k < 11; ++k)
          {
            g.render(scene, cam, rs, mask, acc);
          }
        }
        ASSERT_EQ(acc.samples(), 11u);
        image[batched].assign(acc.rgba(), acc.rgba() + P * 4);
        ASSERT_NE(acc.evenRGBA(), nullptr);
        image[batched].insert(image[batched].end(), acc.evenRGBA(), acc.evenRGBA() + P * 4);
        bytes[batched] = g.memory().imageBytes;
      }
      const std::string what = std::to_string(c.width) + "x" + std::to_string(c.height) + ", " +
        std::to_string(c.ranks) + " ranks, batch " + std::to_string(c.batch) + ", ambient " + std::to_string(ambient);
      const auto [worst, sum] = worstAndSum(image[0], image[1]);
      EXPECT_GT(sum, 1.0) << what;
      EXPECT_EQ(worst, 0.0) << what;
      EXPECT_TRUE(image[0] == image[1]) << what;
      // The slots, and a queue entry per path beyond one per pixel.
      const size_t open = P / size_t(c.ranks);
      const size_t queue = c.batch * open > P ? (c.batch * open - P) * sizeof(DeferredShadows) : 0;
      EXPECT_GE(bytes[1], bytes[0] + c.batch * P * sizeof(float) * 4 + queue) << what;
      EXPECT_LT(bytes[1], bytes[0] + (c.batch + 1) * P * sizeof(float) * 4 + queue) << what;
    }
  }
}

// The estimator choice's pilots rendered at once (CUDARenderer::renderPilots:
// each replicate's samples as one-sample renders of their own, folded on the
// host) equal the renders one after the other (Renderer::renderPilots, the
// concurrent path switched off): the same means to float rounding (the fold
// runs on the host, the device folds with fused multiply-adds), the same work
// counters, and chooseEstimator() the same choice from the same trials. Every
// estimator code and blend mode the pilots run, scalar and cubic sampling.
TEST(CudaRender, ConcurrentPilotsEqualOneAfterTheOther)
{
  EXPECT_TRUE(CUDARenderer().concurrentPilots()); // the default
  const TypedVolume v(ScalarType::UInt16, 3, 30, 28, 26);
  const Camera cam = orbitCamera(v.dims, std::array<double, 3>{ 1, 1, 1 }.data(), 20, 16, 30, 20);
  for (BlendMode mode : { BlendMode::Density, BlendMode::Max, BlendMode::Mix })
  {
    for (Interpolation interp : { Interpolation::Linear, Interpolation::Cubic })
    {
      Scene scene;
      v.configure(scene, mode);
      scene.setInterpolation(interp);
      scene.update();
      std::vector<PilotJob> jobs[2];
      for (int concurrent = 0; concurrent < 2; ++concurrent)
      {
        PilotJob ev;
        ev.settings.estimator = Estimator::ExpectedValue;
        ev.seeds[0] = 11u;
        ev.seeds[1] = 12u;
        ev.checkpoints = { 1, 2, 4, 8 };
        PilotJob march = ev;
        march.settings.estimator = Estimator::UnbiasedMarch;
        march.settings.marchSamplesPerVoxel = 0.5f;
        march.checkpoints = { 1, 2 };
        PilotJob control = march; // pixel centres, control variates (estimator code 3)
        control.settings.jitterPixels = false;
        control.settings.marchControlVariatesFrom = 0.f;
        control.checkpoints = { 1, 3 };
        jobs[concurrent] = { ev, march, control };
        CUDARenderer g;
        g.setConcurrentPilots(concurrent == 1);
        g.renderPilots(scene, cam, jobs[concurrent]);
      }
      for (size_t j = 0; j < jobs[0].size(); ++j)
      {
        const PilotJob& a = jobs[0][j];
        const PilotJob& b = jobs[1][j];
        EXPECT_EQ(a.counters.rays, b.counters.rays);
        EXPECT_EQ(a.counters.ddaSteps, b.counters.ddaSteps) << j;
        EXPECT_EQ(a.counters.tentativeCollisions, b.counters.tentativeCollisions) << j;
        EXPECT_EQ(a.counters.channelSamples, b.counters.channelSamples) << j;
        EXPECT_GT(a.counters.channelSamples, 0u) << j;
        for (int r = 0; r < 2; ++r)
        {
          ASSERT_EQ(a.means[r].size(), a.checkpoints.size());
          ASSERT_EQ(b.means[r].size(), a.checkpoints.size());
          for (size_t i = 0; i < a.checkpoints.size(); ++i)
          {
            ASSERT_EQ(a.means[r][i].size(), size_t(cam.width) * cam.height * 4);
            double worst = 0.0, sum = 0.0;
            for (size_t k = 0; k < a.means[r][i].size(); ++k)
            {
              worst = std::max(worst, double(std::fabs(a.means[r][i][k] - b.means[r][i][k])));
              sum += a.means[r][i][k];
            }
            EXPECT_GT(sum, 0.1) << toString(mode) << " job " << j;
            EXPECT_LE(worst, 1e-6) << toString(mode) << " " << toString(interp) << " job " << j << " replicate " << r
                                   << " checkpoint " << i;
          }
        }
        // The replicates differ (independent scrambles).
        EXPECT_NE(a.means[0][0], a.means[1][0]) << j;
      }
      if (interp == Interpolation::Linear)
      {
        for (bool jitter : { true, false })
        {
          RenderSettings base;
          base.seed = 3;
          base.jitterPixels = jitter;
          EstimatorChoice c[2];
          for (int concurrent = 0; concurrent < 2; ++concurrent)
          {
            CUDARenderer g;
            g.setConcurrentPilots(concurrent == 1);
            c[concurrent] = chooseEstimator(g, scene, cam, base);
          }
          ASSERT_TRUE(c[0].applies);
          ASSERT_EQ(c[0].trials.size(), c[1].trials.size());
          EXPECT_EQ(c[0].chosen, c[1].chosen);
          for (size_t i = 0; i < c[0].trials.size(); ++i)
          {
            EXPECT_EQ(c[0].trials[i].costPerSample, c[1].trials[i].costPerSample) << i;
            EXPECT_NEAR(c[0].trials[i].firstFrameMSE, c[1].trials[i].firstFrameMSE,
              1e-4 * c[0].trials[i].firstFrameMSE) << i;
          }
        }
      }
    }
  }
}

// Frames rendered during the pilots (ChoiceAhead): on the default stream
// while the pilots run on their own streams. Kept (the previous choice's
// estimator chosen again), the image equals the same frames rendered after
// the choice, bit for bit; dropped (another estimator), the image restarts
// and the frames rendered after the choice equal them too. The choice is the
// one made without frames ahead. Jittered and at pixel centres.
TEST(CudaRender, FramesAheadOfTheChoiceEqualFramesAfterIt)
{
  const TypedVolume v(ScalarType::UInt16, 3, 30, 28, 26);
  const Camera cam = orbitCamera(v.dims, std::array<double, 3>{ 1, 1, 1 }.data(), 96, 80, 30, 20);
  Scene scene;
  v.configure(scene, BlendMode::Density);
  scene.update();
  for (bool jitter : { true, false })
  {
    RenderSettings base;
    base.seed = 5;
    base.samplesPerPixel = 2;
    base.jitterPixels = jitter;
    CUDARenderer g;
    ASSERT_TRUE(g.rendersPilotsAtOnce());
    const EstimatorChoice first = chooseEstimator(g, scene, cam, base);
    ASSERT_TRUE(first.applies);
    // The image of the choice's first two renders, rendered after it.
    Accumulator after;
    after.setErrorEstimation(false);
    for (int i = 0; i < 2; ++i)
    {
      g.render(scene, cam, first.settings, nullptr, after);
    }
    g.readBack(after);
    const std::vector<float> want(after.rgba(), after.rgba() + 4 * size_t(cam.width) * cam.height);
    double sum = 0;
    for (float x : want)
    {
      sum += x;
    }
    EXPECT_GT(sum, 1.0);
    EstimatorCandidate other;
    if (first.chosenCandidate().estimator == Estimator::ExpectedValue)
    {
      other.estimator = Estimator::UnbiasedMarch;
      other.marchSamplesPerVoxel = 0.5f;
    }
    for (const EstimatorCandidate& c : { first.chosenCandidate(), other })
    {
      Accumulator image;
      image.setErrorEstimation(false);
      ChoiceAhead ahead;
      ahead.candidate = c;
      ahead.renders = 2;
      ahead.accum = &image;
      EstimatorChoiceSettings hinted;
      hinted.hint = first.hint();
      const EstimatorChoice again = chooseEstimator(g, scene, cam, base, hinted, ahead);
      ASSERT_EQ(again.trials.size(), first.trials.size());
      EXPECT_EQ(again.chosen, first.chosen);
      EXPECT_TRUE(ahead.rendered);
      const bool mine = c.estimator == first.chosenCandidate().estimator &&
        c.marchSamplesPerVoxel == first.chosenCandidate().marchSamplesPerVoxel;
      EXPECT_EQ(ahead.kept, mine) << again.chosenName();
      if (!ahead.kept)
      {
        EXPECT_EQ(image.samples(), 0u);
        for (int i = 0; i < 2; ++i)
        {
          g.render(scene, cam, again.settings, nullptr, image);
        }
      }
      EXPECT_EQ(image.samples(), 4u);
      g.readBack(image);
      size_t differ = 0;
      for (size_t k = 0; k < want.size(); ++k)
      {
        differ += image.rgba()[k] != want[k] ? 1 : 0;
      }
      EXPECT_EQ(differ, 0u) << (jitter ? "jittered " : "centres ") << (mine ? "kept" : "dropped");
    }
  }
}

// Depth clipping and counters on the device: geometry at mid-depth stops the
// rays (less alpha, fewer collisions), and the counters add up like the CPU's.
TEST(CudaRender, DepthAndCounters)
{
  const TypedVolume v(ScalarType::Float32, 3, 30, 28, 26);
  Scene scene;
  v.configure(scene, BlendMode::Density);
  const Camera cam = orbitCamera(v.dims, std::array<double, 3>{ 1, 1, 1 }.data(), 32, 32, 30, 20);
  CUDARenderer g;
  CPURenderer cpu;
  RenderCounters cg, cc;
  const std::vector<float> a = renderImage(g, scene, cam, 32, 4, Tracker::OneDDA, &cg);
  renderImage(cpu, scene, cam, 32, 4, Tracker::OneDDA, &cc);
  EXPECT_EQ(cg.rays, cc.rays);
  // Same seed, nearly the same paths: work within 2% of the CPU's.
  EXPECT_NEAR(double(cg.tentativeCollisions), double(cc.tentativeCollisions), 0.02 * double(cc.tentativeCollisions));
  EXPECT_NEAR(double(cg.realCollisions), double(cc.realCollisions), 0.02 * double(cc.realCollisions));
  std::vector<float> depth(size_t(cam.width) * cam.height, 1.f);
  for (size_t i = 0; i < depth.size() / 2; ++i)
  {
    depth[i] = 0.f; // geometry at the near plane over the lower half
  }
  Accumulator acc;
  RenderSettings rs;
  rs.samplesPerPixel = 8;
  g.render(scene, cam, rs, depth.data(), acc);
  for (size_t p = 0; p < depth.size() / 2; ++p)
  {
    ASSERT_EQ(acc.rgba()[4 * p + 3], 0.f) << "pixel " << p << " is behind geometry";
  }
  double upper = 0;
  for (size_t p = depth.size() / 2; p < depth.size(); ++p)
  {
    upper += acc.rgba()[4 * p + 3];
  }
  double upperFree = 0;
  for (size_t p = depth.size() / 2; p < depth.size(); ++p)
  {
    upperFree += a[4 * p + 3];
  }
  EXPECT_GT(upper, 0.5 * upperFree) << "the unoccluded half still renders";
}

// Bad input gives errors, not crashes.
TEST(CudaRender, BadInputIsAnError)
{
  CUDARenderer g;
  EXPECT_THROW(g.setBlockSize(3, 5), std::invalid_argument);
  EXPECT_THROW(g.setBlockSize(64, 32), std::invalid_argument);
  Scene empty;
  Accumulator acc;
  Camera cam;
  cam.width = 4;
  cam.height = 4;
  EXPECT_THROW(g.render(empty, cam, RenderSettings(), nullptr, acc), std::logic_error);
  cam.width = 0;
  EXPECT_THROW(g.render(empty, cam, RenderSettings(), nullptr, acc), std::invalid_argument);
  std::string why;
  EXPECT_TRUE(Renderer::cudaAvailable(&why)) << why;
  std::string choice;
  const std::unique_ptr<Renderer> autoR = Renderer::create(Backend::Auto, &choice);
  EXPECT_STREQ(autoR->name(), "cuda") << choice;
}

// Cubic B-spline sampling on the device. The device
// builds the cubic ranges (apron 2) and majorants bit for bit as the host,
// for every voxel type; switching interpolation to and from cubic rebuilds
// the device ranges (and only that: no upload), also when the Scene skips
// its host build; linear <-> nearest rebuilds nothing.
TEST(CudaCubic, MajorantsEqualHostBuildAndSwitchRebuilds)
{
  for (ScalarType type : { ScalarType::UInt8, ScalarType::Int16, ScalarType::Float32, ScalarType::Float64 })
  {
    const TypedVolume v(type, 3, 29, 23, 17);
    Scene scene;
    v.configure(scene, BlendMode::Density, 3);
    scene.setInterpolation(Interpolation::Cubic);
    scene.update();
    CUDARenderer g;
    const Camera cam = orbitCamera(v.dims, std::array<double, 3>{ 1, 1, 1 }.data(), 8, 8, 30, 20);
    renderImage(g, scene, cam, 1, 1);
    const int64_t cells = int64_t(scene.macrocellDims()[0]) * scene.macrocellDims()[1] * scene.macrocellDims()[2];
    for (int n = 0; n < 3; ++n)
    {
      const std::vector<float> dev = g.downloadMajorants(n);
      ASSERT_EQ(int64_t(dev.size()), cells);
      int64_t differ = 0;
      for (int64_t c = 0; c < cells; ++c)
      {
        differ += dev[size_t(c)] != scene.majorants()[size_t(c) * 3 + size_t(n)] ? 1 : 0;
      }
      EXPECT_EQ(differ, 0) << toString(type) << " channel " << n << " (cubic ranges)";
    }
  }
  const TypedVolume v(ScalarType::Float32, 2, 30, 28, 26);
  Scene scene;
  scene.setHostAcceleration(false);
  v.configure(scene, BlendMode::Density);
  CUDARenderer g;
  const Camera cam = orbitCamera(v.dims, std::array<double, 3>{ 1, 1, 1 }.data(), 16, 16, 30, 20);
  Accumulator acc;
  RenderSettings rs;
  g.render(scene, cam, rs, nullptr, acc);
  CudaUpdateCounters u = g.updateCounters();
  EXPECT_EQ(u.rangeBuilds, 1u);
  scene.setNearestInterpolation(true);
  scene.update();
  g.render(scene, cam, rs, nullptr, acc);
  EXPECT_EQ(g.updateCounters().rangeBuilds, 1u) << "nearest reads within the trilinear ranges";
  scene.setInterpolation(Interpolation::Cubic);
  scene.update();
  g.render(scene, cam, rs, nullptr, acc);
  u = g.updateCounters();
  EXPECT_EQ(u.rangeBuilds, 2u) << "cubic widens the ranges";
  EXPECT_EQ(u.dataUploads, 2u) << "no upload";
  scene.setInterpolation(Interpolation::Linear);
  scene.update();
  g.render(scene, cam, rs, nullptr, acc);
  EXPECT_EQ(g.updateCounters().rangeBuilds, 3u);
}

// With global-memory sampling the device runs the CPU's 64-tap arithmetic on
// the same random numbers: with the same seed nearly every pixel matches
// (float rounding, as in SameSeedGlobalSamplingNearlyIdentical). With texture
// sampling the 8 hardware-filtered fetches (Sigg and Hadwiger) are close to
// the software sum but not equal (8-bit fractional weights): the images
// agree statistically with the CPU's at the level of
// EveryModeTrackerTypeAndChannelCount (24 renders per image; the hardware
// weights' bias is far below that test's resolution). Families: 3 modes x 2
// types x 2 samplings x 12 checks at kAlpha.
TEST(CudaCubic, AgreesWithCpu)
{
  CPURenderer cpu;
  const std::unique_ptr<CUDARenderer> tex = cudaRenderer(CudaSampling::Texture);
  const std::unique_ptr<CUDARenderer> glob = cudaRenderer(CudaSampling::Global);
  {
    const TypedVolume v(ScalarType::Float32, 3, 32, 30, 28);
    const Camera cam = orbitCamera(v.dims, std::array<double, 3>{ 1, 1, 1 }.data(), 40, 40, 35, 25);
    Scene scene;
    v.configure(scene, BlendMode::Density);
    scene.setInterpolation(Interpolation::Cubic);
    scene.update();
    const std::vector<float> a = renderImage(cpu, scene, cam, 16, 77);
    const std::vector<float> b = renderImage(*glob, scene, cam, 16, 77);
    size_t close = 0;
    for (size_t p = 0; p < a.size() / 4; ++p)
    {
      bool same = true;
      for (int c = 0; c < 4; ++c)
      {
        same = same && std::fabs(a[4 * p + c] - b[4 * p + c]) <= 1e-4f;
      }
      close += same ? 1 : 0;
    }
    const double frac = double(close) / double(a.size() / 4);
    std::printf("cubic, same seed, global sampling: %.4f of pixels within 1e-4\n", frac);
    EXPECT_GE(frac, 0.99);
  }
  const double alpha = kAlpha / (3 * 2 * 2 * 12);
  RenderSettings rs;
  uint32_t seed = 9;
  for (ScalarType type : { ScalarType::UInt8, ScalarType::Float32 })
  {
    const TypedVolume v(type, 3, 24, 22, 20);
    const Camera cam = orbitCamera(v.dims, std::array<double, 3>{ 1, 1, 1 }.data(), 20, 20, 35, 25);
    for (BlendMode mode : { BlendMode::Density, BlendMode::Max, BlendMode::Composite })
    {
      Scene scene;
      v.configure(scene, mode);
      scene.setInterpolation(Interpolation::Cubic);
      scene.update();
      const Moments a = renderMoments(cpu, scene, cam, rs, 24, seed += 1000);
      for (CUDARenderer* g : { tex.get(), glob.get() })
      {
        const Moments b = renderMoments(*g, scene, cam, rs, 24, seed += 1000);
        expectSameImage(a, b, alpha,
          std::string("cubic ") + toString(type) + " " + toString(mode) +
            (g->sampling() == CudaSampling::Texture ? " texture" : " global"));
      }
    }
  }
}
