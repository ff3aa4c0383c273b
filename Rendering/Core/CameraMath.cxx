// SPDX-License-Identifier: BSD-3-Clause
#include "mcvol/CameraMath.h"

#include <cmath>

namespace mcvol
{
namespace
{
void mul4(const double a[16], const double b[16], double out[16])
{
  for (int r = 0; r < 4; ++r)
    for (int c = 0; c < 4; ++c)
    {
      double s = 0;
      for (int k = 0; k < 4; ++k)
        s += a[r * 4 + k] * b[k * 4 + c];
      out[r * 4 + c] = s;
    }
}
} // namespace

bool invert4x4(const double m[16], double out[16])
{
  double a[4][8];
  for (int r = 0; r < 4; ++r)
    for (int c = 0; c < 8; ++c)
      a[r][c] = c < 4 ? m[r * 4 + c] : (c - 4 == r ? 1.0 : 0.0);
  for (int col = 0; col < 4; ++col)
  {
    int piv = col;
    for (int r = col + 1; r < 4; ++r)
      if (std::fabs(a[r][col]) > std::fabs(a[piv][col]))
        piv = r;
    if (std::fabs(a[piv][col]) < 1e-300)
      return false;
    for (int c = 0; c < 8; ++c)
      std::swap(a[col][c], a[piv][c]);
    const double inv = 1.0 / a[col][col];
    for (int c = 0; c < 8; ++c)
      a[col][c] *= inv;
    for (int r = 0; r < 4; ++r)
      if (r != col)
      {
        const double f = a[r][col];
        for (int c = 0; c < 8; ++c)
          a[r][c] -= f * a[col][c];
      }
  }
  for (int r = 0; r < 4; ++r)
    for (int c = 0; c < 4; ++c)
      out[r * 4 + c] = a[r][c + 4];
  return true;
}

std::array<double, 16> viewProjection(const double eye[3], const double target[3], const double up[3], double fovyDeg,
  double aspect, double zNear, double zFar, bool parallel, double parallelScale)
{
  double f[3] = { target[0] - eye[0], target[1] - eye[1], target[2] - eye[2] };
  double fl = std::sqrt(f[0] * f[0] + f[1] * f[1] + f[2] * f[2]);
  for (double& x : f)
    x /= fl;
  double s[3] = { f[1] * up[2] - f[2] * up[1], f[2] * up[0] - f[0] * up[2], f[0] * up[1] - f[1] * up[0] };
  double sl = std::sqrt(s[0] * s[0] + s[1] * s[1] + s[2] * s[2]);
  for (double& x : s)
    x /= sl;
  const double u[3] = { s[1] * f[2] - s[2] * f[1], s[2] * f[0] - s[0] * f[2], s[0] * f[1] - s[1] * f[0] };
  const double view[16] = { s[0], s[1], s[2], -(s[0] * eye[0] + s[1] * eye[1] + s[2] * eye[2]), u[0], u[1], u[2],
    -(u[0] * eye[0] + u[1] * eye[1] + u[2] * eye[2]), -f[0], -f[1], -f[2],
    (f[0] * eye[0] + f[1] * eye[1] + f[2] * eye[2]), 0, 0, 0, 1 };
  double proj[16] = { 0 };
  if (parallel)
  {
    const double t = parallelScale, r = t * aspect;
    proj[0] = 1.0 / r;
    proj[5] = 1.0 / t;
    proj[10] = -2.0 / (zFar - zNear);
    proj[11] = -(zFar + zNear) / (zFar - zNear);
    proj[15] = 1.0;
  }
  else
  {
    const double t = 1.0 / std::tan(fovyDeg * M_PI / 360.0);
    proj[0] = t / aspect;
    proj[5] = t;
    proj[10] = -(zFar + zNear) / (zFar - zNear);
    proj[11] = -2.0 * zFar * zNear / (zFar - zNear);
    proj[14] = -1.0;
  }
  std::array<double, 16> out;
  mul4(proj, view, out.data());
  return out;
}

Camera orbitCamera(const int dims[3], const double spacing[3], int width, int height, double azimuthDeg,
  double elevationDeg, bool parallel, double zoom)
{
  Camera cam;
  cam.width = width;
  cam.height = height;
  double ext[3];
  double center[3];
  double radius = 0;
  for (int a = 0; a < 3; ++a)
  {
    ext[a] = (dims[a] > 1 ? dims[a] - 1 : 1) * spacing[a];
    center[a] = dims[a] > 1 ? 0.5 * ext[a] : 0.0;
    radius += 0.25 * ext[a] * ext[a];
  }
  radius = std::sqrt(radius);
  const double az = azimuthDeg * M_PI / 180.0, el = elevationDeg * M_PI / 180.0;
  const double fovy = 30.0;
  const double dist = radius / std::sin(fovy * M_PI / 360.0) / zoom;
  const double eye[3] = { center[0] + dist * std::cos(el) * std::sin(az), center[1] + dist * std::sin(el),
    center[2] + dist * std::cos(el) * std::cos(az) };
  const double up[3] = { 0, 1, 0 };
  const auto vp = viewProjection(eye, center, up, fovy, double(width) / double(height),
    std::max(1e-6, dist - 2 * radius), dist + 2 * radius, parallel, radius / zoom);
  invert4x4(vp.data(), cam.invViewProj);
  for (int i = 0; i < 12; ++i)
    cam.worldToIndex[i] = 0;
  for (int a = 0; a < 3; ++a)
  {
    cam.worldToIndex[a * 4 + a] = 1.0 / spacing[a];
  }
  return cam;
}
} // namespace mcvol
