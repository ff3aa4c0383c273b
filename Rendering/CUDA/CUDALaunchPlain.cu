// SPDX-License-Identifier: BSD-3-Clause
//
// The render kernels for plain scenes, unlit and lit: scalar channels only,
// linear or nearest interpolation (CUDARenderKernels.h says why they are
// compiled twice). MCVOL_DEVICE_PLAIN_CHANNELS changes device code only (Blend.h's
// channelOptics under __CUDA_ARCH__), so the host code of the core's inline
// functions is the same in every translation unit.
#define MCVOL_DEVICE_PLAIN_CHANNELS 1
#include "CUDARenderKernels.h"

namespace mcvol
{
void launchPlainUnlit(BlendMode mode, int unlit, bool count, const SceneView& s, const CameraView& cam,
  const FrameParams& fp, const RenderLaunch& k)
{
  withBlendMode(mode, [&](auto m) { launchUnlit<decltype(m)::value>(unlit, count, s, cam, fp, k); });
}

void launchPlainLit(
  BlendMode mode, bool count, const SceneView& s, const CameraView& cam, const FrameParams& fp, const RenderLaunch& k)
{
  // Composite blending takes no lighting on this backend (CUDARenderer
  // refuses it), so no lit composite kernel is compiled here.
  withBlendMode(mode,
    [&](auto m)
    {
      if constexpr (decltype(m)::value != BlendMode::Composite)
      {
        launchRenderKernel<decltype(m)::value, true, 0>(count, s, cam, fp, k);
      }
    });
}
} // namespace mcvol
