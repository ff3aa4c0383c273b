// SPDX-License-Identifier: BSD-3-Clause
#pragma once

#include "mcvol/Renderer.h"

#include <array>

namespace mcvol
{
/**
 * Cameras for VTK-free programs (tests, benchmark): a perspective or parallel
 * view looking at the centre of a volume with `dims` voxels of `spacing`,
 * placed with its origin at zero, from azimuth/elevation in degrees, framing
 * the whole volume. worldToIndex is filled for that placement.
 */
Camera orbitCamera(const int dims[3], const double spacing[3], int width, int height, double azimuthDeg,
  double elevationDeg, bool parallel = false, double zoom = 1.0);

/// Row-major 4x4 inverse (returns false if singular).
bool invert4x4(const double m[16], double out[16]);

/// World-to-NDC matrix of a look-at camera (OpenGL conventions).
std::array<double, 16> viewProjection(const double eye[3], const double target[3], const double up[3], double fovyDeg,
  double aspect, double zNear, double zFar, bool parallel, double parallelScale);
} // namespace mcvol
