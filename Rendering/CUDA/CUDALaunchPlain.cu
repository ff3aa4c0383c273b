// SPDX-License-Identifier: BSD-3-Clause
//
// The unlit render kernels for plain scenes: scalar channels only, linear or
// nearest interpolation (CUDARenderKernels.h says why they are compiled
// twice). MCVOL_DEVICE_PLAIN_CHANNELS changes device code only (Blend.h's
// channelOptics under __CUDA_ARCH__), so the host code of the core's inline
// functions is the same in every translation unit.
#define MCVOL_DEVICE_PLAIN_CHANNELS 1
#include "CUDARenderKernels.h"

namespace mcvol
{
void launchPlainUnlit(BlendMode mode, bool count, int unlit, dim3 grid, dim3 block, const SceneView& s,
  const CameraView& cam, const FrameParams& fp, const float* depth, float4* accum, float4* even, uint32_t previous,
  unsigned long long* counters, cudaStream_t stream)
{
  switch (mode)
  {
    case BlendMode::Max:
      launchUnlit<BlendMode::Max>(unlit, count, grid, block, s, cam, fp, depth, accum, even, previous, counters, stream);
      break;
    case BlendMode::Mix:
      launchUnlit<BlendMode::Mix>(unlit, count, grid, block, s, cam, fp, depth, accum, even, previous, counters, stream);
      break;
    case BlendMode::Composite:
      launchUnlit<BlendMode::Composite>(unlit, count, grid, block, s, cam, fp, depth, accum, even, previous, counters, stream);
      break;
    case BlendMode::Density:
    default:
      launchUnlit<BlendMode::Density>(unlit, count, grid, block, s, cam, fp, depth, accum, even, previous, counters, stream);
      break;
  }
}
} // namespace mcvol
