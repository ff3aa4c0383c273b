// SPDX-License-Identifier: BSD-3-Clause
// Scene: importance functions and weights of the visibility optimization
// (Lerzer and Dachsbacher) into the ImportanceView.
#include "mcvol/ray/Importance.h"
#include "mcvol/Scene.h"

#include "SceneInternal.h"

#include <cmath>
#include <stdexcept>
#include <string>

namespace mcvol
{
namespace
{
std::string classifiedImportanceText(int n)
{
  return "mcvol: " + detail::channelText(n) +
    " is pre-classified (extinction format) and has no scalar to look an importance function up by; give it an "
    "empty importance table (the visibility optimization of pre-classified channels is not supported)";
}
} // namespace

float snapImportance(float v)
{
  if (!(v > 0.f))
  {
    return 0.f; // NaN and negatives: unimportant
  }
  if (v >= 1.f)
  {
    return 1.f;
  }
  return std::round(v * 4.f) / 4.f;
}

void Scene::setImportance(const ImportanceDesc& d)
{
  if (!(d.p > 0.0) || !std::isfinite(d.p) || !(d.q >= 0.0) || !std::isfinite(d.q) || !(d.r >= 0.0) ||
    !std::isfinite(d.r) || !(d.lambda >= 0.0) || !std::isfinite(d.lambda))
  {
    throw std::invalid_argument(
      "mcvol: the visibility weights need p > 0 and finite q, r, lambda >= 0 (deviation, occlusion, clutter, "
      "emphasis)");
  }
  if (!(d.mergeDistance >= 0.0) || !std::isfinite(d.mergeDistance))
  {
    throw std::invalid_argument("mcvol: the importance merge distance must be finite and >= 0 (0: automatic)");
  }
  if (d.samplesPerPass < 1 || d.samplesPerPass > kMaxImportanceSamples || d.refinePasses < 1)
  {
    throw std::invalid_argument("mcvol: importance samples per pass must be in [1, " +
      std::to_string(kMaxImportanceSamples) + "] and refinement passes >= 1");
  }
  if (d.lightRaySamples < 2 || d.lightRaySamples > 4096)
  {
    throw std::invalid_argument("mcvol: light-ray importance samples must be in [2, 4096]");
  }
  if (d.tables.size() > size_t(kMaxChannels))
  {
    throw std::invalid_argument("mcvol: more importance tables than channels are supported");
  }
  for (int n = 0; n < this->NumChannels && n < int(d.tables.size()); ++n)
  {
    if (!d.tables[size_t(n)].empty() && this->Channels[size_t(n)].format == ChannelFormat::Extinction)
    {
      throw std::invalid_argument(classifiedImportanceText(n));
    }
  }
  this->Importance = d;
}

void Scene::refreshImportance()
{
  ImportanceView& iv = this->View.importance;
  const ImportanceDesc& d = this->Importance;
  const int K = this->View.tables.size;
  iv = ImportanceView();
  this->ImportanceTables.assign(size_t(this->NumChannels) * size_t(K > 0 ? K : 0), 0.f);
  bool any = false;
  for (int n = 0; n < this->NumChannels && n < int(d.tables.size()); ++n)
  {
    const std::vector<float>& t = d.tables[size_t(n)];
    if (t.empty())
    {
      continue;
    }
    if (this->Channels[size_t(n)].format == ChannelFormat::Extinction)
    {
      throw std::invalid_argument(classifiedImportanceText(n));
    }
    if (int(t.size()) != K)
    {
      throw std::invalid_argument("mcvol: the importance table of " + detail::channelText(n) + " has " +
        std::to_string(t.size()) + " entries; it needs " + std::to_string(K) + ", as its colour table");
    }
    bool nonZero = false;
    for (int i = 0; i < K; ++i)
    {
      const float v = snapImportance(t[size_t(i)]);
      this->ImportanceTables[size_t(n) * size_t(K) + size_t(i)] = v;
      nonZero = nonZero || v > 0.f;
    }
    if (nonZero)
    {
      iv.channels[iv.numChannels++] = n;
      any = true;
    }
  }
  // Off, or importance 0 everywhere: the factor would be exactly 1, so the
  // unoptimized code runs (no importance samples, no segment lists).
  iv.enabled = d.enabled && any;
  iv.table = this->ImportanceTables.data();
  iv.p = float(d.p);
  iv.q = float(d.q);
  iv.r = float(d.r);
  iv.twoLambda = float(2.0 * d.lambda);
  iv.mergeDistance = float(d.mergeDistance);
  iv.samplesPerPass = d.samplesPerPass;
  iv.refinePasses = d.refinePasses;
  iv.lightRays = d.lightRays;
  iv.lightRaySamples = d.lightRaySamples;
  iv.lightRaysFromLight = d.lightRaysFromLight;
}
} // namespace mcvol
