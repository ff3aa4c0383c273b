// SPDX-License-Identifier: BSD-3-Clause
//
// Macrocell ranges and majorants built on the GPU from the device copy of
// each channel (texture or array), and the active-channel list reduced from
// the majorants. The kernels call the same cellVoxelBounds() and cellMajorant() as the host
// build (Acceleration.h).
#include "CUDAInternal.h"

#include "mcvol/ray/Acceleration.h"

#include <vector>

namespace mcvol
{
namespace
{
__device__ MCVOL_FORCE_INLINE int3 cellOf(int64_t c, int3 g)
{
  return make_int3(int(c % g.x), int((c / g.x) % g.y), int(c / (int64_t(g.x) * g.y)));
}

// Warp reduction with shuffles (any architecture from sm_70).
__device__ MCVOL_FORCE_INLINE unsigned warpMaxU32(unsigned v)
{
  for (int o = 16; o > 0; o >>= 1)
  {
    const unsigned w = __shfl_xor_sync(0xffffffffu, v, o);
    v = w > v ? w : v;
  }
  return v;
}

/// Reads voxel (i, j, k) of a dense device array.
template <typename T>
struct ArrayVoxels
{
  const T* __restrict__ data;
  int nx;
  int ny;
  __device__ MCVOL_FORCE_INLINE float operator()(int i, int j, int k) const
  {
    return float(data[(int64_t(k) * ny + j) * nx + i]);
  }
};

/// Reads voxel (i, j, k) of a texture-held channel through its point object,
/// in data units, as sampleChannel() and fetchVoxel() read it.
struct TextureVoxels
{
  cudaTextureObject_t point;
  float scale;
  __device__ MCVOL_FORCE_INLINE float operator()(int i, int j, int k) const
  {
    return scale * tex3D<float>(point, float(i) + 0.5f, float(j) + 0.5f, float(k) + 0.5f);
  }
};

/// Scalar range of channel n over each macrocell's voxels (NaN voxels
/// skipped, as on the host): one thread per cell.
template <typename Voxels>
__global__ void rangeKernel(const Voxels voxel, int3 dims, int3 gdims, int macrocell, int apron, int numChannels, int n,
  int64_t cells, float2* __restrict__ ranges, unsigned* __restrict__ nonFiniteFlags)
{
  const int64_t c = int64_t(blockIdx.x) * blockDim.x + threadIdx.x;
  if (c >= cells)
  {
    return;
  }
  const int3 cc = cellOf(c, gdims);
  const int d[3] = { dims.x, dims.y, dims.z };
  const int cell[3] = { cc.x, cc.y, cc.z };
  int lo[3];
  int hi[3];
  cellVoxelBounds(d, macrocell, cell, apron, lo, hi);
  float mn = __int_as_float(0x7f800000);  // +inf
  float mx = -__int_as_float(0x7f800000); // -inf
  bool nonFinite = false;
  for (int k = lo[2]; k <= hi[2]; ++k)
  {
    for (int j = lo[1]; j <= hi[1]; ++j)
    {
      for (int i = lo[0]; i <= hi[0]; ++i)
      {
        const float v = voxel(i, j, k);
        if (v == v)
        {
          mn = fminf(mn, v);
          mx = fmaxf(mx, v);
        }
        nonFinite = nonFinite || !isfinite(v);
      }
    }
  }
  ranges[c * numChannels + n] = make_float2(mn, mx);
  if (nonFinite)
  {
    atomicOr(nonFiniteFlags + n, 1u);
  }
}

/// Voxels of a pre-classified channel held as packed float4 in an array.
struct ArrayClassified
{
  const float* data;
  int3 dims;
  __device__ bool operator()(int i, int j, int k, float x[4]) const
  {
    return classifiedVoxel(data + ((int64_t(k) * dims.y + j) * dims.x + i) * 4, x);
  }
};

/// Voxels of a pre-classified channel held as a float4 texture (its point
/// object; the texels were sanitised on upload, classifiedVoxel is then the
/// identity on them).
struct TextureClassified
{
  cudaTextureObject_t tex;
  __device__ bool operator()(int i, int j, int k, float x[4]) const { return classifiedTexel(tex, i, j, k, x); }
};

/// Range of a pre-classified channel's sanitised sigma (classifiedVoxel, as
/// the host build and the per-ray sampling read it) over each macrocell.
template <typename Voxels>
__global__ void classifiedRangeKernel(const Voxels voxel, int3 dims, int3 gdims, int macrocell, int apron,
  int numChannels, int n, int64_t cells, float2* __restrict__ ranges)
{
  const int64_t c = int64_t(blockIdx.x) * blockDim.x + threadIdx.x;
  if (c >= cells)
  {
    return;
  }
  const int3 cc = cellOf(c, gdims);
  const int d[3] = { dims.x, dims.y, dims.z };
  const int cell[3] = { cc.x, cc.y, cc.z };
  int lo[3];
  int hi[3];
  cellVoxelBounds(d, macrocell, cell, apron, lo, hi);
  float mn = __int_as_float(0x7f800000);  // +inf
  float mx = -__int_as_float(0x7f800000); // -inf
  for (int k = lo[2]; k <= hi[2]; ++k)
  {
    for (int j = lo[1]; j <= hi[1]; ++j)
    {
      for (int i = lo[0]; i <= hi[0]; ++i)
      {
        float x[4];
        if (voxel(i, j, k, x))
        {
          mn = fminf(mn, x[0]);
          mx = fmaxf(mx, x[0]);
        }
      }
    }
  }
  ranges[c * numChannels + n] = make_float2(mn, mx);
}

/// Majorants of channel n from the ranges and the channel's sparse table; the
/// channel's largest majorant goes to channelMax[n] (float bits, >= 0, so
/// unsigned comparison orders them).
__global__ void majorantKernel(const __grid_constant__ TableView tv, int n, int numChannels, int64_t cells,
  const float2* __restrict__ ranges, const float* __restrict__ sparse, float* __restrict__ majorants,
  unsigned* __restrict__ channelMax, bool classified)
{
  const int64_t c = int64_t(blockIdx.x) * blockDim.x + threadIdx.x;
  float m = 0.f;
  if (c < cells)
  {
    const float2 r = ranges[c * numChannels + n];
    // Pre-classified channels: the range is sigma's own (identity rule).
    m = classified ? classifiedCellMajorant(r.x, r.y) : cellMajorant(tv, n, r.x, r.y, sparse);
    majorants[c * numChannels + n] = m;
  }
  const unsigned warpMax = warpMaxU32(__float_as_uint(m));
  if ((threadIdx.x & 31) == 0 && warpMax != 0u)
  {
    atomicMax(channelMax + n, warpMax);
  }
}
} // namespace

void CUDARenderer::Internal::buildRanges(int macrocell, int apron)
{
  const GridView& g = this->View.grid;
  const int64_t cells = int64_t(g.dims[0]) * g.dims[1] * g.dims[2];
  const int N = this->NumChannels;
  this->Ranges.resize(size_t(cells) * size_t(N));
  this->Majorants.resize(size_t(cells) * size_t(N));
  const int3 dims = make_int3(this->Dims[0], this->Dims[1], this->Dims[2]);
  const int3 gd = make_int3(g.dims[0], g.dims[1], g.dims[2]);
  const int M = macrocell;
  const unsigned threads = 128;
  const unsigned blocks = unsigned((cells + threads - 1) / threads);
  MCVOL_CUDA(cudaMemset(this->NaNFlags.ptr, 0, sizeof(unsigned) * kMaxChannels));
  MCVOL_CUDA(cudaEventRecord(this->Start));
  for (int n = 0; n < N; ++n)
  {
    const DeviceChannel& dc = this->Channels[n];
    if (dc.format == ChannelFormat::Extinction)
    {
      if (dc.array)
      {
        classifiedRangeKernel<<<blocks, threads>>>(
          TextureClassified{ dc.point }, dims, gd, M, apron, N, n, cells, this->Ranges.ptr);
      }
      else
      {
        classifiedRangeKernel<<<blocks, threads>>>(
          ArrayClassified{ reinterpret_cast<const float*>(dc.bytes.ptr), dims }, dims, gd, M, apron, N, n, cells,
          this->Ranges.ptr);
      }
      MCVOL_CUDA(cudaGetLastError());
      continue;
    }
    if (dc.array)
    {
      rangeKernel<<<blocks, threads>>>(TextureVoxels{ dc.point, dc.textureScale }, dims, gd, M, apron, N, n, cells,
        this->Ranges.ptr, this->NaNFlags.ptr);
    }
    else
    {
      visitScalarType(dc.type,
        [&](auto tag)
        {
          using T = DeviceScalar<typename decltype(tag)::type>;
          const ArrayVoxels<T> voxels{ reinterpret_cast<const T*>(dc.bytes.ptr), dims.x, dims.y };
          rangeKernel<<<blocks, threads>>>(
            voxels, dims, gd, M, apron, N, n, cells, this->Ranges.ptr, this->NaNFlags.ptr);
        });
    }
    MCVOL_CUDA(cudaGetLastError());
  }
  MCVOL_CUDA(cudaEventRecord(this->Stop));
  this->Updates.lastRangeMs = this->elapsedMs();
  ++this->Updates.rangeBuilds;
  unsigned flags[kMaxChannels];
  MCVOL_CUDA(cudaMemcpy(flags, this->NaNFlags.ptr, sizeof(flags), cudaMemcpyDeviceToHost));
  for (int n = 0; n < N; ++n)
  {
    this->Channels[n].nonFinite = flags[n] != 0u;
  }
}

void CUDARenderer::Internal::buildMajorants(const Scene& scene, const bool* which)
{
  const GridView& g = this->View.grid;
  const int64_t cells = int64_t(g.dims[0]) * g.dims[1] * g.dims[2];
  const int N = this->NumChannels;
  const int K = this->TableSize;
  const int levels = sparseLevels(K);
  // Sparse tables of the channels to rebuild (K log K floats each, built on
  // the host from the Scene's tables: microseconds).
  const std::vector<float>& tables = scene.tables();
  std::vector<float> sparse(size_t(levels) * size_t(K), 0.f);
  this->Sparse.resize(size_t(kMaxChannels) * size_t(levels) * size_t(K));
  const unsigned threads = 256;
  const unsigned blocks = unsigned((cells + threads - 1) / threads);
  TableView tv = this->View.tables;
  MCVOL_CUDA(cudaEventRecord(this->Start));
  int rebuilt = 0;
  for (int n = 0; n < N; ++n)
  {
    if (!which[n])
    {
      continue;
    }
    buildSparseTable(tables.data() + size_t(n) * size_t(K) * 4, K, sparse.data());
    float* dst = this->Sparse.ptr + size_t(n) * size_t(levels) * size_t(K);
    MCVOL_CUDA(cudaMemcpyAsync(dst, sparse.data(), sparse.size() * sizeof(float), cudaMemcpyHostToDevice));
    MCVOL_CUDA(cudaMemsetAsync(this->ChannelMax.ptr + n, 0, sizeof(unsigned)));
    majorantKernel<<<blocks, threads>>>(tv, n, N, cells, this->Ranges.ptr, dst, this->Majorants.ptr,
      this->ChannelMax.ptr, this->Channels[n].format == ChannelFormat::Extinction);
    MCVOL_CUDA(cudaGetLastError());
    ++rebuilt;
    ++this->Updates.majorantChannelBuilds;
  }
  MCVOL_CUDA(cudaEventRecord(this->Stop));
  this->Updates.lastMajorantMs = this->elapsedMs();
  if (rebuilt == 0)
  {
    return;
  }
  // Channels whose majorant is zero everywhere are never traversed.
  unsigned maxBits[kMaxChannels];
  MCVOL_CUDA(cudaMemcpy(maxBits, this->ChannelMax.ptr, sizeof(unsigned) * size_t(N), cudaMemcpyDeviceToHost));
  this->View.numActive = 0;
  for (int n = 0; n < N; ++n)
  {
    if (maxBits[n] != 0u)
    {
      this->View.active[this->View.numActive++] = n;
    }
  }
}
} // namespace mcvol
