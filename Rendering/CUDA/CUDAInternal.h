// SPDX-License-Identifier: BSD-3-Clause
//
// Internal to the CUDA backend: the renderer's state (CUDARenderer::Internal)
// and the helpers every part of it uses. No kernels: each .cu file keeps its
// kernels next to their launchers, so no relocatable device code is needed.
#pragma once

#include "mcvol/CUDARenderer.h"
#include "mcvol/HostShadowCache.h"

#include "mcvol/ray/Lighting.h"
#include "mcvol/ray/SceneView.h"

#include <cuda_runtime.h>

#include <cstdint>
#include <memory>
#include <stdexcept>
#include <string>
#include <type_traits>
#include <vector>

namespace mcvol
{
struct RenderLaunch;
inline void check(cudaError_t e, const char* what)
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

/// A warp's sum of `v` with shuffles (any architecture from sm_70), 64-bit so
/// that high sample counts cannot wrap: the kernels add their work counters
/// with one atomic per warp.
__device__ MCVOL_FORCE_INLINE unsigned long long warpSumU64(unsigned long long v)
{
  for (int o = 16; o > 0; o >>= 1)
  {
    v += __shfl_xor_sync(0xffffffffu, v, o);
  }
  return v;
}

/**
 * Calls f(std::integral_constant<BlendMode, M>()) with M the blend mode
 * known at run time (Density for any other value), so that a kernel
 * templated on the mode is launched from one piece of code.
 */
template <typename F>
void withBlendMode(BlendMode mode, F&& f)
{
  switch (mode)
  {
    case BlendMode::Max:
      f(std::integral_constant<BlendMode, BlendMode::Max>());
      break;
    case BlendMode::Mix:
      f(std::integral_constant<BlendMode, BlendMode::Mix>());
      break;
    case BlendMode::Composite:
      f(std::integral_constant<BlendMode, BlendMode::Composite>());
      break;
    case BlendMode::Density:
    default:
      f(std::integral_constant<BlendMode, BlendMode::Density>());
      break;
  }
}

/// Calls f(std::true_type()) or f(std::false_type()) for a flag known at run
/// time, the kernels' template switch (counters, lighting).
template <typename F>
void withFlag(bool flag, F&& f)
{
  if (flag)
  {
    f(std::true_type());
  }
  else
  {
    f(std::false_type());
  }
}

/// Most samples per pixel one pair of deferred launches traces
/// (RenderLaunch::deferredBatch): 8 restores a whole image's paths per
/// launch to one of 8 processes' rows of a split image.
constexpr size_t kMaxDeferredBatch = 8;
/// Paths one pair of deferred launches is given where the batch allows
/// (those of a 1024^2 image, which fill the GPUs measured).
constexpr size_t kFullLaunchPaths = size_t(1) << 20;

/// Blocks of `block` threads covering an image of width x height pixels,
/// one thread per pixel.
inline dim3 imageGrid(dim3 block, int width, int height)
{
  return dim3((unsigned(width) + block.x - 1) / block.x, (unsigned(height) + block.y - 1) / block.y);
}

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

/// The type a voxel stored as T on the host has in device memory: float64
/// channels are uploaded as float32 (uploadChannels()), so per-type device
/// code is never compiled for double.
template <typename T>
using DeviceScalar = std::conditional_t<std::is_same<T, double>::value, float, T>;

/// One channel in device memory, held once: as a 3D texture (array, linear
/// and point objects) or as a dense array (bytes), never both.
struct DeviceChannel
{
  /// Dense array in the native type (float64 converted to float32 on
  /// upload); empty when texture-held.
  DeviceBuffer<uint8_t> bytes;
  ScalarType type = ScalarType::Float32;
  /// Extinction: 4 floats per voxel, a float4 texture of the sanitised voxels
  /// (texture sampling, NaN-free channels) or packed (stride 4) in `bytes`.
  ChannelFormat format = ChannelFormat::Scalar;
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

/// A scalar channel classifyLevel() copied to the device (CUDAPyramid.cu),
/// kept while its key matches (ClassifyInput::dataVersion nonzero).
struct LevelInput
{
  const void* host = nullptr;
  ScalarType type = ScalarType::Float32;
  int64_t stride = 1;
  size_t elements = 0; ///< copied elements: (voxels - 1) * stride + 1
  uint64_t version = 0;
  DeviceBuffer<uint8_t> data;
};

/// What the visibility optimization's kernel reads besides a render's
/// buffers (CUDALaunch.cu): the per-pixel importance segment lists and the
/// refining pass of this render (-1: none, the lists are final).
struct ImportanceLaunch
{
  ImportanceSegment* segments = nullptr;
  uint8_t* counts = nullptr;
  float* totals = nullptr;
  int refinePass = -1;
};

/**
 * Everything the renderer keeps on the device, and the versions it was made
 * from. The members are defined where their work is done:
 * - CUDARenderer.cu: sync() (what to refresh at each render), device setup
 *   and queries;
 * - CUDAUpload.cu: uploadChannels(), moveNonFiniteToArrays();
 * - CUDAAcceleration.cu: buildRanges(), buildMajorants();
 * - CUDALaunch.cu: render() and readBack() use Accum, Depth and Counters;
 * - CUDAMarch.cu: march(), the ray-marching reference, on the same copies;
 * - CUDAPyramid.cu: classifyLevel(), pyramid levels built on the device.
 */
/// Device copy of a Scene's stand-in for lighting across pieces
/// (Scene::setOutside): its channels, tables and host-built majorants, and
/// the per-render view the kernels' SceneView::outside points to. A scalar
/// channel of finite voxels is a texture under texture sampling, as the
/// piece's channels are (light paths spend most of their time reading the
/// stand-in once it is exact); the others are packed arrays read in
/// software, as the CPU reads them.
struct OutsideCopy
{
  uint64_t SceneId = 0;
  uint64_t ContentVersion = ~0ull;
  uint64_t DataVersion = ~0ull;
  DeviceBuffer<uint8_t> Channels[kMaxChannels];
  DeviceChannel Textures[kMaxChannels];
  DeviceBuffer<float> Tables;
  DeviceBuffer<float> Majorants;
  DeviceBuffer<SceneView> View;
  /// The per-render view as the host sends it to a lit kernel as its
  /// light view (RenderLaunch::light) when the stand-in is exact.
  SceneView HostView;
  size_t bytes() const
  {
    size_t b = this->Tables.bytes() + this->Majorants.bytes() + this->View.bytes();
    for (const DeviceBuffer<uint8_t>& c : this->Channels)
    {
      b += c.bytes();
    }
    for (const DeviceChannel& t : this->Textures)
    {
      b += t.array ? t.arrayBytes : 0;
    }
    return b;
  }
};

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
  /// Running mean of the even samples (Accumulator::evenRGBA), for the
  /// error estimate; AccumEven: it is in step with Accum.
  DeviceBuffer<float4> Even;
  bool AccumEven = false;
  /// Each pixel's sum of its samples (RGBA, Accumulator::sums), and the even
  /// half's; AccumSumsCurrent: they hold Accum's samples (the ray marcher
  /// writes Accum alone).
  DeviceBuffer<double> AccumSums;
  DeviceBuffer<double> EvenSums;
  bool AccumSumsCurrent = false;
  bool SkipEvenReadBack = false; ///< set by render() for RenderSettings::readBackEven off
  bool PlainKernels = true;      ///< setPlainKernels()
  bool DeferShadows = true;      ///< setDeferredShadows()
  unsigned DeferredBatch = 4;    ///< setDeferredBatch()
  bool DeviceLevels = true;      ///< setDeviceLevels()
  /// The deferred shadow rays' queue (RenderLaunch::deferred), one entry
  /// per path of a launch (kept at the most rendered), and its count.
  DeviceBuffer<DeferredShadows> Deferred;
  DeviceBuffer<unsigned> DeferredCount;
  /// Batches of deferred samples (RenderLaunch::deferredSlots): up to
  /// kMaxDeferredBatch images, kept at the largest batch rendered.
  DeviceBuffer<float4> DeferredSlots;
  /// displayImage(): the 8-bit image on the device and its page-locked host copy.
  DeviceBuffer<uchar4> Display;
  uint8_t* DisplayHost = nullptr;
  size_t DisplayHostBytes = 0;
  DeviceBuffer<float> Depth;
  std::vector<float> LastDepth;
  bool HaveDepth = false;
  /// The depth image's pixels where a ray can start (depth above 0),
  /// counted when it is uploaded (deviceDepth()).
  size_t OpenDepthPixels = 0;
  DeviceBuffer<unsigned long long> Counters;
  // Visibility optimization: the importance tables and the per-pixel segment
  // lists of the Accumulator PoolId (restarted when another one renders).
  DeviceBuffer<float> ImportanceTables; ///< [channel][K]
  std::vector<float> LastImportanceTables;
  DeviceBuffer<ImportanceSegment> Segments; ///< [pixel][kImportanceCapacity]
  DeviceBuffer<uint8_t> SegmentCounts;
  DeviceBuffer<float> SegmentTotals;
  uint64_t PoolId = 0;
  cudaEvent_t Start = nullptr;
  cudaEvent_t Stop = nullptr;
  /// renderPilots(): the one-sample images, the counters (a block of 9 per
  /// job for replicate 0, one more for the rest) and the streams.
  DeviceBuffer<float4> PilotImages;
  DeviceBuffer<unsigned long long> PilotCounters;
  std::vector<cudaStream_t> PilotStreams;
  /// Page-locked host copy of PilotImages (a copy from pageable memory
  /// goes through a staging buffer of the driver), PilotHostCount floats.
  float* PilotHost = nullptr;
  size_t PilotHostCount = 0;
  /// Page-locked host copy of PilotCounters, PilotHostCounterCount items.
  unsigned long long* PilotHostCounters = nullptr;
  size_t PilotHostCounterCount = 0;
  /// One event per pilot stream: the first stream's "buffers cleared" and
  /// the others' "launches done", so that a round never touches the legacy
  /// default stream, where a frame rendered ahead (ChoiceAhead) runs.
  std::vector<cudaEvent_t> PilotEvents;
  bool ConcurrentPilots = true;
  /// classifyLevel()'s kept inputs (CUDAPyramid.cu).
  std::vector<std::unique_ptr<LevelInput>> LevelInputs;
  OutsideCopy Outside;
  /// Cached shadows (LightingDesc::cacheShadows): each light's grid and the
  /// key it was filled for (CUDAShadowCache.cu).
  DeviceBuffer<float> ShadowGrids[kMaxLights];
  ShadowCacheFrame ShadowFrames[kMaxLights];
  ShadowCacheKey ShadowKeys[kMaxLights];
  bool ShadowValid[kMaxLights] = {};

