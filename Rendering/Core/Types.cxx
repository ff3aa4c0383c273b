// SPDX-License-Identifier: BSD-3-Clause
#include "mcvol/Types.h"

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

int scalarTypeSize(ScalarType t)
{
  return visitScalarType(t, [](auto tag) { return int(sizeof(typename decltype(tag)::type)); });
}
} // namespace mcvol
