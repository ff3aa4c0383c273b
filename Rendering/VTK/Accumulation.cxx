// SPDX-License-Identifier: BSD-3-Clause
#include "Accumulation.h"

#include "vtkMatrix4x4.h"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <iterator>

namespace mcvol
{
namespace adapter
{
//------------------------------------------------------------------------------
bool SameRays(const double a[16], const double b[16], int width, int height)
{
  if (std::equal(a, a + 16, b))
  {
    return true;
  }
  double bInverse[16];
  vtkMatrix4x4::Invert(b, bInverse);
  for (int corner = 0; corner < 8; ++corner)
  {
    const double ndc[4] = { corner & 1 ? 1.0 : -1.0, corner & 2 ? 1.0 : -1.0, corner & 4 ? 1.0 : -1.0, 1.0 };
    double world[4];
    vtkMatrix4x4::MultiplyPoint(a, ndc, world);
    double back[4];
    vtkMatrix4x4::MultiplyPoint(bInverse, world, back);
    if (!(back[3] != 0.0) || !std::isfinite(back[3]))
    {
      return false;
    }
    const double dx = (back[0] / back[3] - ndc[0]) * 0.5 * width;
    const double dy = (back[1] / back[3] - ndc[1]) * 0.5 * height;
    const double dz = back[2] / back[3] - ndc[2];
    if (!(std::abs(dx) <= kSameRayPixels && std::abs(dy) <= kSameRayPixels && std::abs(dz) <= kSameRayDepth))
    {
      return false;
    }
  }
  return true;
}

//------------------------------------------------------------------------------
bool AccumulationKey::operator==(const AccumulationKey& o) const
{
  return this->MapperMTime == o.MapperMTime && this->TablesVersion == o.TablesVersion &&
    this->PropertyMTime == o.PropertyMTime && this->DataMTime == o.DataMTime && this->LightsMTime == o.LightsMTime &&
    this->Width == o.Width && this->Height == o.Height &&
    SameRays(this->InvViewProj, o.InvViewProj, this->Width, this->Height) &&
    std::equal(std::begin(this->WorldToIndex), std::end(this->WorldToIndex), std::begin(o.WorldToIndex)) &&
    this->Backend == o.Backend && this->Level == o.Level && this->LevelVersion == o.LevelVersion &&
    this->InteractiveEstimator == o.InteractiveEstimator;
}

//------------------------------------------------------------------------------
bool Accumulation::Update(const AccumulationKey& key, std::vector<float>& depth, Accumulator& accum)
{
  const bool depthChanged = this->LastDepth.size() != depth.size() ||
    (!depth.empty() && std::memcmp(this->LastDepth.data(), depth.data(), depth.size() * sizeof(float)) != 0);
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
void SampleCost::Record(int samples, double seconds)
{
  if (samples <= 0 || !(seconds > 0.0) || !std::isfinite(seconds))
  {
    return;
  }
  const double s = seconds / samples;
  // Half the weight on the newest batch: follows a changed view within a few
  // renders, and one slow render (the first after an upload) fades quickly.
  this->SecondsPerSample = this->SecondsPerSample > 0.0 ? 0.5 * (this->SecondsPerSample + s) : s;
}

int SampleCost::Budget(double frameTime, int first, int cap) const
{
  if (!(this->SecondsPerSample > 0.0))
  {
    return std::max(1, std::min(first, cap));
  }
  const double n = std::floor(frameTime / this->SecondsPerSample);
  return static_cast<int>(std::max(1.0, std::min(n, double(cap))));
}

int SamplesThisRender(
  bool addsSamples, bool progressive, int samplesPerPixel, long long maximumTotalSamples, long long traced)
{
  int batch = samplesPerPixel;
  if (addsSamples)
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
