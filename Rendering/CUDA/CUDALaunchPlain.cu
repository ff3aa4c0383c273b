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
namespace
{
template <BlendMode Mode>
void launchPlain(bool count, bool ev, dim3 grid, dim3 block, const SceneView& s, const CameraView& cam,
  const FrameParams& fp, const float* depth, float4* accum, float4* even, uint32_t previous,
  unsigned long long* counters)
{
  if (ev)
  {
    if (count)
    {
      renderKernelUnlit<Mode, true, true><<<grid, block>>>(s, cam, fp, depth, accum, even, previous, counters);
    }
    else
    {
      renderKernelUnlit<Mode, false, true><<<grid, block>>>(s, cam, fp, depth, accum, even, previous, counters);
    }
  }
  else if (count)
  {
    renderKernelUnlit<Mode, true, false><<<grid, block>>>(s, cam, fp, depth, accum, even, previous, counters);
  }
  else
  {
    renderKernelUnlit<Mode, false, false><<<grid, block>>>(s, cam, fp, depth, accum, even, previous, counters);
  }
}
} // namespace

void launchPlainUnlit(BlendMode mode, bool count, bool expectedValue, dim3 grid, dim3 block, const SceneView& s,
  const CameraView& cam, const FrameParams& fp, const float* depth, float4* accum, float4* even, uint32_t previous,
  unsigned long long* counters)
{
  switch (mode)
  {
    case BlendMode::Max:
      launchPlain<BlendMode::Max>(count, expectedValue, grid, block, s, cam, fp, depth, accum, even, previous, counters);
      break;
    case BlendMode::Mix:
      launchPlain<BlendMode::Mix>(count, expectedValue, grid, block, s, cam, fp, depth, accum, even, previous, counters);
      break;
    case BlendMode::Composite:
      launchPlain<BlendMode::Composite>(
        count, expectedValue, grid, block, s, cam, fp, depth, accum, even, previous, counters);
      break;
    case BlendMode::Density:
    default:
      launchPlain<BlendMode::Density>(
        count, expectedValue, grid, block, s, cam, fp, depth, accum, even, previous, counters);
      break;
  }
}
} // namespace mcvol
