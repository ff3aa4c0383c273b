// SPDX-License-Identifier: BSD-3-Clause
// Scene: what update() rebuilds and when, the view it publishes, and the
// small settings (blend mode, mix weights, host acceleration). The other
// members are defined by topic in SceneVolume.cxx, SceneTransferFunction.cxx,
// SceneMacrocells.cxx, SceneMajorants.cxx and SceneLighting.cxx.
#include "mcvol/Scene.h"

#include "SceneInternal.h"

#include <chrono>
#include <cmath>
#include <stdexcept>
#include <string>
#include <vector>

namespace mcvol
{
using detail::channelText;

Scene::Scene()
{
  this->MixWeights.fill(0.f);
}

void Scene::setHostAcceleration(bool on)
{
  if (on != this->HostAcceleration)
  {
    this->HostAcceleration = on;
    this->MacrocellsDirty = true;
    if (!on)
    {
      // Release the host copies.
      std::vector<float>().swap(this->Ranges);
      std::vector<float>().swap(this->Majorants);
    }
  }
}

void Scene::setBlendMode(BlendMode mode)
{
  this->View.blend.mode = mode;
}

void Scene::setInterpolation(Interpolation interpolation)
{
  if (interpolation != Interpolation::Nearest && interpolation != Interpolation::Linear &&
    interpolation != Interpolation::Cubic)
  {
    throw std::invalid_argument(
      "mcvol: unknown interpolation type " + std::to_string(int(interpolation)) + " (nearest, linear or cubic)");
  }
  const bool cubic = interpolation == Interpolation::Cubic;
  if (cubic != this->View.volume.cubic)
  {
    // The macrocell ranges cover the filter's footprint (cellVoxelBounds'
    // apron), which the cubic B-spline widens by one voxel per side.
    this->MacrocellsDirty = true;
  }
  this->InterpolationType = interpolation;
  this->View.volume.nearest = interpolation == Interpolation::Nearest;
  this->View.volume.cubic = cubic;
}

void Scene::setMixWeights(const float* weights, int count)
{
  if (count < 0 || count > kMaxChannels)
  {
    throw std::invalid_argument("mcvol: too many mix weights");
  }
  this->MixWeights.fill(0.f);
  for (int i = 0; i < count; ++i)
  {
    if (!(weights[i] >= 0.f) || !std::isfinite(weights[i]))
    {
      throw std::invalid_argument("mcvol: mix weight " + std::to_string(i) + " must be a finite number >= 0");
    }
    this->MixWeights[i] = weights[i];
  }
}

MemoryStats Scene::memory() const
{
  MemoryStats m;
  const size_t voxels = size_t(this->Dims[0]) * this->Dims[1] * this->Dims[2];
  for (int n = 0; n < this->NumChannels; ++n)
  {
    m.dataBytes += voxels * size_t(scalarTypeSize(this->Channels[n].type)) *
      (this->Channels[n].format == ChannelFormat::Extinction ? 4u : 1u);
  }
  m.macrocellBytes = this->Ranges.size() * sizeof(float);
  m.majorantBytes = this->Majorants.size() * sizeof(float);
  m.tableBytes = size_t(this->NumChannels) * size_t(this->View.tables.size) * 4 * sizeof(float);
  return m;
}

void Scene::refreshView(bool majorantsChanged)
{
  this->View.tables.texels = this->Tables.data();
  this->View.grid.majorants = this->Majorants.data();
  // Mix weights normalised to sum 1 (Eq. 10); none or all zero: equal.
  float sum = 0.f;
  for (int n = 0; n < this->NumChannels; ++n)
  {
    sum += this->MixWeights[n];
  }
  for (int n = 0; n < kMaxChannels; ++n)
  {
    this->View.blend.mixWeights[n] =
      n < this->NumChannels ? (sum > 0.f ? this->MixWeights[n] / sum : 1.f / float(this->NumChannels)) : 0.f;
  }
  if (!majorantsChanged)
  {
    return;
  }
  const int64_t cells = int64_t(this->View.grid.dims[0]) * this->View.grid.dims[1] * this->View.grid.dims[2];
  this->View.numActive =
    detail::findActiveChannels(this->Majorants.data(), cells, this->NumChannels, this->View.active);
}

bool Scene::update()
{
  if (this->NumChannels == 0)
  {
    throw std::invalid_argument("mcvol: no volume was given");
  }
  for (int n = 0; n < this->NumChannels; ++n)
  {
    // Pre-classified channels read no table.
    if (!this->HasTF[n] && this->Channels[n].format != ChannelFormat::Extinction)
    {
      throw std::invalid_argument("mcvol: " + channelText(n) + " has no transfer function (" +
        std::to_string(this->NumChannels) + " channels need " + std::to_string(this->NumChannels) + ")");
    }
  }
  if (this->View.tables.size < 2)
  {
    // Only pre-classified channels and no table set: the tables become 2
    // transparent texels per channel. Pre-classified channels never read
    // them, but the backends require non-empty tables (the size check of
    // Scene::update's contract) and no code path may read a null table.
    this->Tables.assign(size_t(kMaxChannels) * 2 * 4, 0.f);
    this->View.tables.size = 2;
    for (int n = 0; n < kMaxChannels; ++n)
    {
      this->View.tables.scalarMin[n] = 0.f;
      this->View.tables.scale[n] = 1.f;
    }
    ++this->TableVersion;
  }
  this->refreshImportance();
  bool changed = false;
  if (!this->HostAcceleration)
  {
    // Tables only; the backend builds ranges and majorants from the versions.
    if (this->MacrocellsDirty)
    {
      this->layoutGrid();
      this->MacrocellsDirty = false;
      ++this->DataVersion;
      changed = true;
    }
    for (int n = 0; n < this->NumChannels; ++n)
    {
      changed = changed || this->MajorantDirty[n];
      this->MajorantDirty[n] = false;
    }
    this->refreshView(false);
    this->View.grid.majorants = nullptr;
    this->View.numActive = this->NumChannels;
    for (int n = 0; n < this->NumChannels; ++n)
    {
      this->View.active[n] = n;
    }
    return changed;
  }
  if (this->MacrocellsDirty)
  {
    this->rebuildMacrocells();
    this->MacrocellsDirty = false;
    for (int n = 0; n < this->NumChannels; ++n)
    {
      this->MajorantDirty[n] = true;
    }
    changed = true;
  }
  const auto t0 = std::chrono::steady_clock::now();
  int rebuilt = 0;
  for (int n = 0; n < this->NumChannels; ++n)
  {
    if (this->MajorantDirty[n])
    {
      this->rebuildMajorants(n);
      this->MajorantDirty[n] = false;
      ++rebuilt;
    }
  }
  if (rebuilt > 0)
  {
    this->LastMajorantSeconds = detail::secondsSince(t0);
    this->LastMajorantChannels = rebuilt;
    ++this->TableVersion;
    changed = true;
  }
  this->refreshView(changed);
  return changed;
}
} // namespace mcvol
