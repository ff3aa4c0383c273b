// SPDX-License-Identifier: BSD-3-Clause
#pragma once

#include "mcvol/ray/Integrator.h"
#include "mcvol/Renderer.h"
#include "mcvol/Scene.h"

#include <cmath>
#include <stdexcept>

namespace mcvol
{
/// Host-side set-up every backend does the same way before tracing.

/// The per-ray code's copy of a Camera.
inline CameraView toView(const Camera& c)
{
  CameraView v;
  v.width = c.width;
  v.height = c.height;
  for (int i = 0; i < 16; ++i)
  {
    v.invViewProj[i] = c.invViewProj[i];
  }
  for (int i = 0; i < 12; ++i)
  {
    v.worldToIndex[i] = c.worldToIndex[i];
  }
  v.jitterScale = c.jitterScale;
  return v;
}

/// The linear part of a camera's worldToIndex (row-major 3x3) and its inverse.
inline void worldToIndexLinear(const Camera& camera, double m[9], double inv[9])
{
  const double* w = camera.worldToIndex;
  const double a[9] = { w[0], w[1], w[2], w[4], w[5], w[6], w[8], w[9], w[10] };
  const double det =
    a[0] * (a[4] * a[8] - a[5] * a[7]) - a[1] * (a[3] * a[8] - a[5] * a[6]) + a[2] * (a[3] * a[7] - a[4] * a[6]);
  const double b[9] = { (a[4] * a[8] - a[5] * a[7]) / det, (a[2] * a[7] - a[1] * a[8]) / det,
    (a[1] * a[5] - a[2] * a[4]) / det, (a[5] * a[6] - a[3] * a[8]) / det, (a[0] * a[8] - a[2] * a[6]) / det,
    (a[2] * a[3] - a[0] * a[5]) / det, (a[3] * a[7] - a[4] * a[6]) / det, (a[1] * a[6] - a[0] * a[7]) / det,
    (a[0] * a[4] - a[1] * a[3]) / det };
  for (int i = 0; i < 9; ++i)
  {
    m[i] = a[i];
    inv[i] = b[i];
  }
}

/// The per-render frame of lighting: world-to-index maps from the camera.
inline void setLightingFrame(SceneView& s, const Camera& camera)
{
  LightingView& L = s.lighting;
  double m[9], inv[9];
  worldToIndexLinear(camera, m, inv);
  for (int i = 0; i < 9; ++i)
  {
    L.toIndex[i] = float(m[i]);
    L.toWorld[i] = float(inv[i]);
  }
  const double* w = camera.worldToIndex;
  L.indexOffset = Vec3f(float(w[3]), float(w[7]), float(w[11]));
}

/**
 * The per-render view of a lit Scene's stand-in (Scene::setOutside), after
 * `s` (the Scene's own per-render view) has its lighting frame: `o` gets the
 * stand-in's volume, tables and grids with `s`'s blend and lighting, the
 * lighting frame and extinction limit of the stand-in's index space, no
 * visibility optimization and no stand-in of its own; `s` gets the index
 * map. Sets neither pointer (s.outside is the backend's: a host or a
 * device address). Returns false, touching nothing, when the Scene has no
 * stand-in or is unlit. Throws std::invalid_argument for a stand-in that
 * is not ready or does not match.
 */
inline bool prepareOutside(const Scene& scene, const Camera& camera, SceneView& s, SceneView& o)
{
  const Scene* outside = scene.outside();
  if (!outside || !s.lighting.enabled)
  {
    return false;
  }
  o = outside->view();
  if (outside->numChannels() != scene.numChannels() || o.volume.numChannels != s.volume.numChannels ||
    o.tables.size < 2)
  {
    throw std::invalid_argument("mcvol: the stand-in of the other pieces (Scene::setOutside) must be updated and have "
                                "the piece's number of channels");
  }
  if (!o.grid.majorants)
  {
    throw std::invalid_argument("mcvol: the stand-in of the other pieces needs its host macrocells and majorants "
                                "(Scene::setHostAcceleration on)");
  }
  const double* scale = scene.outsideScale();
  const double* offset = scene.outsideOffset();
  Camera standIn = camera;
  for (int r = 0; r < 3; ++r)
  {
    for (int col = 0; col < 4; ++col)
    {
      standIn.worldToIndex[4 * r + col] = camera.worldToIndex[4 * r + col] * scale[r];
    }
    standIn.worldToIndex[4 * r + 3] += offset[r];
  }
  o.blend = s.blend;
  o.lighting = s.lighting;
  setLightingFrame(o, standIn);
  o.sigmaLimit = extinctionLimit(toView(standIn));
  o.importance.enabled = false;
  o.outside = nullptr;
  s.outsideScale = Vec3f(float(scale[0]), float(scale[1]), float(scale[2]));
  s.outsideOffset = Vec3f(float(offset[0]), float(offset[1]), float(offset[2]));
  // The visibility optimization acts on light rays inside the piece
  // (Lerzer and Dachsbacher, Sec. 5.3), which only the piece's view
  // carries: its light paths keep reading the piece.
  s.outsideExact = scene.outsideExact() && !scene.view().importance.enabled;
  return true;
}

/// The per-render frame of the visibility optimization: the world length of
/// one normalised ray unit is half the largest world extent of the volume's
/// box (the paper scales volumes into [-1, 1]^3, so its weights carry over).
inline void setImportanceFrame(SceneView& s, const Camera& camera)
{
  double m[9], inv[9];
  worldToIndexLinear(camera, m, inv);
  double lo[3] = { 1e300, 1e300, 1e300 }, hi[3] = { -1e300, -1e300, -1e300 };
  for (int corner = 0; corner < 8; ++corner)
  {
    const double idx[3] = { (corner & 1) ? s.volume.boxHi.x : s.volume.boxLo.x,
      (corner & 2) ? s.volume.boxHi.y : s.volume.boxLo.y, (corner & 4) ? s.volume.boxHi.z : s.volume.boxLo.z };
    for (int a = 0; a < 3; ++a)
    {
      // Translation drops out of an extent; the linear part is enough.
      const double v = inv[3 * a] * idx[0] + inv[3 * a + 1] * idx[1] + inv[3 * a + 2] * idx[2];
      lo[a] = v < lo[a] ? v : lo[a];
      hi[a] = v > hi[a] ? v : hi[a];
    }
  }
  double extent = 0.0;
  for (int a = 0; a < 3; ++a)
  {
    extent = hi[a] - lo[a] > extent ? hi[a] - lo[a] : extent;
  }
  const double unit = 0.5 * extent;
  s.importance.invLengthUnit = unit > 0.0 && std::isfinite(unit) ? float(1.0 / unit) : 1.f;
}

/// Whether the camera rays go through the pixel centres: no jitter asked
/// for, or none to spread (Camera::jitterScale 0).
inline bool pixelCentres(const RenderSettings& s, const Camera& camera)
{
  return !(s.jitterPixels && camera.jitterScale > 0.f);
}

/// Whether the unbiased march takes its control variates (SceneView::
/// marchControlVariates; kMarchControlVariateRate says when and why). Both
/// backends' rule.
inline bool marchControlVariates(const RenderSettings& s, const Camera& camera)
{
  return s.marchControlVariates && s.marchSamplesPerVoxel >= s.marchControlVariatesFrom && pixelCentres(s, camera);
}

/// What a render asks of every pixel, continuing after `firstSample` samples.
inline FrameParams frameParams(const RenderSettings& s, uint32_t firstSample)
{
  FrameParams fp;
  fp.samplesPerPixel = s.samplesPerPixel;
  fp.firstSample = firstSample;
  fp.seed = s.seed;
  fp.tracker = s.tracker;
  fp.jitter = s.jitterPixels;
  fp.sampler = s.sampler;
  fp.estimator = s.estimator;
  return fp;
}

/// The checks of Renderer::renderPilots on a job's checkpoints, shared by
/// the backends (the render arguments are checkRenderArguments').
inline void checkPilotCheckpoints(const PilotJob& job)
{
  if (job.checkpoints.empty())
  {
    throw std::invalid_argument("mcvol: a pilot needs at least one checkpoint");
  }
  int last = 0;
  for (int c : job.checkpoints)
  {
    if (c <= last)
    {
      throw std::invalid_argument("mcvol: pilot checkpoints must be positive and ascending");
    }
    last = c;
  }
}

/// The argument checks of Renderer::render, shared by the backends; sizes
/// `accum` to the camera (which restarts it when the size changes).
inline void checkRenderArguments(const Camera& camera, const RenderSettings& settings, Accumulator& accum)
{
  if (camera.width <= 0 || camera.height <= 0)
  {
    throw std::invalid_argument("mcvol: the image size must be positive");
  }
  if (settings.samplesPerPixel < 1)
  {
    throw std::invalid_argument("mcvol: samples per pixel must be at least 1");
  }
  if (!(settings.minSamplesPerVoxel >= 0.f && settings.minSamplesPerVoxel <= 1e6f))
  {
    throw std::invalid_argument("mcvol: the minimum samples per voxel must be between 0 and 1e6");
  }
  if (!(settings.marchSamplesPerVoxel >= 0.01f && settings.marchSamplesPerVoxel <= 1024.f))
  {
    throw std::invalid_argument("mcvol: the unbiased march's samples per voxel must be between 0.01 and 1024");
  }
  if (!(settings.marchControlVariatesFrom >= 0.f) || !std::isfinite(settings.marchControlVariatesFrom))
  {
    throw std::invalid_argument("mcvol: the rate from which the march takes control variates must be at least 0 and finite");
  }
  if (accum.width() != camera.width || accum.height() != camera.height)
  {
    accum.resize(camera.width, camera.height);
  }
}
} // namespace mcvol
