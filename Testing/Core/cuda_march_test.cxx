// SPDX-License-Identifier: BSD-3-Clause
// The ray-marching reference on the CUDA backend (CUDARenderer::march)
// against the CPU march (RayMarcher): the same per-ray code (RayMarch.h), so
// the images agree to float rounding. Needs a CUDA device; TestMain skips
// with 125 without one.
//
// Tolerance: kTol = 1e-4 per pixel and component (premultiplied RGBA). Both
// sides run the same float operations; the device contracts a * b + c into
// fused multiply-adds and its expf/expm1f differ from the host's by an ulp
// or two, which over a few hundred compositing steps moves values by about
// 1e-6. Comparisons run without early termination, where a ray whose
// transmittance crosses the threshold one step apart on the two sides would
// differ by up to the threshold itself; one case with the default threshold
// (1e-4) allows kTol + 1e-4 * channels. Deterministic: no statistics.
#include "TestUtil.h"

#include "mcvol/CUDARenderer.h"
#include "mcvol/RayMarcher.h"

#include <limits>
#include <sstream>

using namespace mcvol;
using namespace mcvol::test;

namespace
{
constexpr double kTol = 1e-4;

struct Marched
{
  std::vector<float> rgba;
  MarchCounters counters;
};

Marched marchOn(
  Renderer& r, const Scene& scene, const Camera& cam, const MarchSettings& ms, const float* depth = nullptr)
{
  Marched m;
  Accumulator acc;
  r.march(scene, cam, ms, depth, acc, &m.counters);
  EXPECT_EQ(acc.samples(), 1u);
  EXPECT_FALSE(acc.pendingOnDevice());
  m.rgba.assign(acc.rgba(), acc.rgba() + size_t(cam.width) * cam.height * 4);
  return m;
}

/// Largest |a - b| over the image; fails (with the pixel) above `tol`.
double expectClose(const Marched& a, const Marched& b, double tol, const std::string& what)
{
  EXPECT_EQ(a.rgba.size(), b.rgba.size()) << what;
  double worst = 0.0;
  size_t at = 0;
  for (size_t i = 0; i < a.rgba.size() && i < b.rgba.size(); ++i)
  {
    EXPECT_TRUE(std::isfinite(b.rgba[i])) << what << ": value " << i;
    const double d = std::fabs(double(a.rgba[i]) - double(b.rgba[i]));
    if (d > worst || !(d == d))
    {
      worst = d == d ? d : HUGE_VAL;
      at = i;
    }
  }
  double sum = 0.0;
  for (float v : a.rgba)
  {
    sum += v;
  }
  std::printf("%-44s max |CPU - CUDA| %.3g (value %zu), image sum %.4g\n", what.c_str(), worst, at, sum);
  EXPECT_LE(worst, tol) << what << ": value " << at << " (pixel " << at / 4 << ", component " << at % 4 << "): CPU "
                        << a.rgba[at] << ", CUDA " << b.rgba[at];
  return worst;
}

/// CPU and CUDA march of the same scene; the sample counts agree too (the
/// same lattice, the same skipping and termination decisions), up to rays
/// whose decisions sit on a float rounding.
void expectSameMarch(CUDARenderer& gpu, const Scene& scene, const Camera& cam, const MarchSettings& ms,
  const std::string& what, double tol = kTol, const float* depth = nullptr)
{
  CPURenderer cpu;
  const Marched a = marchOn(cpu, scene, cam, ms, depth);
  const Marched b = marchOn(gpu, scene, cam, ms, depth);
  expectClose(a, b, tol, what);
  EXPECT_NEAR(double(b.counters.samples), double(a.counters.samples), 1e-3 * double(a.counters.samples) + 8) << what;
  EXPECT_NEAR(
    double(b.counters.skippedCells), double(a.counters.skippedCells), 1e-3 * double(a.counters.skippedCells) + 8)
    << what;
}

LightingDesc twoLights(int channels, double ambient)
{
  LightingDesc ld;
  const LightDesc sun = testSun(1.5);
  const LightDesc lamp = testLamp(400);
  ld.lights = { sun, lamp };
  ld.ambient[0] = ambient;
  ld.ambient[1] = 0.8 * ambient;
  ld.ambient[2] = 0.6 * ambient;
  const float albedo[4] = { 0.9f, 0.6f, 0.8f, 0.3f };
  const float g[4] = { 0.4f, -0.2f, 0.f, 0.7f };
  for (int n = 0; n < channels; ++n)
  {
    ld.albedo.push_back(albedo[n % 4]);
    ld.anisotropy.push_back(g[n % 4]);
  }
  ld.maxDepth = 1;
  return ld;
}

const double kUnitSpacing[3] = { 1, 1, 1 };

const char* modelName(Compositing c)
{
  return c == Compositing::Opacity ? "opacity" : "extinction";
}
} // namespace

