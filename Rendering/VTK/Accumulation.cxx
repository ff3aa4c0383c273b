// SPDX-License-Identifier: BSD-3-Clause
#include "Accumulation.h"

#include <algorithm>
#include <cstring>
#include <iterator>

namespace mcvol
{
namespace adapter
{
//------------------------------------------------------------------------------
bool AccumulationKey::operator==(const AccumulationKey& o) const
{
  return this->MapperMTime == o.MapperMTime && this->TablesVersion == o.TablesVersion &&
    this->PropertyMTime == o.PropertyMTime && this->DataMTime == o.DataMTime && this->LightsMTime == o.LightsMTime &&
    this->Width == o.Width && this->Height == o.Height &&
    std::equal(std::begin(this->InvViewProj), std::end(this->InvViewProj), std::begin(o.InvViewProj)) &&
    std::equal(std::begin(this->WorldToIndex), std::end(this->WorldToIndex), std::begin(o.WorldToIndex)) &&
    this->Backend == o.Backend;
}

//------------------------------------------------------------------------------
bool Accumulation::Update(const AccumulationKey& key, std::vector<float>& depth, Accumulator& accum)
{
  const bool depthChanged = this->LastDepth.size() != depth.size() ||
    std::memcmp(this->LastDepth.data(), depth.data(), depth.size() * sizeof(float)) != 0;
  if (this->HaveKey && key == this->Key && !depthChanged && !this->ResetRequested && accum.width() == key.Width &&
    accum.height() == key.Height)
  {
    return false;
  }
  if (accum.width() != key.Width || accum.height() != key.Height)
  {
    accum.resize(key.Width, key.Height);
  }
  accum.reset();
  this->Key = key;
  this->HaveKey = true;
  this->ResetRequested = false;
  this->LastDepth.swap(depth);
  depth.resize(this->LastDepth.size());
  return true;
}

//------------------------------------------------------------------------------
int SamplesThisRender(
  bool usesBackend, bool progressive, int samplesPerPixel, long long maximumTotalSamples, long long traced)
{
  int batch = samplesPerPixel;
  if (usesBackend)
  {
    if (!progressive && traced > 0)
    {
      batch = 0;
    }
    else if (maximumTotalSamples > 0)
    {
      batch = static_cast<int>(std::min<long long>(batch, std::max<long long>(0, maximumTotalSamples - traced)));
    }
  }
  return batch;
}
} // namespace adapter
} // namespace mcvol
