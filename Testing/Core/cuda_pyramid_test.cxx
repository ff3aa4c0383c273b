// SPDX-License-Identifier: BSD-3-Clause
// Pyramid levels built on the GPU (CUDARenderer::classifyLevel;
// Documentation/user-guide/levels-of-detail.md) against the host build
// (classifyExtinctionLevel): every filter, levels 1 and 2, odd dims and axes
// of one voxel, one channel and two summed,
// every scalar type (float64 far from zero), a strided channel, scalars
// outside the table's range and a NaN voxel; the kept inputs; bad input.
// Needs a CUDA device (TestMain skips with 125 without one).
//
// Tolerance: the kernels do the host's operations in the host's order with
// explicitly rounded arithmetic, so the levels are expected to agree bit for
// bit; the check allows float rounding, |gpu - cpu| <= 1e-5 |cpu| + 1e-6 max
// |cpu| of that component, and the test prints how many voxels differ at all.
#include "TestUtil.h"

#include "mcvol/CUDARenderer.h"
#include "mcvol/Pyramid.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <limits>
#include <memory>
#include <stdexcept>
#include <string>

using namespace mcvol;
using namespace mcvol::test;

namespace
{
/// One scalar channel of any type, generated from a smooth field over
/// [lo, hi] (data units), planar or interleaved with `stride` components.
struct Channel
{
  ScalarType type = ScalarType::Float32;
  int64_t stride = 1;
  double offset = 0.0;
  double lo = 0.0;
  double hi = 1.0;
  std::vector<uint8_t> bytes;

