// SPDX-License-Identifier: BSD-3-Clause
//
// The render kernels' entry points and their per-pixel helpers, shared by
// the two translation units that instantiate them:
// - CUDALaunch.cu: every kernel, for every scene (pre-classified channels,
//   cubic interpolation, lighting, the visibility optimization);
// - CUDALaunchPlain.cu: the unlit kernels again, compiled with
//   MCVOL_DEVICE_PLAIN_CHANNELS, for scenes of scalar channels with linear or
//   nearest interpolation (the common case; CUDARenderer::setPlainKernels,
//   on by default). There channelOptics() has no
//   out-of-line call for pre-classified or cubic sampling, whose register
//   needs otherwise weigh on every kernel that can make it (ptxas, sm_90:
//   unlit kernels 72-80 instead of 116-124 registers; on the H100 an
//   expected-value NYX-like frame took 1.05 ms with the pre-classified call
//   alone, 1.24 ms with cubic sampling added and 0.86 ms with the plain
//   kernels, Benchmarks/RESULTS.md).
// Included once per translation unit, inside namespace mcvol.
#pragma once

#include "CUDAInternal.h"

#include "mcvol/RenderSetup.h"

namespace mcvol
{
namespace
{
// Warp sums with shuffles (any architecture from sm_70), 64-bit so that high
// sample counts cannot wrap.
__device__ MCVOL_FORCE_INLINE unsigned long long warpSumU64(unsigned long long v)
{
  for (int o = 16; o > 0; o >>= 1)
  {
    v += __shfl_xor_sync(0xffffffffu, v, o);
  }
  return v;
}

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
/// atomic per warp and counter).
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
  // every render of the mapper, read the frame's parameters as before
  // (their PTX is unchanged by the batch). Read in every kernel, the copy
  // made the expected-value frame 7.5% slower on the H100 (NYX-like 0.75 ->
  // 0.81 ms; Benchmarks/RESULTS.md, eighteenth session).
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
    const Vec4f sum =
      renderPixel<Mode, Lit, false, Unlit>(s, cam, f, x, y, z, c, nullptr, even ? &evenSum : nullptr);
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

template <BlendMode Mode, bool Count, bool Lit, int Unlit = 0>
__global__ void renderKernel(const __grid_constant__ SceneView s, const __grid_constant__ CameraView cam,
  const __grid_constant__ FrameParams fp, const float* __restrict__ depth, float4* __restrict__ accum,
  float4* __restrict__ even, uint32_t previous, unsigned long long* __restrict__ counters)
{
  renderKernelBody<Mode, Count, Lit, Unlit>(s, cam, fp, depth, accum, even, previous, counters);
}

/// The unlit kernels, a separate entry so that a build can cap their registers
/// without touching the lit ones: -DMCVOL_UNLIT_MAXREG=N (off by default).
/// Measured on the H100 (NYX-like, 1024^2; unlit kernels at 114-118
/// registers): a cap of 96 (spilling 140-200 bytes) made the 1-DDA frame 0.83
/// -> 0.77 ms and the expected-value one 1.24 -> 1.13 ms; 112 changed
/// nothing; 80 spilled too much (1-DDA 1.37 ms). Without float4 texture reads
/// in the kernels (the default build) they need 96-106 registers and
/// the expected-value frame takes 1.05 ms uncapped.
#if defined(MCVOL_UNLIT_MAXREG) && MCVOL_UNLIT_MAXREG > 0
#define MCVOL_UNLIT_BOUNDS __maxnreg__(MCVOL_UNLIT_MAXREG)
#else
#define MCVOL_UNLIT_BOUNDS
#endif
template <BlendMode Mode, bool Count, int Unlit>
__global__ void MCVOL_UNLIT_BOUNDS renderKernelUnlit(const __grid_constant__ SceneView s,
  const __grid_constant__ CameraView cam, const __grid_constant__ FrameParams fp, const float* __restrict__ depth,
  float4* __restrict__ accum, float4* __restrict__ even, uint32_t previous, unsigned long long* __restrict__ counters)
{
  renderKernelBody<Mode, Count, false, Unlit>(s, cam, fp, depth, accum, even, previous, counters);
}

/// Launches the unlit kernel of estimator code Unlit (unlitEstimator()),
/// with or without counters. Composite is only ever launched with 0.
template <BlendMode Mode, int Unlit>
void launchUnlitKernel(bool count, dim3 grid, dim3 block, const SceneView& s, const CameraView& cam,
  const FrameParams& fp, const float* depth, float4* accum, float4* even, uint32_t previous,
  unsigned long long* counters, cudaStream_t stream)
{
  if constexpr (Unlit == 0 || Mode != BlendMode::Composite)
  {
    if (count)
    {
      renderKernelUnlit<Mode, true, Unlit><<<grid, block, 0, stream>>>(s, cam, fp, depth, accum, even, previous, counters);
    }
    else
    {
      renderKernelUnlit<Mode, false, Unlit><<<grid, block, 0, stream>>>(s, cam, fp, depth, accum, even, previous, counters);
    }
  }
}

/// The same for a runtime estimator code.
template <BlendMode Mode>
void launchUnlit(int unlit, bool count, dim3 grid, dim3 block, const SceneView& s, const CameraView& cam,
  const FrameParams& fp, const float* depth, float4* accum, float4* even, uint32_t previous,
  unsigned long long* counters, cudaStream_t stream)
{
  if (unlit == 3)
  {
    launchUnlitKernel<Mode, 3>(count, grid, block, s, cam, fp, depth, accum, even, previous, counters, stream);
  }
  else if (unlit == 2)
  {
    launchUnlitKernel<Mode, 2>(count, grid, block, s, cam, fp, depth, accum, even, previous, counters, stream);
  }
  else if (unlit == 1)
  {
    launchUnlitKernel<Mode, 1>(count, grid, block, s, cam, fp, depth, accum, even, previous, counters, stream);
  }
  else
  {
    launchUnlitKernel<Mode, 0>(count, grid, block, s, cam, fp, depth, accum, even, previous, counters, stream);
  }
}

} // namespace

/// CUDALaunchPlain.cu: launches the plain unlit kernel of `mode` (estimator
/// code `unlit`, with or without counters) on `stream`.
void launchPlainUnlit(BlendMode mode, bool count, int unlit, dim3 grid, dim3 block, const SceneView& s,
  const CameraView& cam, const FrameParams& fp, const float* depth, float4* accum, float4* even, uint32_t previous,
  unsigned long long* counters, cudaStream_t stream);
} // namespace mcvol
