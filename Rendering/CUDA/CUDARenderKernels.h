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
  float4* even = nullptr;                 ///< even-sample mean of the error estimate, or null
  uint32_t previous = 0;                  ///< samples already in the mean
  unsigned long long* counters = nullptr; ///< work counters (counting kernels)
};

namespace
{
/// The core's running mean (accumulate()) on one pixel of the device image.
__device__ MCVOL_FORCE_INLINE void accumulatePixel(float4* pixel, const Vec4f& sum, uint32_t previous, int added)
{
  const float4 old = *pixel;
  float v[4] = { old.x, old.y, old.z, old.w };
  accumulate(v, sum, previous, added);
  *pixel = make_float4(v[0], v[1], v[2], v[3]);
}

/// The even half of the error estimate (accumulateEven()) on one pixel of
/// the device's even-sample image.
__device__ MCVOL_FORCE_INLINE void accumulateEvenPixel(float4* pixel, const Vec4f& sum, uint32_t previous, int added)
{
  if (addedEvenSamples(previous, added) == 0u)
  {
    return; // no sample of even index in this render: leave the pixel unread
  }
  const float4 old = *pixel;
  float v[4] = { old.x, old.y, old.z, old.w };
  accumulateEven(v, sum, previous, added);
  *pixel = make_float4(v[0], v[1], v[2], v[3]);
}

/// One thread per pixel: renderPixel() from the core, folded into the
/// running mean in `accum` (and the even samples into `even`, when not
/// null: the error estimate). Count adds the work counters (warp sums, one
/// atomic per warp and counter). Lit false compiles the lighting out; Unlit
/// is the unlit estimator's code (unlitEstimator(), Integrator.h).
template <BlendMode Mode, bool Count, bool Lit, int Unlit>
__device__ __forceinline__ void renderKernelBody(const SceneView& s, const CameraView& cam, const FrameParams& fp,
  const float* __restrict__ depth, float4* __restrict__ accum, float4* __restrict__ even, uint32_t previous,
  unsigned long long* __restrict__ counters)
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
    Vec4f evenSum;
    const Vec4f sum = renderPixel<Mode, Lit, false, Unlit>(s, cam, f, x, y, z, c, nullptr, even ? &evenSum : nullptr);
    accumulatePixel(accum + p, sum, previous, fp.samplesPerPixel);
    if (even)
    {
      accumulateEvenPixel(even + p, evenSum, previous, fp.samplesPerPixel);
    }
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

/// The render kernel: renderKernelBody() on the kernel's parameters.
template <BlendMode Mode, bool Count, bool Lit, int Unlit = 0>
__global__ void renderKernel(const __grid_constant__ SceneView s, const __grid_constant__ CameraView cam,
  const __grid_constant__ FrameParams fp, const float* __restrict__ depth, float4* __restrict__ accum,
  float4* __restrict__ even, uint32_t previous, unsigned long long* __restrict__ counters)
{
  renderKernelBody<Mode, Count, Lit, Unlit>(s, cam, fp, depth, accum, even, previous, counters);
}

/// Launches renderKernel<Mode, Count, Lit, Unlit> with `count` as Count.
template <BlendMode Mode, bool Lit, int Unlit>
void launchRenderKernel(
  bool count, const SceneView& s, const CameraView& cam, const FrameParams& fp, const RenderLaunch& k)
{
  withFlag(count,
    [&](auto counted)
    {
      renderKernel<Mode, decltype(counted)::value, Lit, Unlit>
        <<<k.grid, k.block, 0, k.stream>>>(s, cam, fp, k.depth, k.accum, k.even, k.previous, k.counters);
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
/// estimator), with or without counters. Post-render composite only ever
/// takes code 0.
template <BlendMode Mode>
void launchLit(
  int unlit, bool count, const SceneView& s, const CameraView& cam, const FrameParams& fp, const RenderLaunch& k)
{
  if constexpr (Mode == BlendMode::Composite)
  {
    launchRenderKernel<Mode, true, 0>(count, s, cam, fp, k);
  }
  else
  {
    unlit == 1 ? launchRenderKernel<Mode, true, 1>(count, s, cam, fp, k)
               : launchRenderKernel<Mode, true, 0>(count, s, cam, fp, k);
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
