// SPDX-License-Identifier: BSD-3-Clause
//
// CUDA backend. The kernels below are launchers: the per-pixel work is
// renderPixel<Mode>() from the core (Integrator.h -> Tracking.h -> DDA.h,
// Sampling.h), the same functions the OpenMP backend runs, compiled for the
// device through MCVOL_HOST_DEVICE. The grid builds call the same
// cellVoxelBounds() and cellMajorant() as the host build (Acceleration.h).
#include "mcvol/CUDARenderer.h"

#include "mcvol/Acceleration.h"
#include "mcvol/RenderSetup.h"

#include <cuda_runtime.h>

#include <algorithm>
#include <cstring>
#include <sstream>
#include <stdexcept>
#include <string>
#include <vector>

namespace mcvol
{
namespace
{
void check(cudaError_t e, const char* what)
{
  if (e != cudaSuccess)
  {
    // Reset the last-error state (a sticky error, such as an illegal
    // address, cannot be cleared: the context stays unusable).
    (void)cudaGetLastError();
    throw std::runtime_error(std::string("mcvol (CUDA): ") + what + " failed: " + cudaGetErrorString(e));
  }
}
#define MCVOL_CUDA(call) check((call), #call)

/// Owning device array (no copies).
template <typename T>
struct DeviceBuffer
{
  T* ptr = nullptr;
  size_t count = 0;

  DeviceBuffer() = default;
  DeviceBuffer(const DeviceBuffer&) = delete;
  DeviceBuffer& operator=(const DeviceBuffer&) = delete;
  ~DeviceBuffer() { this->release(); }

  void resize(size_t n)
  {
    if (n == this->count)
    {
      return;
    }
    this->release();
    if (n > 0)
    {
      MCVOL_CUDA(cudaMalloc(reinterpret_cast<void**>(&this->ptr), n * sizeof(T)));
      this->count = n;
    }
  }
  void release()
  {
    if (this->ptr)
    {
      cudaFree(this->ptr);
    }
    this->ptr = nullptr;
    this->count = 0;
  }
  size_t bytes() const { return this->count * sizeof(T); }
};

/// One channel in device memory, with its optional 3D texture.
struct DeviceChannel
{
  DeviceBuffer<uint8_t> bytes; ///< native type (float64 converted to float32 on upload)
  ScalarType type = ScalarType::Float32;
  cudaArray_t array = nullptr;
  cudaTextureObject_t linear = 0;
  cudaTextureObject_t point = 0;
  float textureScale = 1.f;
  size_t arrayBytes = 0;
  /// Holds NaN or infinite voxels: sampled from global memory even with
  /// texture sampling on, since hardware filtering drops a non-finite corner
  /// whose weight rounds to 0, where the core's arithmetic (0 * Inf, NaN)
  /// makes the sample NaN or infinite.
  bool nonFinite = false;

  DeviceChannel() = default;
  DeviceChannel(const DeviceChannel&) = delete;
  DeviceChannel& operator=(const DeviceChannel&) = delete;
  ~DeviceChannel() { this->releaseTexture(); }