  Channel(ScalarType t, const int d[3], TestRand& r, int64_t components = 1)
  {
    this->type = t;
    this->stride = components;
    switch (t)
    {
      case ScalarType::UInt8:
        this->hi = 255;
        break;
      case ScalarType::Int16:
        this->lo = -32768;
        this->hi = 32767;
        break;
      case ScalarType::UInt16:
        this->hi = 65535;
        break;
      case ScalarType::Float64:
        this->offset = 1e6; // far from zero: the texel coordinate needs double
        this->lo = 1e6;
        this->hi = 1e6 + 1;
        break;
      default:
        break;
    }
    const double f[3] = { r.uniform(0.2, 0.6), r.uniform(0.2, 0.6), r.uniform(0.2, 0.6) };
    const double ph[3] = { r.uniform(0, 6), r.uniform(0, 6), r.uniform(0, 6) };
    const size_t voxels = size_t(d[0]) * size_t(d[1]) * size_t(d[2]);
    const size_t es = size_t(scalarTypeSize(t));
    this->bytes.assign(voxels * size_t(components) * es, 0);
    size_t v = 0;
    for (int k = 0; k < d[2]; ++k)
      for (int j = 0; j < d[1]; ++j)
        for (int i = 0; i < d[0]; ++i, ++v)
        {
          const double s =
            0.5 + 0.5 * std::sin(f[0] * i + ph[0]) * std::sin(f[1] * j + ph[1]) * std::sin(f[2] * k + ph[2]);
          const double x = this->lo + s * (this->hi - this->lo);
          uint8_t* p = this->bytes.data() + v * size_t(components) * es;
          switch (t)
          {
            case ScalarType::UInt8:
              *p = uint8_t(std::lround(x));
              break;
            case ScalarType::Int16:
            {
              const int16_t q = int16_t(std::lround(x));
              std::memcpy(p, &q, sizeof(q));
              break;
            }
            case ScalarType::UInt16:
            {
              const uint16_t q = uint16_t(std::lround(x));
              std::memcpy(p, &q, sizeof(q));
              break;
            }
            case ScalarType::Float32:
            {
              const float q = float(x);
              std::memcpy(p, &q, sizeof(q));
              break;
            }
            case ScalarType::Float64:
              std::memcpy(p, &x, sizeof(x));
              break;
          }
        }
  }
  /// Voxel v set to NaN (floating-point types only).
  void setNaN(size_t v)
  {
    uint8_t* p = this->bytes.data() + v * size_t(this->stride) * size_t(scalarTypeSize(this->type));
    if (this->type == ScalarType::Float32)
    {
      const float q = std::numeric_limits<float>::quiet_NaN();
      std::memcpy(p, &q, sizeof(q));
    }
    else if (this->type == ScalarType::Float64)
    {
      const double q = std::numeric_limits<double>::quiet_NaN();
      std::memcpy(p, &q, sizeof(q));
    }
  }
  ChannelSource source() const
  {
    ChannelSource s;
    s.data = this->bytes.data();
    s.type = this->type;
    s.stride = this->stride;
    s.offset = this->offset;
    return s;
  }
  /// A random table over the middle 80% of the data's range, so that the
  /// ends clamp.
  TransferFunctionDesc table(TestRand& r, int K, float unit) const
  {
    TransferFunctionDesc tf = flatTF(0.f, 0, 0, 0, unit, K);
    tf.scalarMin = this->lo + 0.1 * (this->hi - this->lo);
    tf.scalarMax = this->lo + 0.9 * (this->hi - this->lo);
    for (int i = 0; i < K; ++i)
    {
      tf.opacity[size_t(i)] = float(r.uniform(0.0, 0.7));
      for (int c = 0; c < 3; ++c)
      {
        tf.rgb[size_t(i) * 3 + size_t(c)] = float(r.uniform(-0.2, 1.2)); // clamped to [0, 1]
      }
    }
    tf.opacity[1] = 1.f; // opacity 1: clamped to kMaxOpacity
    return tf;
  }
};

/// Compares a device level with the host's; returns the voxels that differ.
size_t expectLevelsAgree(const PyramidLevel& gpu, const PyramidLevel& cpu, const std::string& what)
{
  EXPECT_EQ(gpu.level, cpu.level) << what;
  for (int a = 0; a < 3; ++a)
  {
    EXPECT_EQ(gpu.dims[a], cpu.dims[a]) << what << " axis " << a;
    EXPECT_DOUBLE_EQ(gpu.spacing[a], cpu.spacing[a]) << what << " axis " << a;
    EXPECT_DOUBLE_EQ(gpu.origin[a], cpu.origin[a]) << what << " axis " << a;
    EXPECT_DOUBLE_EQ(gpu.boundsLo[a], cpu.boundsLo[a]) << what << " axis " << a;
    EXPECT_DOUBLE_EQ(gpu.boundsHi[a], cpu.boundsHi[a]) << what << " axis " << a;
  }
  EXPECT_EQ(gpu.voxels.size(), cpu.voxels.size()) << what;
  if (gpu.voxels.size() != cpu.voxels.size())
  {
    return cpu.numVoxels();
  }
  double maxAbs[4] = { 0, 0, 0, 0 };
  for (size_t i = 0; i < cpu.voxels.size(); ++i)
  {
    maxAbs[i % 4] = std::max(maxAbs[i % 4], std::fabs(double(cpu.voxels[i])));
  }
  size_t differ = 0, bad = 0;
  for (size_t i = 0; i < cpu.voxels.size(); ++i)
  {
    const double g = gpu.voxels[i], c = cpu.voxels[i];
    differ += g != c ? 1 : 0;
    const bool ok = std::fabs(g - c) <= 1e-5 * std::fabs(c) + 1e-6 * maxAbs[i % 4];
    if (!ok && bad++ < 5)
    {
      ADD_FAILURE() << what << ": voxel " << i / 4 << " component " << i % 4 << " is " << g << " on the GPU, " << c
                    << " on the host";
    }
  }
  EXPECT_EQ(bad, 0u) << what;
  return differ;
}

std::unique_ptr<CUDARenderer> device()
{
  return std::unique_ptr<CUDARenderer>(new CUDARenderer(CUDARenderer::defaultDevice()));
}
} // namespace

