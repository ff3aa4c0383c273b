// SPDX-License-Identifier: BSD-3-Clause
// Majorants are never below the true extinction, for all five scalar
// types (random data with NaN and Inf for float types, random transfer
// functions, random macrocell sizes, interleaved channels, trilinear and
// nearest-voxel sampling).
// Changing one channel's transfer function rebuilds only its majorants
// (Sahistan et al., Sec. 4.3). Deterministic (fixed seeds).
#include "TestUtil.h"

#include "mcvol/ray/DDA.h"
#include "mcvol/ray/Sampling.h"

#include <cfloat>
#include <cstring>
#include <limits>

using namespace mcvol;
using mcvol::test::TestRand;

namespace
{
template <typename T>
T randomValue(TestRand& r, ScalarType type)
{
  switch (type)
  {
    case ScalarType::UInt8:
      return T(r.integer(0, 255));
    case ScalarType::Int16:
      return T(r.integer(-2000, 2000));
    case ScalarType::UInt16:
      return T(r.integer(0, 60000));
    default:
    {
      const double p = r.uniform();
      if (p < 0.05)
      {
        return T(std::numeric_limits<double>::quiet_NaN());
      }
      if (p < 0.06)
      {
        return T(r.chance(0.5) ? std::numeric_limits<double>::infinity() : -std::numeric_limits<double>::infinity());
      }
      // Mostly smooth-ish magnitudes, sometimes wild.
      return T(p < 0.1 ? r.uniform(-1e6, 1e6) : r.uniform(-3.0, 7.0));
    }
  }
}

/// Random table: zeros, exact ones and random opacities; random range.
TransferFunctionDesc randomTF(TestRand& r, int K, float dataLo, float dataHi)
{
  TransferFunctionDesc tf;
  tf.opacity.resize(size_t(K));
  tf.rgb.resize(size_t(K) * 3);
  for (int i = 0; i < K; ++i)
  {
    const double p = r.uniform();
    tf.opacity[size_t(i)] = p < 0.3 ? 0.f : (p < 0.35 ? 1.f : float(r.uniform()));
    for (int c = 0; c < 3; ++c)
    {
      tf.rgb[size_t(i) * 3 + size_t(c)] = float(r.uniform());
    }
  }
  const float w = dataHi - dataLo;
  if (r.chance(0.1))
  {
    tf.scalarMin = tf.scalarMax = float(r.uniform(dataLo, dataHi)); // degenerate range
  }
  else
  {
    float a = float(r.uniform(dataLo - 0.2 * w, dataHi + 0.2 * w));
    float b = float(r.uniform(dataLo - 0.2 * w, dataHi + 0.2 * w));
    tf.scalarMin = std::min(a, b);
    tf.scalarMax = std::max(a, b);
  }
  tf.unitDistance = float(r.uniform(0.1, 10.0));
  return tf;
}

/// Cell the DDA assigns to point p (as in DDA::init), and neighbours when p
/// is within a relative 1e-3 cell of a boundary (a DDA segment ending there
/// may have either cell).
std::vector<int> candidateCells(const GridView& g, Vec3f p)
{
  std::vector<int> axis[3];
  for (int a = 0; a < 3; ++a)
  {
    const float x = (p[a] - g.lo[a]) * g.invCellSize[a];
    int c = x >= 0.f ? int(x) : -1;
    c = clampi(c, 0, g.dims[a] - 1);
    axis[a].push_back(c);
    const double frac = double(x) - std::floor(double(x));
    if (frac < 1e-3 && c - 1 >= 0)
    {
      axis[a].push_back(c - 1);
    }
    if (frac > 1 - 1e-3 && c + 1 < g.dims[a])
    {
      axis[a].push_back(c + 1);
    }
  }
  std::vector<int> out;
  for (int i : axis[0])
    for (int j : axis[1])
      for (int k : axis[2])
        out.push_back(i + g.dims[0] * (j + g.dims[1] * k));
  return out;
}

template <typename T>
void checkType(ScalarType type, uint64_t seed, int scenes)
{
  TestRand r(seed);
  for (int sc = 0; sc < scenes; ++sc)
  {
    int dims[3];
    for (int& d : dims)
    {
      d = r.chance(0.2) ? 1 : r.integer(2, 22);
    }
    const size_t voxels = size_t(dims[0]) * dims[1] * dims[2];
    // Two channels interleaved (stride 2) plus one planar channel.
    std::vector<T> inter(voxels * 2), planar(voxels);
    for (T& v : inter)
    {
      v = randomValue<T>(r, type);
    }
    for (size_t i = 0; i < voxels; ++i)
    {
      // A smoother channel: a ramp with noise.
      planar[i] = r.chance(0.5) ? randomValue<T>(r, type) : T(double(i % 97) * (type == ScalarType::UInt8 ? 2 : 7));
    }
    ChannelSource src[3];
    src[0].data = inter.data();
    src[0].type = type;
    src[0].stride = 2;
    src[1].data = inter.data() + 1;
    src[1].type = type;
    src[1].stride = 2;
    src[2].data = planar.data();
    src[2].type = type;
    src[2].stride = 1;
    Scene scene;
    scene.setVolume(dims, 3, src);
    const int K = r.integer(2, 300);
    const float lo = type == ScalarType::UInt8 ? 0.f : (type == ScalarType::UInt16 ? 0.f : -3.f);
    const float hi = type == ScalarType::UInt8 ? 255.f : (type == ScalarType::UInt16 ? 60000.f : 7.f);
    for (int n = 0; n < 3; ++n)
    {
      scene.setTransferFunction(
        n, randomTF(r, K, type == ScalarType::Int16 ? -2000.f : lo, type == ScalarType::Int16 ? 2000.f : hi));
    }
    scene.setMacrocellSize(r.integer(1, 9));
    const bool nearest = r.chance(0.3);
    scene.setNearestInterpolation(nearest);
    scene.update();
    const SceneView& s = scene.view();
    const GridView& g = s.grid;
    const std::string what = std::string(toString(type)) + " scene " + std::to_string(sc) + " dims " +
      std::to_string(dims[0]) + "x" + std::to_string(dims[1]) + "x" + std::to_string(dims[2]) + " macrocell " +
      std::to_string(scene.macrocellSize()) + (nearest ? " nearest" : " trilinear");
    for (size_t i = 0; i < scene.majorants().size(); ++i)
    {
      ASSERT_TRUE(std::isfinite(scene.majorants()[i]) && scene.majorants()[i] >= 0.f) << what;
    }
    int failures = 0;
    auto check = [&](Vec3f p, const std::vector<int>& cells, const char* how)
    {
      for (int n = 0; n < 3 && failures < 5; ++n)
      {
        const float v = sampleChannel(s.volume, n, p);
        const float sigma = lookupTF(s.tables, n, v).sigma;
        ASSERT_TRUE(std::isfinite(sigma) && sigma >= 0.f) << what;
        for (int c : cells)
        {
          const float m = g.majorants[size_t(c) * 3 + size_t(n)];
          if (!(sigma <= m))
          {
            ++failures;
            ADD_FAILURE() << what << " (" << how << "): channel " << n << " at (" << p.x << ", " << p.y << ", " << p.z
                          << ") value " << v << " extinction " << sigma << " > majorant " << m << " of cell " << c;
          }
        }
      }
    };
    // Random points, some placed exactly on (or one float step off) cell
    // boundaries.
    for (int i = 0; i < 3000; ++i)
    {
      Vec3f p;
      for (int a = 0; a < 3; ++a)
      {
        p[a] = float(r.uniform(s.volume.boxLo[a], s.volume.boxHi[a]));
      }
      if (r.chance(0.3))
      {
        const int a = r.integer(0, 2);
        float b = g.lo[a] + float(r.integer(0, g.dims[a])) * g.cellSize[a];
        const double q = r.uniform();
        b = q < 0.33 ? b : (q < 0.66 ? std::nextafter(b, -FLT_MAX) : std::nextafter(b, FLT_MAX));
        p[a] = clampf(b, s.volume.boxLo[a], s.volume.boxHi[a]);
      }
      check(p, candidateCells(g, p), "point");
    }
    // Along DDA segments of random rays: every sample the tracker could take
    // in a segment is bounded by that segment's majorant.
    for (int i = 0; i < 300; ++i)
    {
      Vec3f a, b;
      for (int k = 0; k < 3; ++k)
      {
        a[k] = float(r.uniform(s.volume.boxLo[k] - 2.0, s.volume.boxHi[k] + 2.0));
        b[k] = float(r.uniform(s.volume.boxLo[k], s.volume.boxHi[k]));
      }
      Vec3f d = b - a;
      if (r.chance(0.3))
      {
        d[r.integer(0, 2)] = 0.f;
      }
      if (!(length(d) > 0.f))
      {
        continue;
      }
      float t0 = 0.f, t1 = FLT_MAX;
      if (!intersectBox(s.volume.boxLo, s.volume.boxHi, a, d, t0, t1))
      {
        continue;
      }
      DDA dda;
      dda.init(g, a, d, t0, t1);
      while (!dda.done)
      {
        for (int k = 0; k < 4; ++k)
        {
          const float t = k == 0 ? dda.t0 : (k == 1 ? dda.t1 : dda.t0 + float(r.uniform()) * (dda.t1 - dda.t0));
          check(a + d * t, { int(dda.cellIndex()) }, "DDA segment");
        }
        dda.next();
      }
    }
  }
}
} // namespace

