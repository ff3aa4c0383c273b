// SPDX-License-Identifier: BSD-3-Clause
//
// CUDARenderer::classifyLevel: a level of the extinction-based pyramid
// (Kraus and Buerger, extinction-based downsampling) built on the device from
// scalar channels, so that a transfer-function edit at a coarse level
// rebuilds it at interactive rates. The arithmetic is the host build's (Pyramid.cxx: classifyRangeOf,
// SliceStage) operation for operation, with explicitly rounded intrinsics so
// that nvcc contracts nothing into a fused multiply-add:
// - classification: texel coordinate (s - scalarMin) * scale in double,
//   clamped to [0, K - 1], texel i = min(floor, K - 2), f = float(x - i);
//   sigma = a.w + f (b.w - a.w) and sigma (a.c + f (b.c - a.c)) in float;
//   a NaN scalar gives (0, 0, 0, 0); inputs added in order in float;
// - filtering: per axis (x, y, z in that order) the taps in order,
//   acc += w[k] * double(x) in double, stored as float; an axis of 1 is
//   copied; taps outside the grid clamped to the edge voxel.
// Passes: classify + x (one kernel: the classified level-0 voxels are never
// stored), y, z; a level L > 1 repeats x, y, z on the float4 level.
#include "CUDAInternal.h"

#include "mcvol/Pyramid.h"

#include <algorithm>
#include <chrono>
#include <memory>
#include <stdexcept>
#include <string>
#include <vector>

