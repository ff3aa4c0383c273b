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
} // namespace

//------------------------------------------------------------------------------
bool DependentClassifier::Update(
  vtkImageData* image, const ChannelFunctions& functions, BoundChannels& channels, std::string& error)
{
  this->Classified = false;
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
    return false;
  }
  for (int c = 1; c < nc; ++c)
  {
    if (channels.Arrays[size_t(c)] != array)
    {
      error = "IndependentComponentsOff needs the components of one scalar array, not separate channel arrays.";
      return false;
    }
  }
  if (!functions.Color || !functions.Opacity || !(functions.UnitDistance > 0.0))
  {
    error = "IndependentComponentsOff: component 0 of the volume property has no colour or scalar opacity function.";
    return false;
  }
  const int type = array->GetDataType();

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

  Key key;
  key.Array = array;
  key.ArrayMTime = array->GetMTime();
  key.Components = nc;
  key.Type = type;
  std::copy(channels.Dims, channels.Dims + 3, key.Dims);
  key.Color = functions.Color;
  key.ColorMTime = functions.ColorMTime;
  key.Gray = functions.Gray;
  key.Opacity = functions.Opacity;
  key.OpacityMTime = functions.OpacityMTime;
  key.UnitDistance = functions.UnitDistance;

  if (!this->Valid || !(key == this->LastKey))
  {
    const bool sameData = this->Valid && key.Array == this->LastKey.Array &&
      key.ArrayMTime == this->LastKey.ArrayMTime && key.Components == this->LastKey.Components &&
      key.Type == this->LastKey.Type && std::equal(key.Dims, key.Dims + 3, this->LastKey.Dims) &&
      key.UnitDistance == this->LastKey.UnitDistance;
    // The tables of the functions over the components' finite ranges.
    const std::array<double, 2> alphaRange = FiniteRange(array, nc - 1);
    Table opacity = SampleOpacity(functions.Opacity, alphaRange[0], alphaRange[1], type);
    Table color;
    std::array<std::array<double, 2>, 3> colorRanges{};
    if (nc == 2)
    {
      const std::array<double, 2> r = FiniteRange(array, 0);
      color = SampleColor(functions.Color, functions.Gray, r[0], r[1], type);
    }
    else if (type != VTK_UNSIGNED_CHAR)
    {
      for (int k = 0; k < 3; ++k)
      {
        colorRanges[size_t(k)] = FiniteRange(array, k);
      }
    }
    // Only the functions' times moved (ParaView touches its lookup tables on
    // every render) and their values did not: keep the buffer.
    const bool sameTables =
      sameData && opacity == this->OpacityTable && color == this->ColorTable && colorRanges == this->ColorRanges;
    if (!sameTables)
    {
      const vtkIdType tuples = array->GetNumberOfTuples();
      Work w;
      w.Voxels = static_cast<int64_t>(tuples);
      w.Components = nc;
      w.UnsignedChar = type == VTK_UNSIGNED_CHAR;
      w.Color = &color;
      w.Opacity = &opacity;
      w.ColorRanges = colorRanges;
      w.UnitDistance = static_cast<float>(functions.UnitDistance);
      try
      {
        this->Buffer.resize(4 * size_t(tuples));
      }
      catch (const std::exception& e)
      {
        this->Release();
        std::ostringstream msg;
        msg << "IndependentComponentsOff: could not allocate the classified copy (" << 16.0 * double(tuples) / 1048576.0
            << " MiB, 16 bytes a voxel): " << e.what();
        error = msg.str();
        return false;
      }
      w.Out = this->Buffer.data();
      const void* data = array->GetVoidPointer(0);
      switch (type)
      {
        case VTK_UNSIGNED_CHAR:
          Classify(static_cast<const unsigned char*>(data), w);
          break;
        case VTK_SHORT:
          Classify(static_cast<const short*>(data), w);
          break;
        case VTK_UNSIGNED_SHORT:
          Classify(static_cast<const unsigned short*>(data), w);
          break;
        case VTK_FLOAT:
          Classify(static_cast<const float*>(data), w);
          break;
        case VTK_DOUBLE:
          Classify(static_cast<const double*>(data), w);
          break;
        default:
          this->Release();
          error = std::string("IndependentComponentsOff: unsupported scalar type ") + array->GetDataTypeAsString() +
            " (unsigned char, short, unsigned short, float and double are).";
          return false;
      }
      this->OpacityTable = std::move(opacity);
      this->ColorTable = std::move(color);
      this->ColorRanges = colorRanges;
      this->ClassifiedTime.Modified();
      this->Classified = true;
      ++this->Count;
    }
    this->LastKey = key;
    this->Valid = true;
  }

  // The one classified channel. Its time is the classification's: the Scene
  // is told of new values, and the image restarts, only when it changed.
  ChannelSource source;
  source.data = this->Buffer.data();
  source.type = ScalarType::Float32;
  source.stride = 4;
  source.offset = 0.0;
  source.format = ChannelFormat::Extinction;
  channels.Count = 1;
  channels.Arrays.assign(1, array);
  channels.Components.assign(1, 0);
  channels.Sources = {};
  channels.Sources[0] = source;
  channels.DataMTime = this->ClassifiedTime.GetMTime();
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
