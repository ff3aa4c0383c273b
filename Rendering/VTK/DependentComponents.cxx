// SPDX-License-Identifier: BSD-3-Clause
#include "DependentComponents.h"

#include "vtkColorTransferFunction.h"
#include "vtkDataArray.h"
#include "vtkImageData.h"
#include "vtkPiecewiseFunction.h"

#include "mcvol/Scene.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <exception>
#include <sstream>
#include <type_traits>

namespace mcvol
{
namespace adapter
{
namespace
{
using Table = DependentClassifier::Table;

/// Samples over float data (or integer data of a wider range).
constexpr int kFloatTableSize = 4096;
/// Integer data with at most this many distinct values get an exact table.
constexpr double kMaxExactTableSize = 65536.0;

/// Finite range of one component; [0, 1] when it has no finite value.
/// Unsigned char: all its values, [0, 255] (an exact table, no scan).
std::array<double, 2> FiniteRange(vtkDataArray* array, int component)
{
  if (array->GetDataType() == VTK_UNSIGNED_CHAR)
  {
    return { 0.0, 255.0 };
  }
  double r[2];
  array->GetFiniteRange(r, component);
  if (!(r[0] <= r[1]) || !std::isfinite(r[0]) || !std::isfinite(r[1]))
  {
    r[0] = 0.0;
    r[1] = 1.0;
  }
  return { r[0], r[1] };
}

/// The layout of a table over [lo, hi] for data of `vtkType`.
Table TableLayout(double lo, double hi, int vtkType, int width)
{
  Table t;
  t.Lo = lo;
  t.Hi = hi;
  t.Width = width;
  const bool integer = vtkType != VTK_FLOAT && vtkType != VTK_DOUBLE;
  if (!(hi > lo))
  {
    t.Size = 1;
  }
  else if (integer && hi - lo + 1.0 <= kMaxExactTableSize)
  {
    t.Size = static_cast<int>(hi - lo) + 1; // one sample per value: exact
  }
  else
  {
    t.Size = kFloatTableSize;
  }
  t.Scale = t.Size > 1 ? double(t.Size - 1) / (hi - lo) : 0.0;
  t.Values.resize(size_t(t.Size) * size_t(width));
  return t;
}

/// Opacity function over the component's range, clamped to [0, 1].
Table SampleOpacity(vtkPiecewiseFunction* f, double lo, double hi, int vtkType)
{
  Table t = TableLayout(lo, hi, vtkType, 1);
  if (t.Size == 1)
  {
    t.Values[0] = static_cast<float>(f->GetValue(lo));
  }
  else
  {
    f->GetTable(lo, hi, t.Size, t.Values.data());
  }
  for (float& v : t.Values)
  {
    v = std::isfinite(v) ? std::min(1.f, std::max(0.f, v)) : 0.f;
  }
  return t;
}

/// Colour (RGB, or gray repeated) over the component's range, in [0, 1].
Table SampleColor(vtkObject* color, bool gray, double lo, double hi, int vtkType)
{
  Table t = TableLayout(lo, hi, vtkType, 3);
  if (gray)
  {
    auto* f = static_cast<vtkPiecewiseFunction*>(color);
    std::vector<float> g(size_t(t.Size));
    if (t.Size == 1)
    {
      g[0] = static_cast<float>(f->GetValue(lo));
    }
    else
    {
      f->GetTable(lo, hi, t.Size, g.data());
    }
    for (int i = 0; i < t.Size; ++i)
    {
      t.Values[3 * size_t(i)] = t.Values[3 * size_t(i) + 1] = t.Values[3 * size_t(i) + 2] = g[size_t(i)];
    }
  }
  else
  {
    auto* f = static_cast<vtkColorTransferFunction*>(color);
    std::vector<double> rgb(3 * size_t(t.Size));
    if (t.Size == 1)
    {
      f->GetColor(lo, rgb.data());
    }
    else
    {
      f->GetTable(lo, hi, t.Size, rgb.data());
    }
    for (size_t i = 0; i < rgb.size(); ++i)
    {
      t.Values[i] = static_cast<float>(rgb[i]);
    }
  }
  for (float& v : t.Values)
  {
    v = std::isfinite(v) ? std::min(1.f, std::max(0.f, v)) : 0.f;
  }
  return t;
}

/// The table at value v (finite or infinite; not NaN): out[0..Width).
inline void Lookup(const Table& t, double v, float* out)
{
  double x = (v - t.Lo) * t.Scale; // NaN for an infinite v and one sample
  x = x > 0.0 ? std::min(x, double(t.Size - 1)) : 0.0;
  const int i = std::min(static_cast<int>(x), t.Size - 1);
  const int j = std::min(i + 1, t.Size - 1);
  const float f = static_cast<float>(x - i);
  const float* a = t.Values.data() + size_t(i) * size_t(t.Width);
  const float* b = t.Values.data() + size_t(j) * size_t(t.Width);
  for (int k = 0; k < t.Width; ++k)
  {
    out[k] = a[k] + f * (b[k] - a[k]);
  }
}

template <class T>
inline bool IsNaN(T v)
{
  if constexpr (std::is_floating_point<T>::value)
  {
    return std::isnan(v);
  }
  else
  {
    (void)v;
    return false;
  }
}

/// What one classification reads.
struct Work
{
  int64_t Voxels = 0;
  int Components = 0; // 2 or 4
  bool UnsignedChar = false;
  const Table* Color = nullptr;   // 2 components
  const Table* Opacity = nullptr; // of the last component
  std::array<std::array<double, 2>, 3> ColorRanges{};
  float UnitDistance = 1.f;
  float* Out = nullptr;
};

template <class T>
void Classify(const T* data, const Work& w)
{
  const int nc = w.Components;
  // Per component k of a 4-component colour that is not unsigned char:
  // c = (v - lo) * scale (scale 0: the value itself, clamped).
  double lo[3] = { 0.0, 0.0, 0.0 }, scale[3] = { 1.0, 1.0, 1.0 };
  if (nc == 4)
  {
    for (int k = 0; k < 3; ++k)
    {
      if (w.UnsignedChar)
      {
        scale[k] = 1.0 / 255.0;
      }
      else
      {
        const double width = w.ColorRanges[size_t(k)][1] - w.ColorRanges[size_t(k)][0];
        lo[k] = width > 0.0 ? w.ColorRanges[size_t(k)][0] : 0.0;
        scale[k] = width > 0.0 ? 1.0 / width : 1.0;
      }
    }
  }
#pragma omp parallel for schedule(static)
  for (int64_t v = 0; v < w.Voxels; ++v)
  {
    const T* x = data + v * nc;
    float* o = w.Out + 4 * v;
    bool nan = false;
    for (int k = 0; k < nc; ++k)
    {
      nan = nan || IsNaN(x[k]);
    }
    if (nan)
    {
      o[0] = o[1] = o[2] = o[3] = 0.f; // transparent
      continue;
    }
    float alpha;
    Lookup(*w.Opacity, static_cast<double>(x[nc - 1]), &alpha);
    const float sigma = opacityToExtinction(alpha, w.UnitDistance);
    float rgb[3];
    if (nc == 4)
    {
      for (int k = 0; k < 3; ++k)
      {
        const double c = (static_cast<double>(x[k]) - lo[k]) * scale[k];
        rgb[k] = static_cast<float>(std::min(1.0, std::max(0.0, c)));
      }
    }
    else
    {
      Lookup(*w.Color, static_cast<double>(x[0]), rgb);
    }
    o[0] = sigma;
    o[1] = sigma * rgb[0];
    o[2] = sigma * rgb[1];
    o[3] = sigma * rgb[2];
  }
}

/// The one array whose components are the dependent components, or nullptr
/// (and `error`) when the input or channel 0's functions do not fit.
vtkDataArray* DependentArray(const ChannelFunctions& functions, const BoundChannels& channels, std::string& error)
{
  const int nc = channels.Count;
  vtkDataArray* array = channels.Arrays.empty() ? nullptr : channels.Arrays[0];
  if ((nc != 2 && nc != 4) || !array || array->GetNumberOfComponents() != nc)
  {
    std::ostringstream msg;
    msg << "IndependentComponentsOff needs one point scalar array of 2 or 4 components (VTK's dependent "
           "components: 4 = RGB and an opacity component, 2 = a colour and an opacity component); the input has "
        << nc << " channel" << (nc == 1 ? "" : "s") << ". Use IndependentComponentsOn to render the components "
        << "as independent channels.";
    error = msg.str();
    return nullptr;
  }
  for (int c = 1; c < nc; ++c)
  {
    if (channels.Arrays[size_t(c)] != array)
    {
      error = "IndependentComponentsOff needs the components of one scalar array, not separate channel arrays.";
      return nullptr;
    }
  }
  if (!functions.Color || !functions.Opacity || !(functions.UnitDistance > 0.0))
  {
    error = "IndependentComponentsOff: component 0 of the volume property has no colour or scalar opacity function.";
    return nullptr;
  }
  return array;
}

/// The functions sampled over the components' finite ranges: what a
/// classification reads besides the voxels.
struct SampledFunctions
{
  Table Opacity;                                      // of the last component
  Table Color;                                        // 2 components: of component 0
  std::array<std::array<double, 2>, 3> ColorRanges{}; // 4 components, not unsigned char
};

SampledFunctions SampleFunctions(vtkDataArray* array, const ChannelFunctions& functions, int nc, int type)
{
  SampledFunctions f;
  const std::array<double, 2> alphaRange = FiniteRange(array, nc - 1);
  f.Opacity = SampleOpacity(functions.Opacity, alphaRange[0], alphaRange[1], type);
  if (nc == 2)
  {
    const std::array<double, 2> r = FiniteRange(array, 0);
    f.Color = SampleColor(functions.Color, functions.Gray, r[0], r[1], type);
  }
  else if (type != VTK_UNSIGNED_CHAR)
  {
    for (int k = 0; k < 3; ++k)
    {
      f.ColorRanges[size_t(k)] = FiniteRange(array, k);
    }
  }
  return f;
}

/// Sizes `buffer` for w.Voxels voxels (4 floats each) and classifies the
/// array into it. On failure (no memory, a scalar type without a
/// classification) returns false and sets `error`.
bool ClassifyInto(vtkDataArray* array, Work w, std::vector<float>& buffer, std::string& error)
{
  try
  {
    buffer.resize(4 * size_t(w.Voxels));
  }
  catch (const std::exception& e)
  {
    std::ostringstream msg;
    msg << "IndependentComponentsOff: could not allocate the classified copy (" << 16.0 * double(w.Voxels) / 1048576.0
        << " MiB, 16 bytes a voxel): " << e.what();
    error = msg.str();
    return false;
  }
  w.Out = buffer.data();
  const void* data = array->GetVoidPointer(0);
  switch (array->GetDataType())
  {
    case VTK_UNSIGNED_CHAR:
      Classify(static_cast<const unsigned char*>(data), w);
      return true;
    case VTK_SHORT:
      Classify(static_cast<const short*>(data), w);
      return true;
    case VTK_UNSIGNED_SHORT:
      Classify(static_cast<const unsigned short*>(data), w);
      return true;
    case VTK_FLOAT:
      Classify(static_cast<const float*>(data), w);
      return true;
    case VTK_DOUBLE:
      Classify(static_cast<const double*>(data), w);
      return true;
    default:
      error = std::string("IndependentComponentsOff: unsupported scalar type ") + array->GetDataTypeAsString() +
        " (unsigned char, short, unsigned short, float and double are).";
      return false;
  }
}

/// Replaces the bound components with the one classified channel (the
/// buffer, ChannelFormat::Extinction) whose values changed at `time`.
void BindClassified(BoundChannels& channels, vtkDataArray* array, const float* buffer, vtkMTimeType time)
{
  ChannelSource source;
  source.data = buffer;
  source.type = ScalarType::Float32;
  source.stride = 4;
  source.offset = 0.0;
  source.format = ChannelFormat::Extinction;
  channels.Count = 1;
  channels.Arrays.assign(1, array);
  channels.Components.assign(1, 0);
  channels.Sources = {};
  channels.Sources[0] = source;
  channels.DataMTime = time;
}
} // namespace

//------------------------------------------------------------------------------
bool DependentClassifier::Update(
  vtkImageData* image, const ChannelFunctions& functions, BoundChannels& channels, std::string& error)
{
  this->Classified = false;
  vtkDataArray* array = DependentArray(functions, channels, error);
  if (!array)
  {
    return false;
  }
  this->NoteInPlaceWrites(image, channels, array);
  const Key key = KeyOf(array, functions, channels);
  if (!this->Valid || !(key == this->LastKey))
  {
    if (!this->Reclassify(key, array, functions, error))
    {
      return false;
    }
    this->LastKey = key;
    this->Valid = true;
  }
  // The one classified channel. Its time is the classification's: the Scene
  // is told of new values, and the image restarts, only when it changed.
  BindClassified(channels, array, this->Buffer.data(), this->ClassifiedTime.GetMTime());
  return true;
}

//------------------------------------------------------------------------------
void DependentClassifier::NoteInPlaceWrites(vtkImageData* image, const BoundChannels& channels, vtkDataArray* array)
{
  // Values written in place with only the image marked modified (the same
  // image, the same geometry): mark the array, as ChannelData does, so that
  // its time and its cached ranges follow.
  const bool sameImage = this->LastImage == image;
  if (sameImage && channels.ImageMTime != this->ImageMTime && channels.Geometry == this->Geometry &&
    array->GetMTime() == this->LastKey.ArrayMTime)
  {
    array->Modified();
  }
  this->LastImage = image;
  this->ImageMTime = channels.ImageMTime;
  this->Geometry = channels.Geometry;
}

//------------------------------------------------------------------------------
DependentClassifier::Key DependentClassifier::KeyOf(
  vtkDataArray* array, const ChannelFunctions& functions, const BoundChannels& channels)
{
  Key key;
  key.Array = array;
  key.ArrayMTime = array->GetMTime();
  key.Components = channels.Count;
  key.Type = array->GetDataType();
  std::copy(channels.Dims, channels.Dims + 3, key.Dims);
  key.Color = functions.Color;
  key.ColorMTime = functions.ColorMTime;
  key.Gray = functions.Gray;
  key.Opacity = functions.Opacity;
  key.OpacityMTime = functions.OpacityMTime;
  key.UnitDistance = functions.UnitDistance;
  return key;
}

//------------------------------------------------------------------------------
bool DependentClassifier::Reclassify(
  const Key& key, vtkDataArray* array, const ChannelFunctions& functions, std::string& error)
{
  const int nc = key.Components;
  const int type = key.Type;
  const bool sameData = this->Valid && key.Array == this->LastKey.Array && key.ArrayMTime == this->LastKey.ArrayMTime &&
    key.Components == this->LastKey.Components && key.Type == this->LastKey.Type &&
    std::equal(key.Dims, key.Dims + 3, this->LastKey.Dims) && key.UnitDistance == this->LastKey.UnitDistance;
  SampledFunctions f = SampleFunctions(array, functions, nc, type);
  // Only the functions' times moved (ParaView touches its lookup tables on
  // every render) and their values did not: keep the buffer.
  if (sameData && f.Opacity == this->OpacityTable && f.Color == this->ColorTable && f.ColorRanges == this->ColorRanges)
  {
    return true;
  }
  Work w;
  w.Voxels = static_cast<int64_t>(array->GetNumberOfTuples());
  w.Components = nc;
  w.UnsignedChar = type == VTK_UNSIGNED_CHAR;
  w.Color = &f.Color;
  w.Opacity = &f.Opacity;
  w.ColorRanges = f.ColorRanges;
  w.UnitDistance = static_cast<float>(functions.UnitDistance);
  if (!ClassifyInto(array, w, this->Buffer, error))
  {
    this->Release();
    return false;
  }
  this->OpacityTable = std::move(f.Opacity);
  this->ColorTable = std::move(f.Color);
  this->ColorRanges = f.ColorRanges;
  this->ClassifiedTime.Modified();
  this->Classified = true;
  ++this->Count;
  return true;
}

//------------------------------------------------------------------------------
void DependentClassifier::Release()
{
  std::vector<float>().swap(this->Buffer);
  this->Valid = false;
  this->LastKey = Key();
  this->OpacityTable = Table();
  this->ColorTable = Table();
  this->ColorRanges = {};
  this->LastImage = nullptr;
}
} // namespace adapter
} // namespace mcvol
