// SPDX-License-Identifier: BSD-3-Clause
#pragma once

#include "mcvol/Scene.h"
#include "mcvol/ray/Types.h"

#include <array>
#include <cstdint>
#include <string>
#include <vector>

namespace mcvol
{
/**
 * A transfer function given by control points over the channel's data range
 * normalised to [0, 1] (0 = channel minimum, 1 = maximum), so one definition
 * fits the small stored datasets and the large benchmark versions alike.
 */
struct DemoTransferFunction
{
  std::vector<std::array<float, 4>> color;   ///< (x, r, g, b)
  std::vector<std::array<float, 2>> opacity; ///< (x, a)
  float unitDistance = 1.f;                  ///< in voxels (times the spacing)
};

/**
 * A generated multi-channel dataset: planar channels (channel n's voxels are
 * contiguous, x fastest), a suggested transfer function per channel.
 * Generation is deterministic: the same name and size give the same bytes on
 * every machine (integer hashing, no std random engines).
 */
struct DemoVolume
{
  std::string name;
  int dims[3] = { 0, 0, 0 }; ///< voxels per axis of the generated box (the channels' layout)
  /// Size of the whole dataset and the generated box's first voxel in it:
  /// the whole volume unless made by makeDemoPiece.
  int wholeDims[3] = { 0, 0, 0 };
  int offset[3] = { 0, 0, 0 };
  double spacing[3] = { 1, 1, 1 };
  ScalarType type = ScalarType::Float32;
  std::vector<std::string> channelNames;
  std::vector<std::vector<uint8_t>> channels; ///< raw bytes of each channel
  std::vector<DemoTransferFunction> transferFunctions;

  int numChannels() const { return int(this->channels.size()); }
  ChannelSource source(int n) const;
  /// Finite min and max of channel n.
  std::array<float, 2> range(int n) const;
};

/// Names of the built-in datasets: "figure3" (paper Fig. 3: three overlapping
/// cubes, red/green/blue, densities falling along +X, -X, -Y), "microscopy"
/// (3 x uint8: membranes, nuclei, puncta), "cosmology" (4 x float32
/// correlated fields), "weather" (12 x float32 hurricane-like fields).
std::vector<std::string> demoNames();

/// Default size of a built-in dataset (the size stored under Data/).
std::array<int, 3> demoDefaultDims(const std::string& name);

/// Generates a dataset; dims all zero means the default size. The channel
/// count of "figure3", "microscopy" and "cosmology" can be raised by
/// `channels` (extra channels repeat the fields with other transfer
/// functions, as the paper does for its channel-count study); 0 = natural.
/// Throws std::invalid_argument for an unknown name or a bad size.
DemoVolume makeDemo(const std::string& name, std::array<int, 3> dims = { 0, 0, 0 }, int channels = 0);

/// Generates the box `extent` (first and last voxel index per axis, as a VTK
/// extent) of the dataset of size `dims`: the same values as those voxels of
/// makeDemo(name, dims, channels), so that each MPI rank can make its own
/// piece of a volume none of them holds whole. Throws std::invalid_argument
/// for an extent outside the volume or empty.
DemoVolume makeDemoPiece(
  const std::string& name, std::array<int, 3> dims, int channels, const std::array<int, 6>& extent);

/// Samples a demo transfer function into a table of K entries over
/// [lo, hi], with the unit distance scaled by `spacing`.
TransferFunctionDesc sampleTransferFunction(const DemoTransferFunction& tf, float lo, float hi, int K, double spacing);
} // namespace mcvol