// Unlit: every blend mode, both compositing models, trilinear and nearest
// interpolation, two datasets (float32 and uint8 channels), an explicit step
// and the Nyquist step, with and without jitter.
TEST(CudaMarch, UnlitEqualsCPU)
{
  CUDARenderer gpu;
  for (const char* name : { "cosmology", "microscopy" })
  {
    const DemoVolume v = makeDemo(name, { 24, 20, 28 });
    const Camera cam = orbitCamera(v.dims, v.spacing, 40, 32, 30, 20);
    for (BlendMode mode : { BlendMode::Density, BlendMode::Max, BlendMode::Mix, BlendMode::Composite })
    {
      Scene scene;
      configureDemo(scene, v, 4, 128, 0.5, mode);
      for (Compositing model : { Compositing::Extinction, Compositing::Opacity })
      {
        for (bool nearest : { false, true })
        {
          scene.setNearestInterpolation(nearest);
          MarchSettings ms;
          ms.compositing = model;
          ms.terminateTransmittance = 0.f;
          ms.step = nearest ? 0.0 : 0.3;
          ms.jitter = nearest;
          ms.seed = 5;
          std::ostringstream what;
          what << name << " " << toString(mode) << " " << modelName(model) << (nearest ? " nearest" : " linear");
          expectSameMarch(gpu, scene, cam, ms, what.str());
        }
      }
    }
  }
}

// Mix with the average colour off, and the default early termination (the
// tolerance then allows one termination decision apart).
TEST(CudaMarch, MixSumAndEarlyTermination)
{
  CUDARenderer gpu;
  const DemoVolume v = makeDemo("weather", { 20, 20, 16 });
  const Camera cam = orbitCamera(v.dims, v.spacing, 32, 32, 60, 10);
  Scene scene;
  configureDemo(scene, v, 8, 128, 0.25, BlendMode::Mix);
  scene.setMixAverage(false);
  scene.update();
  MarchSettings ms;
  ms.step = 0.5;
  ms.terminateTransmittance = 0.f;
  expectSameMarch(gpu, scene, cam, ms, "weather mix (sum)");
  ms.terminateTransmittance = 1e-4f;
  expectSameMarch(gpu, scene, cam, ms, "weather mix, termination 1e-4", kTol + 1e-4 * v.numChannels());
  scene.setBlendMode(BlendMode::Density);
  scene.update();
  expectSameMarch(gpu, scene, cam, ms, "weather density, termination 1e-4", kTol + 1e-4 * v.numChannels());
}

// Lit: single scattering with shadows from a directional and a point light,
// ambient radiance through the 32-direction quadrature, with and without
// shadows and gradient shading, for density, max and mix.
TEST(CudaMarch, LitEqualsCPU)
{
  CUDARenderer gpu;
  const DemoVolume v = makeDemo("cosmology", { 16, 16, 16 });
  const Camera cam = orbitCamera(v.dims, v.spacing, 20, 16, 30, 20);
  for (BlendMode mode : { BlendMode::Density, BlendMode::Max, BlendMode::Mix })
  {
    Scene scene;
    configureDemo(scene, v, 4, 128, 0.5, mode);
    for (int variant = 0; variant < 3; ++variant)
    {
      LightingDesc ld = twoLights(v.numChannels(), 0.4);
      ld.shadows = variant != 1;
      ld.gradientShading = variant == 2;
      scene.setLighting(ld);
      scene.update();
      MarchSettings ms;
      ms.step = 0.25;
      ms.terminateTransmittance = 0.f;
      const char* names[3] = { "shadows + ambient", "no shadows", "gradient shading" };
      expectSameMarch(gpu, scene, cam, ms, std::string("lit ") + toString(mode) + " " + names[variant]);
    }
  }
}

