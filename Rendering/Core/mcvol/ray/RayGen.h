// SPDX-License-Identifier: BSD-3-Clause
#pragma once

#include "mcvol/ray/DDA.h"
#include "mcvol/ray/SceneView.h"

namespace mcvol
{
/// Camera data the per-pixel code reads (doubles: ray set-up only, once per
/// sample, so far-from-origin scenes keep their precision).
struct CameraView
{
  int width = 0;
  int height = 0;
  double invViewProj[16];
  double worldToIndex[12];
  float jitterScale = 1.f; ///< Camera::jitterScale
};

/// A ray in index space, clipped to the volume box: points o + t d for t in
/// [0, tmax], with t in world units (d is the index-space image of a unit
/// world direction).
struct IndexRay
{
  Vec3f o;
  Vec3f d;
  float tmax = 0.f;
  Vec3f world; ///< the unit world direction d is the image of (lighting reads it)
};

struct Dvec3
{
  double x, y, z;
};

MCVOL_FUNC Dvec3 unproject(const double* m, double x, double y, double z)
{
  const double X = m[0] * x + m[1] * y + m[2] * z + m[3];
  const double Y = m[4] * x + m[5] * y + m[6] * z + m[7];
  const double Z = m[8] * x + m[9] * y + m[10] * z + m[11];
  const double W = m[12] * x + m[13] * y + m[14] * z + m[15];
  return { X / W, Y / W, Z / W };
}

/// Optical depth one voxel may hold at most (transmittance e^-16, about 1e-7,
/// across it: opaque for every image, yet finite work per macrocell).
constexpr float kMaxOpticalDepthPerVoxel = 16.f;

/// ||A||_F^2 for A the linear part of the camera's worldToIndex.
MCVOL_FUNC double worldToIndexNorm2(const CameraView& cam)
{
  const double* w = cam.worldToIndex;
  double f2 = 0.0;
  for (int r = 0; r < 3; ++r)
  {
    for (int c = 0; c < 3; ++c)
    {
      f2 += w[4 * r + c] * w[4 * r + c];
    }
  }
  return f2;
}

/**
 * Extinction limit for a render: kMaxOpticalDepthPerVoxel per 1 / ||A||_F
 * world units, A the linear part of worldToIndex (1 / ||A||_F is at most the
 * world length of a voxel's thinnest side). A voxel then holds at most about
 * 16 optical depths across its thinnest side, and 16 times its aspect ratio
 * along its longest, so the null collisions per macrocell are bounded by the
 * macrocell size and the spacing's anisotropy. Without a limit, opacity 1
 * over a unit distance of a thousandth of a voxel makes Woodcock tracking
 * take hundreds of thousands of null collisions per macrocell.
 */
MCVOL_FUNC float extinctionLimit(const CameraView& cam)
{
  const double limit = double(kMaxOpticalDepthPerVoxel) * sqrt(worldToIndexNorm2(cam));
  return limit > 0.0 && limit < 3.4e38 ? float(limit) : 3.4e38f;
}

/// Rays' voxel crossings per world unit, sqrt(||A||_F^2 / 3) for A the
/// linear part of worldToIndex: 1 / h for cubic voxels of side h (the RMS
/// of the axes' inverse spacings for others).
MCVOL_FUNC float voxelRate(const CameraView& cam)
{
  const double rate = sqrt(worldToIndexNorm2(cam) / 3.0);
  return rate > 0.0 && rate < 3.4e38 ? float(rate) : 0.f;
}

/**
 * Builds the ray through film position (px, py) (pixel units, origin at the
 * bottom-left corner) and clips it to the volume box and to the window depth
 * `depth` (1 = nothing drawn there). The origin is moved to the box entry so
 * that t stays small in float even for very long rays. Returns false when the
 * ray misses the box or is hidden by geometry in front of it.
 */
MCVOL_FUNC bool generateRay(
  const CameraView& cam, const VolumeView& vol, float px, float py, float depth, IndexRay& ray)
{
  const double x = 2.0 * double(px) / double(cam.width) - 1.0;
  const double y = 2.0 * double(py) / double(cam.height) - 1.0;
  const Dvec3 n = unproject(cam.invViewProj, x, y, -1.0);
  const Dvec3 f = unproject(cam.invViewProj, x, y, 1.0);
  double dx = f.x - n.x, dy = f.y - n.y, dz = f.z - n.z;
  const double len = sqrt(dx * dx + dy * dy + dz * dz);
  if (!(len > 0.0))
  {
    return false;
  }
  dx /= len;
  dy /= len;
  dz /= len;
  double tLimit = len;
  if (depth < 1.f)
  {
    const Dvec3 g = unproject(cam.invViewProj, x, y, 2.0 * double(depth) - 1.0);
    tLimit = (g.x - n.x) * dx + (g.y - n.y) * dy + (g.z - n.z) * dz;
  }
  const double* w = cam.worldToIndex;
  const double o[3] = { w[0] * n.x + w[1] * n.y + w[2] * n.z + w[3], w[4] * n.x + w[5] * n.y + w[6] * n.z + w[7],
    w[8] * n.x + w[9] * n.y + w[10] * n.z + w[11] };
  const double d[3] = { w[0] * dx + w[1] * dy + w[2] * dz, w[4] * dx + w[5] * dy + w[6] * dz,
    w[8] * dx + w[9] * dy + w[10] * dz };
  double t0 = 0.0;
  double t1 = tLimit;
  for (int a = 0; a < 3; ++a)
  {
    const double lo = vol.boxLo[a];
    const double hi = vol.boxHi[a];
    if (d[a] == 0.0)
    {
      if (o[a] < lo || o[a] > hi)
      {
        return false;
      }
      continue;
    }
    double ta = (lo - o[a]) / d[a];
    double tb = (hi - o[a]) / d[a];
    if (ta > tb)
    {
      const double tmp = ta;
      ta = tb;
      tb = tmp;
    }
    t0 = ta > t0 ? ta : t0;
    t1 = tb < t1 ? tb : t1;
  }
  // A camera or matrix with a NaN or an infinity (core callers pass them
  // unchecked) gives no ray: such a ray would pass every comparison above,
  // and a DDA with an infinite end never finishes. (x - x == 0 exactly when x
  // is finite, in host and device code alike.)
  const double span = t1 - t0;
  if (!(t0 < t1) || !(span - span == 0.0))
  {
    return false;
  }
  for (int a = 0; a < 3; ++a)
  {
    if (!(o[a] - o[a] == 0.0) || !(d[a] - d[a] == 0.0))
    {
      return false;
    }
  }
  ray.o = Vec3f(float(o[0] + d[0] * t0), float(o[1] + d[1] * t0), float(o[2] + d[2] * t0));
  ray.d = Vec3f(float(d[0]), float(d[1]), float(d[2]));
  ray.tmax = float(t1 - t0);
  ray.world = Vec3f(float(dx), float(dy), float(dz));
  return ray.tmax > 0.f;
}
} // namespace mcvol
