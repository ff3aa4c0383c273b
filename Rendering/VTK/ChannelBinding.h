// SPDX-License-Identifier: BSD-3-Clause
#pragma once

#include "vtkSmartPointer.h" // For vtkSmartPointer
#include "vtkType.h"         // For vtkMTimeType

#include "mcvol/Scene.h"

#include <array>
#include <string>
#include <vector>

class vtkDataArray;
class vtkImageData;

namespace mcvol
{
namespace adapter
{
/**
 * Stage 1 of vtkMultiChannelVolumeMapper::Render: which arrays and
 * components of the input image are the channels, read in place as core
 * ChannelSources (no copy), and whether their values changed since the
 * Scene last saw them.
 */

/// Where the channels come from: named single-component point arrays, or
/// else the components of the mapper's selected scalars.
struct ChannelSelection
{
  const std::vector<std::string>* ArrayNames = nullptr;
  int ScalarMode = 0;
  int ArrayAccessMode = 0;
  int ArrayId = -1;
  const char* ArrayName = nullptr;
};

/// The channels of one render, as found on the input.
struct BoundChannels
{
  int Extent[6] = {};
  int Dims[3] = {};
  int Count = 0;
  std::vector<vtkDataArray*> Arrays; ///< one per channel
  std::vector<int> Components;       ///< the component of that array
  std::array<ChannelSource, kMaxChannels> Sources{};
  /// The arrays' times: their values. The image's time also moves when only
  /// its origin, spacing or direction do, which needs no rebuild (those reach
  /// the renderer through the camera's worldToIndex).
  vtkMTimeType DataMTime = 0;
  /// The image's and its point data's own times (Modified() on either),
  /// without their arrays': a writer that changed values in place may have
  /// marked only these; so do pipeline steps that change nothing the
  /// channels hold (ParaView's colouring sets the active scalars).
  vtkMTimeType ImageMTime = 0;
  std::array<double, 15> Geometry{}; ///< origin, spacing, direction
};

/// Checks the image's extent and finds its channels. On failure `error` says
/// what is wrong, in words a user can act on.
bool BindChannels(vtkImageData* image, const ChannelSelection& selection, BoundChannels& out, std::string& error);

/**
 * What the Scene holds of the data: the channel sources, the arrays kept
 * alive, their times and value ranges. Update() gives the Scene a new volume
 * when the channels' layout changed, or marks its data modified when only
 * values did.
 */
class ChannelData
{
public:
  struct Change
  {
    bool Volume = false; ///< new channel layout: setVolume was called
    bool Values = false; ///< values changed (Volume or values written in place)
  };

  /// May mark `channels`' arrays modified (see the .cxx) and may throw what
  /// Scene::setVolume throws. `forgetTables` runs before a new volume is set.
  template <class Forget>
  Change Update(Scene& scene, vtkImageData* image, BoundChannels& channels, Forget&& forgetTables)
  {
    Change change = this->Detect(scene, image, channels);
    if (change.Volume)
    {
      this->Forget();
      forgetTables();
      this->SetVolume(scene, channels);
    }
    else if (change.Values)
    {
      scene.dataModified();
    }
    return change;
  }

  /// Nothing is bound any more (after an error): the next Update sets the
  /// volume again.
  void Forget()
  {
    this->VolumeSet = false;
    this->Arrays.clear();
  }

  /// Finite value range of channel c, as the transfer-function tables use it.
  const std::array<double, 2>& Range(int c) const { return this->Ranges[c]; }

private:
  Change Detect(Scene& scene, vtkImageData* image, BoundChannels& channels);
  void SetVolume(Scene& scene, const BoundChannels& channels);

  bool VolumeSet = false;
  std::array<ChannelSource, kMaxChannels> Sources{};
  std::vector<vtkSmartPointer<vtkDataArray>> Arrays; // keeps the channel data alive
  vtkMTimeType DataMTime = 0;                        // of the arrays: their values
  vtkMTimeType ImageMTime = 0;                       // the image's and point data's own
  std::array<double, 15> Geometry{};                 // origin, spacing, direction of ImageMTime
  // A digest of the channel arrays' bytes, taken when the image was marked
  // modified but its arrays were not: the next such mark compares with it,
  // and a change restarts only if the values differ.
  std::vector<unsigned long long> Digests;
  bool DigestsValid = false;
  std::array<std::array<double, 2>, kMaxChannels> Ranges{};
  // The input image of the last render (compared, never dereferenced).
  const void* LastImage = nullptr;
};
} // namespace adapter
} // namespace mcvol
