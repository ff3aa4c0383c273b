// SPDX-License-Identifier: BSD-3-Clause
//
// The ray-marching reference on the GPU: one thread per pixel running
// marchPixel<Mode>() from the core (RayMarch.h, the same functions the OpenMP
// RayMarcher runs), over the device copies of the channels, tables,
// macrocells and majorants that the Monte Carlo renders use (sync(): nothing
// is uploaded twice). The checks and refusals are prepareMarch()'s, shared
// with the CPU march.
#include "CUDAInternal.h"

#include "mcvol/MarchSetup.h"
#include "mcvol/RenderSetup.h"

namespace mcvol
{
namespace
{
/// One thread per pixel: the pixel's reference value, written (not
/// accumulated) to `image`. Count adds the march counters (warp sums, one
/// atomic per warp and counter). Lit false compiles the lit march out.
template <BlendMode Mode, bool Lit, bool Count>
__global__ void marchKernel(const __grid_constant__ SceneView s, const __grid_constant__ CameraView cam,
  const __grid_constant__ MarchParams mp, bool jitter, uint32_t seed, const float* __restrict__ depth,
  float4* __restrict__ image, unsigned long long* __restrict__ counters)
{
  const int x = int(blockIdx.x * blockDim.x + threadIdx.x);
  const int y = int(blockIdx.y * blockDim.y + threadIdx.y);
  MarchCounters c;
  if (x < cam.width && y < cam.height)
  {
    const size_t p = size_t(y) * size_t(cam.width) + size_t(x);
    const float phase = marchPhase(jitter, uint32_t(p), seed);
    const Vec4f v = marchPixel<Mode, Lit>(s, cam, mp, x, y, depth ? depth[p] : 1.f, phase, c);
    image[p] = make_float4(v.r, v.g, v.b, v.a);
  }
  if (Count)
  {
    const unsigned long long smp = warpSumU64(c.samples);
    const unsigned long long skp = warpSumU64(c.skippedCells);
    const unsigned long long trm = warpSumU64(c.terminated);
    const unsigned lane = (threadIdx.y * blockDim.x + threadIdx.x) & 31u;
    if (lane == 0)
    {
      atomicAdd(counters + 0, smp);
      atomicAdd(counters + 1, skp);
      atomicAdd(counters + 2, trm);
    }
  }
}

/// Launches the march kernel for the blend mode, lighting and counting
/// known at run time. Post-render composite is never lit on this backend
/// (CUDARenderer::march() refuses it): no lit kernel is compiled for it.
void launchMarch(BlendMode mode, bool lit, bool count, dim3 grid, dim3 block, const SceneView& s, const CameraView& cam,
  const MarchParams& mp, bool jitter, uint32_t seed, const float* depth, float4* image, unsigned long long* counters)
{
  withBlendMode(mode,
    [&](auto m)
    {
      constexpr BlendMode Mode = decltype(m)::value;
      withFlag(lit,
        [&](auto l)
        {
          withFlag(count,
            [&](auto c)
            {
              constexpr bool Lit = decltype(l)::value && Mode != BlendMode::Composite;
              marchKernel<Mode, Lit, decltype(c)::value>
                <<<grid, block>>>(s, cam, mp, jitter, seed, depth, image, counters);
            });
        });
    });
}
} // namespace

void CUDARenderer::march(const Scene& scene, const Camera& camera, const MarchSettings& settings, const float* depth,
  Accumulator& accum, MarchCounters* counters)
{
  Internal& in = *this->In;
  MCVOL_CUDA(cudaSetDevice(in.Device));
  if (settings.deviceTextures && in.Sampling != CudaSampling::Texture)
  {
    throw std::invalid_argument("mcvol: MarchSettings::deviceTextures reads hardware-filtered textures, and this "
                                "renderer holds the channels as arrays (CudaSampling::Global): set texture sampling");
  }
  in.sync(scene);
  SceneView s = in.renderView(scene, settings.deviceTextures);
  const SceneView& hv = scene.view();
  if (hv.importance.enabled)
  {
    s.importance = hv.importance;
  }
  // The same checks, refusals and per-render fields as the CPU march.
  const MarchParams mp = prepareMarch(camera, settings, s);
  if (s.lighting.enabled && s.blend.mode == BlendMode::Composite)
  {
    // The composite kernels are compiled unlit (launchMarch()).
    throw std::invalid_argument("mcvol: the CUDA backend does not light post-render composite blending; use "
                                "the CPU backend, or density, max or mix blending");
  }
  if (s.importance.enabled)
  {
    s.importance.table = in.deviceImportanceTables(scene);
  }
  // Lit, one piece of a split volume: the stand-in of the other pieces.
  in.linkOutside(scene, camera, s);
  if (s.lighting.enabled)
  {
    in.linkShadowCaches(scene, s);
  }
  const CameraView cam = toView(camera);

  // The image goes to the device accumulation buffer, which then holds this
  // Accumulator's image at 1 sample (a Monte Carlo render of the same
  // Accumulator would continue from it, as from the host copy).
  const size_t P = size_t(camera.width) * size_t(camera.height);
  accum.resize(camera.width, camera.height);
  accum.reset();
  in.Accum.resize(P);
  in.AccumId = 0;
  in.AccumSumsCurrent = false; // the march writes the mean alone
  const float* devDepth = in.deviceDepth(depth, P);
  const bool count = counters != nullptr;
  if (count)
  {
    MCVOL_CUDA(cudaMemsetAsync(in.Counters.ptr, 0, 3 * sizeof(unsigned long long)));
  }
  const bool lit = s.lighting.enabled;
  const dim3 block = in.Block;
  const dim3 grid = imageGrid(block, camera.width, camera.height);
  launchMarch(s.blend.mode, lit, count, grid, block, s, cam, mp, settings.jitter, settings.seed, devDepth, in.Accum.ptr,
    in.Counters.ptr);
  MCVOL_CUDA(cudaGetLastError());
  accum.addSamples(1);
  in.AccumId = accum.id();
  in.AccumSamples = accum.samples();
  accum.setPendingOnDevice(true);
  this->readBack(accum); // waits for the kernel
  if (counters)
  {
    unsigned long long c[3] = {};
    MCVOL_CUDA(cudaMemcpy(c, in.Counters.ptr, sizeof(c), cudaMemcpyDeviceToHost));
    counters->samples += c[0];
    counters->skippedCells += c[1];
    counters->terminated += c[2];
  }
}
} // namespace mcvol