// Hard cases: opacity exactly 1 (extinction at the per-voxel limit), NaN
// voxels (transparent), a one-voxel volume at extreme spacings, a depth
// buffer that clips half the rays, float64 data far from 0.
TEST(CudaMarch, HardCasesEqualCPU)
{
  CUDARenderer gpu;
  MarchSettings ms;
  ms.terminateTransmittance = 0.f;
  {
    TestVolume v(8, 8, 8, 1, 1.f);
    Scene scene;
    configure(scene, v, { flatTF(1.f, 1, 1, 1) }, 4);
    const Camera cam = orthoAlongZ(8, 8, 0, 7, 0, 7, 20, 40);
    for (Compositing model : { Compositing::Extinction, Compositing::Opacity })
    {
      ms.compositing = model;
      expectSameMarch(gpu, scene, cam, ms, std::string("opacity 1, ") + modelName(model));
    }
  }
  {
    TestVolume n(8, 8, 8, 2, 1.f);
    for (int k = 0; k < 8; ++k)
      for (int j = 0; j < 8; ++j)
        for (int i = 0; i < 4; ++i)
          n.channels[0][n.index(i, j, k)] = std::numeric_limits<float>::quiet_NaN();
    n.channels[1][n.index(5, 5, 5)] = std::numeric_limits<float>::quiet_NaN();
    Scene scene;
    configure(scene, n, { flatTF(0.3f, 1, 0.5f, 0.2f), flatTF(0.2f, 0.1f, 0.4f, 1) }, 2);
    const Camera cam = orbitCamera(n.dims, kUnitSpacing, 16, 16, 20, 30);
    for (BlendMode mode : { BlendMode::Density, BlendMode::Max, BlendMode::Mix, BlendMode::Composite })
    {
      scene.setBlendMode(mode);
      scene.update();
      for (Compositing model : { Compositing::Extinction, Compositing::Opacity })
      {
        ms.compositing = model;
        expectSameMarch(gpu, scene, cam, ms, std::string("NaN voxels, ") + toString(mode) + ", " + modelName(model));
      }
    }
  }
  ms.compositing = Compositing::Extinction;
  {
    TestVolume one(1, 1, 1, 1, 1.f);
    for (double sp : { 1e-6, 1.0, 1e6 })
    {
      Scene scene;
      configure(scene, one, { flatTF(0.5f, 1, 1, 1, float(sp)) }, 1);
      const double spacing[3] = { sp, sp, sp };
      const double origin[3] = { 0, 0, 0 };
      Camera c = orthoAlongZ(4, 4, -sp, sp, -sp, sp, 10 * sp, 20 * sp);
      setWorldToIndex(c, spacing, origin);
      std::ostringstream what;
      what << "one voxel, spacing " << sp;
      expectSameMarch(gpu, scene, c, ms, what.str());
    }
  }
  {
    const DemoVolume v = makeDemo("figure3", { 20, 20, 20 });
    const Camera cam = orbitCamera(v.dims, v.spacing, 24, 24, 30, 20);
    Scene scene;
    configureDemo(scene, v, 4, 128, 1.0, BlendMode::Density);
    std::vector<float> depth(size_t(cam.width) * cam.height, 1.f);
    for (size_t p = 0; p < depth.size(); p += 2)
    {
      depth[p] = 0.5f + 0.4f * float(p % 7) / 7.f; // geometry in front of and inside the volume
    }
    expectSameMarch(gpu, scene, cam, ms, "depth buffer", kTol, depth.data());
  }
  {
    // float64 at 1e6 + [0, 1]: read relative to the channel's offset on both sides.
    const int dims[3] = { 10, 10, 10 };
    std::vector<double> data(1000);
    for (int i = 0; i < 1000; ++i)
    {
      data[size_t(i)] = 1e6 + 0.5 + 0.5 * std::sin(0.37 * i);
    }
    ChannelSource src;
    src.data = data.data();
    src.type = ScalarType::Float64;
    src.offset = 1e6;
    Scene scene;
    scene.setVolume(dims, 1, &src);
    TransferFunctionDesc tf = flatTF(0.2f, 0.9f, 0.6f, 0.3f, 1.f, 16);
    tf.scalarMin = 1e6;
    tf.scalarMax = 1e6 + 1;
    for (size_t i = 0; i < tf.opacity.size(); ++i)
    {
      tf.opacity[i] = 0.4f * float(i) / float(tf.opacity.size());
    }
    scene.setTransferFunction(0, tf);
    scene.setMacrocellSize(4);
    scene.update();
    expectSameMarch(gpu, scene, orbitCamera(dims, kUnitSpacing, 16, 16, 40, 10), ms, "float64 at 1e6");
  }
}

