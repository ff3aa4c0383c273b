// SPDX-License-Identifier: BSD-3-Clause
#include "LevelOfDetail.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstring>
#include <sstream>
#include <stdexcept>

namespace mcvol
{
namespace adapter
{
namespace
{
std::string MiB(size_t bytes)
{
  // Small levels (tests, far views) in KiB or bytes, so they do not read 0.
  std::ostringstream s;
  s << std::fixed;
  if (bytes < 1024)
  {
    s << bytes << " bytes";
  }
  else if (bytes < (size_t(1) << 20))
  {
    s.precision(1);
    s << double(bytes) / 1024.0 << " KiB";
  }
  else
  {
    s.precision(bytes >= (size_t(100) << 20) ? 0 : 1);
    s << double(bytes) / 1048576.0 << " MiB";
  }
  return s.str();
}

std::string DimsText(const int d[3])
{
  return std::to_string(d[0]) + "x" + std::to_string(d[1]) + "x" + std::to_string(d[2]);
}

bool SameSource(const ChannelSource& a, const ChannelSource& b)
{
  return a.data == b.data && a.type == b.type && a.stride == b.stride && a.offset == b.offset &&
    a.format == b.format && a.scale == b.scale;
}
} // namespace

//------------------------------------------------------------------------------
size_t LevelMemory(const BoundChannels& channels, int level, int outChannels, bool deviceCopy, bool halfPrecision)
{
  size_t bytes = 0;
  if (level == 0)
  {
    const size_t voxels = size_t(channels.Dims[0]) * size_t(channels.Dims[1]) * size_t(channels.Dims[2]);
    for (int c = 0; c < channels.Count; ++c)
    {
      const ChannelSource& s = channels.Sources[size_t(c)];
      const size_t values = s.format == ChannelFormat::Extinction ? 4 : 1;
      const bool narrowed = deviceCopy && s.type == ScalarType::Float64; // the device holds float32
      bytes += voxels * values * size_t(narrowed ? 4 : scalarTypeSize(s.type));
    }
  }
  else
  {
    bytes = levelBytes(channels.Dims, level, outChannels, halfPrecision);
  }
  return bytes;
}

//------------------------------------------------------------------------------
LevelChoice ChooseLevel(const LevelPolicy& policy, const BoundChannels& channels, int outChannels, double footprint,
  const double worldSpacing[3])
{
  LevelChoice choice;
  choice.Levels = maxPyramidLevels(channels.Dims);
  std::ostringstream why;
  if (policy.Requested < 0)
  {
    choice.Automatic = true;
    choice.Footprint = footprint;
    choice.FinestSpacing = std::min(worldSpacing[0], std::min(worldSpacing[1], worldSpacing[2]));
    choice.Wanted = chooseLevelOfDetail(footprint, worldSpacing, choice.Levels);
    why.precision(3);
    why << "automatic footprint: a pixel is " << footprint << " world units at the volume's centre, "
        << footprint / choice.FinestSpacing << " times the finest voxel spacing " << choice.FinestSpacing;
  }
  else if (policy.Requested > choice.Levels)
  {
    choice.Clamped = true;
    choice.Wanted = choice.Levels;
    why << "requested " << policy.Requested << ", clamped: this " << DimsText(channels.Dims) << " volume has "
        << choice.Levels << " levels above 0";
  }
  else
  {
    choice.Wanted = policy.Requested;
    why << "requested";
  }
  choice.Level = choice.Wanted;
  choice.WantedBytes = LevelMemory(channels, choice.Wanted, outChannels, policy.DeviceCopy, policy.HalfPrecision);
  choice.Bytes = choice.WantedBytes;
  if (policy.MemoryBudget > 0.0 && double(choice.Bytes) > policy.MemoryBudget)
  {
    // The finest level at or above the wanted one that fits; the coarsest
    // when none does (a picture rather than none).
    while (choice.Level<choice.Levels&& double(choice.Bytes)> policy.MemoryBudget)
    {
      ++choice.Level;
      choice.Bytes = LevelMemory(channels, choice.Level, outChannels, policy.DeviceCopy, policy.HalfPrecision);
    }
    choice.Fallback = true;
    choice.NoneFits = double(choice.Bytes) > policy.MemoryBudget;
    why << "; memory fallback: level " << choice.Wanted << " needs " << MiB(choice.WantedBytes)
        << (policy.DeviceCopy ? " on the device" : "") << ", more than the budget of "
        << MiB(size_t(policy.MemoryBudget));
    if (choice.NoneFits)
    {
      why << ", and even the coarsest level (" << MiB(choice.Bytes) << ") does not fit";
    }
    else
    {
      why << "; level " << choice.Level << " needs " << MiB(choice.Bytes);
    }
  }
  std::ostringstream report;
  int d[3];
  levelDims(channels.Dims, choice.Level, d);
  report << "level " << choice.Level << " of " << choice.Levels << " (" << DimsText(d) << ", " << MiB(choice.Bytes)
         << ") "
         << (choice.Level == 0 && !choice.Fallback && !choice.Automatic && !choice.Clamped ? "full resolution, " : "")
         << why.str();
  choice.Report = report.str();
  return choice;
}

//------------------------------------------------------------------------------
bool LevelOfDetailCache::Key::operator==(const Key& o) const
{
  if (this->Sources.size() != o.Sources.size())
  {
    return false;
  }
  for (size_t c = 0; c < this->Sources.size(); ++c)
  {
    if (!SameSource(this->Sources[c], o.Sources[c]))
    {
      return false;
    }
  }
  return std::equal(this->Dims, this->Dims + 3, o.Dims) && this->DataMTime == o.DataMTime &&
    this->TablesVersion == o.TablesVersion && this->Filter == o.Filter && this->Summed == o.Summed &&
    this->HalfPrecision == o.HalfPrecision;
}

//------------------------------------------------------------------------------
size_t LevelOfDetailCache::Level::Bytes() const
{
  size_t bytes = 0;
  for (const PyramidLevel& l : this->Channels)
  {
    bytes += l.bytes();
  }
  return bytes;
}

//------------------------------------------------------------------------------
size_t LevelOfDetailCache::Bytes() const
{
  size_t bytes = 0;
  for (const auto& entry : this->Levels)
  {
    bytes += entry.second.Bytes();
  }
  return bytes;
}

//------------------------------------------------------------------------------
void LevelOfDetailCache::Clear()
{
  this->Levels.clear();
  this->HaveKey = false;
  this->Current = Key();
}

//------------------------------------------------------------------------------
void LevelOfDetailCache::DropIfStale(const Key& key)
{
  if (this->HaveKey && !(key == this->Current))
  {
    this->Clear();
  }
}

//------------------------------------------------------------------------------
const LevelOfDetailCache::Level& LevelOfDetailCache::Get(const Key& key, int level, const BoundChannels& channels,
  const std::vector<const TransferFunctionDesc*>& tables, DeviceRenderer* device)
{
  if (!this->HaveKey || !(key == this->Current))
  {
    // New data, tables, filter or grouping: every level is stale. Free them
    // before building, so the old and the new level are never held together.
    this->Levels.clear();
    this->Current = key;
    this->HaveKey = true;
  }
  auto found = this->Levels.find(level);
  if (found != this->Levels.end())
  {
    return found->second;
  }
  // Built in level 0's index space (spacing 1, origin 0): ApplyToCamera maps
  // the camera to it, whatever the image's world geometry.
  const double spacing[3] = { 1.0, 1.0, 1.0 };
  const double origin[3] = { 0.0, 0.0, 0.0 };
  const DownsampleFilter filter = static_cast<DownsampleFilter>(key.Filter);
  const auto start = std::chrono::steady_clock::now();
  Level built;
  size_t work = 0;
  const bool classified = channels.Count == 1 && channels.Sources[0].format == ChannelFormat::Extinction;
  if (classified)
  {
    // Dependent components: level 0 is already the mapper's classified
    // copy; stream it slice by slice.
    const ChannelSource& s = channels.Sources[0];
    const float* voxels = static_cast<const float*>(s.data);
    const size_t slice = size_t(channels.Dims[0]) * size_t(channels.Dims[1]);
    const int64_t stride = s.stride;
    auto copySlice = [voxels, slice, stride](int z, float* out)
    {
      const float* in = voxels + size_t(z) * slice * size_t(stride);
      for (size_t v = 0; v < slice; ++v)
      {
        std::memcpy(out + 4 * v, in + v * size_t(stride), 4 * sizeof(float));
      }
    };
    built.Channels.push_back(streamExtinctionLevel(channels.Dims, spacing, origin, level, filter, copySlice, &work));
  }
  else
  {
    if (int(tables.size()) < channels.Count)
    {
      throw std::invalid_argument("mcvol: a level of detail needs a transfer-function table per channel");
    }
    std::vector<ClassifyInput> inputs(size_t(channels.Count));
    for (int c = 0; c < channels.Count; ++c)
    {
      inputs[size_t(c)].source = channels.Sources[size_t(c)];
      inputs[size_t(c)].tf = tables[size_t(c)];
      // The arrays' modification time names their values: a device builder
      // keeps its copies of them while it stays the same.
      inputs[size_t(c)].dataVersion = static_cast<uint64_t>(key.DataMTime);
    }
    // On the render backend's device where it builds levels there (CUDA),
    // else streamed on the host; the same level to float rounding.
    bool onDevice = device && device->buildsLevelsOnDevice();
    auto build = [&](const ClassifyInput* first, int count, size_t* peak)
    {
      if (onDevice)
      {
        try
        {
          return device->classifyLevel(first, count, channels.Dims, spacing, origin, level, filter, peak);
        }
        catch (const std::runtime_error&)
        {
          // The device failed (out of memory, say): this level and the
          // next channels' are built on the host. Bad input throws
          // std::invalid_argument on both, and is not caught.
          onDevice = false;
        }
      }
      return classifyExtinctionLevel(first, count, channels.Dims, spacing, origin, level, filter, peak);
    };
    if (key.Summed)
    {
      built.Channels.push_back(build(inputs.data(), channels.Count, &work));
    }
    else
    {
      for (int c = 0; c < channels.Count; ++c)
      {
        size_t channelWork = 0;
        built.Channels.push_back(build(&inputs[size_t(c)], 1, &channelWork));
        work = std::max(work, channelWork);
      }
    }
  }
  if (key.HalfPrecision)
  {
    // Half precision: the level's voxels as binary16 (PyramidLevel::
    // toHalfPrecision). The mapper asks for it only where the backend reads
    // the levels in place (the CPU).
    for (PyramidLevel& channel : built.Channels)
    {
      channel.toHalfPrecision();
    }
  }
  built.BuildSeconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  built.WorkBytes = work;
  built.Version = this->NextVersion++;
  ++this->BuildCount;
  this->LastSeconds = built.BuildSeconds;
  this->LastWork = work;
  return this->Levels.emplace(level, std::move(built)).first->second;
}

//------------------------------------------------------------------------------
void ApplyToCamera(const PyramidLevel& level, Camera& camera)
{
  for (int r = 0; r < 3; ++r)
  {
    const double s = level.spacing[r];
    for (int k = 0; k < 3; ++k)
    {
      camera.worldToIndex[4 * r + k] /= s;
    }
    camera.worldToIndex[4 * r + 3] = (camera.worldToIndex[4 * r + 3] - level.origin[r]) / s;
  }
}
} // namespace adapter
} // namespace mcvol
