// SPDX-License-Identifier: BSD-3-Clause
#include "mcvol/ray/Types.h"

#include <cmath>
#include <cstring>

namespace mcvol
{
const char* toString(ScalarType t)
{
  switch (t)
  {
    case ScalarType::UInt8:
      return "uint8";
    case ScalarType::Int16:
      return "int16";
    case ScalarType::UInt16:
      return "uint16";
    case ScalarType::Float32:
      return "float32";
    case ScalarType::Float64:
      return "float64";
    case ScalarType::Float16:
      return "float16";
  }
  return "unknown";
}

const char* toString(ChannelFormat f)
{
  switch (f)
  {
    case ChannelFormat::Scalar:
      return "scalar";
    case ChannelFormat::Extinction:
      return "extinction";
  }
  return "unknown";
}

const char* toString(BlendMode m)
{
  switch (m)
  {
    case BlendMode::Density:
      return "density";
    case BlendMode::Max:
      return "max";
    case BlendMode::Mix:
      return "mix";
    case BlendMode::Composite:
      return "composite";
  }
  return "unknown";
}

const char* toString(Tracker t)
{
  return t == Tracker::NDDA ? "N-DDA" : "1-DDA";
}

const char* toString(Sampler s)
{
  return s == Sampler::Sobol ? "sobol" : "independent";
}

const char* toString(Estimator e)
{
  return e == Estimator::ExpectedValue ? "expected-value"
    : e == Estimator::UnbiasedMarch    ? "unbiased-march"
                                       : "collision";
}

const char* toString(Interpolation i)
{
  switch (i)
  {
    case Interpolation::Nearest:
      return "nearest";
    case Interpolation::Linear:
      return "linear";
    case Interpolation::Cubic:
      return "cubic";
  }
  return "unknown";
}

const char* toString(Backend b)
{
  switch (b)
  {
    case Backend::Auto:
      return "auto";
    case Backend::CPU:
      return "cpu";
    case Backend::CUDA:
      return "cuda";
  }
  return "unknown";
}

uint16_t floatToHalf(float x)
{
  uint32_t u;
  std::memcpy(&u, &x, sizeof u);
  const uint16_t sign = uint16_t((u >> 16) & 0x8000u);
  u &= 0x7fffffffu;
  if (u > 0x7f800000u)
  {
    return uint16_t(sign | 0x7e00u); // NaN (quiet)
  }
  if (u >= 0x477ff000u)
  {
    return uint16_t(sign | 0x7c00u); // 65520 and above (and Inf): infinity
  }
  if (u < 0x38800000u)
  {
    // Below 2^-14: a subnormal (or zero), in units of 2^-24. The product is
    // exact (a power of two), and lrintf rounds to nearest even; 1024 units
    // is the smallest normal, whose bits are 0x400 as well.
    float f;
    std::memcpy(&f, &u, sizeof f);
    return uint16_t(sign | uint16_t(std::lrint(f * 0x1p24f)));
  }
  // A normal: rebias the exponent (127 -> 15) and round the 13 dropped
  // mantissa bits to nearest, ties to even (a carry into the exponent is the
  // right result, up to 65504's neighbour, excluded above).
  const uint32_t rebased = u - ((127u - 15u) << 23);
  const uint32_t rounded = rebased + 0x0fffu + ((rebased >> 13) & 1u);
  return uint16_t(sign | uint16_t(rounded >> 13));
}

int scalarTypeSize(ScalarType t)
{
  if (t == ScalarType::Float16)
  {
    return 2;
  }
  return visitScalarType(t, [](auto tag) { return int(sizeof(typename decltype(tag)::type)); });
}
} // namespace mcvol
