// SPDX-License-Identifier: BSD-3-Clause
#include "mcvol/Scene.h"

#include "mcvol/Acceleration.h"
#include "mcvol/Renderer.h"

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <limits>
#include <stdexcept>
#include <string>

namespace mcvol
{
namespace
{
double secondsSince(std::chrono::steady_clock::time_point t0)
{
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
}

std::string channelText(int n)
{
  return "channel " + std::to_string(n);
}

/// A voxel as the per-ray code reads it (fetchVoxel): float, with a float64
/// channel's offset taken off first.
template <typename T>
float asSample(T v, double)
{
  return float(v);
}
float asSample(double v, double offset)
{
  return float(v - offset);
}

template <typename T>
void rangeOf(const T* data, int64_t stride, double offset, const int dims[3], const int lo[3], const int hi[3],
  float& mn, float& mx)
{
  for (int k = lo[2]; k <= hi[2]; ++k)
  {
    for (int j = lo[1]; j <= hi[1]; ++j)
    {
      const int64_t row = (int64_t(k) * dims[1] + j) * dims[0];
      for (int i = lo[0]; i <= hi[0]; ++i)
      {
        const float v = asSample(data[(row + i) * stride], offset);
        if (v == v) // NaN voxels are transparent: they do not widen the range
        {
          mn = v < mn ? v : mn;
          mx = v > mx ? v : mx;
        }
      }
    }
  }
}
} // namespace

float opacityToExtinction(float opacity, float unitDistance)
{
  const float a = std::min(std::max(opacity, 0.f), kMaxOpacity);
  return float(-std::log1p(-double(a)) / double(unitDistance));
}

void Accumulator::resize(int width, int height)
{
  if (width < 0 || height < 0)
  {
    throw std::invalid_argument("mcvol: negative image size");
  }
  if (width != this->Width || height != this->Height)
  {
    this->Width = width;
    this->Height = height;
    this->RGBA.assign(size_t(width) * size_t(height) * 4, 0.f);
    this->Samples = 0;
    this->Pending = false;
  }
}

void Accumulator::reset()
{
  std::fill(this->RGBA.begin(), this->RGBA.end(), 0.f);
  this->Samples = 0;
  this->Pending = false;
}

namespace
{
uint64_t nextObjectId()
{
  static std::atomic<uint64_t> counter{ 0 };
  return ++counter;
}
} // namespace

ObjectId::ObjectId()
  : value(nextObjectId())
{
}

ObjectId::ObjectId(const ObjectId&)
  : value(nextObjectId())
{
}

ObjectId& ObjectId::operator=(const ObjectId&)
{
  this->value = nextObjectId();
  return *this;
}

Scene::Scene()
{
  this->MixWeights.fill(0.f);
}

void Scene::setVolume(const int dims[3], int numChannels, const ChannelSource* channels)
{
  for (int a = 0; a < 3; ++a)
  {
    if (dims[a] < 1)
    {
      throw std::invalid_argument("mcvol: the volume has an empty extent (dimension " + std::to_string(a) + " is " +
        std::to_string(dims[a]) + ")");
    }
  }
  if (numChannels < 1 || numChannels > kMaxChannels)
  {
    throw std::invalid_argument("mcvol: " + std::to_string(numChannels) + " channels given; 1 to " +
      std::to_string(kMaxChannels) + " are supported");
  }
  for (int n = 0; n < numChannels; ++n)
  {
    if (!channels[n].data)
    {
      throw std::invalid_argument("mcvol: " + channelText(n) + " has no data");
    }
    if (channels[n].stride < 1)
    {
      throw std::invalid_argument("mcvol: " + channelText(n) + " has a stride below 1");
    }
    if (!std::isfinite(channels[n].offset) || (channels[n].offset != 0.0 && channels[n].type != ScalarType::Float64))
    {
      throw std::invalid_argument("mcvol: " + channelText(n) +
        " has an offset; only finite offsets of float64 channels "
        "are supported");
    }
  }
  const bool sameShape = numChannels == this->NumChannels && dims[0] == this->Dims[0] && dims[1] == this->Dims[1] &&
    dims[2] == this->Dims[2];
  std::copy(dims, dims + 3, this->Dims);
  if (!sameShape)
  {
    this->HasTF.fill(false);
  }
  for (int n = 0; n < numChannels; ++n)
  {
    if (channels[n].offset != this->Channels[size_t(n)].offset)
    {
      this->HasTF[size_t(n)] = false; // its table was placed relative to the old offset
    }
  }
  this->NumChannels = numChannels;
  std::copy(channels, channels + numChannels, this->Channels.begin());
  this->MacrocellsDirty = true;
  ++this->ContentVersion;
}

void Scene::dataModified()
{
  this->MacrocellsDirty = true;
  ++this->ContentVersion;
}

void Scene::setHostAcceleration(bool on)
{
  if (on != this->HostAcceleration)
  {
    this->HostAcceleration = on;
    this->MacrocellsDirty = true;
    if (!on)
    {
      // Release the host copies.
      std::vector<float>().swap(this->Ranges);
      std::vector<float>().swap(this->Majorants);
    }
  }
}

void Scene::setTransferFunction(int channel, const TransferFunctionDesc& tf)
{
  if (channel < 0 || channel >= this->NumChannels)
  {
    throw std::invalid_argument("mcvol: transfer function for " + channelText(channel) + ", but the volume has " +
      std::to_string(this->NumChannels) + " channels");
  }
  const size_t K = tf.opacity.size();
  if (K < 2 || tf.rgb.size() != 3 * K)
  {
    throw std::invalid_argument("mcvol: the transfer function of " + channelText(channel) +
      " needs at least 2 opacity entries and 3 colour values per entry");
  }
  if (!(tf.unitDistance > 0.f) || !std::isfinite(tf.unitDistance))
  {
    throw std::invalid_argument(
      "mcvol: the opacity unit distance of " + channelText(channel) + " must be a positive finite number");
  }
  if (!std::isfinite(tf.scalarMin) || !std::isfinite(tf.scalarMax) || !(tf.scalarMax >= tf.scalarMin) ||
    std::fabs(tf.scalarMin) > 3e38 || std::fabs(tf.scalarMax) > 3e38)
  {
    throw std::invalid_argument(
      "mcvol: the scalar range of " + channelText(channel) + "'s transfer function is invalid");
  }
  for (size_t i = 0; i < K; ++i)
  {
    if (!std::isfinite(tf.opacity[i]) || !std::isfinite(tf.rgb[3 * i]) || !std::isfinite(tf.rgb[3 * i + 1]) ||
      !std::isfinite(tf.rgb[3 * i + 2]))
    {
      throw std::invalid_argument(
        "mcvol: the transfer function of " + channelText(channel) + " has a non-finite entry");
    }
  }
  const int Kcur = this->View.tables.size;
  if (int(K) != Kcur)
  {
    for (int n = 0; n < this->NumChannels; ++n)
    {
      if (n != channel && this->HasTF[n])
      {
        throw std::invalid_argument("mcvol: all channels' transfer-function tables must have the same size (" +
          std::to_string(Kcur) + " entries, " + channelText(channel) + " has " + std::to_string(K) + ")");
      }
    }
    this->Tables.assign(size_t(kMaxChannels) * K * 4, 0.f);
    this->View.tables.size = int(K);
  }
  float* t = this->Tables.data() + size_t(channel) * K * 4;
  for (size_t i = 0; i < K; ++i)
  {
    t[4 * i + 0] = std::min(std::max(tf.rgb[3 * i + 0], 0.f), 1.f);
    t[4 * i + 1] = std::min(std::max(tf.rgb[3 * i + 1], 0.f), 1.f);
    t[4 * i + 2] = std::min(std::max(tf.rgb[3 * i + 2], 0.f), 1.f);
    t[4 * i + 3] = opacityToExtinction(tf.opacity[i], tf.unitDistance);
  }
  // The table's range in the units the per-ray code sees (offset taken off),
  // with a width that keeps (K - 1) / width a finite float: a constant
  // channel, or one whose range is narrower than float resolution, would
  // otherwise get an infinite scale and NaN texel coordinates.
  const double lo = tf.scalarMin - this->Channels[size_t(channel)].offset;
  double width = tf.scalarMax - tf.scalarMin;
  const double minWidth = std::max(1e-30, 1e-6 * std::fabs(lo));
  if (!(width >= minWidth))
  {
    width = minWidth;
  }
  this->View.tables.scalarMin[channel] = float(lo);
  this->View.tables.scale[channel] = float(double(K - 1) / width);
  this->HasTF[channel] = true;
  this->MajorantDirty[channel] = true;
  ++this->ChannelTableVersion[size_t(channel)];
  ++this->TableVersion;
}

void Scene::setMacrocellSize(int voxels)
{
  if (voxels < 1)
  {
    throw std::invalid_argument("mcvol: the macrocell size must be at least 1 voxel");
  }
  if (voxels != this->MacrocellSize)
  {
    this->MacrocellSize = voxels;
    this->MacrocellsDirty = true;
  }
}

void Scene::setBlendMode(BlendMode mode)
{
  this->View.blend.mode = mode;
}

void Scene::setMixWeights(const float* weights, int count)
{
  if (count < 0 || count > kMaxChannels)
  {
    throw std::invalid_argument("mcvol: too many mix weights");
  }
  this->MixWeights.fill(0.f);
  for (int i = 0; i < count; ++i)
  {
    if (!(weights[i] >= 0.f) || !std::isfinite(weights[i]))
    {
      throw std::invalid_argument("mcvol: mix weight " + std::to_string(i) + " must be a finite number >= 0");
    }
    this->MixWeights[i] = weights[i];
  }
}

void Scene::setLighting(const LightingDesc& d)
{
  LightingView& L = this->View.lighting;
  if (d.lights.size() > size_t(kMaxLights))
  {
    throw std::invalid_argument("mcvol: at most " + std::to_string(kMaxLights) + " lights are supported");
  }
  auto finite3 = [](const double* v) { return std::isfinite(v[0]) && std::isfinite(v[1]) && std::isfinite(v[2]); };
  bool anyLight = false;
  for (size_t l = 0; l < d.lights.size(); ++l)
  {
    const LightDesc& ld = d.lights[l];
    const double len =
      std::sqrt(ld.vector[0] * ld.vector[0] + ld.vector[1] * ld.vector[1] + ld.vector[2] * ld.vector[2]);
    if (!finite3(ld.vector) || !finite3(ld.color) || !std::isfinite(ld.intensity) || ld.intensity < 0 ||
      ld.color[0] < 0 || ld.color[1] < 0 || ld.color[2] < 0 || (!ld.point && !(len > 0)))
    {
      throw std::invalid_argument("mcvol: light " + std::to_string(l) +
        " needs a finite non-zero direction (or a position), a colour >= 0 and an intensity >= 0");
    }
    L.lightType[l] = ld.point ? 1 : 0;
    const double inv = ld.point ? 1.0 : 1.0 / len;
    L.lightVector[l] = Vec3f(float(ld.vector[0] * inv), float(ld.vector[1] * inv), float(ld.vector[2] * inv));
    L.lightRadiance[l] =
      Vec3f(float(ld.color[0] * ld.intensity), float(ld.color[1] * ld.intensity), float(ld.color[2] * ld.intensity));
    anyLight = anyLight || ld.intensity > 0;
  }
  if (!finite3(d.ambient) || d.ambient[0] < 0 || d.ambient[1] < 0 || d.ambient[2] < 0)
  {
    throw std::invalid_argument("mcvol: the ambient radiance must be finite and >= 0");
  }
  if (d.maxDepth < 1 || d.maxDepth > 1024)
  {
    throw std::invalid_argument("mcvol: the maximum scattering depth must be in [1, 1024]");
  }
  if (!(d.shininess >= 0.f) || !std::isfinite(d.shininess))
  {
    throw std::invalid_argument("mcvol: the shininess must be a finite number >= 0");
  }
  for (int n = 0; n < kMaxChannels; ++n)
  {
    const float a = size_t(n) < d.albedo.size() ? d.albedo[size_t(n)] : 0.5f;
    const float g = size_t(n) < d.anisotropy.size() ? d.anisotropy[size_t(n)] : 0.f;
    if (!(a >= 0.f && a <= 1.f) || !(g > -1.f && g < 1.f))
    {
      throw std::invalid_argument(
        "mcvol: channel " + std::to_string(n) + " needs an albedo in [0, 1] and an anisotropy in (-1, 1)");
    }
    L.albedo[n] = a;
    L.anisotropy[n] = g;
  }
  L.numLights = int(d.lights.size());
  L.ambient = Vec3f(float(d.ambient[0]), float(d.ambient[1]), float(d.ambient[2]));
  L.shadows = d.shadows;
  L.shadowEstimator = d.deltaShadows ? 1 : 0;
  L.maxDepth = d.maxDepth;
  L.gradientShading = d.gradientShading;
  L.shininess = d.shininess;
  L.enabled = anyLight || d.ambient[0] > 0 || d.ambient[1] > 0 || d.ambient[2] > 0;
}

MemoryStats Scene::memory() const
{
  MemoryStats m;
  const size_t voxels = size_t(this->Dims[0]) * this->Dims[1] * this->Dims[2];
  for (int n = 0; n < this->NumChannels; ++n)
  {
    m.dataBytes += voxels * size_t(scalarTypeSize(this->Channels[n].type));
  }
  m.macrocellBytes = this->Ranges.size() * sizeof(float);
  m.majorantBytes = this->Majorants.size() * sizeof(float);
  m.tableBytes = size_t(this->NumChannels) * size_t(this->View.tables.size) * 4 * sizeof(float);
  return m;
}

void Scene::layoutGrid()
{
  GridView& g = this->View.grid;
  VolumeView& v = this->View.volume;
  for (int a = 0; a < 3; ++a)
  {
    v.dims[a] = this->Dims[a];
    if (this->Dims[a] == 1)
    {
      // One voxel along this axis: give it one spacing of thickness so a
      // single slice (or a single voxel) is visible rather than zero-width.
      v.boxLo[a] = -0.5f;
      v.boxHi[a] = 0.5f;
      g.dims[a] = 1;
      g.lo[a] = -0.5f;
      g.cellSize[a] = 1.f;
    }
    else
    {
      v.boxLo[a] = 0.f;
      v.boxHi[a] = float(this->Dims[a] - 1);
      const int cells = (this->Dims[a] - 1 + this->MacrocellSize - 1) / this->MacrocellSize;
      g.dims[a] = std::max(1, cells);
      g.lo[a] = 0.f;
      g.cellSize[a] = float(this->MacrocellSize);
    }
    g.invCellSize[a] = 1.f / g.cellSize[a];
  }
  v.numChannels = this->NumChannels;
  for (int n = 0; n < this->NumChannels; ++n)
  {
    v.channels[n].data = this->Channels[n].data;
    v.channels[n].stride = this->Channels[n].stride;
    v.channels[n].offset = this->Channels[n].offset;
    v.channels[n].type = this->Channels[n].type;
  }
  g.numChannels = this->NumChannels;
}

void Scene::rebuildMacrocells()
{
  const auto t0 = std::chrono::steady_clock::now();
  this->layoutGrid();
  const GridView& g = this->View.grid;
  const int N = this->NumChannels;
  const int64_t cells = int64_t(g.dims[0]) * g.dims[1] * g.dims[2];
  this->Ranges.assign(size_t(cells) * N * 2, 0.f);
  const int M = this->MacrocellSize;
  const int* D = this->Dims;
  float* ranges = this->Ranges.data();
  const ChannelSource* ch = this->Channels.data();
  const int gd0 = g.dims[0], gd1 = g.dims[1];
#pragma omp parallel for schedule(dynamic, 4)
  for (int64_t c = 0; c < cells; ++c)
  {
    const int cell[3] = { int(c % gd0), int((c / gd0) % gd1), int(c / (int64_t(gd0) * gd1)) };
    int lo[3];
    int hi[3];
    cellVoxelBounds(D, M, cell, lo, hi);
    for (int n = 0; n < N; ++n)
    {
      float mn = std::numeric_limits<float>::infinity();
      float mx = -std::numeric_limits<float>::infinity();
      switch (ch[n].type)
      {
        case ScalarType::UInt8:
          rangeOf(static_cast<const uint8_t*>(ch[n].data), ch[n].stride, ch[n].offset, D, lo, hi, mn, mx);
          break;
        case ScalarType::Int16:
          rangeOf(static_cast<const int16_t*>(ch[n].data), ch[n].stride, ch[n].offset, D, lo, hi, mn, mx);
          break;
        case ScalarType::UInt16:
          rangeOf(static_cast<const uint16_t*>(ch[n].data), ch[n].stride, ch[n].offset, D, lo, hi, mn, mx);
          break;
        case ScalarType::Float32:
          rangeOf(static_cast<const float*>(ch[n].data), ch[n].stride, ch[n].offset, D, lo, hi, mn, mx);
          break;
        case ScalarType::Float64:
          rangeOf(static_cast<const double*>(ch[n].data), ch[n].stride, ch[n].offset, D, lo, hi, mn, mx);
          break;
      }
      ranges[(c * N + n) * 2 + 0] = mn;
      ranges[(c * N + n) * 2 + 1] = mx;
    }
  }
  this->Majorants.assign(size_t(cells) * N, 0.f);
  this->LastMacrocellSeconds = secondsSince(t0);
  ++this->DataVersion;
}

void Scene::rebuildMajorants(int channel)
{
  const GridView& g = this->View.grid;
  const TableView& tv = this->View.tables;
  const int N = this->NumChannels;
  const int K = tv.size;
  const int64_t cells = int64_t(g.dims[0]) * g.dims[1] * g.dims[2];
  const float* table = this->Tables.data() + size_t(channel) * K * 4;
  const float* ranges = this->Ranges.data();
  float* maj = this->Majorants.data();
  // Range-maximum queries over the table's extinctions in O(1) per cell (a
  // sparse table): a cell's scalar range can cover most of the table, so a
  // per-cell loop over texels would make a rebuild cost cells x K.
  std::vector<float> sparse(size_t(sparseLevels(K)) * size_t(K), 0.f);
  buildSparseTable(table, K, sparse.data());
  const float* sp = sparse.data();
  // Threads only pay off on large grids; a small rebuild is sub-millisecond
  // on one core and would otherwise wait for busy threads to wake.
#pragma omp parallel for schedule(static) if (cells > 100000)
  for (int64_t c = 0; c < cells; ++c)
  {
    maj[c * N + channel] =
      cellMajorant(tv, channel, ranges[(c * N + channel) * 2 + 0], ranges[(c * N + channel) * 2 + 1], sp);
  }
}

void Scene::refreshView(bool majorantsChanged)
{
  this->View.tables.texels = this->Tables.data();
  this->View.grid.majorants = this->Majorants.data();
  // Mix weights normalised to sum 1 (Eq. 10); none or all zero: equal.
  float sum = 0.f;
  for (int n = 0; n < this->NumChannels; ++n)
  {
    sum += this->MixWeights[n];
  }
  for (int n = 0; n < kMaxChannels; ++n)
  {
    this->View.blend.mixWeights[n] =
      n < this->NumChannels ? (sum > 0.f ? this->MixWeights[n] / sum : 1.f / float(this->NumChannels)) : 0.f;
  }
  if (!majorantsChanged)
  {
    return;
  }
  const int64_t cells = int64_t(this->View.grid.dims[0]) * this->View.grid.dims[1] * this->View.grid.dims[2];
  this->View.numActive = 0;
  for (int n = 0; n < this->NumChannels; ++n)
  {
    bool any = false;
    for (int64_t c = 0; c < cells && !any; ++c)
    {
      any = this->Majorants[size_t(c) * this->NumChannels + n] > 0.f;
    }
    if (any)
    {
      this->View.active[this->View.numActive++] = n;
    }
  }
}

bool Scene::update()
{
  if (this->NumChannels == 0)
  {
    throw std::invalid_argument("mcvol: no volume was given");
  }
  for (int n = 0; n < this->NumChannels; ++n)
  {
    if (!this->HasTF[n])
    {
      throw std::invalid_argument("mcvol: " + channelText(n) + " has no transfer function (" +
        std::to_string(this->NumChannels) + " channels need " + std::to_string(this->NumChannels) + ")");
    }
  }
  bool changed = false;
  if (!this->HostAcceleration)
  {
    // Tables only; the backend builds ranges and majorants from the versions.
    if (this->MacrocellsDirty)
    {
      this->layoutGrid();
      this->MacrocellsDirty = false;
      ++this->DataVersion;
      changed = true;
    }
    for (int n = 0; n < this->NumChannels; ++n)
    {
      changed = changed || this->MajorantDirty[n];
      this->MajorantDirty[n] = false;
    }
    this->refreshView(false);
    this->View.grid.majorants = nullptr;
    this->View.numActive = this->NumChannels;
    for (int n = 0; n < this->NumChannels; ++n)
    {
      this->View.active[n] = n;
    }
    return changed;
  }
  if (this->MacrocellsDirty)
  {
    this->rebuildMacrocells();
    this->MacrocellsDirty = false;
    for (int n = 0; n < this->NumChannels; ++n)
    {
      this->MajorantDirty[n] = true;
    }
    changed = true;
  }
  const auto t0 = std::chrono::steady_clock::now();
  int rebuilt = 0;
  for (int n = 0; n < this->NumChannels; ++n)
  {
    if (this->MajorantDirty[n])
    {
      this->rebuildMajorants(n);
      this->MajorantDirty[n] = false;
      ++rebuilt;
    }
  }
  if (rebuilt > 0)
  {
    this->LastMajorantSeconds = secondsSince(t0);
    this->LastMajorantChannels = rebuilt;
    ++this->TableVersion;
    changed = true;
  }
  this->refreshView(changed);
  return changed;
}
} // namespace mcvol
