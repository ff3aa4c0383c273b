// SPDX-License-Identifier: BSD-3-Clause
#pragma once

#include "vtkSmartPointer.h" // For vtkSmartPointer
#include "vtkType.h"         // For vtkMTimeType

#include "mcvol/Scene.h"

#include <array>
#include <string>
#include <vector>

class vtkColorTransferFunction;
class vtkObject;
class vtkPiecewiseFunction;
class vtkVolumeProperty;

namespace mcvol
{
namespace adapter
{
/**
 * Stage 2 of vtkMultiChannelVolumeMapper::Render: each channel's VTK colour
 * and opacity functions become the core's sampled tables. A table is rebuilt
 * (and with it only that channel's majorants) when the functions' values
 * change, not merely their times.
 */

/// What the user set on the mapper for each channel (overriding the volume
/// property's per-component functions, which exist for channels 0-3 only).
struct ChannelFunctionOverrides
{
  std::array<vtkSmartPointer<vtkColorTransferFunction>, kMaxChannels> Colors;
  std::array<vtkSmartPointer<vtkPiecewiseFunction>, kMaxChannels> Opacities;
  std::array<double, kMaxChannels> UnitDistances{};
  /// Visibility optimization: importance of the channel's value (none: null).
  std::array<vtkSmartPointer<vtkPiecewiseFunction>, kMaxChannels> Importance;
};

/// Everything that decides which transfer-function table a channel gets; a
/// channel's table is rebuilt (and only its majorants) when this changes.
struct ChannelFunctions
{
  bool Valid = false;
  vtkObject* Color = nullptr; // vtkColorTransferFunction or gray vtkPiecewiseFunction
  bool Gray = false;
  vtkMTimeType ColorMTime = 0;
  vtkPiecewiseFunction* Opacity = nullptr;
  vtkMTimeType OpacityMTime = 0;
  double UnitDistance = 0.0;
  double Range[2] = { 0.0, 0.0 };
  /// With the visibility optimization on: the channel's importance function,
  /// whose range joins the functions' range in FUNCTION_RANGE mode (the
  /// importance table shares the colour table's range). Not compared: a
  /// change that matters shows in Range.
  vtkPiecewiseFunction* Importance = nullptr;

  bool operator==(const ChannelFunctions& o) const
  {
    return this->Valid == o.Valid && this->Color == o.Color && this->Gray == o.Gray &&
      this->ColorMTime == o.ColorMTime && this->Opacity == o.Opacity && this->OpacityMTime == o.OpacityMTime &&
      this->UnitDistance == o.UnitDistance && this->Range[0] == o.Range[0] && this->Range[1] == o.Range[1];
  }
  bool operator!=(const ChannelFunctions& o) const { return !(*this == o); }
};

using ChannelFunctionSet = std::array<ChannelFunctions, kMaxChannels>;

/// The functions of channels [0, numChannels): the mapper's own where set,
/// else the volume property's component functions (VTK's convention).
bool ResolveChannelFunctions(const ChannelFunctionOverrides& overrides, vtkVolumeProperty* property, int numChannels,
  ChannelFunctionSet& out, std::string& error);

/// The tables last given to the Scene, and a version that moves whenever one
/// really changes: a function whose time moves but whose values do not
/// (ParaView's lookup tables are touched on every render while they colour
/// something) neither rebuilds the grids nor restarts the image.
class TransferFunctionTables
{
public:
  static constexpr int kTableSize = 1024;

  /// Gives the Scene the tables of `functions` over each channel's value
  /// range (DATA_RANGE: `ranges`; FUNCTION_RANGE: the functions' own range,
  /// the same on every rank of a parallel render). Returns how many tables
  /// changed.
  template <class RangeOf>
  int Update(Scene& scene, ChannelFunctionSet& functions, int numChannels, bool functionRange, RangeOf&& ranges)
  {
    int updates = 0;
    for (int c = 0; c < numChannels; ++c)
    {
      const std::array<double, 2>& range = ranges(c);
      updates += this->UpdateChannel(scene, c, functions[c], range[0], range[1], functionRange) ? 1 : 0;
    }
    return updates;
  }

  /// Importance tables of the channels that have an importance function,
  /// sampled over the same ranges as their colour tables (call after
  /// Update()); empty for the others. A change moves Version().
  void UpdateImportance(const ChannelFunctionOverrides& overrides, int numChannels);
  const std::vector<std::vector<float>>& ImportanceTables() const { return this->Importance; }

  /// The Scene holds no tables any more (new volume or an error).
  void Forget();

  /// The channels whose colour or opacity function has no points (a
  /// function without points reads 0 everywhere: transparent, or black), in
  /// words for a warning; empty when every function has a point.
  std::string EmptyFunctions(int numChannels) const;

  /// The table last given to the Scene for channel c (the levels of detail
  /// pre-classify with the same tables, so level 0 and level L agree).
  const TransferFunctionDesc& Table(int c) const { return this->Tables[size_t(c)]; }

  /// Moves whenever a table given to the Scene changes (accumulation key).
  unsigned long long Version() const { return this->TablesVersion; }

private:
  bool UpdateChannel(Scene& scene, int c, ChannelFunctions& s, double lo, double hi, bool functionRange);

  std::array<ChannelFunctions, kMaxChannels> Functions{};
  std::array<TransferFunctionDesc, kMaxChannels> Tables{};
  unsigned long long TablesVersion = 0;
  struct ImportanceKey
  {
    vtkPiecewiseFunction* Function = nullptr;
    vtkMTimeType MTime = 0;
    double Range[2] = { 0.0, 0.0 };
  };
  std::array<ImportanceKey, kMaxChannels> ImportanceKeys{};
  std::vector<std::vector<float>> Importance;
};
} // namespace adapter
} // namespace mcvol
