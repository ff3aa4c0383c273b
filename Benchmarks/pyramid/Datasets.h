// SPDX-License-Identifier: BSD-3-Clause
//
// mcvol-pyramid: the datasets of the levels section, pre-classified to
// level 0.

#pragma once

#include "mcvol/DemoData.h"
#include "mcvol/Pyramid.h"
#include "mcvol/Scene.h"

#include <array>
#include <string>
#include <vector>

namespace mcvolbench
{
/// A dataset pre-classified to level 0 (packed float4), with what it came from.
struct Classified
{
  std::string name;
  int dims[3] = { 0, 0, 0 };
  double spacing[3] = { 1, 1, 1 };
  std::vector<float> voxels;
  int channels = 0;       ///< scalar channels classified (0: made classified)
  double scalarBytes = 0; ///< the scalar channels' bytes
  double classifyMs = 0;
  mcvol::DemoVolume demo; ///< the scalar data (demo datasets), for the normal path's frame time
  std::vector<mcvol::TransferFunctionDesc> tfs;

  mcvol::ClassifiedVolumeView view() const
  {
    mcvol::ClassifiedVolumeView v;
    v.voxels = this->voxels.data();
    for (int a = 0; a < 3; ++a)
    {
      v.dims[a] = this->dims[a];
      v.spacing[a] = this->spacing[a];
    }
    return v;
  }
};

/// A dataset by name: a demo dataset ("figure3", "microscopy", "cosmology",
/// "weather"; its channels classified, density blend), "wall" or "wall-x" (a
/// one-voxel wall, paper Sec. 3.6 / 4.1) or "figure2" (the paper's Figure 2/3
/// example), made pre-classified. `dims` all zero: the dataset's own size
/// (64^3 for the made ones).
Classified makeDataset(const std::string& name, std::array<int, 3> dims);
} // namespace mcvolbench