// The visibility-optimized march (Lerzer and Dachsbacher, Sec. 6.2), unlit
// for every blend mode and lit with optimized light rays.
TEST(CudaMarch, VisibilityOptimizedEqualsCPU)
{
  CUDARenderer gpu;
  const DemoVolume v = makeDemo("figure3", { 24, 24, 24 });
  const Camera cam = orbitCamera(v.dims, v.spacing, 24, 24, 30, 20);
  MarchSettings ms;
  ms.step = 1.0 / 8.0;
  ms.terminateTransmittance = 0.f;
  for (BlendMode mode : { BlendMode::Density, BlendMode::Max, BlendMode::Mix, BlendMode::Composite })
  {
    Scene scene;
    configureDemo(scene, v, 4, 128, 1.0, mode);
    ImportanceDesc imp;
    imp.enabled = true;
    imp.tables.assign(size_t(v.numChannels()), std::vector<float>());
    imp.tables[0].assign(128, 0.5f);
    imp.tables[2].assign(128, 1.f);
    scene.setImportance(imp);
    scene.update();
    ASSERT_TRUE(scene.optimized());
    expectSameMarch(gpu, scene, cam, ms, std::string("optimized ") + toString(mode));
    if (mode != BlendMode::Composite)
    {
      // Lit, optimized light rays and ambient: 32 optimized transmittance
      // marches per sample, so a coarser step and a smaller image.
      scene.setLighting(twoLights(v.numChannels(), 0.3));
      scene.update();
      MarchSettings lit = ms;
      lit.step = 0.5;
      const Camera small = orbitCamera(v.dims, v.spacing, 16, 16, 30, 20);
      expectSameMarch(gpu, scene, small, lit, std::string("optimized lit ") + toString(mode));
    }
  }
}

// The march reads the Monte Carlo renders' device copies: after a render, a
// march uploads nothing and builds no grid, and the reverse. Global sampling
// holds arrays, texture sampling textures (each channel once); the reference
// march reads the same voxels from either. MarchSettings::deviceTextures
// filters in hardware and stays close to the reference (hardware weights are
// 9-bit fixed point: a loose bound, not the reference's tolerance); it needs
// texture sampling and says so otherwise.
TEST(CudaMarch, SharesTheUploadAndSamplingIsChosen)
{
  const DemoVolume v = makeDemo("cosmology", { 24, 24, 24 });
  const Camera cam = orbitCamera(v.dims, v.spacing, 24, 24, 30, 20);
  Scene scene;
  configureDemo(scene, v, 4, 128, 0.5, BlendMode::Density);
  CUDARenderer gpu;
  gpu.setSampling(CudaSampling::Global);
  Accumulator mc;
  RenderSettings rs;
  gpu.render(scene, cam, rs, nullptr, mc);
  const CudaUpdateCounters before = gpu.updateCounters();
  MarchSettings ms;
  const Marched a = marchOn(gpu, scene, cam, ms);
  EXPECT_EQ(gpu.updateCounters().dataUploads, before.dataUploads);
  EXPECT_EQ(gpu.updateCounters().rangeBuilds, before.rangeBuilds);
  EXPECT_EQ(gpu.updateCounters().majorantChannelBuilds, before.majorantChannelBuilds);
  EXPECT_EQ(gpu.memory().textureBytes, 0u) << "global sampling holds arrays";
  gpu.render(scene, cam, rs, nullptr, mc);
  EXPECT_EQ(gpu.updateCounters().dataUploads, before.dataUploads);
  EXPECT_EQ(mc.samples(), 2u);

  CUDARenderer fresh; // texture sampling: the channels are held as textures
  const Marched b = marchOn(fresh, scene, cam, ms);
  EXPECT_EQ(fresh.updateCounters().dataUploads, uint64_t(v.numChannels())) << "one upload per channel";
  EXPECT_GT(fresh.memory().textureBytes, 0u);
  EXPECT_EQ(fresh.memory().dataBytes, 0u) << "texture-held channels keep no array";
  expectClose(a, b, 0.0, "the same voxels read from textures or arrays, the same image");

  ms.deviceTextures = true;
  EXPECT_THROW(marchOn(gpu, scene, cam, ms), std::invalid_argument) << "arrays cannot be hardware-filtered";
  const Marched t = marchOn(fresh, scene, cam, ms);
  expectClose(a, t, 0.02, "texture sampling (loose bound)");
}