// Every filter, levels 1 and 2, over odd dims and axes of one voxel, one
// channel and two summed, each scalar type.
TEST(CudaPyramid, LevelsEqualHostBuild)
{
  const std::unique_ptr<CUDARenderer> r = device();
  EXPECT_TRUE(r->buildsLevelsOnDevice()); // on by default
  r->setDeviceLevels(true);
  EXPECT_TRUE(r->buildsLevelsOnDevice());
  TestRand rnd(4242);
  const int shapes[][3] = { { 37, 20, 9 }, { 16, 1, 12 }, { 1, 9, 14 }, { 11, 7, 1 }, { 64, 33, 40 } };
  const ScalarType types[] = { ScalarType::UInt8, ScalarType::Int16, ScalarType::UInt16, ScalarType::Float32,
    ScalarType::Float64 };
  const DownsampleFilter filters[] = { DownsampleFilter::Box2, DownsampleFilter::Box4, DownsampleFilter::BSpline };
  size_t compared = 0, differ = 0;
  for (const auto& dims : shapes)
  {
    const double spacing[3] = { 0.5, 1.25, 2.0 }, origin[3] = { -3.0, 0.25, 10.0 };
    const size_t voxels = size_t(dims[0]) * size_t(dims[1]) * size_t(dims[2]);
    for (ScalarType t : types)
    {
      // The second channel float, interleaved with 3 components.
      Channel a(t, dims, rnd);
      Channel b(ScalarType::Float32, dims, rnd, 3);
      if (t == ScalarType::Float32 || t == ScalarType::Float64)
      {
        a.setNaN(voxels / 2); // a transparent voxel
      }
      b.setNaN(voxels / 3);
      const TransferFunctionDesc ta = a.table(rnd, 48, 1.5f);
      const TransferFunctionDesc tb = b.table(rnd, 17, 0.75f);
      const ClassifyInput inputs[2] = { { a.source(), &ta }, { b.source(), &tb } };
      for (DownsampleFilter f : filters)
      {
        for (int level = 1; level <= std::min(2, maxPyramidLevels(dims)); ++level)
        {
          for (int count : { 1, 2 })
          {
            const std::string what = std::to_string(dims[0]) + "x" + std::to_string(dims[1]) + "x" +
              std::to_string(dims[2]) + " " + toString(t) + " " + toString(f) + " level " + std::to_string(level) +
              (count == 2 ? " summed" : " one channel");
            const PyramidLevel cpu = classifyExtinctionLevel(inputs, count, dims, spacing, origin, level, f);
            size_t peak = 0;
            const PyramidLevel gpu = r->classifyLevel(inputs, count, dims, spacing, origin, level, f, &peak);
            differ += expectLevelsAgree(gpu, cpu, what);
            compared += cpu.numVoxels();
            EXPECT_GT(peak, cpu.bytes()) << what;
          }
        }
      }
    }
  }
  std::printf("%zu of %zu voxels differ at all between the GPU and host builds\n", differ, compared);
}

// A channel of NaN voxels (over a one-voxel axis) classifies to an empty
// level, as on the host.
TEST(CudaPyramid, NaNVoxelIsTransparent)
{
  const std::unique_ptr<CUDARenderer> r = device();
  TestRand rnd(7);
  const int dims[3] = { 5, 4, 1 };
  Channel a(ScalarType::Float32, dims, rnd);
  const size_t voxels = 20;
  for (size_t v = 0; v < voxels; ++v)
  {
    a.setNaN(v); // all NaN: the level is empty
  }
  const TransferFunctionDesc ta = a.table(rnd, 8, 1.f);
  const ClassifyInput in[1] = { { a.source(), &ta } };
  const double spacing[3] = { 1, 1, 1 }, origin[3] = { 0, 0, 0 };
  const PyramidLevel gpu = r->classifyLevel(in, 1, dims, spacing, origin, 1, DownsampleFilter::Box4);
  for (float x : gpu.voxels)
  {
    EXPECT_EQ(x, 0.f);
  }
  expectLevelsAgree(gpu, classifyExtinctionLevel(in, 1, dims, spacing, origin, 1, DownsampleFilter::Box4), "all NaN");
}

