// SPDX-License-Identifier: BSD-3-Clause
#pragma once

#include "vtkType.h" // For VTK_UNSIGNED_CHAR and friends

#include "mcvol/ray/Types.h"

namespace mcvol
{
namespace adapter
{
/// The VTK scalar types the core reads in place, and their core names: the
/// one table both directions (mapper input, demo source output) use.
struct ScalarTypePair
{
  int vtkType;
  ScalarType coreType;
};

constexpr ScalarTypePair kScalarTypes[] = {
  { VTK_UNSIGNED_CHAR, ScalarType::UInt8 },
  { VTK_SHORT, ScalarType::Int16 },
  { VTK_UNSIGNED_SHORT, ScalarType::UInt16 },
  { VTK_FLOAT, ScalarType::Float32 },
  { VTK_DOUBLE, ScalarType::Float64 },
};

/// The core type of a VTK array type; false for types the core cannot read.
inline bool ToCoreScalarType(int vtkType, ScalarType& out)
{
  for (const ScalarTypePair& p : kScalarTypes)
  {
    if (p.vtkType == vtkType)
    {
      out = p.coreType;
      return true;
    }
  }
  return false;
}

/// The VTK array type holding a core type.
inline int ToVTKScalarType(ScalarType t)
{
  for (const ScalarTypePair& p : kScalarTypes)
  {
    if (p.coreType == t)
    {
      return p.vtkType;
    }
  }
  return VTK_FLOAT;
}
} // namespace adapter
} // namespace mcvol
