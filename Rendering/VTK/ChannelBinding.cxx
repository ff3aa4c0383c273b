// SPDX-License-Identifier: BSD-3-Clause
#include "ChannelBinding.h"

#include "ScalarTypeMap.h"

#include "vtkAbstractMapper.h"
#include "vtkDataArray.h"
#include "vtkImageData.h"
#include "vtkMatrix3x3.h"
#include "vtkPointData.h"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <sstream>

namespace mcvol
{
namespace adapter
{
namespace
{
/// The arrays and components that are the channels (no checks of their
/// types or sizes yet).
bool FindChannelArrays(vtkImageData* image, const ChannelSelection& selection, BoundChannels& out, std::ostream& error)
{
  if (selection.ArrayNames && !selection.ArrayNames->empty())
  {
    for (const std::string& name : *selection.ArrayNames)
    {
      vtkDataArray* array = image->GetPointData()->GetArray(name.c_str());
      if (!array)
      {
        vtkAbstractArray* other = image->GetPointData()->GetAbstractArray(name.c_str());
        if (other)
        {
          error << "Channel array \"" << name << "\" is a point array of " << other->GetClassName()
                << ", which holds no numbers; a channel needs a numeric array ("
                << "unsigned char, short, unsigned short, float or double).";
          return false;
        }
        error << "Channel array \"" << name << "\" is not a point data array of the input.";
        return false;
      }
      if (array->GetNumberOfComponents() != 1)
      {
        error << "Channel array \"" << name << "\" has " << array->GetNumberOfComponents()
              << " components; channel arrays must have one.";
        return false;
      }
      out.Arrays.push_back(array);
      out.Components.push_back(0);
    }
    return true;
  }
  int cellFlag = 0;
  vtkDataArray* scalars = vtkAbstractMapper::GetScalars(
    image, selection.ScalarMode, selection.ArrayAccessMode, selection.ArrayId, selection.ArrayName, cellFlag);
  if (!scalars)
  {
    error << "Input has no point scalars to render (set them, select an array with "
             "SelectScalarArray, or list channel arrays with AddChannelArray).";
    return false;
  }
  if (cellFlag)
  {
    error << "Scalars \"" << (scalars->GetName() ? scalars->GetName() : "")
          << "\" are cell data; only point data is supported.";
    return false;
  }
  for (int c = 0; c < scalars->GetNumberOfComponents(); ++c)
  {
    out.Arrays.push_back(scalars);
    out.Components.push_back(c);
  }
  return true;
}

/// Channel c as a core source read in place: a supported type, one value per
/// point, contiguous tuples.
bool BindChannel(
  int c, vtkDataArray* array, int component, vtkIdType numPoints, ChannelSource& source, std::ostream& error)
{
  const char* arrayName = array->GetName() ? array->GetName() : "(unnamed)";
  ScalarType type;
  if (!ToCoreScalarType(array->GetDataType(), type))
  {
    error << "Channel " << c << " (array \"" << arrayName << "\") has type " << array->GetDataTypeAsString()
          << "; supported types are unsigned char, short, unsigned short, "
             "float and double.";
    return false;
  }
  if (array->GetNumberOfTuples() != numPoints)
  {
    error << "Channel " << c << " (array \"" << arrayName << "\") has " << array->GetNumberOfTuples() << " tuples for "
          << numPoints << " points.";
    return false;
  }
  if (!array->HasStandardMemoryLayout())
  {
    error << "Channel " << c << " (array \"" << arrayName
          << "\") is not a contiguous array of tuples (AOS); it cannot be "
             "read in place.";
    return false;
  }
  source.data = static_cast<const char*>(array->GetVoidPointer(0)) +
    static_cast<size_t>(component) * static_cast<size_t>(array->GetDataTypeSize());
  source.type = type;
  source.stride = array->GetNumberOfComponents();
  return true;
}

// A 64-bit digest of each channel array's bytes (FNV-1a over 8-byte words,
// then the tail), for telling values written in place from a Modified()
// that changed nothing. One pass over the data, as the range computation.
std::vector<unsigned long long> DigestArrays(const BoundChannels& channels)
{
  std::vector<unsigned long long> out;
  for (int c = 0; c < channels.Count; ++c)
  {
    vtkDataArray* array = channels.Arrays[c];
    const auto* bytes = static_cast<const unsigned char*>(array->GetVoidPointer(0));
    const size_t n = static_cast<size_t>(array->GetNumberOfValues()) * static_cast<size_t>(array->GetDataTypeSize());
    unsigned long long h = 1469598103934665603ull;
    size_t i = 0;
    for (; i + 8 <= n; i += 8)
    {
      unsigned long long word;
      std::memcpy(&word, bytes + i, 8);
      h = (h ^ word) * 1099511628211ull;
    }
    for (; i < n; ++i)
    {
      h = (h ^ bytes[i]) * 1099511628211ull;
    }
    out.push_back(h);
  }
  return out;
}
} // namespace

//------------------------------------------------------------------------------
bool BindChannels(vtkImageData* image, const ChannelSelection& selection, BoundChannels& out, std::string& error)
{
  std::ostringstream msg;
  image->GetExtent(out.Extent);
  for (int a = 0; a < 3; ++a)
  {
    out.Dims[a] = out.Extent[2 * a + 1] - out.Extent[2 * a] + 1;
  }
  if (out.Dims[0] < 1 || out.Dims[1] < 1 || out.Dims[2] < 1)
  {
    const int* e = out.Extent;
    msg << "Input image has an empty extent (" << e[0] << " " << e[1] << " " << e[2] << " " << e[3] << " " << e[4]
        << " " << e[5] << ").";
    error = msg.str();
    return false;
  }
  if (!FindChannelArrays(image, selection, out, msg))
  {
    error = msg.str();
    return false;
  }
  out.Count = static_cast<int>(out.Arrays.size());
  if (out.Count < 1 || out.Count > kMaxChannels)
  {
    msg << "The input has " << out.Count << " channels; 1 to " << kMaxChannels << " are supported.";
    error = msg.str();
    return false;
  }

  out.DataMTime = 0;
  out.ImageMTime = std::max(image->vtkObject::GetMTime(), image->GetPointData()->vtkObject::GetMTime());
  std::copy(image->GetOrigin(), image->GetOrigin() + 3, out.Geometry.begin());
  std::copy(image->GetSpacing(), image->GetSpacing() + 3, out.Geometry.begin() + 3);
  std::copy(
    image->GetDirectionMatrix()->GetData(), image->GetDirectionMatrix()->GetData() + 9, out.Geometry.begin() + 6);
  const vtkIdType numPoints = image->GetNumberOfPoints();
  for (int c = 0; c < out.Count; ++c)
  {
    if (!BindChannel(c, out.Arrays[c], out.Components[c], numPoints, out.Sources[c], msg))
    {
      error = msg.str();
      return false;
    }
    out.DataMTime = std::max(out.DataMTime, out.Arrays[c]->GetMTime());
  }
  return true;
}

//------------------------------------------------------------------------------
ChannelData::Change ChannelData::Detect(Scene& scene, vtkImageData* image, BoundChannels& channels)
{
  const int numChannels = channels.Count;
  bool volumeChanged = !this->VolumeSet || scene.numChannels() != numChannels ||
    !std::equal(channels.Dims, channels.Dims + 3, scene.dims());
  for (int c = 0; c < numChannels && !volumeChanged; ++c)
  {
    volumeChanged = channels.Sources[c].data != this->Sources[c].data ||
      channels.Sources[c].type != this->Sources[c].type || channels.Sources[c].stride != this->Sources[c].stride;
  }
  // An image Modified() with the same geometry may mean values written in
  // place (users often call image->Modified() rather than the array's).
  // Only for the same image object: a new image holding the same arrays
  // (ParaView delivers a fresh shallow copy for every parallel render)
  // changed nothing the arrays' times would not show. Such a mark is checked
  // against the values: the first after a change of the arrays is taken as a
  // change (nothing to compare with yet) and records a digest of the bytes;
  // later ones change something only when the digest differs.
  const bool sameImage = this->LastImage == image;
  const bool marked = sameImage && !volumeChanged && channels.ImageMTime != this->ImageMTime &&
    channels.Geometry == this->Geometry && channels.DataMTime == this->DataMTime;
  bool imageValuesChanged = false;
  if (marked)
  {
    std::vector<unsigned long long> digests = DigestArrays(channels);
    imageValuesChanged = !this->DigestsValid || digests != this->Digests;
    this->Digests.swap(digests);
    this->DigestsValid = true;
  }
  else if (volumeChanged || channels.DataMTime != this->DataMTime)
  {
    this->DigestsValid = false;
  }
  this->LastImage = image;
  const bool dataChanged = volumeChanged || channels.DataMTime != this->DataMTime || imageValuesChanged;
  this->ImageMTime = channels.ImageMTime;
  this->Geometry = channels.Geometry;
  if (imageValuesChanged)
  {
    // The arrays were not marked modified, so their cached ranges are
    // stale: mark them (what the writer should have done) and take the
    // new time, so the next render sees no change.
    for (vtkDataArray* a : channels.Arrays)
    {
      a->Modified();
      channels.DataMTime = std::max(channels.DataMTime, a->GetMTime());
    }
  }
  if (dataChanged)
  {
    this->DataMTime = channels.DataMTime;
    for (int c = 0; c < numChannels; ++c)
    {
      // Finite range: NaN and Inf voxels must not stretch or poison the table.
      double range[2];
      channels.Arrays[c]->GetFiniteRange(range, channels.Components[c]);
      if (!(range[0] <= range[1]) || !std::isfinite(range[0]) || !std::isfinite(range[1]))
      {
        range[0] = 0.0; // no finite voxel at all
        range[1] = 1.0;
      }
      if (range[0] == range[1])
      {
        // A constant channel: its value on the table's first texel, so that
        // it reads exactly the functions' value there (between two texels
        // it would blend in its neighbour's, and an all-zero channel whose
        // opacity is 0 at 0 would add a haze). (Ranges narrower than float
        // resolution are widened by the core.)
        range[1] += std::max(1.0, 1e-3 * std::abs(range[0]));
      }
      this->Ranges[c] = { range[0], range[1] };
    }
  }
  // Double data is read relative to its minimum, so values far from zero
  // (1e9 + [0, 500]) keep their resolution when they become float.
  for (int c = 0; c < numChannels; ++c)
  {
    ChannelSource& source = channels.Sources[c];
    source.offset = source.type == ScalarType::Float64 ? this->Ranges[c][0] : 0.0;
    volumeChanged = volumeChanged || source.offset != this->Sources[c].offset;
  }
  Change change;
  change.Volume = volumeChanged;
  change.Values = dataChanged;
  return change;
}

//------------------------------------------------------------------------------
void ChannelData::SetVolume(Scene& scene, const BoundChannels& channels)
{
  scene.setVolume(channels.Dims, channels.Count, channels.Sources.data());
  this->VolumeSet = true;
  this->Sources = channels.Sources;
  this->Arrays.assign(channels.Arrays.begin(), channels.Arrays.end());
}
} // namespace adapter
} // namespace mcvol
