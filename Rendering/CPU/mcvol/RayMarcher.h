// SPDX-License-Identifier: BSD-3-Clause
#pragma once

#include "mcvol/RayMarch.h"
#include "mcvol/Renderer.h"

namespace mcvol
{
/// What one reference render asks for.
struct MarchSettings
{
  /// Step in world units; 0 = the paper's Nyquist rate, half the smallest
  /// voxel spacing (nyquistStep()).
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
};

/**
 * The deterministic OpenMP ray marcher (RayMarch.h): one ray through each
 * pixel centre. render() replaces the Accumulator's image (its sample count
 * becomes 1). The image does not depend on the thread count.
 */
class RayMarcher
{
public:
  void render(const Scene& scene, const Camera& camera, const MarchSettings& settings, const float* depth,
    Accumulator& out, MarchCounters* counters = nullptr);
  /// 0 = OpenMP's default.
  void setThreads(int n) { this->Threads = n; }
  /// Half the smallest voxel spacing (world units) of the camera's volume.
  static double nyquistStep(const Camera& camera);
  /// The step a render with these settings uses.
  static double effectiveStep(const Camera& camera, const MarchSettings& settings);

private:
  int Threads = 0;
};
} // namespace mcvol
