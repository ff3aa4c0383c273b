// SPDX-License-Identifier: BSD-3-Clause
#pragma once

#include "vtkTimeStamp.h" // For vtkTimeStamp
#include "vtkType.h"      // For vtkMTimeType

#include "ChannelBinding.h"
#include "TransferFunctionTables.h"

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
 * Stage 1b of vtkMultiChannelVolumeMapper::Render: dependent components
 * (vtkVolumeProperty::IndependentComponentsOff), VTK's convention:
 * - 4 components: RGB directly from components 0-2 (unsigned char: value /
 *   255; other types: each component scaled over its finite range to [0, 1],
 *   as VTK's GPU ray caster does; a constant component is clamped to [0, 1]),
 *   opacity from component 3 through channel 0's scalar opacity function;
 * - 2 components: colour from component 0 through channel 0's colour
 *   function, opacity from component 1 through its scalar opacity function.
 * The voxels are classified into an owned float buffer in the core's
 * pre-classified layout (ChannelFormat::Extinction: sigma, sigma r, sigma g,
 * sigma b; sigma = -ln(1 - alpha) / unit distance), which becomes the one
 * channel the Scene renders. The buffer is rebuilt only when the data, the
 * functions' values or the unit distance change.
 */
class DependentClassifier
{
public:
  /// Classifies `channels` (the components of one 2- or 4-component array,
  /// as BindChannels found them) when needed and replaces them with the one
  /// classified channel. `functions` are channel 0's (colour, opacity, unit
  /// distance). On failure returns false and sets `error`.
  bool Update(vtkImageData* image, const ChannelFunctions& functions, BoundChannels& channels, std::string& error);

  /// Frees the buffer (the Scene no longer reads it).
  void Release();

  /// Whether the last Update() rebuilt the buffer.
  bool LastUpdateClassified() const { return this->Classified; }
  /// Classifications since the mapper was created.
  int Classifications() const { return this->Count; }
  /// Bytes of the classified copy (16 per voxel).
  size_t Bytes() const { return this->Buffer.size() * sizeof(float); }

  /// A function sampled at `Size` points over [Lo, Hi] (linear in between,
  /// clamped beyond): `Width` floats a sample. Integer data whose range has
  /// at most 65536 values get one sample per value (exact).
  struct Table
  {
    double Lo = 0.0;
    double Hi = 0.0;
    double Scale = 0.0; ///< (Size - 1) / (Hi - Lo), 0 for one sample
    int Size = 0;
    int Width = 1;
    std::vector<float> Values;
    bool operator==(const Table& o) const
    {
      return this->Lo == o.Lo && this->Hi == o.Hi && this->Size == o.Size && this->Width == o.Width &&
        this->Values == o.Values;
    }
    bool operator!=(const Table& o) const { return !(*this == o); }
  };

private:
  struct Key
  {
    const void* Array = nullptr;
    vtkMTimeType ArrayMTime = 0;
    int Components = 0;
    int Type = 0;
    int Dims[3] = { 0, 0, 0 };
    const void* Color = nullptr;
    vtkMTimeType ColorMTime = 0;
    bool Gray = false;
    const void* Opacity = nullptr;
    vtkMTimeType OpacityMTime = 0;
    double UnitDistance = 0.0;
    bool operator==(const Key& o) const
    {
      return this->Array == o.Array && this->ArrayMTime == o.ArrayMTime && this->Components == o.Components &&
        this->Type == o.Type && this->Dims[0] == o.Dims[0] && this->Dims[1] == o.Dims[1] &&
        this->Dims[2] == o.Dims[2] && this->Color == o.Color && this->ColorMTime == o.ColorMTime &&
        this->Gray == o.Gray && this->Opacity == o.Opacity && this->OpacityMTime == o.OpacityMTime &&
        this->UnitDistance == o.UnitDistance;
    }
  };

  /// What the classification of `array` depends on.
  static Key KeyOf(vtkDataArray* array, const ChannelFunctions& functions, const BoundChannels& channels);
  /// Marks the array modified when only the image's time moved (values
  /// written in place), and remembers the image.
  void NoteInPlaceWrites(vtkImageData* image, const BoundChannels& channels, vtkDataArray* array);
  /// Samples the functions and classifies the voxels into Buffer unless only
  /// the functions' times moved. On failure releases the buffer, returns
  /// false and sets `error`.
  bool Reclassify(const Key& key, vtkDataArray* array, const ChannelFunctions& functions, std::string& error);

  std::vector<float> Buffer;
  bool Valid = false; // Buffer holds the classification of LastKey
  Key LastKey;
  // What the last classification used (a key whose times moved but whose
  // tables did not change reuses the buffer).
  Table ColorTable;                                   // 2 components: colour of component 0
  Table OpacityTable;                                 // opacity of the last component
  std::array<std::array<double, 2>, 3> ColorRanges{}; // 4 components, not unsigned char
  vtkTimeStamp ClassifiedTime;
  bool Classified = false;
  int Count = 0;
  // The image of the last update (compared, never dereferenced), for values
  // written in place with only the image marked modified.
  const void* LastImage = nullptr;
  vtkMTimeType ImageMTime = 0;
  std::array<double, 15> Geometry{};
};
} // namespace adapter
} // namespace mcvol
