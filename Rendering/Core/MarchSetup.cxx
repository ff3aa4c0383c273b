// SPDX-License-Identifier: BSD-3-Clause
#include "mcvol/MarchSetup.h"
#include "mcvol/RenderSetup.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>

namespace mcvol
{
namespace
{
/// World length of one index step along each axis: the column norms of the
/// inverse of worldToIndex's linear part.
void voxelSpacing(const Camera& camera, double spacing[3])
{
  const double* w = camera.worldToIndex;
  const double a = w[0], b = w[1], c = w[2], d = w[4], e = w[5], f = w[6], g = w[8], h = w[9], i = w[10];
  const double det = a * (e * i - f * h) - b * (d * i - f * g) + c * (d * h - e * g);
  if (!(std::fabs(det) > 0.0) || !std::isfinite(det))
  {
    throw std::invalid_argument("mcvol: the volume's world-to-index map is singular");
  }
  const double inv[9] = { (e * i - f * h) / det, (c * h - b * i) / det, (b * f - c * e) / det, (f * g - d * i) / det,
    (a * i - c * g) / det, (c * d - a * f) / det, (d * h - e * g) / det, (b * g - a * h) / det, (a * e - b * d) / det };
  for (int col = 0; col < 3; ++col)
  {
    spacing[col] = std::sqrt(inv[col] * inv[col] + inv[3 + col] * inv[3 + col] + inv[6 + col] * inv[6 + col]);
  }
}
} // namespace

double marchNyquistStep(const Camera& camera)
{
  double spacing[3];
  voxelSpacing(camera, spacing);
  return 0.5 * std::min(spacing[0], std::min(spacing[1], spacing[2]));
}

double marchEffectiveStep(const Camera& camera, const MarchSettings& settings)
{
  return settings.step > 0.0 ? settings.step : marchNyquistStep(camera);
}

MarchParams prepareMarch(const Camera& camera, const MarchSettings& settings, SceneView& s)
{
  if (camera.width <= 0 || camera.height <= 0)
  {
    throw std::invalid_argument("mcvol: the image size must be positive");
  }
  if (!(settings.step >= 0.0) || !std::isfinite(settings.step))
  {
    throw std::invalid_argument("mcvol: the ray-marching step must be a finite number >= 0 (0 = Nyquist)");
  }
  if (!(settings.terminateTransmittance >= 0.f && settings.terminateTransmittance < 1.f))
  {
    throw std::invalid_argument("mcvol: the termination transmittance must be in [0, 1)");
  }
  if (s.volume.numChannels == 0 || s.tables.size < 2)
  {
    throw std::logic_error("mcvol: Scene::update() must succeed before rendering");
  }
  const double step = marchEffectiveStep(camera, settings);
  // Work guard: a step far below the voxel size over a long ray would run
  // for hours, and past about 2^22 samples per ray the float sample
  // positions stop being distinct. The longest ray through the box is at
  // most the sum of its edges, each edge's world length its index extent
  // times that axis's spacing.
  {
    double spacing[3];
    voxelSpacing(camera, spacing);
    double longest = 0.0;
    for (int col = 0; col < 3; ++col)
    {
      longest += (double(s.volume.boxHi[col] - s.volume.boxLo[col]) + 1.0) * spacing[col];
    }
    const double samples = longest / step;
    if (!(samples <= double(1 << 22)))
    {
      throw std::invalid_argument("mcvol: the ray-marching step " + std::to_string(step) + " would take up to " +
        std::to_string(samples) + " samples per ray (at most 2^22 are allowed); use a larger step");
    }
  }
  if (s.volume.cubic && settings.compositing == Compositing::Opacity)
  {
    // The opacity model interpolates per-voxel opacities over the trilinear
    // corners (cornersOf()); it is kept only as Kraus and Buerger's
    // comparison baseline and has no B-spline variant.
    throw std::invalid_argument("mcvol: the opacity compositing model samples trilinearly; cubic interpolation "
                                "needs the extinction model (or use linear or nearest interpolation)");
  }
  const CameraView cam = toView(camera);
  s.sigmaLimit = extinctionLimit(cam);
  if (s.lighting.enabled)
  {
    if (settings.compositing != Compositing::Extinction)
    {
      throw std::invalid_argument("mcvol: the lit reference supports the extinction compositing model only");
    }
    if (s.lighting.maxDepth > 1)
    {
      throw std::invalid_argument("mcvol: the lit reference is single scattering: it does not render a maximum "
                                  "scattering depth of " +
        std::to_string(s.lighting.maxDepth) + " (set it to 1 to compare)");
    }
    setLightingFrame(s, camera);
  }
  if (s.importance.enabled)
  {
    if (settings.compositing != Compositing::Extinction)
    {
      throw std::invalid_argument("mcvol: the visibility optimization scales extinctions; it needs the extinction "
                                  "compositing model");
    }
    setImportanceFrame(s, camera);
  }
  MarchParams mp;
  mp.step = float(step);
  mp.terminateTransmittance = settings.terminateTransmittance;
  mp.skipEmpty = settings.skipEmpty;
  mp.compositing = settings.compositing;
  if (!(mp.step > 0.f))
  {
    throw std::invalid_argument("mcvol: the ray-marching step is too small for float precision");
  }
  return mp;
}
} // namespace mcvol
