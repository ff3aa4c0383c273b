// SPDX-License-Identifier: BSD-3-Clause
#pragma once

#include "mcvol/Integrator.h"
#include "mcvol/Renderer.h"

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
  return v;
}

/// The per-render frame of lighting: world-to-index maps from the camera.
inline void setLightingFrame(SceneView& s, const Camera& camera)
{
  LightingView& L = s.lighting;
  const double* w = camera.worldToIndex;
  const double m[9] = { w[0], w[1], w[2], w[4], w[5], w[6], w[8], w[9], w[10] };
  const double det =
    m[0] * (m[4] * m[8] - m[5] * m[7]) - m[1] * (m[3] * m[8] - m[5] * m[6]) + m[2] * (m[3] * m[7] - m[4] * m[6]);
  const double inv[9] = { (m[4] * m[8] - m[5] * m[7]) / det, (m[2] * m[7] - m[1] * m[8]) / det,
    (m[1] * m[5] - m[2] * m[4]) / det, (m[5] * m[6] - m[3] * m[8]) / det, (m[0] * m[8] - m[2] * m[6]) / det,
    (m[2] * m[3] - m[0] * m[5]) / det, (m[3] * m[7] - m[4] * m[6]) / det, (m[1] * m[6] - m[0] * m[7]) / det,
    (m[0] * m[4] - m[1] * m[3]) / det };
  for (int i = 0; i < 9; ++i)
  {
    L.toIndex[i] = float(m[i]);
    L.toWorld[i] = float(inv[i]);
  }
  L.indexOffset = Vec3f(float(w[3]), float(w[7]), float(w[11]));
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
  return fp;
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
  if (accum.width() != camera.width || accum.height() != camera.height)
  {
    accum.resize(camera.width, camera.height);
  }
}
} // namespace mcvol
