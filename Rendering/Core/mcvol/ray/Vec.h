// SPDX-License-Identifier: BSD-3-Clause
#pragma once

#include "mcvol/ray/Macros.h"

#include <cmath>

namespace mcvol
{
/// Small float vector used by the per-ray code on CPU and GPU.
struct Vec3f
{
  float x = 0.f, y = 0.f, z = 0.f;

  Vec3f() = default;
  MCVOL_HOST_DEVICE constexpr Vec3f(float a, float b, float c)
    : x(a)
    , y(b)
    , z(c)
  {
  }
  // x, y, z are laid out contiguously (standard layout, no padding).
  MCVOL_FUNC float operator[](int i) const { return (&this->x)[i]; }
  MCVOL_FUNC float& operator[](int i) { return (&this->x)[i]; }
};

MCVOL_FUNC Vec3f operator+(Vec3f a, Vec3f b)
{
  return { a.x + b.x, a.y + b.y, a.z + b.z };
}
MCVOL_FUNC Vec3f operator-(Vec3f a, Vec3f b)
{
  return { a.x - b.x, a.y - b.y, a.z - b.z };
}
MCVOL_FUNC Vec3f operator*(Vec3f a, float s)
{
  return { a.x * s, a.y * s, a.z * s };
}
MCVOL_FUNC Vec3f operator*(float s, Vec3f a)
{
  return a * s;
}
MCVOL_FUNC Vec3f operator*(Vec3f a, Vec3f b)
{
  return { a.x * b.x, a.y * b.y, a.z * b.z };
}
MCVOL_FUNC Vec3f& operator+=(Vec3f& a, Vec3f b)
{
  a.x += b.x;
  a.y += b.y;
  a.z += b.z;
  return a;
}
MCVOL_FUNC float dot(Vec3f a, Vec3f b)
{
  return a.x * b.x + a.y * b.y + a.z * b.z;
}
MCVOL_FUNC float length(Vec3f a)
{
  return sqrtf(dot(a, a));
}

/// Premultiplied RGB plus alpha.
struct Vec4f
{
  float r = 0.f, g = 0.f, b = 0.f, a = 0.f;
};

/// A pixel's running sum of premultiplied RGBA samples (Integrator.h).
struct Vec4d
{
  double r = 0.0, g = 0.0, b = 0.0, a = 0.0;
};

/// Adds one sample to a running sum (in double: exact for a float sample
/// until the sum is 2^29 times larger than it).
MCVOL_FUNC void addSample(Vec4d& sum, const Vec4f& v)
{
  sum.r += double(v.r);
  sum.g += double(v.g);
  sum.b += double(v.b);
  sum.a += double(v.a);
}

/// Premultiplied RGB `rgb` with alpha 1 - T (T: the transmittance left).
MCVOL_FUNC Vec4f premultipliedRGBA(Vec3f rgb, float T)
{
  Vec4f out;
  out.r = rgb.x;
  out.g = rgb.y;
  out.b = rgb.z;
  out.a = 1.f - T;
  return out;
}

/// min without fminf's NaN rules, which compilers turn into library calls.
MCVOL_FUNC float minf(float a, float b)
{
  return a < b ? a : b;
}
MCVOL_FUNC float maxf(float a, float b)
{
  return a > b ? a : b;
}
MCVOL_FUNC float clampf(float v, float lo, float hi)
{
  return v < lo ? lo : (v > hi ? hi : v);
}
MCVOL_FUNC int clampi(int v, int lo, int hi)
{
  return v < lo ? lo : (v > hi ? hi : v);
}
} // namespace mcvol
