// SPDX-License-Identifier: BSD-3-Clause
#pragma once

#include "vtkType.h" // For vtkMTimeType

#include "ChannelBinding.h"

#include "mcvol/Pyramid.h"
#include "mcvol/DeviceRenderer.h"
#include "mcvol/Scene.h"

#include <map>
#include <string>
#include <vector>

namespace mcvol
{
namespace adapter
{
/**
 * Stage 4b of vtkMultiChannelVolumeMapper::Render: levels of detail (Kraus
 * and Buerger, Sec. 4). Which level this render uses (the
 * one asked for, the automatic footprint rule, or the finest that fits the
 * memory budget), and that level's pre-classified channels, built by
 * streaming level 0 slice by slice (mcvol::classifyExtinctionLevel), or on
 * the render backend's device where it builds levels there
 * (DeviceRenderer::classifyLevel: CUDA), and kept until the data, a transfer-function table, the filter or the channel
 * grouping changes.
 *
 * A level's geometry is kept in level 0's continuous index space (level 0's
 * voxel i at index i): the level's voxel j is at index origin + spacing * j
 * (Pyramid.h's cell-centred alignment), so the camera's world-to-index map
 * of level 0 becomes the level's by one affine map per axis
 * (ApplyToCamera), whatever the image's spacing, direction or the volume's
 * matrix.
 */

/// How a level is asked for, and what bounds it.
struct LevelPolicy
{
  int Requested = 0;         ///< -1 automatic, 0 full resolution, L > 0 level L
  double MemoryBudget = 0.0; ///< bytes the volume may take (0: no cap)
  /// The backend copies the channels to a device (CUDA: each channel held
  /// once, as a texture or an array; float64 stored as float32); the CPU
  /// reads them in place.
  bool DeviceCopy = false;
  /// Levels L > 0 held in half precision (8 bytes a voxel and channel): the
  /// mapper's LevelOfDetailHalfPrecision where there is no device copy (it
  /// keeps float32 levels for a device, which holds 16 bytes).
  bool HalfPrecision = false;
};

/// The level a render uses, and why.
struct LevelChoice
{
  int Level = 0;          ///< the level rendered
  int Levels = 0;         ///< levels available above 0 (maxPyramidLevels)
  int Wanted = 0;         ///< before the memory fallback
  bool Clamped = false;   ///< the request was above Levels
  bool Automatic = false; ///< chosen by the footprint rule
  bool Fallback = false;  ///< coarser than Wanted for the memory budget
  bool NoneFits = false;  ///< even the coarsest level exceeds the budget
  double Footprint = 0.0; ///< automatic: world size of a pixel at the volume
  double FinestSpacing = 0.0;
  size_t WantedBytes = 0; ///< what Wanted would hold
  size_t Bytes = 0;       ///< what Level holds
  std::string Report;     ///< one sentence: the level and why
};

/// The memory one level of the volume takes in the backend: level 0 the
/// channels as bound (read in place on the CPU; on a device float64 is held
/// as float32), a level L > 0 `outChannels` pre-classified channels of 16
/// bytes a voxel, or 8 in half precision (`halfPrecision`).
size_t LevelMemory(
  const BoundChannels& channels, int level, int outChannels, bool deviceCopy, bool halfPrecision = false);

/**
 * Chooses the level: the request (clamped to [0, levels]) or, for -1, the
 * footprint rule (mcvol::chooseLevelOfDetail with `footprint` and the
 * finest world spacing of `worldSpacing`); then, with a budget, the finest
 * level at or above it whose LevelMemory fits.
 */
LevelChoice ChooseLevel(const LevelPolicy& policy, const BoundChannels& channels, int outChannels, double footprint,
  const double worldSpacing[3]);

/**
 * The levels built for the current data, tables, filter and grouping. A
 * level is built when first asked for and kept; all are dropped when any
 * of those change (Key).
 */
class LevelOfDetailCache
{
public:
  /// What a level's voxels depend on.
  struct Key
  {
    std::vector<ChannelSource> Sources; ///< data pointers, types, strides, offsets
    int Dims[3] = { 0, 0, 0 };
    vtkMTimeType DataMTime = 0;           ///< the arrays' values (or the classified copy's)
    unsigned long long TablesVersion = 0; ///< the transfer-function tables
    int Filter = 0;
    bool Summed = false; ///< channels summed into one (density blend)
    bool HalfPrecision = false; ///< levels converted by PyramidLevel::toHalfPrecision
    bool operator==(const Key& o) const;
  };

  /// One built level: one pre-classified channel, or one per input channel.
  struct Level
  {
    std::vector<PyramidLevel> Channels;
    unsigned long long Version = 0; ///< unique per build (accumulation key)
    double BuildSeconds = 0.0;
    size_t WorkBytes = 0; ///< peak working memory of the build (the device's when built there)
    size_t Bytes() const;
  };

  /**
   * Level `level` (> 0) for `key`: from the cache, or built from
   * `channels` (scalar channels through `tables`, one per channel; or the
   * one classified channel of dependent components). `summed` adds the
   * channels into one (Eq. 6/7). Scalar channels are built by `device`'s
   * DeviceRenderer::classifyLevel when it builds levels on the device (CUDA:
   * the same level to float rounding, the channels kept on the
   * device under the key's DataMTime so that a transfer-function edit
   * copies nothing but the tables), otherwise by classifyExtinctionLevel on
   * the host, streamed. The dependent components' classified channel is
   * always streamed on the host. Throws what the core throws.
   */
  const Level& Get(const Key& key, int level, const BoundChannels& channels,
    const std::vector<const TransferFunctionDesc*>& tables, DeviceRenderer* device = nullptr);

  /// Drops every level (the mapper's data went away).
  void Clear();

  /// Drops the levels if they were built for another key (a render at level
  /// 0 after the data or a function changed: they would be rebuilt anyway,
  /// and would only hold memory meanwhile).
  void DropIfStale(const Key& key);

  int Builds() const { return this->BuildCount; }
  /// Bytes of all cached levels.
  size_t Bytes() const;
  /// The last build's seconds and peak working memory (0 before any).
  double LastBuildSeconds() const { return this->LastSeconds; }
  size_t LastWorkBytes() const { return this->LastWork; }

private:
  bool HaveKey = false;
  Key Current;
  std::map<int, Level> Levels;
  int BuildCount = 0;
  unsigned long long NextVersion = 1;
  double LastSeconds = 0.0;
  size_t LastWork = 0;
};

/// Turns level 0's camera (world to level-0 index) into the level's:
/// index_L = (index_0 - origin) / spacing per axis, with the level's
/// origin and spacing in level-0 index units.
void ApplyToCamera(const PyramidLevel& level, Camera& camera);
} // namespace adapter
} // namespace mcvol