// Inputs with a data version stay on the device: a transfer-function edit
// uploads nothing; a new version, or none, uploads again.
TEST(CudaPyramid, KeepsInputsByDataVersion)
{
  const std::unique_ptr<CUDARenderer> r = device();
  TestRand rnd(11);
  const int dims[3] = { 24, 18, 10 };
  const double spacing[3] = { 1, 1, 1 }, origin[3] = { 0, 0, 0 };
  Channel a(ScalarType::UInt16, dims, rnd), b(ScalarType::Float32, dims, rnd);
  TransferFunctionDesc ta = a.table(rnd, 32, 1.f), tb = b.table(rnd, 32, 1.f);
  ClassifyInput inputs[2] = { { a.source(), &ta, 5 }, { b.source(), &tb, 9 } };
  auto build = [&](const std::string& what)
  {
    const PyramidLevel gpu = r->classifyLevel(inputs, 2, dims, spacing, origin, 1, DownsampleFilter::Box4);
    expectLevelsAgree(gpu, classifyExtinctionLevel(inputs, 2, dims, spacing, origin, 1, DownsampleFilter::Box4), what);
  };
  const uint64_t u0 = r->updateCounters().levelInputUploads;
  build("first build");
  EXPECT_EQ(r->updateCounters().levelInputUploads, u0 + 2);
  EXPECT_EQ(r->memory().levelInputBytes, a.bytes.size() + b.bytes.size());
  ta = a.table(rnd, 32, 1.f); // an edit
  build("after an edit");
  EXPECT_EQ(r->updateCounters().levelInputUploads, u0 + 2) << "the kept inputs were copied again";
  // One level per channel, as the per-channel levels are built: both stay.
  for (int n : { 0, 1, 0, 1 })
  {
    const PyramidLevel gpu = r->classifyLevel(inputs + n, 1, dims, spacing, origin, 2, DownsampleFilter::BSpline);
    expectLevelsAgree(gpu, classifyExtinctionLevel(inputs + n, 1, dims, spacing, origin, 2, DownsampleFilter::BSpline),
      "channel " + std::to_string(n));
  }
  EXPECT_EQ(r->updateCounters().levelInputUploads, u0 + 2) << "per-channel builds copied the kept inputs again";
  // New data in place, with a new version: copied again.
  Channel a2(ScalarType::UInt16, dims, rnd);
  a.bytes = a2.bytes;
  inputs[0].source = a.source();
  inputs[0].dataVersion = 6;
  build("new data");
  EXPECT_EQ(r->updateCounters().levelInputUploads, u0 + 3);
  // No version: copied every time and not kept.
  inputs[0].dataVersion = 0;
  inputs[1].dataVersion = 0;
  build("no version");
  build("no version again");
  EXPECT_EQ(r->updateCounters().levelInputUploads, u0 + 7);
  EXPECT_EQ(r->memory().levelInputBytes, 0u);
  inputs[1].dataVersion = 1;
  build("kept again");
  EXPECT_GT(r->memory().levelInputBytes, 0u);
  r->releaseLevelInputs();
  EXPECT_EQ(r->memory().levelInputBytes, 0u);
  EXPECT_GT(r->updateCounters().levelBuilds, 5u);
  EXPECT_GT(r->updateCounters().lastLevelPeakBytes, 0u);
}

// The host build's refusals.
TEST(CudaPyramid, BadInputErrors)
{
  const std::unique_ptr<CUDARenderer> r = device();
  const int dims[3] = { 4, 4, 4 };
  const double spacing[3] = { 1, 1, 1 }, origin[3] = { 0, 0, 0 };
  std::vector<float> data(64, 0.5f);
  ChannelSource src;
  src.data = data.data();
  const TransferFunctionDesc tf = flatTF(0.5f, 1, 1, 1, 1.f, 4);
  const ClassifyInput ok[1] = { { src, &tf } };
  EXPECT_THROW(r->classifyLevel(nullptr, 0, dims, spacing, origin, 1, DownsampleFilter::Box4), std::invalid_argument);
  const ClassifyInput noTable[1] = { { src, nullptr } };
  EXPECT_THROW(r->classifyLevel(noTable, 1, dims, spacing, origin, 1, DownsampleFilter::Box4), std::invalid_argument);
  EXPECT_THROW(r->classifyLevel(ok, 1, dims, spacing, origin, 0, DownsampleFilter::Box4), std::invalid_argument);
  EXPECT_THROW(r->classifyLevel(ok, 1, dims, spacing, origin, 3, DownsampleFilter::Box4), std::invalid_argument);
  const double badSpacing[3] = { 1, 0, 1 };
  EXPECT_THROW(r->classifyLevel(ok, 1, dims, badSpacing, origin, 1, DownsampleFilter::Box4), std::invalid_argument);
  TransferFunctionDesc oneEntry = tf;
  oneEntry.opacity.resize(1);
  const ClassifyInput badTable[1] = { { src, &oneEntry } };
  EXPECT_THROW(r->classifyLevel(badTable, 1, dims, spacing, origin, 1, DownsampleFilter::Box4), std::invalid_argument);
  EXPECT_THROW(r->classifyLevel(ok, 1, dims, spacing, origin, 1, DownsampleFilter(7)), std::invalid_argument);
  // Still usable afterwards.
  const PyramidLevel l = r->classifyLevel(ok, 1, dims, spacing, origin, 2, DownsampleFilter::Box2);
  expectLevelsAgree(
    l, classifyExtinctionLevel(ok, 1, dims, spacing, origin, 2, DownsampleFilter::Box2), "after errors");
}
