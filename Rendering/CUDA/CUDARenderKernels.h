// SPDX-License-Identifier: BSD-3-Clause
//
// The render kernels' entry points, their per-pixel helpers and their
// launcher, shared by the two translation units that compile them:
// - CUDALaunch.cu: every kernel, for every scene (pre-classified channels,
//   cubic interpolation, lighting, the visibility optimization);
// - CUDALaunchPlain.cu: the unlit and lit kernels again, compiled with
//   MCVOL_DEVICE_PLAIN_CHANNELS, for scenes of scalar channels with linear or
//   nearest interpolation (the common case; CUDARenderer::setPlainKernels,
//   on by default). There channelOptics() has no out-of-line call for
//   pre-classified or cubic sampling. On the GPU an out-of-line function
//   shares the registers of every kernel that can call it, so without it the
//   kernels need far fewer registers per thread (ptxas
//   --resource-usage), keep more rays in flight and finish a frame sooner
//   (Documentation/performance.md).
// Included once per translation unit: the kernels and launchUnlit() sit in
// an anonymous namespace, so each unit has its own compilation of them.
#pragma once

#include "CUDAInternal.h"

#include <algorithm>

#include "mcvol/RenderSetup.h"

namespace mcvol
{
/// One launch of a render kernel: its blocks, its stream and the buffers the
/// kernel takes after the frame's parameters.
struct RenderLaunch
{
  dim3 grid;
  dim3 block;
  cudaStream_t stream = 0;                ///< 0: the legacy default stream
  const float* depth = nullptr;           ///< window depth per pixel, or null
  float4* accum = nullptr;                ///< running mean
  double* sums = nullptr;                 ///< the mean's per-pixel sums (RGBA), or null: previous is 0
  float4* even = nullptr;                 ///< even-sample mean of the error estimate, or null
  double* evenSums = nullptr;             ///< its sums (with even)
  uint32_t previous = 0;                  ///< samples already in the mean
  unsigned long long* counters = nullptr; ///< work counters (counting kernels)
  /// Lit kernels: the view light paths run in (lightView(): the exact
  /// stand-in's view with its device pointers, or the render's own view).
  const SceneView* light = nullptr;
  /// Lit renders whose shadow rays wait for a kernel of their own
  /// (deferrableShadows(), CUDARenderer::setDeferredShadows): room for
  /// `deferredRoom` DeferredShadows (every path of a launch pair), and the
  /// count queued. Null otherwise.
  DeferredShadows* deferred = nullptr;
  unsigned* deferredCount = nullptr;
  size_t deferredRoom = 0;
  /// Samples per pixel that one pair of deferred launches traces (1: one
  /// at a time, folded as they finish): CUDARenderer::setDeferredBatch()'s
  /// count when a render asks for several, and more when few pixels can
  /// have rays (a small image, or a depth mask: one process's rows of a
  /// split image), so that a launch holds as many paths as a 1024^2 image's
  /// (kFullLaunchPaths). A launch lasts as long as its longest paths,
  /// however few it holds. Each batch's samples wait in `deferredSlots`
  /// (deferredBatch images) and are folded in order.
  unsigned deferredBatch = 1;
  float4* deferredSlots = nullptr;
};

namespace
{
/// The core's accumulation on pixel p of the device image: its sum of
/// `previous` samples (loadSum(); zero without a sums buffer).
__device__ MCVOL_FORCE_INLINE Vec4d pixelSum(const double* sums, size_t p, uint32_t previous)
{
  return loadSum(sums ? sums + 4 * p : nullptr, previous);
}

/// Stores pixel p's sum of `samples` samples and its mean (storeSum()).
__device__ MCVOL_FORCE_INLINE void storePixel(float4* mean, double* sums, size_t p, const Vec4d& sum, uint32_t samples)
{
  float v[4];
  storeSum(v, sums ? sums + 4 * p : nullptr, sum, samples);
  mean[p] = make_float4(v[0], v[1], v[2], v[3]);
}

/// Renders pixel (x, y) into the running mean and sums, and the error
/// estimate's even half when `even` is not null; the even half is neither
/// read nor written by a render that adds no sample of even index.
template <BlendMode Mode, bool Lit, bool Optimized, int Unlit>
__device__ MCVOL_FORCE_INLINE void renderIntoPixel(const SceneView& s, const SceneView& light, const CameraView& cam,
  const FrameParams& fp, int x, int y, float z, size_t p, RayCounters& c, const RayImportance* ri, float4* accum,
  double* sums, float4* even, double* evenSums, uint32_t previous)
{
  const bool addsEven = even && addedEvenSamples(previous, fp.samplesPerPixel) > 0u;
  Vec4d sum = pixelSum(sums, p, previous);
  Vec4d evenSum = addsEven ? pixelSum(evenSums, p, evenSampleCount(previous)) : Vec4d();
  renderPixel<Mode, Lit, Optimized, Unlit>(s, light, cam, fp, x, y, z, c, sum, ri, addsEven ? &evenSum : nullptr);
  const uint32_t total = previous + uint32_t(fp.samplesPerPixel);
  storePixel(accum, sums, p, sum, total);
  if (addsEven)
  {
    storePixel(even, evenSums, p, evenSum, evenSampleCount(total));
  }
}

/// One thread per pixel: renderPixel() from the core, folded into the
/// running mean in `accum` (and the even samples into `even`, when not
/// null: the error estimate). Count adds the work counters (warp sums, one
/// atomic per warp and counter). Lit false compiles the lighting out; Unlit
/// is the unlit estimator's code (unlitEstimator(), Integrator.h).
template <BlendMode Mode, bool Count, bool Lit, int Unlit>
__device__ __forceinline__ void renderKernelBody(const SceneView& s, const SceneView& light, const CameraView& cam,
  const FrameParams& fp, const float* __restrict__ depth, float4* __restrict__ accum, double* __restrict__ sums, float4* __restrict__ even,
  double* __restrict__ evenSums, uint32_t previous, unsigned long long* __restrict__ counters)
{
  const int x = int(blockIdx.x * blockDim.x + threadIdx.x);
  const int y = int(blockIdx.y * blockDim.y + threadIdx.y);
  RayCounters c;
  // A batch of pilot images (FrameParams::batchSamples): this block's image,
  // sample and replicate from blockIdx.z. Only in the counting kernels, which
  // are what the pilots launch (CUDARenderer::renderPilots): the others,
  // every render of the mapper, read the frame's parameters directly and
  // carry no code for the batch, since the copy of the parameters costs
  // registers and frame time in every kernel that makes it.
  FrameParams batch = fp;
  if constexpr (Count)
  {
    if (fp.batchSamples > 0)
    {
      const int image = int(blockIdx.z);
      const int replicate = image / fp.batchSamples;
      batch.firstSample = uint32_t(image - replicate * fp.batchSamples);
      if (replicate > 0)
      {
        batch.seed = fp.batchSeed;
        counters += fp.batchCounterOffset;
      }
      accum += size_t(image) * size_t(cam.width) * size_t(cam.height);
    }
  }
  const FrameParams& f = Count ? batch : fp;
  if (x < cam.width && y < cam.height)
  {
    const size_t p = size_t(y) * size_t(cam.width) + size_t(x);
    const float z = depth ? depth[p] : 1.f;
    renderIntoPixel<Mode, Lit, false, Unlit>(
      s, light, cam, f, x, y, z, p, c, nullptr, accum, sums, even, evenSums, previous);
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

/// Folds one sample of index `index` into pixel p (none when `v` is null:
/// the ray missed the volume): renderIntoPixel() for a render of one sample.
__device__ MCVOL_FORCE_INLINE void foldOneSample(const Vec4f* v, uint32_t index, size_t p, float4* accum, double* sums,
  float4* even, double* evenSums, uint32_t previous)
{
  Vec4d sum = pixelSum(sums, p, previous);
  if (v)
  {
    addSample(sum, *v);
  }
  storePixel(accum, sums, p, sum, previous + 1u);
  if (even && addedEvenSamples(previous, 1) > 0u)
  {
    Vec4d evenSum = pixelSum(evenSums, p, evenSampleCount(previous));
    if (v && (index & 1u) == 0u)
    {
      addSample(evenSum, *v);
    }
    storePixel(even, evenSums, p, evenSum, evenSampleCount(previous + 1u));
  }
}

/**
 * Registers per thread of the plain density-blending kernels, 255 (no cap)
 * elsewhere: the kernels that trace no shadow rays, the camera kernels whose
 * shadow rays are deferred (litDeferKernel()) and the deferred shadow rays'
 * kernel (plainShadowRegisterCap()). Each cap sits at a step of
 * occupancy (blocks of 8x8: 80 registers give 24 warps per SM, 88 22, 96
 * 20; blocks of 128 threads: 64 give 32) where the kernel would otherwise
 * take more registers and lose a step. The camera and shadow kernels are
 * latency-bound, so a step of warps outweighs the spills at these caps
 * (ptxas, sm_90: at most 40 bytes for the kernels without shadow rays, 148
 * for the expected-value camera kernel with deferred shadow rays, 80 for
 * the shadow rays' kernel); a step lower (88) the camera kernels spill
 * into their loops and are slower again (mcvol-bench --sections effects).
 */
template <BlendMode Mode, bool Lit, int Unlit>
constexpr int plainRegisterCap()
{
#if defined(MCVOL_DEVICE_PLAIN_CHANNELS)
  if constexpr (Mode == BlendMode::Density)
  {
    if constexpr (!Lit)
    {
      return Unlit <= 1 ? 80 : (Unlit == 2 ? 88 : 96);
    }
    else if constexpr ((Unlit & kLocalLight) != 0)
    {
      return (Unlit & 1) != 0 ? 96 : 88;
    }
    else if constexpr ((Unlit & kDeferredShadows) != 0)
    {
      return 96;
    }
  }
#endif
  return 255;
}

/// Registers per thread of deferredShadowKernel() (plainRegisterCap()).
template <BlendMode Mode>
constexpr int plainShadowRegisterCap()
{
#if defined(MCVOL_DEVICE_PLAIN_CHANNELS)
  if constexpr (Mode == BlendMode::Density)
  {
    return 64;
  }
#endif
  return 255;
}

/**
 * The camera rays of a lit render with deferred shadow rays, one sample per
 * pixel (fp.samplesPerPixel 1): a pixel whose path records shadow rays
 * (DeferredShadows) is queued, with its sample so far, for
 * deferredShadowKernel(); the others are folded into the image here. The
 * queue's order depends on the scheduling, the image does not: each entry
 * finishes its own pixel. One atomic per warp.
 */
template <BlendMode Mode, int Unlit>
__global__ void __maxnreg__((plainRegisterCap<Mode, true, Unlit + kDeferredShadows>()))
  litDeferKernel(const __grid_constant__ SceneView s, const __grid_constant__ CameraView cam,
  const __grid_constant__ FrameParams fp, const float* __restrict__ depth, float4* __restrict__ accum,
  double* __restrict__ sums, float4* __restrict__ even, double* __restrict__ evenSums, uint32_t previous,
  DeferredShadows* __restrict__ queue, unsigned* __restrict__ queued, float4* __restrict__ slots)
{
  const int x = int(blockIdx.x * blockDim.x + threadIdx.x);
  const int y = int(blockIdx.y * blockDim.y + threadIdx.y);
  DeferredShadows d;
  bool deferred = false;
  if (x < cam.width && y < cam.height)
  {
    const size_t p = size_t(y) * size_t(cam.width) + size_t(x);
    // A batch (RenderLaunch::deferredBatch): sample fp.firstSample + z,
    // kept in image z of the slots until foldSlotsKernel().
    const size_t slot = size_t(blockIdx.z) * size_t(cam.width) * size_t(cam.height) + p;
    RayCounters c;
    ShadowCounters sc;
    Vec4f v;
    const bool sampled = renderSample<Mode, true, false, Unlit + kDeferredShadows>(
      s, s, cam, fp, x, y, depth ? depth[p] : 1.f, fp.firstSample + blockIdx.z, c, sc, nullptr, v, &d);
    if (sampled && d.count > 0)
    {
      d.sample = v;
      d.pixel = uint32_t(slots ? slot : p);
      deferred = true;
    }
    else if (slots)
    {
      // A missed ray adds nothing: zero, as foldOneSample() adds none.
      slots[slot] = sampled ? make_float4(v.r, v.g, v.b, v.a) : make_float4(0.f, 0.f, 0.f, 0.f);
    }
    else
    {
      foldOneSample(sampled ? &v : nullptr, fp.firstSample, p, accum, sums, even, evenSums, previous);
    }
  }
  // Every thread of the block reaches this point; a warp's lanes are its
  // threads in linear order, the last warp of a block possibly partial.
  const unsigned linear = threadIdx.y * blockDim.x + threadIdx.x;
  const unsigned lane = linear & 31u;
  const unsigned inWarp = min(32u, blockDim.x * blockDim.y - (linear & ~31u));
  const unsigned warp = inWarp == 32u ? 0xffffffffu : (1u << inWarp) - 1u;
  const unsigned ballot = __ballot_sync(warp, deferred);
  if (ballot != 0u)
  {
    const int leader = __ffs(ballot) - 1;
    unsigned base = 0;
    if (int(lane) == leader)
    {
      base = atomicAdd(queued, unsigned(__popc(ballot)));
    }
    base = __shfl_sync(warp, base, leader);
    if (deferred)
    {
      queue[base + unsigned(__popc(ballot & ((1u << lane) - 1u)))] = d;
    }
  }
}

/// The queued shadow rays of litDeferKernel(), one pixel per thread in full
/// warps: each sample finished (finishDeferredSample()) and folded into its
/// pixel.
template <BlendMode Mode>
__global__ void __maxnreg__((plainShadowRegisterCap<Mode>()))
  deferredShadowKernel(const __grid_constant__ SceneView s, uint32_t index, float4* __restrict__ accum,
  double* __restrict__ sums, float4* __restrict__ even, double* __restrict__ evenSums, uint32_t previous,
  const DeferredShadows* __restrict__ queue, const unsigned* __restrict__ queued, float4* __restrict__ slots)
{
  const unsigned i = blockIdx.x * blockDim.x + threadIdx.x;
  if (i >= *queued)
  {
    return;
  }
  DeferredShadows d = queue[i];
  const Vec4f v = finishDeferredSample<Mode>(s, d);
  if (slots)
  {
    slots[d.pixel] = make_float4(v.r, v.g, v.b, v.a);
    return;
  }
  foldOneSample(&v, index, d.pixel, accum, sums, even, evenSums, previous);
}

/// A batch of `batch` samples from their slots into the image, in sample
/// order (indices index, index + 1, ...), as one at a time would add them.
__global__ void foldSlotsKernel(size_t pixels, unsigned batch, uint32_t index, float4* __restrict__ accum,
  double* __restrict__ sums, float4* __restrict__ even, double* __restrict__ evenSums, uint32_t previous,
  const float4* __restrict__ slots)
{
  const size_t p = size_t(blockIdx.x) * blockDim.x + threadIdx.x;
  if (p >= pixels)
  {
    return;
  }
  for (unsigned b = 0; b < batch; ++b)
  {
    const float4 f = slots[size_t(b) * pixels + p];
    Vec4f v;
    v.r = f.x;
    v.g = f.y;
    v.b = f.z;
    v.a = f.w;
    foldOneSample(&v, index + b, p, accum, sums, even, evenSums, previous + b);
  }
}

/// Threads per block of deferredShadowKernel().
constexpr unsigned kDeferredBlock = 128;

/// A lit render with deferred shadow rays (RenderLaunch::deferred): per
/// sample, litDeferKernel() and deferredShadowKernel(), one after the other
/// on the launch's stream. The samples go into the image one at a time as
/// renderPixel() adds them, so the image is the same however many a render
/// asks for.
template <BlendMode Mode, int Unlit>
void launchDeferred(const SceneView& s, const CameraView& cam, const FrameParams& fp, const RenderLaunch& k)
{
  const size_t P = size_t(cam.width) * size_t(cam.height);
  FrameParams one = fp;
  one.samplesPerPixel = 1;
  const int batch = k.deferredSlots ? int(k.deferredBatch) : 1;
  for (int j = 0; j < fp.samplesPerPixel; j += batch)
  {
    const unsigned n = unsigned(std::min(batch, fp.samplesPerPixel - j));
    one.firstSample = fp.firstSample + uint32_t(j);
    const uint32_t previous = k.previous + uint32_t(j);
    float4* slots = n > 1 ? k.deferredSlots : nullptr;
    // Threads for every path the camera kernel may queue; those beyond the
    // count return at once.
    const size_t paths = std::min(k.deferredRoom, size_t(n) * P);
    const unsigned blocks = unsigned((paths + kDeferredBlock - 1) / kDeferredBlock);
    MCVOL_CUDA(cudaMemsetAsync(k.deferredCount, 0, sizeof(unsigned), k.stream));
    litDeferKernel<Mode, Unlit><<<dim3(k.grid.x, k.grid.y, n), k.block, 0, k.stream>>>(
      s, cam, one, k.depth, k.accum, k.sums, k.even, k.evenSums, previous, k.deferred, k.deferredCount, slots);
    deferredShadowKernel<Mode><<<blocks, kDeferredBlock, 0, k.stream>>>(
      s, one.firstSample, k.accum, k.sums, k.even, k.evenSums, previous, k.deferred, k.deferredCount, slots);
    if (slots)
    {
      foldSlotsKernel<<<unsigned((P + 255) / 256), 256, 0, k.stream>>>(
        P, n, one.firstSample, k.accum, k.sums, k.even, k.evenSums, previous, slots);
    }
  }
}

/// The unlit render kernel: renderKernelBody() on the kernel's parameters.
template <BlendMode Mode, bool Count, int Unlit = 0>
__global__ void __maxnreg__((plainRegisterCap<Mode, false, Unlit>()))
  renderKernel(const __grid_constant__ SceneView s, const __grid_constant__ CameraView cam,
  const __grid_constant__ FrameParams fp, const float* __restrict__ depth, float4* __restrict__ accum,
  double* __restrict__ sums, float4* __restrict__ even, double* __restrict__ evenSums, uint32_t previous,
  unsigned long long* __restrict__ counters)
{
  renderKernelBody<Mode, Count, false, Unlit>(s, s, cam, fp, depth, accum, sums, even, evenSums, previous, counters);
}

/// The lit render kernel, with the view its light paths run in
/// (RenderLaunch::light) as a parameter of its own: read through a pointer
/// that may be s or a stand-in in device memory, every field of the view
/// would be a generic load held in a register (150 to 224 registers
/// per thread, ptxas --resource-usage, sm_90); as a parameter, its fields
/// stay constant-bank operands, as s's do.
template <BlendMode Mode, bool Count, int Unlit = 0>
__global__ void __maxnreg__((plainRegisterCap<Mode, true, Unlit>()))
  litRenderKernel(const __grid_constant__ SceneView s, const __grid_constant__ SceneView light,
  const __grid_constant__ CameraView cam, const __grid_constant__ FrameParams fp, const float* __restrict__ depth,
  float4* __restrict__ accum, double* __restrict__ sums, float4* __restrict__ even, double* __restrict__ evenSums,
  uint32_t previous, unsigned long long* __restrict__ counters)
{
  renderKernelBody<Mode, Count, true, Unlit>(s, light, cam, fp, depth, accum, sums, even, evenSums, previous, counters);
}

/// Launches renderKernel<Mode, Count, Unlit>, or litRenderKernel when Lit,
/// with `count` as Count.
template <BlendMode Mode, bool Lit, int Unlit>
void launchRenderKernel(
  bool count, const SceneView& s, const CameraView& cam, const FrameParams& fp, const RenderLaunch& k)
{
  withFlag(count,
    [&](auto counted)
    {
      if constexpr (Lit)
      {
        litRenderKernel<Mode, decltype(counted)::value, Unlit><<<k.grid, k.block, 0, k.stream>>>(
          s, k.light ? *k.light : s, cam, fp, k.depth, k.accum, k.sums, k.even, k.evenSums, k.previous, k.counters);
      }
      else
      {
        renderKernel<Mode, decltype(counted)::value, Unlit><<<k.grid, k.block, 0, k.stream>>>(
          s, cam, fp, k.depth, k.accum, k.sums, k.even, k.evenSums, k.previous, k.counters);
      }
    });
}

/// Launches the unlit kernel of estimator code `unlit` (unlitEstimator(),
/// Integrator.h), with or without counters. Post-render composite only ever
/// takes code 0, so no other instance is compiled for it.
template <BlendMode Mode>
void launchUnlit(
  int unlit, bool count, const SceneView& s, const CameraView& cam, const FrameParams& fp, const RenderLaunch& k)
{
  if constexpr (Mode == BlendMode::Composite)
  {
    launchRenderKernel<Mode, false, 0>(count, s, cam, fp, k);
  }
  else
  {
    switch (unlit)
    {
      case 3:
        launchRenderKernel<Mode, false, 3>(count, s, cam, fp, k);
        break;
      case 2:
        launchRenderKernel<Mode, false, 2>(count, s, cam, fp, k);
        break;
      case 1:
        launchRenderKernel<Mode, false, 1>(count, s, cam, fp, k);
        break;
      default:
        launchRenderKernel<Mode, false, 0>(count, s, cam, fp, k);
        break;
    }
  }
}

/// Launches the lit kernel of estimator code `unlit` (unlitEstimator(): 1
/// the expected-value estimator of lit camera rays, 0 the collision
/// estimator, each plus kLocalLight for light paths that end at the camera
/// ray's collision), with or without counters; with RenderLaunch::deferred
/// and without counters, the deferred pair of kernels. This backend refuses
/// to light post-render composite before it launches (CUDARenderer::render),
/// so no lit composite kernel is compiled: it would only spill registers.
template <BlendMode Mode>
void launchLit(
  int unlit, bool count, const SceneView& s, const CameraView& cam, const FrameParams& fp, const RenderLaunch& k)
{
  if constexpr (Mode == BlendMode::Composite)
  {
    throw std::logic_error("mcvol: lit post-render composite reached the CUDA launcher");
  }
  else
  {
    if (k.deferred && !count && (unlit == 0 || unlit == 1))
    {
      if (unlit == 1)
      {
        launchDeferred<Mode, 1>(s, cam, fp, k);
      }
      else
      {
        launchDeferred<Mode, 0>(s, cam, fp, k);
      }
      return;
    }
    switch (unlit)
    {
      case 1 + kLocalLight:
        launchRenderKernel<Mode, true, 1 + kLocalLight>(count, s, cam, fp, k);
        break;
      case kLocalLight:
        launchRenderKernel<Mode, true, kLocalLight>(count, s, cam, fp, k);
        break;
      case 1:
        launchRenderKernel<Mode, true, 1>(count, s, cam, fp, k);
        break;
      default:
        launchRenderKernel<Mode, true, 0>(count, s, cam, fp, k);
        break;
    }
  }
}

/// launchLit() or launchUnlit() as the scene is lit or not.
template <BlendMode Mode>
void launchKernel(bool lit, int unlit, bool count, const SceneView& s, const CameraView& cam, const FrameParams& fp,
  const RenderLaunch& k)
{
  if (lit)
  {
    launchLit<Mode>(unlit, count, s, cam, fp, k);
  }
  else
  {
    launchUnlit<Mode>(unlit, count, s, cam, fp, k);
  }
}
} // namespace

/// CUDALaunchPlain.cu: launchKernel() for the blend mode known at run time,
/// with the plain compilation of the kernels (lit and unlit).
void launchPlain(BlendMode mode, bool lit, int unlit, bool count, const SceneView& s, const CameraView& cam,
  const FrameParams& fp, const RenderLaunch& k);
} // namespace mcvol
