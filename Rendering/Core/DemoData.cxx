// SPDX-License-Identifier: BSD-3-Clause
#include "mcvol/DemoData.h"

#include "mcvol/ray/Random.h"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <limits>
#include <stdexcept>

namespace mcvol
{
namespace
{
constexpr float kPi = 3.14159265358979f;

/// Hash of an integer lattice point to [0, 1).
float latticeValue(int x, int y, int z, uint32_t seed)
{
  const uint64_t h = splitmix64((uint64_t(uint32_t(x)) * 73856093ull) ^ (uint64_t(uint32_t(y)) * 19349663ull << 20) ^
    (uint64_t(uint32_t(z)) * 83492791ull << 40) ^ (uint64_t(seed) << 7));
  return float(h >> 40) * 0x1p-24f;
}

float smooth(float t)
{
  return t * t * (3.f - 2.f * t);
}

/// Value noise with lattice period `period` voxels, in [0, 1).
float valueNoise(float x, float y, float z, float period, uint32_t seed)
{
  const float fx = x / period, fy = y / period, fz = z / period;
  const int ix = int(std::floor(fx)), iy = int(std::floor(fy)), iz = int(std::floor(fz));
  const float tx = smooth(fx - ix), ty = smooth(fy - iy), tz = smooth(fz - iz);
  float v[2][2][2];
  for (int c = 0; c < 2; ++c)
    for (int b = 0; b < 2; ++b)
      for (int a = 0; a < 2; ++a)
        v[c][b][a] = latticeValue(ix + a, iy + b, iz + c, seed);
  const float x00 = v[0][0][0] + tx * (v[0][0][1] - v[0][0][0]);
  const float x10 = v[0][1][0] + tx * (v[0][1][1] - v[0][1][0]);
  const float x01 = v[1][0][0] + tx * (v[1][0][1] - v[1][0][0]);
  const float x11 = v[1][1][0] + tx * (v[1][1][1] - v[1][1][0]);
  const float y0 = x00 + ty * (x10 - x00);
  const float y1 = x01 + ty * (x11 - x01);
  return y0 + tz * (y1 - y0);
}

/// Fractal sum of value noise in about [0, 1).
float fbm(float x, float y, float z, float period, int octaves, uint32_t seed)
{
  float sum = 0.f, amp = 0.5f, norm = 0.f;
  for (int o = 0; o < octaves; ++o)
  {
    sum += amp * valueNoise(x, y, z, period, seed + 101u * uint32_t(o));
    norm += amp;
    amp *= 0.5f;
    period *= 0.5f;
  }
  return sum / norm;
}

template <typename T>
std::vector<uint8_t> allocate(size_t voxels)
{
  return std::vector<uint8_t>(voxels * sizeof(T));
}

template <typename T>
T* as(std::vector<uint8_t>& bytes)
{
  return reinterpret_cast<T*>(bytes.data());
}

DemoTransferFunction flat(float r, float g, float b, float a0, float a1, float unit)
{
  DemoTransferFunction tf;
  tf.color = { { 0.f, r, g, b }, { 1.f, r, g, b } };
  tf.opacity = { { 0.f, a0 }, { 1.f, a1 } };
  tf.unitDistance = unit;
  return tf;
}

DemoTransferFunction ramp(
  std::vector<std::array<float, 4>> color, std::vector<std::array<float, 2>> opacity, float unit)
{
  DemoTransferFunction tf;
  tf.color = std::move(color);
  tf.opacity = std::move(opacity);
  tf.unitDistance = unit;
  return tf;
}

// Colours cycled by extra channels of the channel-count study.
const float kPalette[8][3] = { { 0.9f, 0.2f, 0.2f }, { 0.2f, 0.85f, 0.3f }, { 0.25f, 0.4f, 0.95f },
  { 0.95f, 0.8f, 0.2f }, { 0.8f, 0.3f, 0.85f }, { 0.2f, 0.85f, 0.85f }, { 0.95f, 0.55f, 0.2f }, { 0.9f, 0.9f, 0.9f } };

void checkDims(const std::array<int, 3>& d)
{
  for (int a = 0; a < 3; ++a)
  {
    if (d[a] < 1 || d[a] > 8192)
    {
      throw std::invalid_argument("mcvol: demo dimensions must be between 1 and 8192");
    }
  }
}

/// Visits the generated box's voxels: p indexes the box's channels, (i, j, k)
/// are the voxel's indices in the whole volume.
template <typename Fn>
void forEachVoxel(const DemoVolume& v, Fn fn)
{
  const int64_t nz = v.dims[2];
#pragma omp parallel for schedule(dynamic, 1)
  for (int64_t k = 0; k < nz; ++k)
  {
    for (int j = 0; j < v.dims[1]; ++j)
    {
      for (int i = 0; i < v.dims[0]; ++i)
      {
        const size_t p = (size_t(k) * v.dims[1] + j) * v.dims[0] + i;
        fn(p, i + v.offset[0], j + v.offset[1], int(k) + v.offset[2]);
      }
    }
  }
}

/// Paper Figure 3: red, green and blue cubes with densities falling linearly
/// along +X, -X and -Y respectively, overlapping in the middle.
void makeFigure3(DemoVolume& v)
{
  const int* d = v.wholeDims;
  const size_t voxels = size_t(v.dims[0]) * v.dims[1] * v.dims[2];
  v.type = ScalarType::Float32;
  v.channelNames = { "red_cube", "green_cube", "blue_cube" };
  v.channels.assign(3, allocate<float>(voxels));
  float* c0 = as<float>(v.channels[0]);
  float* c1 = as<float>(v.channels[1]);
  float* c2 = as<float>(v.channels[2]);
  auto unit = [&](int i, int a) { return d[a] > 1 ? float(i) / float(d[a] - 1) : 0.5f; };
  auto inside = [](float x, float y, float z, float x0, float y0, float z0)
  {
    const float s = 0.55f;
    return x >= x0 && x <= x0 + s && y >= y0 && y <= y0 + s && z >= z0 && z <= z0 + s;
  };
  forEachVoxel(v,
    [&](size_t p, int i, int j, int k)
    {
      const float x = unit(i, 0), y = unit(j, 1), z = unit(k, 2);
      // Each cube spans 0.55 of the domain; density 1 at one face, 0 at the other.
      c0[p] = inside(x, y, z, 0.08f, 0.08f, 0.2f) ? 1.f - (x - 0.08f) / 0.55f : 0.f;
      c1[p] = inside(x, y, z, 0.37f, 0.22f, 0.22f) ? (x - 0.37f) / 0.55f : 0.f;
      c2[p] = inside(x, y, z, 0.22f, 0.37f, 0.12f) ? (y - 0.37f) / 0.55f : 0.f;
    });
  const float u = 0.08f * float(std::max({ d[0], d[1], d[2] }));
  v.transferFunctions = { flat(1.f, 0.f, 0.f, 0.f, 0.9f, u), flat(0.f, 1.f, 0.f, 0.f, 0.9f, u),
    flat(0.f, 0.f, 1.f, 0.f, 0.9f, u) };
}

/// Microscopy-like phantom: cells of a jittered Voronoi tessellation; membranes
/// on cell borders, a nucleus in each cell, small bright puncta.
void makeMicroscopy(DemoVolume& v)
{
  const int* d = v.wholeDims;
  const size_t voxels = size_t(v.dims[0]) * v.dims[1] * v.dims[2];
  v.type = ScalarType::UInt8;
  v.channelNames = { "membranes", "nuclei", "puncta" };
  v.channels.assign(3, allocate<uint8_t>(voxels));
  uint8_t* mem = as<uint8_t>(v.channels[0]);
  uint8_t* nuc = as<uint8_t>(v.channels[1]);
  uint8_t* pun = as<uint8_t>(v.channels[2]);
  const float cell = std::max(6.f, float(std::min(d[0], d[1])) / 6.f);
  const float zScale = 1.f; // isotropic cells in index space
  const float pcell = std::max(3.f, cell / 3.f);
  auto seedOf = [&](int a, int b, int c, uint32_t s, float period, float out[3])
  {
    out[0] = (float(a) + 0.15f + 0.7f * latticeValue(a, b, c, s)) * period;
    out[1] = (float(b) + 0.15f + 0.7f * latticeValue(a, b, c, s + 1)) * period;
    out[2] = (float(c) + 0.15f + 0.7f * latticeValue(a, b, c, s + 2)) * period;
  };
  forEachVoxel(v,
    [&](size_t p, int i, int j, int k)
    {
      const float x = float(i), y = float(j), z = float(k) * zScale;
      const int ci = int(std::floor(x / cell)), cj = int(std::floor(y / cell)), ck = int(std::floor(z / cell));
      float d1 = std::numeric_limits<float>::max(), d2 = d1;
      for (int c = ck - 1; c <= ck + 1; ++c)
        for (int b = cj - 1; b <= cj + 1; ++b)
          for (int a = ci - 1; a <= ci + 1; ++a)
          {
            float s[3];
            seedOf(a, b, c, 11u, cell, s);
            const float dd = std::sqrt((x - s[0]) * (x - s[0]) + (y - s[1]) * (y - s[1]) + (z - s[2]) * (z - s[2]));
            if (dd < d1)
            {
              d2 = d1;
              d1 = dd;
            }
            else if (dd < d2)
            {
              d2 = dd;
            }
          }
      const float noise = valueNoise(x, y, z, 3.f, 5u);
      const float wall = std::exp(-(d2 - d1) * (d2 - d1) / 2.0f);
      const float nucleus = d1 < 0.28f * cell ? 1.f : std::exp(-(d1 - 0.28f * cell) * (d1 - 0.28f * cell) / 1.5f);
      float punct = 0.f;
      const int pi = int(std::floor(x / pcell)), pj = int(std::floor(y / pcell)), pk = int(std::floor(z / pcell));
      for (int c = pk - 1; c <= pk + 1; ++c)
        for (int b = pj - 1; b <= pj + 1; ++b)
          for (int a = pi - 1; a <= pi + 1; ++a)
          {
            if (latticeValue(a, b, c, 77u) > 0.35f)
            {
              continue; // about a third of the sites carry a punctum
            }
            float s[3];
            seedOf(a, b, c, 31u, pcell, s);
            const float r2 = (x - s[0]) * (x - s[0]) + (y - s[1]) * (y - s[1]) + (z - s[2]) * (z - s[2]);
            punct = std::max(punct, std::exp(-r2 / 1.2f));
          }
      mem[p] = uint8_t(std::min(255.f, 255.f * wall * (0.6f + 0.4f * noise)));
      nuc[p] = uint8_t(std::min(255.f, 255.f * nucleus * (0.7f + 0.3f * noise)));
      pun[p] = uint8_t(std::min(255.f, 255.f * punct));
    });
  const float u = 2.f;
  v.transferFunctions = {
    ramp({ { 0.f, 0.9f, 0.3f, 0.8f }, { 1.f, 1.f, 0.6f, 0.95f } }, { { 0.f, 0.f }, { 0.3f, 0.f }, { 1.f, 0.5f } }, u),
    ramp({ { 0.f, 0.2f, 0.4f, 1.f }, { 1.f, 0.4f, 0.8f, 1.f } }, { { 0.f, 0.f }, { 0.4f, 0.f }, { 1.f, 0.35f } }, u),
    ramp({ { 0.f, 0.3f, 1.f, 0.3f }, { 1.f, 0.9f, 1.f, 0.3f } }, { { 0.f, 0.f }, { 0.25f, 0.f }, { 1.f, 0.95f } }, u),
  };
}

/// Cosmology-like: a log-normal dark-matter density and three fields
/// correlated with it (baryon density, temperature, velocity magnitude).
void makeCosmology(DemoVolume& v)
{
  const int* d = v.wholeDims;
  const size_t voxels = size_t(v.dims[0]) * v.dims[1] * v.dims[2];
  v.type = ScalarType::Float32;
  v.channelNames = { "dark_matter_density", "baryon_density", "temperature", "velocity_magnitude" };
  v.channels.assign(4, allocate<float>(voxels));
  float* dm = as<float>(v.channels[0]);
  float* ba = as<float>(v.channels[1]);
  float* te = as<float>(v.channels[2]);
  float* ve = as<float>(v.channels[3]);
  const float period = float(std::max({ d[0], d[1], d[2] })) / 3.f;
  forEachVoxel(v,
    [&](size_t p, int i, int j, int k)
    {
      const float x = float(i), y = float(j), z = float(k);
      const float f = fbm(x, y, z, period, 5, 1u);
      const float g = fbm(x, y, z, period * 0.5f, 3, 2u);
      const float h = fbm(x, y, z, period, 3, 3u);
      const float delta = (f - 0.5f) * 9.f; // filaments: log-normal contrast
      dm[p] = std::exp(delta);
      ba[p] = std::exp(0.85f * delta + 1.5f * (g - 0.5f));
      te[p] = std::pow(ba[p], 0.6f) * (0.6f + 0.8f * h);
      ve[p] = 1.f + 4.f * std::fabs(h - 0.5f) + 0.3f * delta * delta / 9.f;
    });
  const float u = 0.05f * float(std::max({ d[0], d[1], d[2] }));
  v.transferFunctions = {
    ramp({ { 0.f, 0.2f, 0.2f, 0.6f }, { 0.3f, 0.8f, 0.3f, 0.5f }, { 1.f, 1.f, 0.9f, 0.7f } },
      { { 0.f, 0.f }, { 0.05f, 0.f }, { 0.3f, 0.6f }, { 1.f, 0.9f } }, u),
    ramp({ { 0.f, 0.1f, 0.5f, 0.9f }, { 1.f, 0.6f, 0.9f, 1.f } }, { { 0.f, 0.f }, { 0.05f, 0.f }, { 1.f, 0.6f } }, u),
    ramp({ { 0.f, 0.9f, 0.4f, 0.1f }, { 1.f, 1.f, 0.9f, 0.3f } }, { { 0.f, 0.f }, { 0.1f, 0.f }, { 1.f, 0.5f } }, u),
    ramp({ { 0.f, 0.3f, 0.9f, 0.4f }, { 1.f, 0.8f, 1.f, 0.6f } }, { { 0.f, 0.f }, { 0.6f, 0.f }, { 1.f, 0.3f } }, u),
  };
}

/// Weather-like: a hurricane vortex on a flat grid with 12 fields.
void makeWeather(DemoVolume& v)
{
  const int* d = v.wholeDims;
  const size_t voxels = size_t(v.dims[0]) * v.dims[1] * v.dims[2];
  v.type = ScalarType::Float32;
  v.channelNames = { "pressure", "temperature", "u_wind", "v_wind", "w_wind", "wind_speed", "vapor", "cloud", "rain",
    "snow", "ice", "graupel" };
  v.channels.assign(12, allocate<float>(voxels));
  std::vector<float*> c(12);
  for (int n = 0; n < 12; ++n)
  {
    c[n] = as<float>(v.channels[n]);
  }
  const float cx = 0.5f * float(d[0] - 1), cy = 0.5f * float(d[1] - 1);
  const float R = 0.5f * float(std::min(d[0], d[1]));
  forEachVoxel(v,
    [&](size_t p, int i, int j, int k)
    {
      const float x = (float(i) - cx) / R, y = (float(j) - cy) / R;
      const float z = d[2] > 1 ? float(k) / float(d[2] - 1) : 0.5f;
      const float r = std::sqrt(x * x + y * y) + 1e-6f;
      const float theta = std::atan2(y, x);
      const float n1 = valueNoise(float(i), float(j), float(k), 6.f, 9u);
      const float vmax = 60.f, rm = 0.15f;
      const float speed = vmax * (r < rm ? r / rm : std::exp(-(r - rm) * 2.5f)) * (1.f - 0.5f * z);
      const float spiral = 0.5f + 0.5f * std::cos(3.f * theta + 12.f * r);
      const float band = std::exp(-std::pow((r - 0.45f) / 0.25f, 2.f)) * spiral + std::exp(-std::pow(r / 0.12f, 2.f));
      const float eye = r < 0.05f ? 0.f : 1.f;
      c[0][p] = 1000.f - 60.f * std::exp(-r * r / 0.1f) - 700.f * z;
      c[1][p] = 300.f - 70.f * z + 8.f * std::exp(-r * r / 0.02f);
      c[2][p] = -speed * std::sin(theta);
      c[3][p] = speed * std::cos(theta);
      c[4][p] = 4.f * band * eye * std::sin(kPi * z) * (0.5f + n1);
      c[5][p] = speed;
      c[6][p] = 0.02f * std::exp(-3.f * z) * (0.5f + 0.5f * band);
      c[7][p] = 1e-3f * band * eye * std::sin(kPi * z) * (0.3f + n1);
      c[8][p] = 1e-3f * band * eye * (z < 0.4f ? 1.f : 0.f) * n1;
      c[9][p] = 1e-3f * band * eye * (z > 0.5f ? 1.f : 0.f) * n1;
      c[10][p] = 1e-3f * band * eye * (z > 0.7f ? 1.f : 0.f) * (1.f - n1);
      c[11][p] = 1e-3f * band * eye * (z > 0.3f && z < 0.6f ? 1.f : 0.f) * n1 * n1;
    });
  const float u = 0.05f * float(std::max({ d[0], d[1], d[2] }));
  v.transferFunctions.clear();
  for (int n = 0; n < 12; ++n)
  {
    const float* col = kPalette[n % 8];
    // Fields with a background level (pressure, temperature, vapour) show a
    // thin shell around their mid value (a surface that dips in the eye);
    // signed winds show both extremes; the rest shows where it is strong.
    const bool shell = n < 2 || n == 6;
    const bool signedWind = n == 2 || n == 3;
    std::vector<std::array<float, 2>> op;
    if (shell)
      op = { { 0.f, 0.f }, { 0.45f, 0.f }, { 0.5f, 0.25f }, { 0.55f, 0.f }, { 1.f, 0.f } };
    else if (signedWind)
      op = { { 0.f, 0.3f }, { 0.2f, 0.f }, { 0.8f, 0.f }, { 1.f, 0.3f } };
    else
      op = { { 0.f, 0.f }, { 0.3f, 0.f }, { 1.f, 0.4f } };
    v.transferFunctions.push_back(
      ramp({ { 0.f, col[0] * 0.6f, col[1] * 0.6f, col[2] * 0.6f }, { 1.f, col[0], col[1], col[2] } }, op, u));
  }
}

/// Repeats channels (with other colours) up to `count`, as the paper does to
/// study channel counts beyond a dataset's own.
void repeatChannels(DemoVolume& v, int count)
{
  const int natural = v.numChannels();
  for (int n = natural; n < count; ++n)
  {
    const int src = n % natural;
    v.channels.push_back(v.channels[size_t(src)]);
    v.channelNames.push_back(v.channelNames[size_t(src)] + "_" + std::to_string(n / natural));
    DemoTransferFunction tf = v.transferFunctions[size_t(src)];
    const float* col = kPalette[n % 8];
    for (auto& cp : tf.color)
    {
      cp = { cp[0], col[0], col[1], col[2] };
    }
    // Each repetition shows a different band of the field's values.
    const float shift = 0.1f * float((n / natural) % 5);
    for (auto& op : tf.opacity)
    {
      op[0] = std::min(1.f, op[0] + shift * (1.f - op[0]));
    }
    v.transferFunctions.push_back(tf);
  }
  v.channels.resize(size_t(count));
  v.channelNames.resize(size_t(count));
  v.transferFunctions.resize(size_t(count));
}
} // namespace

ChannelSource DemoVolume::source(int n) const
{
  ChannelSource s;
  s.data = this->channels.at(size_t(n)).data();
  s.type = this->type;
  s.stride = 1;
  return s;
}

std::array<float, 2> DemoVolume::range(int n) const
{
  const int64_t voxels = int64_t(this->dims[0]) * this->dims[1] * this->dims[2];
  const void* data = this->channels.at(size_t(n)).data();
  const ScalarType type = this->type;
  float lo = std::numeric_limits<float>::infinity(), hi = -lo;
#pragma omp parallel for reduction(min : lo) reduction(max : hi)
  for (int64_t i = 0; i < voxels; ++i)
  {
    const float x = visitScalarType(type,
      [&](auto tag)
      {
        using T = typename decltype(tag)::type;
        return float(static_cast<const T*>(data)[i]);
      });
    if (std::isfinite(x))
    {
      lo = std::min(lo, x);
      hi = std::max(hi, x);
    }
  }
  if (!(lo <= hi))
  {
    lo = hi = 0.f;
  }
  return { lo, hi };
}

std::vector<std::string> demoNames()
{
  return { "figure3", "microscopy", "cosmology", "weather" };
}

std::array<int, 3> demoDefaultDims(const std::string& name)
{
  if (name == "figure3")
    return { 64, 64, 64 };
  if (name == "microscopy")
    return { 128, 128, 40 };
  if (name == "cosmology")
    return { 64, 64, 64 };
  if (name == "weather")
    return { 100, 100, 20 };
  throw std::invalid_argument(
    "mcvol: unknown demo dataset '" + name + "' (known: figure3, microscopy, cosmology, weather)");
}

DemoVolume makeDemo(const std::string& name, std::array<int, 3> dims, int channels)
{
  if (dims[0] == 0 && dims[1] == 0 && dims[2] == 0)
  {
    dims = demoDefaultDims(name);
  }
  checkDims(dims);
  return makeDemoPiece(name, dims, channels, { 0, dims[0] - 1, 0, dims[1] - 1, 0, dims[2] - 1 });
}

DemoVolume makeDemoPiece(
  const std::string& name, std::array<int, 3> dims, int channels, const std::array<int, 6>& extent)
{
  demoDefaultDims(name); // rejects an unknown name first
  checkDims(dims);
  for (int a = 0; a < 3; ++a)
  {
    if (extent[2 * a] < 0 || extent[2 * a + 1] >= dims[a] || extent[2 * a] > extent[2 * a + 1])
    {
      throw std::invalid_argument("mcvol: a demo piece must be a non-empty box inside the volume");
    }
  }
  if (channels < 0 || channels > kMaxChannels)
  {
    throw std::invalid_argument("mcvol: demo channel count must be between 1 and " + std::to_string(kMaxChannels));
  }
  DemoVolume v;
  v.name = name;
  for (int a = 0; a < 3; ++a)
  {
    v.wholeDims[a] = dims[a];
    v.offset[a] = extent[2 * a];
    v.dims[a] = extent[2 * a + 1] - extent[2 * a] + 1;
  }
  if (name == "figure3")
    makeFigure3(v);
  else if (name == "microscopy")
    makeMicroscopy(v);
  else if (name == "cosmology")
    makeCosmology(v);
  else
    makeWeather(v);
  if (channels > 0 && channels != v.numChannels())
  {
    if (channels < v.numChannels())
    {
      v.channels.resize(size_t(channels));
      v.channelNames.resize(size_t(channels));
      v.transferFunctions.resize(size_t(channels));
    }
    else
    {
      repeatChannels(v, channels);
    }
  }
  return v;
}

TransferFunctionDesc sampleTransferFunction(const DemoTransferFunction& tf, float lo, float hi, int K, double spacing)
{
  if (K < 2 || tf.color.empty() || tf.opacity.empty())
  {
    throw std::invalid_argument("mcvol: a transfer function needs points and at least 2 table entries");
  }
  TransferFunctionDesc out;
  out.scalarMin = lo;
  out.scalarMax = hi;
  out.unitDistance = float(double(tf.unitDistance) * spacing);
  out.rgb.resize(size_t(K) * 3);
  out.opacity.resize(size_t(K));
  auto interp = [](const auto& pts, float x, int comp)
  {
    if (x <= pts.front()[0])
      return pts.front()[size_t(comp)];
    if (x >= pts.back()[0])
      return pts.back()[size_t(comp)];
    for (size_t i = 1; i < pts.size(); ++i)
    {
      if (x <= pts[i][0])
      {
        const float w = (x - pts[i - 1][0]) / std::max(1e-12f, pts[i][0] - pts[i - 1][0]);
        return pts[i - 1][size_t(comp)] + w * (pts[i][size_t(comp)] - pts[i - 1][size_t(comp)]);
      }
    }
    return pts.back()[size_t(comp)];
  };
  for (int i = 0; i < K; ++i)
  {
    const float x = float(i) / float(K - 1);
    out.rgb[size_t(i) * 3 + 0] = interp(tf.color, x, 1);
    out.rgb[size_t(i) * 3 + 1] = interp(tf.color, x, 2);
    out.rgb[size_t(i) * 3 + 2] = interp(tf.color, x, 3);
    out.opacity[size_t(i)] = interp(tf.opacity, x, 1);
  }
  return out;
}
} // namespace mcvol
