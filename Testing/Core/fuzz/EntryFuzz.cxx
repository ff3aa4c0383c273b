// SPDX-License-Identifier: BSD-3-Clause
#include "EntryFuzz.h"

#include "mcvol/Renderer.h"
#include "mcvol/Scene.h"
#include "mcvol/ray/DDA.h"
#include "mcvol/ray/RayGen.h"

#include <cfloat>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <limits>
#include <stdexcept>
#include <vector>

namespace mcvol
{
namespace fuzz
{
namespace
{
/// Reads the input front to back; past its end every read is 0.
class Reader
{
public:
  Reader(const uint8_t* data, size_t size)
    : Data(data)
    , Size(size)
  {
  }
  uint8_t Byte() { return this->Pos < this->Size ? this->Data[this->Pos++] : 0; }
  int Range(int lo, int hi) { return lo + this->Byte() % (hi - lo + 1); }
  template <class T>
  T Raw()
  {
    unsigned char bytes[sizeof(T)];
    for (unsigned char& b : bytes)
    {
      b = this->Byte();
    }
    T v;
    std::memcpy(&v, bytes, sizeof(T));
    return v;
  }
  /// A double: one of the interesting values, or 8 raw bytes.
  double Number()
  {
    static const double special[] = { 0.0, 1.0, -1.0, 0.5, 1e-30, 1e30, 1e-300, 1e300, 255.0, 65535.0,
      std::numeric_limits<double>::infinity(), -std::numeric_limits<double>::infinity(),
      std::numeric_limits<double>::quiet_NaN(), std::numeric_limits<double>::denorm_min() };
    const uint8_t k = this->Byte();
    return k < 2 * sizeof(special) / sizeof(special[0]) ? special[k / 2] : this->Raw<double>();
  }
  float Float() { return static_cast<float>(this->Number()); }

private:
  const uint8_t* Data;
  size_t Size;
  size_t Pos = 0;
};

[[noreturn]] void Fail(const char* what)
{
  std::fprintf(stderr, "mcvol entry fuzz: %s\n", what);
  std::abort();
}

/// Walks a DDA to its end; it may visit at most one cell per grid line
/// crossed, plus a few for rounding.
void Walk(const GridView& g, Vec3f o, Vec3f d, float t0, float t1)
{
  DDA dda;
  dda.init(g, o, d, t0, t1);
  const long limit = long(g.dims[0]) + g.dims[1] + g.dims[2] + 8;
  long steps = 0;
  while (!dda.done)
  {
    const int64_t cell = dda.cellIndex();
    if (cell < 0 || cell >= int64_t(g.dims[0]) * g.dims[1] * g.dims[2])
    {
      Fail("the DDA left its grid");
    }
    if (++steps > limit)
    {
      std::fprintf(stderr, "grid %d %d %d lo %g %g %g cell %g %g %g; ray o %g %g %g d %g %g %g t %g..%g\n", g.dims[0],
        g.dims[1], g.dims[2], g.lo[0], g.lo[1], g.lo[2], g.cellSize[0], g.cellSize[1], g.cellSize[2], o[0], o[1],
        o[2], d[0], d[1], d[2], t0, t1);
      Fail("the DDA visited more cells than its ray crosses");
    }
    dda.next();
  }
}
} // namespace

void RunOne(const uint8_t* data, size_t size)
{
  Reader in(data, size);
  // ---- Volume -------------------------------------------------------------------
  const int dims[3] = { in.Range(1, 9), in.Range(1, 9), in.Range(1, 9) };
  const int numChannels = in.Range(1, 4);
  const size_t voxels = size_t(dims[0]) * dims[1] * dims[2];
  std::vector<std::vector<unsigned char>> storage(static_cast<size_t>(numChannels));
  std::vector<ChannelSource> sources(static_cast<size_t>(numChannels));
  static const ScalarType types[] = { ScalarType::UInt8, ScalarType::Int16, ScalarType::UInt16, ScalarType::Float32,
    ScalarType::Float64 };
  static const size_t typeSizes[] = { 1, 2, 2, 4, 8 };
  for (int c = 0; c < numChannels; ++c)
  {
    const int t = in.Range(0, 4);
    const int stride = in.Range(0, 3); // 0: refused by setVolume
    std::vector<unsigned char>& bytes = storage[size_t(c)];
    bytes.resize(voxels * size_t(stride > 0 ? stride : 1) * typeSizes[t]);
    for (size_t i = 0; i < bytes.size(); i += typeSizes[t])
    {
      if (t >= 3 && in.Byte() < 32)
      {
        // Floats: NaN, infinities, huge and tiny values often.
        const double v = in.Number();
        if (t == 3)
        {
          const float f = static_cast<float>(v);
          std::memcpy(&bytes[i], &f, 4);
        }
        else
        {
          std::memcpy(&bytes[i], &v, 8);
        }
        continue;
      }
      for (size_t k = 0; k < typeSizes[t]; ++k)
      {
        bytes[i + k] = in.Byte();
      }
    }
    ChannelSource& s = sources[size_t(c)];
    s.data = in.Byte() < 8 ? nullptr : bytes.data();
    s.type = types[t];
    s.stride = stride;
    s.offset = t == 4 && in.Byte() < 128 ? in.Number() : 0.0;
  }
  Scene scene;
  try
  {
    scene.setVolume(dims, numChannels, sources.data());
  }
  catch (const std::invalid_argument&)
  {
    return;
  }
  // ---- Transfer functions, macrocells -------------------------------------------
  for (int c = 0; c < numChannels; ++c)
  {
    TransferFunctionDesc tf;
    tf.scalarMin = in.Number();
    tf.scalarMax = in.Byte() < 128 ? tf.scalarMin + in.Range(1, 255) : in.Number();
    const int k = in.Range(0, 9);
    tf.rgb.resize(size_t(3 * k) + (in.Byte() < 16 ? 1 : 0)); // sometimes one too many
    for (float& v : tf.rgb)
    {
      v = in.Byte() < 32 ? in.Float() : in.Byte() / 255.f;
    }
    tf.opacity.resize(size_t(k));
    for (float& v : tf.opacity)
    {
      v = in.Byte() < 32 ? in.Float() : in.Byte() / 255.f;
    }
    tf.unitDistance = in.Byte() < 64 ? in.Float() : 1.f + in.Byte() / 16.f;
    try
    {
      scene.setTransferFunction(c, tf);
    }
    catch (const std::invalid_argument&)
    {
    }
  }
  try
  {
    scene.setMacrocellSize(in.Range(0, 12));
  }
  catch (const std::invalid_argument&)
  {
  }
  try
  {
    scene.update();
  }
  catch (const std::invalid_argument&)
  {
    return;
  }
  // ---- A camera's rays through the scene's grid ---------------------------------
  CameraView cam;
  cam.width = in.Range(1, 8);
  cam.height = in.Range(1, 8);
  for (double& v : cam.invViewProj)
  {
    v = in.Byte() < 200 ? (in.Byte() - 128) / 16.0 : in.Number();
  }
  for (double& v : cam.worldToIndex)
  {
    v = in.Byte() < 200 ? (in.Byte() - 128) / 16.0 : in.Number();
  }
  const SceneView& view = scene.view();
  for (int py = 0; py < cam.height; ++py)
  {
    for (int px = 0; px < cam.width; ++px)
    {
      IndexRay ray;
      const float depth = in.Byte() < 32 ? in.Float() : 1.f;
      if (generateRay(cam, view.volume, px + 0.5f, py + 0.5f, depth, ray))
      {
        Walk(view.grid, ray.o, ray.d, 0.f, ray.tmax);
      }
    }
  }
  // ---- A DDA over any grid and ray ------------------------------------------------
  GridView g;
  for (int a = 0; a < 3; ++a)
  {
    g.dims[a] = in.Range(1, 9);
    g.cellSize[a] = in.Byte() < 200 ? 0.125f + in.Byte() / 32.f : in.Float();
    g.invCellSize[a] = 1.f / g.cellSize[a];
    g.lo[a] = in.Byte() < 200 ? (in.Byte() - 128) / 8.f : in.Float();
  }
  if (g.cellSize[0] > 0.f && g.cellSize[1] > 0.f && g.cellSize[2] > 0.f)
  {
    Vec3f o, d;
    for (int a = 0; a < 3; ++a)
    {
      o[a] = in.Byte() < 200 ? (in.Byte() - 128) / 8.f : in.Float();
      d[a] = in.Byte() < 200 ? (in.Byte() - 128) / 64.f : in.Float();
    }
    float t0 = 0.f, t1 = in.Byte() < 200 ? in.Byte() : in.Float();
    Vec3f lo, hi;
    for (int a = 0; a < 3; ++a)
    {
      lo[a] = g.lo[a];
      hi[a] = g.lo[a] + float(g.dims[a]) * g.cellSize[a];
    }
    // The DDA's contract: a finite end (generateRay gives no other).
    if (intersectBox(lo, hi, o, d, t0, t1) && t1 <= FLT_MAX)
    {
      Walk(g, o, d, t0, t1);
    }
  }
}
} // namespace fuzz
} // namespace mcvol
