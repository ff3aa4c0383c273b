// SPDX-License-Identifier: BSD-3-Clause
#include "mcvol/Scene.h"

#include <atomic>

namespace mcvol
{
namespace
{
uint64_t nextObjectId()
{
  static std::atomic<uint64_t> counter{ 0 };
  return ++counter;
}
} // namespace

ObjectId::ObjectId()
  : value(nextObjectId())
{
}

ObjectId::ObjectId(const ObjectId&)
  : value(nextObjectId())
{
}

ObjectId& ObjectId::operator=(const ObjectId&)
{
  this->value = nextObjectId();
  return *this;
}
} // namespace mcvol
