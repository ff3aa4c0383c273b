// SPDX-License-Identifier: BSD-3-Clause
#pragma once

#include "vtkObject.h"

#include <cmath>

namespace mcvol
{
namespace adapter
{
/**
 * The mappers' numeric setters: `value` clamped to [lo, hi] (as
 * vtkSetClampMacro) into `member`, Modified() on a change. NaN, which a
 * clamp lets through (every comparison with it is false), is refused with an
 * error naming the setter, and the setting keeps its value.
 */
inline void SetClamped(vtkObject* self, const char* setter, double value, double lo, double hi, double& member)
{
  if (std::isnan(value))
  {
    vtkErrorWithObjectMacro(self, << setter << ": NaN is not a value; the setting stays " << member << ".");
    return;
  }
  const double clamped = value < lo ? lo : (value > hi ? hi : value);
  if (member != clamped)
  {
    member = clamped;
    self->Modified();
  }
}
} // namespace adapter
} // namespace mcvol
