// SPDX-License-Identifier: BSD-3-Clause
//
// CUDA backend: the renderer object (device choice, settings, queries) and
// sync(), which decides at each render what of the device copies is stale.
// The work is done in
// - CUDAUpload.cu: channel arrays and 3D textures;
// - CUDAAcceleration.cu: macrocell ranges, majorants, active channels;
// - CUDALaunch.cu: the render kernels, accumulation image, depth, counters,
//   the concurrent pilots (CUDALaunchPlain.cu: the plain unlit kernels);
// - CUDAMarch.cu: the ray-marching reference;
// - CUDAPyramid.cu: levels of detail built on the device.
// CUDAInternal.h holds the state they share (CUDARenderer::Internal).
#include "CUDAInternal.h"

#include "mcvol/ray/Acceleration.h" // footprintApron

#include <algorithm>
#include <cstdlib>
#include <dlfcn.h>
#include <iterator>
#include <sstream>
#include <stdexcept>
#include <string>
#include <vector>

namespace mcvol
{
namespace
{
__global__ void probeKernel() {}

/// displayImage(): the running mean as premultiplied RGBA8 (clamped to [0, 1],
/// rounded to nearest).
__global__ void displayKernel(const float4* __restrict__ mean, uchar4* __restrict__ out, size_t n)
{
  const size_t i = size_t(blockIdx.x) * blockDim.x + threadIdx.x;
  if (i >= n)
  {
    return;
  }
  const float4 v = mean[i];
  auto q = [](float x) -> unsigned char
  { return static_cast<unsigned char>(__float2int_rn(255.f * fminf(fmaxf(x, 0.f), 1.f))); };
  out[i] = make_uchar4(q(v.x), q(v.y), q(v.z), q(v.w));
}

/// Whether the NVIDIA driver's user-space library is on this machine.
bool driverInstalled()
{
  void* lib = dlopen("libcuda.so.1", RTLD_LAZY | RTLD_LOCAL);
  if (!lib)
  {
    return false;
  }
  dlclose(lib);
  return true;
}
} // namespace

bool CUDARenderer::deviceUsable(std::string* why, int device)
{
  int count = 0;
  const cudaError_t e = cudaGetDeviceCount(&count);
  if (e != cudaSuccess)
  {
    (void)cudaGetLastError();
    if (why)
    {
      if ((e == cudaErrorInsufficientDriver || e == cudaErrorNoDevice) && !driverInstalled())
      {
        // The runtime says "driver version is insufficient" also when there
        // is no driver at all, which misleads.
        *why = "no NVIDIA driver found (libcuda.so.1 is not installed)";
      }
      else if (e == cudaErrorInsufficientDriver)
      {
        *why = std::string("the NVIDIA driver is older than this build's CUDA runtime needs (") +
          cudaGetErrorString(e) + ")";
      }
      else
      {
        *why = std::string("no usable CUDA device (") + cudaGetErrorString(e) + ")";
      }
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

int CUDARenderer::defaultDevice(std::string* how)
{
  int count = 0;
  if (cudaGetDeviceCount(&count) != cudaSuccess || count < 1)
  {
    (void)cudaGetLastError();
    return 0;
  }
  for (const char* var : { "OMPI_COMM_WORLD_LOCAL_RANK", "MPI_LOCALRANKID", "MPI_LOCAL_RANK", "SLURM_LOCALID" })
  {
    const char* value = std::getenv(var);
    char* end = nullptr;
    const long rank = value ? std::strtol(value, &end, 10) : -1;
    if (value && end != value && rank >= 0)
    {
      const int device = static_cast<int>(rank % count);
      if (how)
      {
        *how = "device " + std::to_string(device) + " of " + std::to_string(count) + " (" + var + "=" + value + ")";
      }
      return device;
    }
  }
  if (how)
  {
    *how = "device 0 of " + std::to_string(count);
  }
  return 0;
}

CUDARenderer::CUDARenderer(int device)
  : In(new Internal())
{
  if (device < 0)
  {
    device = defaultDevice();
  }
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
  this->In->Counters.resize(9);
  this->In->ChannelMax.resize(kMaxChannels);
  this->In->NaNFlags.resize(kMaxChannels);
  std::fill(std::begin(this->In->ChannelTableVersion), std::end(this->In->ChannelTableVersion), ~0ull);
}

CUDARenderer::~CUDARenderer() = default;

void CUDARenderer::setSampling(CudaSampling s)
{
  if (s != this->In->Sampling)
  {
    this->In->ContentVersion = ~0ull; // channels move between textures and arrays at the next render
  }
  this->In->Sampling = s;
}

CudaSampling CUDARenderer::sampling() const
{
  return this->In->Sampling;
}

void CUDARenderer::setPlainKernels(bool on)
{
  this->In->PlainKernels = on;
}

bool CUDARenderer::plainKernels() const
{
  return this->In->PlainKernels;
}

void CUDARenderer::setDeferredShadows(bool on)
{
  this->In->DeferShadows = on;
}

bool CUDARenderer::deferredShadows() const
{
  return this->In->DeferShadows;
}

void CUDARenderer::setDeferredBatch(int samples)
{
  if (samples < 1 || size_t(samples) > kMaxDeferredBatch)
  {
    throw std::invalid_argument("CUDARenderer::setDeferredBatch: samples must be 1 to " +
      std::to_string(kMaxDeferredBatch) + ", not " + std::to_string(samples));
  }
  this->In->DeferredBatch = unsigned(samples);
}

int CUDARenderer::deferredBatch() const
{
  return int(this->In->DeferredBatch);
}

bool CUDARenderer::buildsLevelsOnDevice() const
{
  return this->In->DeviceLevels;
}

void CUDARenderer::setDeviceLevels(bool on)
{
  this->In->DeviceLevels = on;
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
  m.imageBytes = this->In->Accum.bytes() + this->In->Even.bytes() + this->In->AccumSums.bytes() +
    this->In->EvenSums.bytes() + this->In->Depth.bytes() + this->In->Display.bytes() + this->In->Deferred.bytes() +
    this->In->DeferredCount.bytes() + this->In->DeferredSlots.bytes();
  for (const auto& li : this->In->LevelInputs)
  {
    m.levelInputBytes += li->data.bytes();
  }
  return m;
}

size_t CUDARenderer::deviceBytes() const
{
  const CudaMemoryStats m = this->memory();
  const Internal& in = *this->In;
  return m.dataBytes + m.textureBytes + m.macrocellBytes + m.majorantBytes + m.imageBytes + m.levelInputBytes +
    in.Tables.bytes() + in.Sparse.bytes() + in.ChannelMax.bytes() + in.NaNFlags.bytes() + in.Counters.bytes() +
    in.ImportanceTables.bytes() + in.Segments.bytes() + in.SegmentCounts.bytes() + in.SegmentTotals.bytes() +
    in.Outside.bytes() + in.shadowCacheBytes();
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
    // Switching to or from cubic sampling bumps dataVersion (Scene::setInterpolation).
    this->buildRanges(scene.macrocellSize(), footprintApron(hv.volume.cubic));
    if (newData)
    {
      this->moveNonFiniteToArrays(scene);
    }
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

void CUDARenderer::finish()
{
  MCVOL_CUDA(cudaSetDevice(this->In->Device));
  MCVOL_CUDA(cudaDeviceSynchronize());
}

const uint8_t* CUDARenderer::displayImage(Accumulator& accum)
{
  Internal& in = *this->In;
  const size_t P = size_t(accum.width()) * size_t(accum.height());
  const bool mine = in.AccumId == accum.id() && in.AccumSamples == accum.samples() && in.Accum.count == P;
  if (!mine)
  {
    if (accum.pendingOnDevice())
    {
      throw std::logic_error("mcvol: this Accumulator's image is no longer on the device (another Accumulator "
                             "was rendered since); it cannot be displayed");
    }
    return nullptr; // nothing of it on the device: the host image is the one to draw
  }
  MCVOL_CUDA(cudaSetDevice(in.Device));
  in.Display.resize(P);
  if (in.DisplayHostBytes != P * 4)
  {
    if (in.DisplayHost)
    {
      MCVOL_CUDA(cudaFreeHost(in.DisplayHost));
      in.DisplayHost = nullptr;
      in.DisplayHostBytes = 0;
    }
    MCVOL_CUDA(cudaMallocHost(reinterpret_cast<void**>(&in.DisplayHost), P * 4));
    in.DisplayHostBytes = P * 4;
  }
  const unsigned threads = 256;
  displayKernel<<<unsigned((P + threads - 1) / threads), threads>>>(in.Accum.ptr, in.Display.ptr, P);
  MCVOL_CUDA(cudaGetLastError());
  // Page-locked destination: the copy runs at the bus's speed, not through
  // the driver's staging of pageable memory.
  MCVOL_CUDA(cudaMemcpy(in.DisplayHost, in.Display.ptr, P * 4, cudaMemcpyDeviceToHost));
  ++in.Updates.imageDownloads;
  return in.DisplayHost;
}
} // namespace mcvol