namespace mcvol
{
namespace
{
constexpr int kThreads = 256;

/// One input as the kernels read it.
struct DeviceClassifyInput
{
  const void* data = nullptr;
  int type = 0; ///< ScalarType
  long long stride = 1;
  double scalarMin = 0.0;
  double scale = 0.0;
  int K = 0;
  const float4* texels = nullptr; ///< K texels (r, g, b, extinction)
};

struct DeviceTaps
{
  int count = 0;
  int first = 0;
  double w[4] = { 0, 0, 0, 0 };
};

__device__ __forceinline__ double loadScalar(const DeviceClassifyInput& in, long long v)
{
  const long long e = v * in.stride;
  switch (in.type)
  {
    case int(ScalarType::UInt8):
      return double(static_cast<const uint8_t*>(in.data)[e]);
    case int(ScalarType::Int16):
      return double(static_cast<const int16_t*>(in.data)[e]);
    case int(ScalarType::UInt16):
      return double(static_cast<const uint16_t*>(in.data)[e]);
    case int(ScalarType::Float64):
      return static_cast<const double*>(in.data)[e];
    default:
      return double(static_cast<const float*>(in.data)[e]);
  }
}

/// Level-0 voxel v classified through every input and summed (the host's
/// classifyRangeOf with accumulate for every input after the first).
__device__ float4 classifyVoxel(const DeviceClassifyInput* __restrict__ inputs, int numInputs, long long v)
{
  float4 y = make_float4(0.f, 0.f, 0.f, 0.f);
  for (int n = 0; n < numInputs; ++n)
  {
    const DeviceClassifyInput& in = inputs[n];
    const double s = loadScalar(in, v);
    float4 r = make_float4(0.f, 0.f, 0.f, 0.f);
    double x = __dmul_rn(__dsub_rn(s, in.scalarMin), in.scale);
    if (x == x)
    {
      const double last = double(in.K - 1);
      x = x < 0.0 ? 0.0 : (x > last ? last : x); // std::min(std::max(x, 0), K - 1)
      int i = int(x);
      i = i > in.K - 2 ? in.K - 2 : i;
      const float f = __double2float_rn(__dsub_rn(x, double(i)));
      const float4 a = in.texels[i];
      const float4 b = in.texels[i + 1];
      const float sigma = __fadd_rn(a.w, __fmul_rn(f, __fsub_rn(b.w, a.w)));
      r.x = sigma;
      r.y = __fmul_rn(sigma, __fadd_rn(a.x, __fmul_rn(f, __fsub_rn(b.x, a.x))));
      r.z = __fmul_rn(sigma, __fadd_rn(a.y, __fmul_rn(f, __fsub_rn(b.y, a.y))));
      r.w = __fmul_rn(sigma, __fadd_rn(a.z, __fmul_rn(f, __fsub_rn(b.z, a.z))));
    }
    if (n == 0)
    {
      y = r;
    }
    else
    {
      y.x = __fadd_rn(y.x, r.x);
      y.y = __fadd_rn(y.y, r.y);
      y.z = __fadd_rn(y.z, r.z);
      y.w = __fadd_rn(y.w, r.w);
    }
  }
  return y;
}

struct Acc4
{
  double v[4] = { 0, 0, 0, 0 };
  __device__ void add(double w, const float4& x)
  {
    v[0] = __dadd_rn(v[0], __dmul_rn(w, double(x.x)));
    v[1] = __dadd_rn(v[1], __dmul_rn(w, double(x.y)));
    v[2] = __dadd_rn(v[2], __dmul_rn(w, double(x.z)));
    v[3] = __dadd_rn(v[3], __dmul_rn(w, double(x.w)));
  }
  __device__ float4 get() const
  {
    return make_float4(
      __double2float_rn(v[0]), __double2float_rn(v[1]), __double2float_rn(v[2]), __double2float_rn(v[3]));
  }
};

__device__ __forceinline__ int clampTap(int j, int n)
{
  return j < 0 ? 0 : (j > n - 1 ? n - 1 : j);
}

/// Level 0 classified and filtered along x: out has (mx, ny, nz) voxels,
/// mx = ceil(nx / 2), or nx = 1 (classified, not filtered).
__global__ void classifyFilterXKernel(const DeviceClassifyInput* __restrict__ inputs, int numInputs, int nx, int ny,
  int nz, int mx, DeviceTaps taps, float4* __restrict__ out)
{
  const long long total = (long long)mx * ny * nz;
  for (long long o = (long long)blockIdx.x * blockDim.x + threadIdx.x; o < total;
       o += (long long)gridDim.x * blockDim.x)
  {
    const int i = int(o % mx);
    const long long row = o / mx; // j + ny * z
    const long long base = row * nx;
    if (nx == 1)
    {
      out[o] = classifyVoxel(inputs, numInputs, base);
      continue;
    }
    Acc4 acc;
    for (int k = 0; k < taps.count; ++k)
    {
      const int q = clampTap(2 * i + taps.first + k, nx);
      acc.add(taps.w[k], classifyVoxel(inputs, numInputs, base + q));
    }
    out[o] = acc.get();
  }
}

/// One separable pass along `axis` (> 1 voxel) of a float4 volume of dims
/// (d0, d1, d2): that axis halved (ceil) into `out`.
__global__ void filterAxisKernel(
  const float4* __restrict__ in, int d0, int d1, int d2, int axis, DeviceTaps taps, float4* __restrict__ out)
{
  const int n = axis == 0 ? d0 : (axis == 1 ? d1 : d2);
  const int m = (n + 1) / 2;
  const int o0 = axis == 0 ? m : d0;
  const int o1 = axis == 1 ? m : d1;
  const int o2 = axis == 2 ? m : d2;
  const long long total = (long long)o0 * o1 * o2;
  const long long stride = axis == 0 ? 1 : (axis == 1 ? (long long)d0 : (long long)d0 * d1);
  for (long long o = (long long)blockIdx.x * blockDim.x + threadIdx.x; o < total;
       o += (long long)gridDim.x * blockDim.x)
  {
    int idx[3];
    idx[0] = int(o % o0);
    idx[1] = int((o / o0) % o1);
    idx[2] = int(o / ((long long)o0 * o1));
    const int c = idx[axis];
    idx[axis] = 0;
    const long long base = idx[0] + (long long)d0 * (idx[1] + (long long)d1 * idx[2]);
    Acc4 acc;
    for (int k = 0; k < taps.count; ++k)
    {
      const int q = clampTap(2 * c + taps.first + k, n);
      acc.add(taps.w[k], in[base + q * stride]);
    }
    out[o] = acc.get();
  }
}

int blocksFor(long long total)
{
  const long long b = (total + kThreads - 1) / kThreads;
  return int(std::max(1ll, std::min(b, 1ll << 20))); // grid-stride loops cover the rest
}

/// Device memory held now and at the peak by one build.
struct DeviceMeter
{
  size_t now = 0;
  size_t peak = 0;
  void add(size_t b)
  {
    this->now += b;
    this->peak = std::max(this->peak, this->now);
  }
  void sub(size_t b) { this->now -= std::min(b, this->now); }
};

/// A float4 device volume of `voxels` voxels, counted by `meter`.
struct Volume4
{
  DeviceBuffer<float4> buf;
  int dims[3] = { 1, 1, 1 };
  DeviceMeter* meter = nullptr;
  void allocate(const int d[3], DeviceMeter& m)
  {
    std::copy(d, d + 3, this->dims);
    this->meter = &m;
    this->buf.resize(size_t(d[0]) * size_t(d[1]) * size_t(d[2]));
    m.add(this->buf.bytes());
  }
  void release()
  {
    if (this->meter)
    {
      this->meter->sub(this->buf.bytes());
    }
    this->buf.release();
  }
};

/// Moves `from` into `to` (the buffer's ownership; no copy).
void moveVolume(Volume4& from, Volume4& to)
{
  to.release();
  std::swap(to.buf.ptr, from.buf.ptr);
  std::swap(to.buf.count, from.buf.count);
  std::copy(from.dims, from.dims + 3, to.dims);
  to.meter = from.meter;
  from.meter = nullptr;
}

/// One level step on `v` along the axes from `first` to z, each one halved
/// unless it has one voxel (then the data are the level's along it).
void filterAxes(Volume4& v, int first, const DeviceTaps& taps, DeviceMeter& meter)
{
  for (int axis = first; axis < 3; ++axis)
  {
    if (v.dims[axis] == 1)
    {
      continue;
    }
    int d[3] = { v.dims[0], v.dims[1], v.dims[2] };
    d[axis] = (d[axis] + 1) / 2;
    Volume4 next;
    next.allocate(d, meter);
    const long long total = (long long)d[0] * d[1] * d[2];
    filterAxisKernel<<<blocksFor(total), kThreads>>>(
      v.buf.ptr, v.dims[0], v.dims[1], v.dims[2], axis, taps, next.buf.ptr);
    MCVOL_CUDA(cudaGetLastError());
    v.release();
    moveVolume(next, v);
  }
}

/// The elements of `src` a device copy holds: the whole strided array from
/// the first voxel's component to the last's.
size_t copiedElements(const ChannelSource& src, size_t voxels)
{
  return (voxels - 1) * size_t(src.stride) + 1;
}

/// The kept copy of `src` under key `version` (nonzero), or null.
const LevelInput* findKept(
  const std::vector<std::unique_ptr<LevelInput>>& pool, const ChannelSource& src, uint64_t version, size_t voxels)
{
  for (const auto& li : pool)
  {
    if (version != 0 && li->host == src.data && li->type == src.type && li->stride == src.stride &&
      li->elements == copiedElements(src, voxels) && li->version == version)
    {
      return li.get();
    }
  }
  return nullptr;
}

bool isUsed(const std::vector<const LevelInput*>& used, const LevelInput* li)
{
  return std::find(used.begin(), used.end(), li) != used.end();
}

/**
 * Frees the kept copies this build cannot use: those of the same host
 * arrays as the inputs under another key (older data), then the least
 * recently used others while the kept copies and the versioned inputs still
 * to copy would exceed `cap` bytes. `used`: the kept copies the inputs take.
 */
void evictLevelInputs(std::vector<std::unique_ptr<LevelInput>>& pool, const std::vector<const LevelInput*>& used,
  const ClassifyInput* inputs, int numInputs, size_t voxels, size_t cap)
{
  size_t needed = 0;
  for (int n = 0; n < numInputs; ++n)
  {
    if (!used[size_t(n)] && inputs[n].dataVersion != 0)
    {
      needed += copiedElements(inputs[n].source, voxels) * size_t(scalarTypeSize(inputs[n].source.type));
    }
  }
  auto stale = [&](const LevelInput& li)
  {
    for (int n = 0; n < numInputs; ++n)
    {
      if (li.host == inputs[n].source.data)
      {
        return true;
      }
    }
    return false;
  };
  size_t keptBytes = 0;
  for (auto it = pool.begin(); it != pool.end();)
  {
    if (!isUsed(used, it->get()) && stale(**it))
    {
      it = pool.erase(it);
    }
    else
    {
      keptBytes += (*it)->data.bytes();
      ++it;
    }
  }
  for (auto it = pool.begin(); it != pool.end() && keptBytes + needed > cap;)
  {
    if (!isUsed(used, it->get()))
    {
      keptBytes -= (*it)->data.bytes();
      it = pool.erase(it); // the front is the least recently used
    }
    else
    {
      ++it;
    }
  }
}

/**
 * The inputs on the device, one copy per input (null entries of `used`
 * filled): a kept copy whose key matches, else a new copy of the whole
 * strided array, kept in `pool` when the input has a key
 * (ClassifyInput::dataVersion nonzero) and in `transient` for this build
 * only when not. The copies this build uses move to the back of `pool` (most
 * recently used).
 */
void copyLevelInputs(std::vector<std::unique_ptr<LevelInput>>& pool,
  std::vector<std::unique_ptr<LevelInput>>& transient, std::vector<const LevelInput*>& used,
  const ClassifyInput* inputs, int numInputs, size_t voxels, CudaUpdateCounters& updates)
{
  for (int n = 0; n < numInputs; ++n)
  {
    const ChannelSource& src = inputs[n].source;
    const uint64_t version = inputs[n].dataVersion;
    if (used[size_t(n)] ||
      (used[size_t(n)] = findKept(pool, src, version, voxels)) != nullptr) // or copied for an earlier input
    {
      continue;
    }
    auto li = std::make_unique<LevelInput>();
    li->host = src.data;
    li->type = src.type;
    li->stride = src.stride;
    li->elements = copiedElements(src, voxels);
    li->version = version;
    const size_t bytes = li->elements * size_t(scalarTypeSize(src.type));
    li->data.resize(bytes);
    MCVOL_CUDA(cudaMemcpy(li->data.ptr, src.data, bytes, cudaMemcpyHostToDevice));
    ++updates.levelInputUploads;
    used[size_t(n)] = li.get();
    (version != 0 ? pool : transient).push_back(std::move(li));
  }
  std::stable_partition(
    pool.begin(), pool.end(), [&](const std::unique_ptr<LevelInput>& li) { return !isUsed(used, li.get()); });
}

/// The classification tables (`texels`, all inputs' in order) and the
/// kernels' input descriptors on the device.
void uploadClassifyInputs(const std::vector<ClassificationTable>& tables, const ClassifyInput* inputs, int numInputs,
  const std::vector<const LevelInput*>& used, DeviceBuffer<float4>& texels,
  DeviceBuffer<DeviceClassifyInput>& descriptors)
{
  size_t texelCount = 0;
  for (const ClassificationTable& t : tables)
  {
    texelCount += t.K;
  }
  texels.resize(texelCount);
  std::vector<DeviceClassifyInput> desc(static_cast<size_t>(numInputs));
  std::vector<float> all;
  all.reserve(texelCount * 4);
  size_t at = 0;
  for (int n = 0; n < numInputs; ++n)
  {
    const ClassificationTable& t = tables[size_t(n)];
    all.insert(all.end(), t.texels.begin(), t.texels.end());
    DeviceClassifyInput& d = desc[size_t(n)];
    d.data = used[size_t(n)]->data.ptr;
    d.type = int(inputs[n].source.type);
    d.stride = (long long)inputs[n].source.stride;
    d.scalarMin = t.scalarMin;
    d.scale = t.scale;
    d.K = int(t.K);
    d.texels = texels.ptr + at;
    at += t.K;
  }
  MCVOL_CUDA(cudaMemcpy(texels.ptr, all.data(), all.size() * sizeof(float), cudaMemcpyHostToDevice));
  descriptors.resize(desc.size());
  MCVOL_CUDA(
    cudaMemcpy(descriptors.ptr, desc.data(), desc.size() * sizeof(DeviceClassifyInput), cudaMemcpyHostToDevice));
}

/// Level `level` of the classified inputs: level 1 from the classification
/// fused with the x filter, then y and z; each further level the float4
/// level downsampled again. The transient input copies are freed once the
/// classification no longer needs them.
void filterLevel(Volume4& v, const DeviceClassifyInput* descriptors, int numInputs, const int dims[3], int level,
  const DeviceTaps& taps, std::vector<std::unique_ptr<LevelInput>>& transient, DeviceMeter& meter)
{
  {
    const int mx = dims[0] > 1 ? (dims[0] + 1) / 2 : 1;
    const int d[3] = { mx, dims[1], dims[2] };
    v.allocate(d, meter);
    const long long total = (long long)d[0] * d[1] * d[2];
    classifyFilterXKernel<<<blocksFor(total), kThreads>>>(
      descriptors, numInputs, dims[0], dims[1], dims[2], mx, taps, v.buf.ptr);
    MCVOL_CUDA(cudaGetLastError());
  }
  // cudaFree waits for the kernel.
  for (auto& li : transient)
  {
    meter.sub(li->data.bytes());
  }
  transient.clear();
  filterAxes(v, 1, taps, meter);
  for (int l = 2; l <= level; ++l)
  {
    filterAxes(v, 0, taps, meter);
  }
}
} // namespace

void CUDARenderer::releaseLevelInputs()
{
  MCVOL_CUDA(cudaSetDevice(this->In->Device));
  this->In->LevelInputs.clear();
}

PyramidLevel CUDARenderer::classifyLevel(const ClassifyInput* inputs, int numInputs, const int dims[3],
  const double spacing[3], const double origin[3], int level, DownsampleFilter filter, size_t* peakWorkBytes)
{
  const auto t0 = std::chrono::steady_clock::now();
  Internal& in = *this->In;
  // The host build's checks, in its order: inputs, tables, geometry, level.
  const std::vector<ClassificationTable> tables = classificationTables(inputs, numInputs);
  PyramidLevel out = pyramidLevelGeometry(dims, spacing, origin, level);
  const FilterTaps hostTaps = filterTaps(filter);
  DeviceTaps taps;
  taps.count = hostTaps.count;
  taps.first = hostTaps.first;
  std::copy(hostTaps.w, hostTaps.w + 4, taps.w);

  MCVOL_CUDA(cudaSetDevice(in.Device));
  const size_t voxels = size_t(dims[0]) * size_t(dims[1]) * size_t(dims[2]);
  DeviceMeter meter;

  // The inputs: kept copies from earlier builds reused, stale ones and, past
  // half the device's memory, the least recently used ones freed, the rest
  // copied.
  std::vector<std::unique_ptr<LevelInput>>& pool = in.LevelInputs;
  std::vector<const LevelInput*> used(static_cast<size_t>(numInputs), nullptr);
  for (int n = 0; n < numInputs; ++n)
  {
    used[size_t(n)] = findKept(pool, inputs[n].source, inputs[n].dataVersion, voxels);
  }
  evictLevelInputs(pool, used, inputs, numInputs, voxels, in.Props.totalGlobalMem / 2);
  std::vector<std::unique_ptr<LevelInput>> transient;
  copyLevelInputs(pool, transient, used, inputs, numInputs, voxels, in.Updates);
  size_t inputBytes = 0;
  for (const auto& li : pool)
  {
    inputBytes += li->data.bytes(); // all kept copies are on the device meanwhile
  }
  for (const auto& li : transient)
  {
    inputBytes += li->data.bytes();
  }
  meter.add(inputBytes);

  DeviceBuffer<float4> texels;
  DeviceBuffer<DeviceClassifyInput> descriptors;
  uploadClassifyInputs(tables, inputs, numInputs, used, texels, descriptors);
  meter.add(texels.bytes() + descriptors.bytes());

  Volume4 v;
  filterLevel(v, descriptors.ptr, numInputs, dims, level, taps, transient, meter);
  for (int a = 0; a < 3; ++a)
  {
    if (v.dims[a] != out.dims[a])
    {
      throw std::logic_error("mcvol (CUDA): the device level's dims differ from the level's geometry");
    }
  }
  out.voxels.resize(out.numVoxels() * 4);
  MCVOL_CUDA(cudaMemcpy(out.voxels.data(), v.buf.ptr, out.voxels.size() * sizeof(float), cudaMemcpyDeviceToHost));
  v.release();
  ++in.Updates.levelBuilds;
  in.Updates.lastLevelPeakBytes = meter.peak;
  in.Updates.lastLevelMs = 1e3 * std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  if (peakWorkBytes)
  {
    *peakWorkBytes = meter.peak;
  }
  return out;
}
} // namespace mcvol