// Refusals are the CPU march's, with the same exceptions, and the renderer
// keeps working after them.
TEST(CudaMarch, UnsupportedSettingsAreErrors)
{
  CUDARenderer gpu;
  CPURenderer cpu;
  const DemoVolume v = makeDemo("cosmology", { 12, 12, 12 });
  const Camera cam = orbitCamera(v.dims, v.spacing, 8, 8, 30, 20);
  Scene scene;
  configureDemo(scene, v, 4, 64, 0.5, BlendMode::Composite);
  Accumulator acc;
  for (Renderer* r : { static_cast<Renderer*>(&cpu), static_cast<Renderer*>(&gpu) })
  {
    SCOPED_TRACE(r->name());
    MarchSettings ms;
    ms.step = -1;
    EXPECT_THROW(r->march(scene, cam, ms, nullptr, acc), std::invalid_argument);
    ms.step = 1e-9;
    EXPECT_THROW(r->march(scene, cam, ms, nullptr, acc), std::invalid_argument);
    ms.step = 0;
    ms.terminateTransmittance = 1.f;
    EXPECT_THROW(r->march(scene, cam, ms, nullptr, acc), std::invalid_argument);
    ms.terminateTransmittance = 1e-4f;
    Camera empty = cam;
    empty.width = 0;
    EXPECT_THROW(r->march(scene, empty, ms, nullptr, acc), std::invalid_argument);
    // Lit composite (the CPU lights it, the CUDA kernels do not), lit
    // opacity model, multiple scattering.
    scene.setLighting(twoLights(v.numChannels(), 0.2));
    scene.update();
    if (r == &gpu)
    {
      EXPECT_THROW(r->march(scene, cam, ms, nullptr, acc), std::invalid_argument);
    }
    else
    {
      EXPECT_NO_THROW(r->march(scene, cam, ms, nullptr, acc));
    }
    scene.setBlendMode(BlendMode::Density);
    scene.update();
    ms.compositing = Compositing::Opacity;
    EXPECT_THROW(r->march(scene, cam, ms, nullptr, acc), std::invalid_argument);
    ms.compositing = Compositing::Extinction;
    LightingDesc deep = twoLights(v.numChannels(), 0.2);
    deep.maxDepth = 2;
    scene.setLighting(deep);
    scene.update();
    EXPECT_THROW(r->march(scene, cam, ms, nullptr, acc), std::invalid_argument);
    scene.setLighting(LightingDesc());
    // The optimization with the opacity model.
    ImportanceDesc imp;
    imp.enabled = true;
    imp.tables.assign(size_t(v.numChannels()), std::vector<float>(64, 1.f));
    scene.setImportance(imp);
    scene.update();
    ms.compositing = Compositing::Opacity;
    EXPECT_THROW(r->march(scene, cam, ms, nullptr, acc), std::invalid_argument);
    ms.compositing = Compositing::Extinction;
    EXPECT_NO_THROW(r->march(scene, cam, ms, nullptr, acc)) << "still works after the errors";
    EXPECT_EQ(acc.samples(), 1u);
    scene.setImportance(ImportanceDesc());
    scene.setBlendMode(BlendMode::Composite);
    scene.update();
  }
  Scene notUpdated;
  EXPECT_THROW(gpu.march(notUpdated, cam, MarchSettings(), nullptr, acc), std::logic_error);
}

