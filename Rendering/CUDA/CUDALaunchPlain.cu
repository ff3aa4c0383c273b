// SPDX-License-Identifier: BSD-3-Clause
//
// The render kernels (unlit and lit) for plain scenes: scalar channels only, linear or
// nearest interpolation (CUDARenderKernels.h says why they are compiled
// twice). MCVOL_DEVICE_PLAIN_CHANNELS changes device code only (Blend.h's
// channelOptics under __CUDA_ARCH__), so the host code of the core's inline
// functions is the same in every translation unit.
#define MCVOL_DEVICE_PLAIN_CHANNELS 1
#include "CUDARenderKernels.h"

namespace mcvol
{
void launchPlain(BlendMode mode, bool lit, int unlit, bool count, const SceneView& s, const CameraView& cam,
  const FrameParams& fp, const RenderLaunch& k)
{
  withBlendMode(mode, [&](auto m) { launchKernel<decltype(m)::value>(lit, unlit, count, s, cam, fp, k); });
}
} // namespace mcvol