TEST(Majorants, BoundTheExtinctionUInt8)
{
  checkType<uint8_t>(ScalarType::UInt8, 11, 12);
}
TEST(Majorants, BoundTheExtinctionInt16)
{
  checkType<int16_t>(ScalarType::Int16, 12, 12);
}
TEST(Majorants, BoundTheExtinctionUInt16)
{
  checkType<uint16_t>(ScalarType::UInt16, 13, 12);
}
TEST(Majorants, BoundTheExtinctionFloat32WithNaNAndInf)
{
  checkType<float>(ScalarType::Float32, 14, 12);
}
TEST(Majorants, BoundTheExtinctionFloat64WithNaNAndInf)
{
  checkType<double>(ScalarType::Float64, 15, 12);
}

// Majorant rebuild locality.
TEST(Majorants, RebuildOnlyChangedChannel)
{
  TestRand r(21);
  test::TestVolume v(20, 17, 13, 3, 0.f);
  for (auto& ch : v.channels)
  {
    for (float& x : ch)
    {
      x = float(r.uniform());
    }
  }
  Scene scene;
  std::vector<TransferFunctionDesc> tfs;
  for (int n = 0; n < 3; ++n)
  {
    TransferFunctionDesc tf = test::flatTF(0.f, 1, 1, 1, 1.f, 16);
    for (int i = 0; i < 16; ++i)
    {
      tf.opacity[size_t(i)] = float(r.uniform());
    }
    tfs.push_back(tf);
  }
  test::configure(scene, v, tfs, 4);
  EXPECT_EQ(scene.lastMajorantChannelsRebuilt(), 3);
  EXPECT_FALSE(scene.update()) << "update() with nothing changed must rebuild nothing";

  const std::vector<float> before = scene.majorants();
  const uint64_t dataVersion = scene.dataVersion();
  TransferFunctionDesc tf = tfs[1];
  for (float& a : tf.opacity)
  {
    a = std::min(1.f, a * 0.5f + 0.3f);
  }
  scene.setTransferFunction(1, tf);
  EXPECT_TRUE(scene.update());
  EXPECT_EQ(scene.lastMajorantChannelsRebuilt(), 1);
  EXPECT_EQ(scene.dataVersion(), dataVersion) << "a transfer-function change must not rebuild the macrocells";
  const std::vector<float>& after = scene.majorants();
  ASSERT_EQ(before.size(), after.size());
  const size_t cells = before.size() / 3;
  size_t changed = 0;
  for (size_t c = 0; c < cells; ++c)
  {
    for (int n : { 0, 2 })
    {
      EXPECT_EQ(0, std::memcmp(&before[c * 3 + size_t(n)], &after[c * 3 + size_t(n)], sizeof(float)))
        << "channel " << n << " majorant of cell " << c << " changed";
    }
    changed += before[c * 3 + 1] != after[c * 3 + 1] ? 1 : 0;
  }
  EXPECT_GT(changed, 0u) << "the changed channel's majorants were not rebuilt";

  // The macrocell size or the data changing rebuilds every channel.
  scene.setMacrocellSize(5);
  scene.update();
  EXPECT_EQ(scene.lastMajorantChannelsRebuilt(), 3);
  scene.dataModified();
  scene.update();
  EXPECT_EQ(scene.lastMajorantChannelsRebuilt(), 3);
}