  void releaseTexture()
  {
    if (this->linear)
    {
      cudaDestroyTextureObject(this->linear);
    }
    if (this->point)
    {
      cudaDestroyTextureObject(this->point);
    }
    if (this->array)
    {
      cudaFreeArray(this->array);
    }
    this->linear = this->point = 0;
    this->array = nullptr;
    this->arrayBytes = 0;
  }
};

// ------------------------------------------------------------------ kernels

__device__ MCVOL_FORCE_INLINE int3 cellOf(int64_t c, int3 g)
{
  return make_int3(int(c % g.x), int((c / g.x) % g.y), int(c / (int64_t(g.x) * g.y)));
}

__global__ void probeKernel() {}

// Warp reductions with shuffles (any architecture from sm_70), 64-bit sums so
// that high sample counts cannot wrap.
__device__ MCVOL_FORCE_INLINE unsigned warpMaxU32(unsigned v)
{
  for (int o = 16; o > 0; o >>= 1)
  {
    const unsigned w = __shfl_xor_sync(0xffffffffu, v, o);
    v = w > v ? w : v;
  }
  return v;
}

__device__ MCVOL_FORCE_INLINE unsigned long long warpSumU64(unsigned long long v)
{
  for (int o = 16; o > 0; o >>= 1)
  {
    v += __shfl_xor_sync(0xffffffffu, v, o);
  }
  return v;
}

/// Scalar range of channel n over each macrocell's voxels (NaN voxels
/// skipped, as on the host): one thread per cell.
template <typename T>
__global__ void rangeKernel(const T* __restrict__ data, int3 dims, int3 gdims, int macrocell, int numChannels, int n,
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
  cellVoxelBounds(d, macrocell, cell, lo, hi);
  float mn = __int_as_float(0x7f800000);  // +inf
  float mx = -__int_as_float(0x7f800000); // -inf
  bool nonFinite = false;
  for (int k = lo[2]; k <= hi[2]; ++k)
  {
    for (int j = lo[1]; j <= hi[1]; ++j)
    {
      const T* row = data + (int64_t(k) * dims.y + j) * dims.x;
      for (int i = lo[0]; i <= hi[0]; ++i)
      {
        const float v = float(row[i]);
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

/// Majorants of channel n from the ranges and the channel's sparse table; the
/// channel's largest majorant goes to channelMax[n] (float bits, >= 0, so
/// unsigned comparison orders them).
__global__ void majorantKernel(const __grid_constant__ TableView tv, int n, int numChannels, int64_t cells,
  const float2* __restrict__ ranges, const float* __restrict__ sparse, float* __restrict__ majorants,
  unsigned* __restrict__ channelMax)
{
  const int64_t c = int64_t(blockIdx.x) * blockDim.x + threadIdx.x;
  float m = 0.f;
  if (c < cells)
  {
    const float2 r = ranges[c * numChannels + n];
    m = cellMajorant(tv, n, r.x, r.y, sparse);
    majorants[c * numChannels + n] = m;
  }
  const unsigned warpMax = warpMaxU32(__float_as_uint(m));
  if ((threadIdx.x & 31) == 0 && warpMax != 0u)
  {
    atomicMax(channelMax + n, warpMax);
  }
}

/// One thread per pixel: renderPixel() from the core, folded into the
/// running mean in `accum`. Count adds the work counters (warp sums, one
/// atomic per warp and counter).
template <BlendMode Mode, bool Count, bool Lit>
__global__ void renderKernel(const __grid_constant__ SceneView s, const __grid_constant__ CameraView cam,
  const __grid_constant__ FrameParams fp, const float* __restrict__ depth, float4* __restrict__ accum,
  uint32_t previous, unsigned long long* __restrict__ counters)
{
  const int x = int(blockIdx.x * blockDim.x + threadIdx.x);
  const int y = int(blockIdx.y * blockDim.y + threadIdx.y);
  RayCounters c;
  if (x < cam.width && y < cam.height)
  {
    const size_t p = size_t(y) * size_t(cam.width) + size_t(x);
    const float z = depth ? depth[p] : 1.f;
    const Vec4f sum = renderPixel<Mode, Lit>(s, cam, fp, x, y, z, c);
    const float4 old = accum[p];
    float v[4] = { old.x, old.y, old.z, old.w };
    accumulate(v, sum, previous, fp.samplesPerPixel);
    accum[p] = make_float4(v[0], v[1], v[2], v[3]);
  }
  if (Count)
  {
    const unsigned long long dda = warpSumU64(c.ddaSteps);
    const unsigned long long tent = warpSumU64(c.tentative);
    const unsigned long long real = warpSumU64(c.real);
    const unsigned long long smp = warpSumU64(c.samples);
    const unsigned long long sca = Lit ? warpSumU64(c.scattering) : 0ull;
    const unsigned long long shd = Lit ? warpSumU64(c.shadowRays) : 0ull;
    const unsigned long long grd = Lit ? warpSumU64(c.gradients) : 0ull;
    const unsigned lane = (threadIdx.y * blockDim.x + threadIdx.x) & 31u;
    if (lane == 0)
    {
      atomicAdd(counters + 0, dda);
      atomicAdd(counters + 1, tent);
      atomicAdd(counters + 2, real);
      atomicAdd(counters + 3, smp);
      if (Lit)
      {
        atomicAdd(counters + 4, sca);
        atomicAdd(counters + 5, shd);
        atomicAdd(counters + 6, grd);
      }
    }
  }
}

template <BlendMode Mode>
void launchRender(bool count, bool lit, dim3 grid, dim3 block, const SceneView& s, const CameraView& cam,
  const FrameParams& fp, const float* depth, float4* accum, uint32_t previous, unsigned long long* counters)
{
  // The unlit kernels contain none of the lighting code.
  if (lit)
  {
    if (count)
    {
      renderKernel<Mode, true, true><<<grid, block>>>(s, cam, fp, depth, accum, previous, counters);
    }
    else
    {
      renderKernel<Mode, false, true><<<grid, block>>>(s, cam, fp, depth, accum, previous, counters);
    }
  }
  else if (count)
  {
    renderKernel<Mode, true, false><<<grid, block>>>(s, cam, fp, depth, accum, previous, counters);
  }
  else
  {
    renderKernel<Mode, false, false><<<grid, block>>>(s, cam, fp, depth, accum, previous, counters);
  }
}

/// Narrow-integer storage of a channel for the texture path.
cudaChannelFormatDesc formatOf(ScalarType t, float& scale, cudaTextureReadMode& mode)
{
  mode = cudaReadModeNormalizedFloat;
  switch (t)
  {
    case ScalarType::UInt8:
      scale = 255.f;
      return cudaCreateChannelDesc<unsigned char>();
    case ScalarType::Int16:
      // Signed normalised reads map v to max(v / 32767, -1): -32768 comes back
      // as -32767, inside every macrocell range that holds -32768.
      scale = 32767.f;
      return cudaCreateChannelDesc<short>();
    case ScalarType::UInt16:
      scale = 65535.f;
      return cudaCreateChannelDesc<unsigned short>();
    default:
      scale = 1.f;
      mode = cudaReadModeElementType;
      return cudaCreateChannelDesc<float>();
  }
}
} // namespace

struct CUDARenderer::Internal
{
  int Device = 0;
  cudaDeviceProp Props{};
  CudaSampling Sampling = CudaSampling::Texture;
  dim3 Block = dim3(8, 8, 1);

  // What the device copies were made from.
  uint64_t SceneId = 0;
  uint64_t ContentVersion = ~0ull;
  uint64_t DataVersion = ~0ull;
  uint64_t TableVersion = ~0ull;
  uint64_t ChannelTableVersion[kMaxChannels];
  int Dims[3] = { 0, 0, 0 };
  int NumChannels = 0;
  int TableSize = 0;
  bool TexturesBuilt = false;

  DeviceChannel Channels[kMaxChannels];
  DeviceBuffer<float> Tables;    ///< [channel][K][4]
  DeviceBuffer<float> Sparse;    ///< [channel][levels][K]
  DeviceBuffer<float2> Ranges;   ///< [cell][channel]
  DeviceBuffer<float> Majorants; ///< [cell][channel]
  DeviceBuffer<unsigned> ChannelMax;
  DeviceBuffer<unsigned> NaNFlags;
  SceneView View; ///< device pointers; per-render fields filled in render()

  DeviceBuffer<float4> Accum;
  uint64_t AccumId = 0; ///< Accumulator::id() of the image in Accum (0: none)
  uint32_t AccumSamples = 0;
  DeviceBuffer<float> Depth;
  std::vector<float> LastDepth;
  bool HaveDepth = false;
  DeviceBuffer<unsigned long long> Counters;
  cudaEvent_t Start = nullptr;
  cudaEvent_t Stop = nullptr;

  CudaUpdateCounters Updates;

  Internal() = default;
  Internal(const Internal&) = delete;
  Internal& operator=(const Internal&) = delete;
  ~Internal()
  {
    cudaSetDevice(this->Device);
    if (this->Start)
    {
      cudaEventDestroy(this->Start);
    }
    if (this->Stop)
    {
      cudaEventDestroy(this->Stop);
    }
  }

  void uploadChannels(const Scene& scene);
  void buildTextures();
  void buildRanges(int macrocell);
  void buildMajorants(const Scene& scene, const bool* which);
  void sync(const Scene& scene);
  double elapsedMs()
  {
    float ms = 0.f;
    MCVOL_CUDA(cudaEventSynchronize(this->Stop));
    MCVOL_CUDA(cudaEventElapsedTime(&ms, this->Start, this->Stop));
    return double(ms);
  }
};

bool CUDARenderer::deviceUsable(std::string* why, int device)
{
  int count = 0;
  const cudaError_t e = cudaGetDeviceCount(&count);
  if (e != cudaSuccess)
  {
    (void)cudaGetLastError();
    if (why)
    {
      *why = std::string("no usable CUDA device (") + cudaGetErrorString(e) + ")";
    }
    return false;
  }
  if (count < 1)
  {
    if (why)
    {
      *why = "no CUDA device was found";
    }
    return false;
  }
  if (device < 0 || device >= count)
  {
    if (why)
    {
      *why = "there is no CUDA device " + std::to_string(device) + " (" + std::to_string(count) + " found)";
    }
    return false;
  }
  if (cudaSetDevice(device) != cudaSuccess)
  {
    (void)cudaGetLastError();
    if (why)
    {
      *why = "CUDA device " + std::to_string(device) + " cannot be used";
    }
    return false;
  }
  // The kernels were compiled for CMAKE_CUDA_ARCHITECTURES: make sure the
  // device can run them.
  cudaFuncAttributes attr;
  const cudaError_t k = cudaFuncGetAttributes(&attr, probeKernel);
  if (k != cudaSuccess)
  {
    (void)cudaGetLastError();
    if (why)
    {
      *why = std::string("the CUDA device cannot run this build's kernels (") + cudaGetErrorString(k) +
        "; rebuild with CMAKE_CUDA_ARCHITECTURES set for it)";
    }
    return false;
  }
  if (why)
  {
    cudaDeviceProp p;
    if (cudaGetDeviceProperties(&p, device) == cudaSuccess)
    {
      *why = std::string("CUDA device ") + p.name;
    }
  }
  return true;
}

CUDARenderer::CUDARenderer(int device)
  : In(new Internal())
{
  std::string why;
  if (!deviceUsable(&why, device))
  {
    throw std::runtime_error("mcvol: " + why);
  }
  this->In->Device = device;
  MCVOL_CUDA(cudaSetDevice(device));
  MCVOL_CUDA(cudaGetDeviceProperties(&this->In->Props, device));
  MCVOL_CUDA(cudaEventCreate(&this->In->Start));
  MCVOL_CUDA(cudaEventCreate(&this->In->Stop));
  this->In->Counters.resize(7);
  this->In->ChannelMax.resize(kMaxChannels);
  this->In->NaNFlags.resize(kMaxChannels);
  std::fill(std::begin(this->In->ChannelTableVersion), std::end(this->In->ChannelTableVersion), ~0ull);
}

CUDARenderer::~CUDARenderer() = default;

void CUDARenderer::setSampling(CudaSampling s)
{
  this->In->Sampling = s;
}

CudaSampling CUDARenderer::sampling() const
{
  return this->In->Sampling;
}

void CUDARenderer::setBlockSize(int x, int y)
{
  if (x < 1 || y < 1 || x * y > 1024 || (x * y) % 32 != 0)
  {
    throw std::invalid_argument("mcvol: the CUDA block size must be a multiple of 32 threads, at most 1024");
  }
  this->In->Block = dim3(unsigned(x), unsigned(y), 1);
}

const CudaUpdateCounters& CUDARenderer::updateCounters() const
{
  return this->In->Updates;
}

std::string CUDARenderer::deviceDescription() const
{
  int driver = 0, runtime = 0;
  cudaDriverGetVersion(&driver);
  cudaRuntimeGetVersion(&runtime);
  std::ostringstream s;
  s << this->In->Props.name << ", compute " << this->In->Props.major << "." << this->In->Props.minor << ", "
    << this->In->Props.multiProcessorCount << " SMs, " << (this->In->Props.totalGlobalMem >> 20) << " MiB; CUDA driver "
    << driver / 1000 << "." << (driver % 1000) / 10 << ", runtime " << runtime / 1000 << "." << (runtime % 1000) / 10;
  return s.str();
}

CudaMemoryStats CUDARenderer::memory() const
{
  CudaMemoryStats m;
  for (int n = 0; n < this->In->NumChannels; ++n)
  {
    m.dataBytes += this->In->Channels[n].bytes.bytes();
    m.textureBytes += this->In->Channels[n].arrayBytes;
  }
  m.macrocellBytes = this->In->Ranges.bytes();
  m.majorantBytes = this->In->Majorants.bytes();
  m.imageBytes = this->In->Accum.bytes() + this->In->Depth.bytes();
  return m;
}

std::vector<float> CUDARenderer::downloadMajorants(int channel) const
{
  const Internal& in = *this->In;
  if (channel < 0 || channel >= in.NumChannels)
  {
    throw std::invalid_argument("mcvol: no such channel");
  }
  std::vector<float> all(in.Majorants.count);
  if (!all.empty())
  {
    MCVOL_CUDA(cudaMemcpy(all.data(), in.Majorants.ptr, in.Majorants.bytes(), cudaMemcpyDeviceToHost));
  }
  std::vector<float> out(all.size() / size_t(in.NumChannels));
  for (size_t c = 0; c < out.size(); ++c)
  {
    out[c] = all[c * size_t(in.NumChannels) + size_t(channel)];
  }
  return out;
}

std::vector<int> CUDARenderer::activeChannels() const
{
  return std::vector<int>(this->In->View.active, this->In->View.active + this->In->View.numActive);
}

void CUDARenderer::Internal::uploadChannels(const Scene& scene)
{
  const int* d = scene.dims();
  const size_t voxels = size_t(d[0]) * size_t(d[1]) * size_t(d[2]);
  std::vector<uint8_t> staging;
  for (int n = scene.numChannels(); n < this->NumChannels; ++n)
  {
    this->Channels[n].bytes.release();
    this->Channels[n].releaseTexture();
  }
  for (int n = 0; n < scene.numChannels(); ++n)
  {
    const ChannelSource& src = scene.channel(n);
    DeviceChannel& dc = this->Channels[n];
    dc.releaseTexture();
    const void* host = src.data;
    if (src.type == ScalarType::Float64)
    {
      // Doubles become floats relative to the channel's offset, exactly as
      // fetchVoxel() converts them, so both backends see the same values.
      staging.resize(voxels * sizeof(float));
      float* out = reinterpret_cast<float*>(staging.data());
      const double* in = static_cast<const double*>(src.data);
      for (size_t v = 0; v < voxels; ++v)
      {
        out[v] = float(in[v * size_t(src.stride)] - src.offset);
      }
      host = staging.data();
      dc.type = ScalarType::Float32;
    }
    else
    {
      dc.type = src.type;
      if (src.stride != 1)
      {
        const size_t es = size_t(scalarTypeSize(src.type));
        staging.resize(voxels * es);
        const uint8_t* in = static_cast<const uint8_t*>(src.data);
        for (size_t v = 0; v < voxels; ++v)
        {
          std::memcpy(staging.data() + v * es, in + v * size_t(src.stride) * es, es);
        }
        host = staging.data();
      }
    }
    const size_t bytes = voxels * size_t(scalarTypeSize(dc.type));
    dc.bytes.resize(bytes);
    MCVOL_CUDA(cudaMemcpy(dc.bytes.ptr, host, bytes, cudaMemcpyHostToDevice));
    ++this->Updates.dataUploads;
  }
  std::copy(d, d + 3, this->Dims);
  this->NumChannels = scene.numChannels();
  this->TexturesBuilt = false;
}

void CUDARenderer::Internal::buildTextures()
{
  MCVOL_CUDA(cudaDeviceSynchronize()); // no kernel may still read the old textures
  const int* d = this->Dims;
  const bool fits =
    d[0] <= this->Props.maxTexture3D[0] && d[1] <= this->Props.maxTexture3D[1] && d[2] <= this->Props.maxTexture3D[2];
  for (int n = 0; n < this->NumChannels; ++n)
  {
    DeviceChannel& dc = this->Channels[n];
    dc.releaseTexture();
    if (!fits)
    {
      continue; // too large for a 3D texture: this channel samples global memory
    }
    cudaTextureReadMode mode;
    cudaChannelFormatDesc fmt = formatOf(dc.type, dc.textureScale, mode);
    const cudaExtent ext = make_cudaExtent(size_t(d[0]), size_t(d[1]), size_t(d[2]));
    const cudaError_t e = cudaMalloc3DArray(&dc.array, &fmt, ext);
    if (e == cudaErrorMemoryAllocation)
    {
      // No room for a second copy: this channel samples global memory.
      (void)cudaGetLastError();
      dc.array = nullptr;
      ++this->Updates.textureFallbacks;
      continue;
    }
    check(e, "cudaMalloc3DArray");
    const size_t es = size_t(scalarTypeSize(dc.type));
    dc.arrayBytes = size_t(d[0]) * size_t(d[1]) * size_t(d[2]) * es;
    cudaMemcpy3DParms copy{};
    copy.srcPtr = make_cudaPitchedPtr(dc.bytes.ptr, size_t(d[0]) * es, size_t(d[0]), size_t(d[1]));
    copy.dstArray = dc.array;
    copy.extent = ext;
    copy.kind = cudaMemcpyDeviceToDevice;
    MCVOL_CUDA(cudaMemcpy3D(&copy));
    cudaResourceDesc res{};
    res.resType = cudaResourceTypeArray;
    res.res.array.array = dc.array;
    cudaTextureDesc td{};
    td.addressMode[0] = td.addressMode[1] = td.addressMode[2] = cudaAddressModeClamp;
    td.readMode = mode;
    td.normalizedCoords = 0;
    td.filterMode = cudaFilterModeLinear;
    MCVOL_CUDA(cudaCreateTextureObject(&dc.linear, &res, &td, nullptr));
    td.filterMode = cudaFilterModePoint;
    MCVOL_CUDA(cudaCreateTextureObject(&dc.point, &res, &td, nullptr));
  }
  this->TexturesBuilt = true;
}

void CUDARenderer::Internal::buildRanges(int macrocell)
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
    switch (dc.type)
    {
      case ScalarType::UInt8:
        rangeKernel<<<blocks, threads>>>(reinterpret_cast<const uint8_t*>(dc.bytes.ptr), dims, gd, M, N, n, cells,
          this->Ranges.ptr, this->NaNFlags.ptr);
        break;
      case ScalarType::Int16:
        rangeKernel<<<blocks, threads>>>(reinterpret_cast<const int16_t*>(dc.bytes.ptr), dims, gd, M, N, n, cells,
          this->Ranges.ptr, this->NaNFlags.ptr);
        break;
      case ScalarType::UInt16:
        rangeKernel<<<blocks, threads>>>(reinterpret_cast<const uint16_t*>(dc.bytes.ptr), dims, gd, M, N, n, cells,
          this->Ranges.ptr, this->NaNFlags.ptr);
        break;
      default:
        rangeKernel<<<blocks, threads>>>(
          reinterpret_cast<const float*>(dc.bytes.ptr), dims, gd, M, N, n, cells, this->Ranges.ptr, this->NaNFlags.ptr);
        break;
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
    majorantKernel<<<blocks, threads>>>(
      tv, n, N, cells, this->Ranges.ptr, dst, this->Majorants.ptr, this->ChannelMax.ptr);
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

void CUDARenderer::Internal::sync(const Scene& scene)
{
  const SceneView& hv = scene.view();
  if (hv.volume.numChannels == 0 || hv.tables.size < 2 || scene.tables().empty())
  {
    throw std::logic_error("mcvol: Scene::update() must succeed before rendering");
  }
  const bool newScene = scene.id() != this->SceneId;
  const bool newData = newScene || scene.contentVersion() != this->ContentVersion ||
    scene.numChannels() != this->NumChannels || !std::equal(this->Dims, this->Dims + 3, scene.dims());
  const bool newGrid = newData || scene.dataVersion() != this->DataVersion;
  const bool newTables = newScene || scene.tableVersion() != this->TableVersion;
  if (newData || newGrid || newTables)
  {
    // Buffers and textures are about to be replaced: let every kernel that
    // may read them (renders issued with readBack off) finish first.
    MCVOL_CUDA(cudaDeviceSynchronize());
  }
  if (newData)
  {
    this->uploadChannels(scene);
  }
  // The grid layout, volume box and table scaling come from the host view.
  SceneView& v = this->View;
  v.volume.dims[0] = hv.volume.dims[0];
  v.volume.dims[1] = hv.volume.dims[1];
  v.volume.dims[2] = hv.volume.dims[2];
  v.volume.numChannels = hv.volume.numChannels;
  v.volume.boxLo = hv.volume.boxLo;
  v.volume.boxHi = hv.volume.boxHi;
  v.grid = hv.grid;
  v.grid.majorants = nullptr;
  if (newGrid)
  {
    this->buildRanges(scene.macrocellSize());
  }
  bool which[kMaxChannels] = {};
  bool any = false;
  if (newTables || newGrid)
  {
    const int K = hv.tables.size;
    if (K != this->TableSize)
    {
      this->TableSize = K;
      std::fill(std::begin(this->ChannelTableVersion), std::end(this->ChannelTableVersion), ~0ull);
    }
    const std::vector<float>& t = scene.tables();
    this->Tables.resize(size_t(this->NumChannels) * size_t(K) * 4);
    MCVOL_CUDA(cudaMemcpy(this->Tables.ptr, t.data(), this->Tables.bytes(), cudaMemcpyHostToDevice));
    v.tables = hv.tables;
    v.tables.texels = this->Tables.ptr;
    for (int n = 0; n < this->NumChannels; ++n)
    {
      which[n] = newGrid || scene.channelTableVersion(n) != this->ChannelTableVersion[n];
      any = any || which[n];
    }
  }
  if (any)
  {
    this->buildMajorants(scene, which);
    for (int n = 0; n < this->NumChannels; ++n)
    {
      this->ChannelTableVersion[n] = scene.channelTableVersion(n);
    }
  }
  v.grid.majorants = this->Majorants.ptr;
  this->SceneId = scene.id();
  this->ContentVersion = scene.contentVersion();
  this->DataVersion = scene.dataVersion();
  this->TableVersion = scene.tableVersion();
}

void CUDARenderer::render(const Scene& scene, const Camera& camera, const RenderSettings& settings, const float* depth,
  Accumulator& accum, RenderCounters* counters)
{
  Internal& in = *this->In;
  checkRenderArguments(camera, settings, accum);
  MCVOL_CUDA(cudaSetDevice(in.Device));
  in.sync(scene);

  // Per-render view: blend parameters, interpolation and sampling path.
  SceneView s = in.View;
  const SceneView& hv = scene.view();
  s.blend = hv.blend;
  s.volume.nearest = hv.volume.nearest;
  const bool textures = in.Sampling == CudaSampling::Texture;
  if (textures && !in.TexturesBuilt)
  {
    in.buildTextures();
  }
  for (int n = 0; n < in.NumChannels; ++n)
  {
    const DeviceChannel& dc = in.Channels[n];
    ChannelView& c = s.volume.channels[n];
    c.data = dc.bytes.ptr;
    c.stride = 1;
    c.type = dc.type;
    c.offset = 0.0;
    c.texture = textures && !dc.nonFinite && dc.array ? (hv.volume.nearest ? dc.point : dc.linear) : 0;
    c.textureScale = dc.textureScale;
  }
  const CameraView cam = toView(camera);
  s.sigmaLimit = extinctionLimit(cam);
  s.lighting = hv.lighting;
  const bool lit = s.lighting.enabled;
  if (lit)
  {
    if (s.blend.mode == BlendMode::Composite)
    {
      throw std::invalid_argument("mcvol: lighting with post-render composite blending is not supported yet");
    }
    setLightingFrame(s, camera);
  }

  // Accumulation buffer: continue the device mean only if it is this
  // Accumulator's, at its sample count; otherwise start from the host's.
  const size_t P = size_t(camera.width) * size_t(camera.height);
  if (accum.pendingOnDevice() && in.AccumId != accum.id())
  {
    throw std::logic_error("mcvol: this Accumulator's image was left on the device (RenderSettings::readBack = "
                           "false) and has since been replaced by another Accumulator's; call readBack() before "
                           "rendering another Accumulator");
  }
  if (in.Accum.count != P)
  {
    in.Accum.resize(P);
    in.AccumId = 0;
  }
  if (in.AccumId != accum.id() || in.AccumSamples != accum.samples())
  {
    if (accum.samples() == 0)
    {
      MCVOL_CUDA(cudaMemsetAsync(in.Accum.ptr, 0, in.Accum.bytes()));
    }
    else
    {
      MCVOL_CUDA(cudaMemcpy(in.Accum.ptr, accum.rgba(), in.Accum.bytes(), cudaMemcpyHostToDevice));
    }
    in.AccumId = accum.id();
  }

  // Depth: uploaded when it changes (geometry or view), else reused.
  const float* devDepth = nullptr;
  if (depth)
  {
    if (!in.HaveDepth || in.LastDepth.size() != P || std::memcmp(in.LastDepth.data(), depth, P * sizeof(float)) != 0)
    {
      in.Depth.resize(P);
      MCVOL_CUDA(cudaMemcpy(in.Depth.ptr, depth, P * sizeof(float), cudaMemcpyHostToDevice));
      in.LastDepth.assign(depth, depth + P);
      in.HaveDepth = true;
    }
    devDepth = in.Depth.ptr;
  }

  const FrameParams fp = frameParams(settings, accum.samples());
  const bool count = counters != nullptr;
  if (count)
  {
    MCVOL_CUDA(cudaMemsetAsync(in.Counters.ptr, 0, 7 * sizeof(unsigned long long)));
  }
  const dim3 block = in.Block;
  const dim3 grid((unsigned(camera.width) + block.x - 1) / block.x, (unsigned(camera.height) + block.y - 1) / block.y);
  const uint32_t previous = accum.samples();
  {
    // Launched even with no active channel: the mean must still take the
    // added (transparent) samples.
    switch (s.blend.mode)
    {
      case BlendMode::Max:
        launchRender<BlendMode::Max>(
          count, lit, grid, block, s, cam, fp, devDepth, in.Accum.ptr, previous, in.Counters.ptr);
        break;
      case BlendMode::Mix:
        launchRender<BlendMode::Mix>(
          count, lit, grid, block, s, cam, fp, devDepth, in.Accum.ptr, previous, in.Counters.ptr);
        break;
      case BlendMode::Composite:
        launchRender<BlendMode::Composite>(
          count, lit, grid, block, s, cam, fp, devDepth, in.Accum.ptr, previous, in.Counters.ptr);
        break;
      case BlendMode::Density:
      default:
        launchRender<BlendMode::Density>(
          count, lit, grid, block, s, cam, fp, devDepth, in.Accum.ptr, previous, in.Counters.ptr);
        break;
    }
    MCVOL_CUDA(cudaGetLastError());
  }
  accum.addSamples(uint32_t(settings.samplesPerPixel));
  in.AccumSamples = accum.samples();
  accum.setPendingOnDevice(true);
  if (count)
  {
    unsigned long long c[7];
    MCVOL_CUDA(cudaMemcpy(c, in.Counters.ptr, sizeof(c), cudaMemcpyDeviceToHost));
    counters->rays += uint64_t(camera.width) * uint64_t(camera.height) * uint64_t(settings.samplesPerPixel);
    counters->ddaSteps += c[0];
    counters->tentativeCollisions += c[1];
    counters->realCollisions += c[2];
    counters->channelSamples += c[3];
    counters->scatteringEvents += c[4];
    counters->shadowRays += c[5];
    counters->gradientEvaluations += c[6];
  }
  if (settings.readBack)
  {
    this->readBack(accum);
  }
}

void CUDARenderer::readBack(Accumulator& accum)
{
  Internal& in = *this->In;
  const bool mine = in.AccumId == accum.id() && in.AccumSamples == accum.samples() &&
    in.Accum.count == size_t(accum.width()) * size_t(accum.height());
  if (!mine)
  {
    if (accum.pendingOnDevice())
    {
      throw std::logic_error("mcvol: this Accumulator's image is no longer on the device (another Accumulator "
                             "was rendered since); it cannot be read back");
    }
    return; // the host copy is current
  }
  MCVOL_CUDA(cudaSetDevice(in.Device));
  MCVOL_CUDA(cudaMemcpy(accum.rgba(), in.Accum.ptr, in.Accum.bytes(), cudaMemcpyDeviceToHost));
  accum.setPendingOnDevice(false);
  ++in.Updates.imageDownloads;
}

void CUDARenderer::finish()
{
  MCVOL_CUDA(cudaSetDevice(this->In->Device));
  MCVOL_CUDA(cudaDeviceSynchronize());
}
} // namespace mcvol
