// SPDX-License-Identifier: BSD-3-Clause
#pragma once

#include "mcvol/Pyramid.h"
#include "mcvol/Renderer.h"

#include <cstddef>
#include <cstdint>

namespace mcvol
{
/**
 * The GPU-level interface of a backend that renders on a device
 * (CUDARenderer): what it keeps resident there, its display path, and the
 * levels of detail it builds there. Callers holding a Renderer reach it
 * through Renderer::device(), which is nullptr on the CPU. The frame-level
 * calls (render, march, pilots, finish, read-back) are Renderer's.
 */
class DeviceRenderer : public Renderer
{
public:
  DeviceRenderer* device() final { return this; }
  const DeviceRenderer* device() const final { return this; }

  // --- Residency -------------------------------------------------------------

  /// True if the backend builds macrocells and majorants itself (on the
  /// device), so the Scene can skip its host build (Scene::setHostAcceleration).
  virtual bool buildsAccelerationOnDevice() const = 0;
  /// Bytes this renderer holds in device memory (channels, textures, grids,
  /// tables, images).
  virtual size_t deviceBytes() const = 0;
  /// Channel copies to the device so far (one per channel per data change).
  virtual uint64_t dataUploads() const = 0;

  // --- Display ---------------------------------------------------------------

  /**
   * The accumulated image of `accum` (the one this renderer rendered last,
   * read back or not) as premultiplied RGBA with 8 bits per component, for
   * display: each component clamped to [0, 1] and rounded to the nearest of
   * 256 levels, converted on the device so that a quarter of the float
   * image's bytes cross the bus, into page-locked host memory. `accum` keeps
   * its state (pendingOnDevice() stays as it was). The pointer is valid
   * until the next call or the renderer's destruction. nullptr where `accum`'s
   * image is on the host (draw accum.rgba()). Throws std::logic_error if
   * `accum`'s image is not the one on the device.
   */
  virtual const uint8_t* displayImage(Accumulator& accum) = 0;
  /// True if displayImage() serves this backend's images: a caller that only
  /// draws them can then render with RenderSettings::readBack off.
  virtual bool hasDisplayImage() const = 0;

  // --- Levels of detail ------------------------------------------------------

  /// True if the mapper should build levels of detail with classifyLevel()
  /// on the device; false to build them on the host (classifyExtinctionLevel).
  virtual bool buildsLevelsOnDevice() const = 0;
  /**
   * Level `level` of the extinction-based pyramid over scalar channels
   * classified through their tables (rebuilt when a transfer function
   * changes), built on the device and copied back:
   * classifyExtinctionLevel's arguments, result (a host PyramidLevel, 4
   * floats per voxel) and errors, equal to the host build to float rounding.
   * Builds on the device whatever buildsLevelsOnDevice() says.
   * `peakWorkBytes` (optional): the device memory of the build at its peak
   * (the level's own buffer and any inputs it keeps included).
   */
  virtual PyramidLevel classifyLevel(const ClassifyInput* inputs, int numInputs, const int dims[3],
    const double spacing[3], const double origin[3], int level, DownsampleFilter filter,
    size_t* peakWorkBytes = nullptr) = 0;
};

/**
 * Level `level` of the extinction-based pyramid built where `backend` builds
 * levels: on its device where it has one that does
 * (DeviceRenderer::buildsLevelsOnDevice()), otherwise on the host
 * (classifyExtinctionLevel, whose `peakWorkBytes` is the host's working
 * memory). The same level either way, to float rounding.
 */
inline PyramidLevel classifyLevel(Renderer& backend, const ClassifyInput* inputs, int numInputs, const int dims[3],
  const double spacing[3], const double origin[3], int level, DownsampleFilter filter,
  size_t* peakWorkBytes = nullptr)
{
  DeviceRenderer* device = backend.device();
  if (device && device->buildsLevelsOnDevice())
  {
    return device->classifyLevel(inputs, numInputs, dims, spacing, origin, level, filter, peakWorkBytes);
  }
  return classifyExtinctionLevel(inputs, numInputs, dims, spacing, origin, level, filter, peakWorkBytes);
}
} // namespace mcvol