  CudaUpdateCounters Updates;

  Internal() = default;
  Internal(const Internal&) = delete;
  Internal& operator=(const Internal&) = delete;
  ~Internal()
  {
    cudaSetDevice(this->Device);
    if (this->DisplayHost)
    {
      cudaFreeHost(this->DisplayHost);
    }
    if (this->PilotHost)
    {
      cudaFreeHost(this->PilotHost);
    }
    if (this->PilotHostCounters)
    {
      cudaFreeHost(this->PilotHostCounters);
    }
    for (cudaEvent_t e : this->PilotEvents)
    {
      cudaEventDestroy(e);
    }
    if (this->Start)
    {
      cudaEventDestroy(this->Start);
    }
    if (this->Stop)
    {
      cudaEventDestroy(this->Stop);
    }
    for (cudaStream_t st : this->PilotStreams)
    {
      cudaStreamDestroy(st);
    }
  }

  /// Holds each channel once: a texture (Texture sampling, if it fits) or a dense array.
  void uploadChannels(const Scene& scene);
  /// Makes dc a texture-held channel from dense host voxels of dc.type,
  /// of the Scene's dimensions or `dims`; false (nothing allocated) when
  /// the device has no room.
  bool uploadTexture(DeviceChannel& dc, const void* host, const int* dims = nullptr);
  /// After buildRanges(): texture-held channels with NaN or Inf voxels move
  /// to dense arrays (the core's NaN rule needs unfiltered reads).
  void moveNonFiniteToArrays(const Scene& scene);
  /// apron: footprintApron() of the scene's interpolation (Acceleration.h).
  void buildRanges(int macrocell, int apron);
  void buildMajorants(const Scene& scene, const bool* which);
  void sync(const Scene& scene);
  // CUDALaunch.cu: what a Monte Carlo render and a march both need.
  /// The per-render device view (after sync()): blend, interpolation,
  /// channels (hardware-filtered reads of texture-held channels when
  /// `textures`) and lighting; no
  /// importance, no per-camera fields.
  SceneView renderView(const Scene& scene, bool textures);
  /// The depth image on the device (uploaded when it changed), or nullptr.
  const float* deviceDepth(const float* depth, size_t pixels);
  /// CUDAOutside.cu: a lit Scene's stand-in (Scene::setOutside) on the
  /// device, uploaded when it changed, and s.outside pointing to its
  /// per-render view (prepareOutside(), as on the CPU); s.outside null
  /// without one. Call after the lighting frame of `s` is set.
  void linkOutside(const Scene& scene, const Camera& camera, SceneView& s);
  /// CUDAShadowCache.cu: the cached shadows `s` asks for (cachesShadow()),
  /// filled when their key changed, and s's lighting pointing at them; the
  /// grids it does not ask for are freed. Call after linkOutside().
  void linkShadowCaches(const Scene& scene, SceneView& s);
  size_t shadowCacheBytes() const;
  /// The Scene's importance tables on the device (uploaded when they changed).
  const float* deviceImportanceTables(const Scene& scene);
  /// render(): makes Accum and AccumSums (and Even and EvenSums, when
  /// `accum` keeps the error estimate) hold `accum`'s image, continuing the
  /// device copy when it is current, and points the launch's buffers at
  /// them (even ones null without the estimate).
  void deviceAccumulation(Accumulator& accum, size_t pixels, RenderLaunch& launch);
  /// render() with the visibility optimization: the view's importance
  /// fields, the device tables and segment lists of `accum` (restarted with
  /// its image); returns its pool and fills `launch`.
  Accumulator::ImportancePool& deviceImportance(const Scene& scene, const Camera& camera, Accumulator& accum,
    SceneView& s, size_t pixels, ImportanceLaunch& launch);
  /// renderPilots(): sizes the round's buffers and streams and clears the
  /// images and counters on the first stream, which the others wait for.
  /// Returns the pixels of images the buffers are reserved for.
  size_t startPilotRound(size_t images, size_t pixels, size_t jobs);
  /// renderPilots(): one launch per job, each on a pilot stream of its own;
  /// the first stream then waits for the others.
  void launchPilots(const Scene& scene, const Camera& camera, const std::vector<PilotJob>& jobs);
  /// renderPilots(): copies `floats` floats of images and `counterItems`
  /// counters to the page-locked host copies (grown to `reservedFloats`)
  /// and waits for them.
  void pilotsToHost(size_t floats, size_t reservedFloats, size_t counterItems);
  double elapsedMs()
  {
    float ms = 0.f;
    MCVOL_CUDA(cudaEventSynchronize(this->Stop));
    MCVOL_CUDA(cudaEventElapsedTime(&ms, this->Start, this->Stop));
    return double(ms);
  }
};
} // namespace mcvol