// Cubic B-spline sampling, extinction model: the device
// march sums the 64 voxels as the CPU does (arrays with global sampling,
// texture-held voxels read exactly through the point object with texture
// sampling), so the images agree to kTol; a pre-classified channel too. With
// MarchSettings::deviceTextures the 8 hardware trilinear fetches of Sigg and
// Hadwiger replace the 64 reads: close to the reference (the hardware's
// fractional weights have 8 bits), a loose bound as for trilinear. The
// opacity model is refused as on the CPU.
TEST(CudaMarch, CubicEqualsCPU)
{
  for (CudaSampling sampling : { CudaSampling::Texture, CudaSampling::Global })
  {
    CUDARenderer gpu;
    gpu.setSampling(sampling);
    const char* how = sampling == CudaSampling::Texture ? " texture-held" : " arrays";
    for (const char* name : { "cosmology", "microscopy" })
    {
      const DemoVolume v = makeDemo(name, { 24, 20, 28 });
      const Camera cam = orbitCamera(v.dims, v.spacing, 40, 32, 30, 20);
      for (BlendMode mode : { BlendMode::Density, BlendMode::Max, BlendMode::Composite })
      {
        Scene scene;
        configureDemo(scene, v, 4, 128, 0.5, mode);
        scene.setInterpolation(Interpolation::Cubic);
        scene.update();
        MarchSettings ms;
        ms.terminateTransmittance = 0.f;
        ms.step = 0.3;
        const std::string what = std::string(name) + " " + toString(mode) + " cubic" + how;
        expectSameMarch(gpu, scene, cam, ms, what);
        if (sampling == CudaSampling::Texture)
        {
          CPURenderer cpu;
          const Marched a = marchOn(cpu, scene, cam, ms);
          ms.deviceTextures = true;
          const Marched t = marchOn(gpu, scene, cam, ms);
          expectClose(a, t, 0.02, what + " hardware (loose bound)");
          ms.deviceTextures = false;
        }
        ms.compositing = Compositing::Opacity;
        EXPECT_THROW(marchOn(gpu, scene, cam, ms), std::invalid_argument) << what;
      }
    }
  }
  // A pre-classified channel beside a scalar one.
  const int dims[3] = { 20, 18, 16 };
  const size_t voxels = size_t(dims[0]) * dims[1] * dims[2];
  std::vector<float> cl(voxels * 4), sc(voxels);
  for (int k = 0; k < dims[2]; ++k)
    for (int j = 0; j < dims[1]; ++j)
      for (int i = 0; i < dims[0]; ++i)
      {
        const size_t x = (size_t(k) * dims[1] + j) * dims[0] + i;
        const float s = 0.3f * std::max(0.f, std::sin(0.5f * i) * std::cos(0.4f * j) + 0.2f * k / dims[2]);
        cl[x * 4] = s;
        cl[x * 4 + 1] = s * 0.9f;
        cl[x * 4 + 2] = s * (0.2f + 0.04f * j);
        cl[x * 4 + 3] = s * 0.3f;
        sc[x] = float(i + j) / float(dims[0] + dims[1]);
      }
  ChannelSource src[2];
  src[0].data = cl.data();
  src[0].stride = 4;
  src[0].format = ChannelFormat::Extinction;
  src[1].data = sc.data();
  Scene scene;
  scene.setVolume(dims, 2, src);
  TransferFunctionDesc tf;
  tf.opacity = { 0.f, 0.f, 0.2f, 0.05f };
  tf.rgb = { 0, 0, 1, 0, 1, 0, 1, 1, 0, 1, 0, 0 };
  scene.setTransferFunction(1, tf);
  scene.setMacrocellSize(4);
  scene.setInterpolation(Interpolation::Cubic);
  scene.update();
  const Camera cam = orbitCamera(dims, kUnitSpacing, 32, 32, 40, 25);
  CUDARenderer gpu;
  MarchSettings ms;
  ms.terminateTransmittance = 0.f;
  ms.step = 0.25;
  expectSameMarch(gpu, scene, cam, ms, "classified + scalar cubic");
}
