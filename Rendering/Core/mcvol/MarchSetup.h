// SPDX-License-Identifier: BSD-3-Clause
#pragma once

#include "mcvol/ray/RayMarch.h"
#include "mcvol/Renderer.h"

#include <cstdint>

namespace mcvol
{
/// What one reference render asks for (Renderer::march, RayMarcher::render).
struct MarchSettings
{
  /// Step in world units; 0 = Sahistan et al.'s Nyquist rate, half the smallest
  /// voxel spacing (marchNyquistStep()).
  double step = 0.0;
  /// Early ray termination: a ray stops once its transmittance is below this
  /// (the image then differs from the full march by at most this much).
  float terminateTransmittance = 1e-4f;
  /// Per-pixel random phase of the sample lattice (deterministic for a
  /// seed); off: the midpoint of each step.
  bool jitter = false;
  uint32_t seed = 0;
  bool skipEmpty = true;
  Compositing compositing = Compositing::Extinction;
  /// Device backends: read voxels through hardware texture filtering, as the
  /// Monte Carlo renders do with CudaSampling::Texture (faster, but the
  /// hardware's interpolation weights are 9-bit fixed point, so the image
  /// is no longer the CPU march's to float rounding). Off by default: the
  /// device march interpolates in software with the core's arithmetic, and
  /// stays a reference. The CPU ignores it.
  bool deviceTextures = false;
};

/// Half the smallest voxel spacing (world units) of the camera's volume.
double marchNyquistStep(const Camera& camera);
/// The step a march with these settings uses.
double marchEffectiveStep(const Camera& camera, const MarchSettings& settings);

/**
 * The checks and per-render set-up every backend's march does the same way:
 * validates the camera and settings against the scene (`s`, the view the
 * backend will march: the Scene's own or its device copy, with blend,
 * lighting and importance already filled in), refuses what the reference
 * does not render (throws std::invalid_argument / std::logic_error naming
 * it), sets the view's per-render fields (extinction limit, lighting and
 * importance frames) and returns the marching parameters.
 */
MarchParams prepareMarch(const Camera& camera, const MarchSettings& settings, SceneView& s);
} // namespace mcvol
