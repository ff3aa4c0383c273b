// SPDX-License-Identifier: BSD-3-Clause
#include "TransferFunctionTables.h"

#include "vtkColorTransferFunction.h"
#include "vtkPiecewiseFunction.h"
#include "vtkVolumeProperty.h"

#include <algorithm>
#include <cmath>
#include <sstream>
#include <vector>

namespace mcvol
{
namespace adapter
{
//------------------------------------------------------------------------------
bool ResolveChannelFunctions(const ChannelFunctionOverrides& overrides, vtkVolumeProperty* property, int numChannels,
  ChannelFunctionSet& out, std::string& error)
{
  out = ChannelFunctionSet{};
  for (int c = 0; c < numChannels; ++c)
  {
    ChannelFunctions& s = out[c];
    s.Valid = true;
    if (overrides.Colors[c])
    {
      s.Color = overrides.Colors[c];
    }
    else if (c < VTK_MAX_VRCOMP && property)
    {
      // Ask for the gray function only when that is what the user set: getting
      // the RGB one would replace it with a default.
      if (property->GetColorChannels(c) == 1)
      {
        s.Color = property->GetGrayTransferFunction(c);
        s.Gray = true;
      }
      else
      {
        s.Color = property->GetRGBTransferFunction(c);
      }
    }
    if (overrides.Opacities[c])
    {
      s.Opacity = overrides.Opacities[c];
    }
    else if (c < VTK_MAX_VRCOMP && property)
    {
      s.Opacity = property->GetScalarOpacity(c);
    }
    if (!s.Color || !s.Opacity)
    {
      std::ostringstream msg;
      msg << "Channel " << c << " has no " << (!s.Color ? "colour" : "scalar opacity")
          << " transfer function: channels >= " << VTK_MAX_VRCOMP
          << " need SetChannelColor and SetChannelScalarOpacity on the "
             "mapper.";
      error = msg.str();
      return false;
    }
    s.ColorMTime = s.Color->GetMTime();
    s.OpacityMTime = s.Opacity->GetMTime();
    s.UnitDistance = overrides.UnitDistances[c];
    if (!(s.UnitDistance > 0.0))
    {
      s.UnitDistance = (c < VTK_MAX_VRCOMP && property) ? property->GetScalarOpacityUnitDistance(c) : 1.0;
    }
    if (!(s.UnitDistance > 0.0) || !std::isfinite(s.UnitDistance))
    {
      std::ostringstream msg;
      msg << "Channel " << c << " has opacity unit distance " << s.UnitDistance << "; it must be finite and > 0.";
      error = msg.str();
      return false;
    }
  }
  return true;
}

//------------------------------------------------------------------------------
void TransferFunctionTables::UpdateImportance(const ChannelFunctionOverrides& overrides, int numChannels)
{
  bool changed = int(this->Importance.size()) != numChannels;
  this->Importance.resize(size_t(numChannels));
  for (int c = 0; c < numChannels; ++c)
  {
    ImportanceKey key;
    key.Function = overrides.Importance[c];
    key.MTime = key.Function ? key.Function->GetMTime() : 0;
    key.Range[0] = this->Functions[c].Range[0];
    key.Range[1] = this->Functions[c].Range[1];
    ImportanceKey& last = this->ImportanceKeys[c];
    if (key.Function == last.Function && key.MTime == last.MTime && key.Range[0] == last.Range[0] &&
      key.Range[1] == last.Range[1])
    {
      continue;
    }
    last = key;
    std::vector<float> table;
    if (key.Function)
    {
      // The same texels as the colour table, so the core looks both up alike.
      table.resize(kTableSize);
      key.Function->GetTable(key.Range[0], key.Range[1], kTableSize, table.data());
    }
    if (table != this->Importance[size_t(c)])
    {
      this->Importance[size_t(c)] = std::move(table);
      changed = true;
    }
  }
  if (changed)
  {
    ++this->TablesVersion;
  }
}

//------------------------------------------------------------------------------
void TransferFunctionTables::Forget()
{
  for (auto& tf : this->Functions)
  {
    tf = ChannelFunctions();
  }
  for (auto& table : this->Tables)
  {
    table = TransferFunctionDesc();
    table.rgb.clear();
  }
  this->ImportanceKeys.fill(ImportanceKey());
  this->Importance.clear();
  ++this->TablesVersion;
}

//------------------------------------------------------------------------------
bool TransferFunctionTables::UpdateChannel(
  Scene& scene, int c, ChannelFunctions& s, double lo, double hi, bool functionRange)
{
  s.Range[0] = lo;
  s.Range[1] = hi;
  // The functions' own range: the union of the colour, opacity and (with the
  // visibility optimization) importance points. Beyond it a clamped function
  // takes its end values.
  double cr[2], orr[2];
  bool clamped = s.Opacity->GetClamping() != 0;
  if (s.Gray)
  {
    static_cast<vtkPiecewiseFunction*>(s.Color)->GetRange(cr);
    clamped = clamped && static_cast<vtkPiecewiseFunction*>(s.Color)->GetClamping() != 0;
  }
  else
  {
    static_cast<vtkColorTransferFunction*>(s.Color)->GetRange(cr);
    clamped = clamped && static_cast<vtkColorTransferFunction*>(s.Color)->GetClamping() != 0;
  }
  s.Opacity->GetRange(orr);
  double flo = std::min(cr[0], orr[0]);
  double fhi = std::max(cr[1], orr[1]);
  if (s.Importance && s.Importance->GetSize() > 0)
  {
    // Importance at values beyond the colour and opacity points must not
    // be clamped away.
    double ir[2];
    s.Importance->GetRange(ir);
    flo = std::min(flo, ir[0]);
    fhi = std::max(fhi, ir[1]);
    clamped = clamped && s.Importance->GetClamping() != 0;
  }
  const bool usable = std::isfinite(flo) && std::isfinite(fhi) && flo < fhi;
  if (functionRange && usable)
  {
    s.Range[0] = flo;
    s.Range[1] = fhi;
  }
  else if (!functionRange && usable && clamped)
  {
    // The data's range, clipped to the functions': below and above the
    // functions the table would hold only their end values, so the 1024
    // entries go where the functions change. The same values at every
    // voxel, at a finer resolution where the data reach far beyond the
    // functions (a few outliers in 16-bit data: 65535 / 1024 = 64 units
    // per entry otherwise). Unclamped functions are 0 beyond their points,
    // and keep the whole data range.
    const double clo = std::max(lo, flo), chi = std::min(hi, fhi);
    if (clo < chi)
    {
      s.Range[0] = clo;
      s.Range[1] = chi;
    }
  }
  if (s == this->Functions[c])
  {
    return false;
  }
  TransferFunctionDesc desc;
  desc.scalarMin = static_cast<float>(s.Range[0]);
  desc.scalarMax = static_cast<float>(s.Range[1]);
  desc.unitDistance = static_cast<float>(s.UnitDistance);
  desc.rgb.resize(3 * kTableSize);
  desc.opacity.resize(kTableSize);
  if (s.Gray)
  {
    std::vector<float> gray(kTableSize);
    static_cast<vtkPiecewiseFunction*>(s.Color)->GetTable(s.Range[0], s.Range[1], kTableSize, gray.data());
    for (int i = 0; i < kTableSize; ++i)
    {
      desc.rgb[3 * i] = desc.rgb[3 * i + 1] = desc.rgb[3 * i + 2] = gray[i];
    }
  }
  else
  {
    std::vector<double> colors(3 * kTableSize);
    static_cast<vtkColorTransferFunction*>(s.Color)->GetTable(s.Range[0], s.Range[1], kTableSize, colors.data());
    for (int i = 0; i < 3 * kTableSize; ++i)
    {
      desc.rgb[i] = static_cast<float>(colors[i]);
    }
  }
  s.Opacity->GetTable(s.Range[0], s.Range[1], kTableSize, desc.opacity.data());
  for (int i = 0; i < kTableSize; ++i)
  {
    // Functions may hold values outside [0, 1]; the core expects [0, 1].
    desc.opacity[i] = std::min(1.f, std::max(0.f, desc.opacity[i]));
    for (int k = 0; k < 3; ++k)
    {
      float& v = desc.rgb[3 * i + k];
      v = std::isfinite(v) ? std::min(1.f, std::max(0.f, v)) : 0.f;
    }
  }
  this->Functions[c] = s;
  const TransferFunctionDesc& last = this->Tables[c];
  if (last.rgb == desc.rgb && last.opacity == desc.opacity && last.scalarMin == desc.scalarMin &&
    last.scalarMax == desc.scalarMax && last.unitDistance == desc.unitDistance)
  {
    return false;
  }
  scene.setTransferFunction(c, desc);
  this->Tables[c] = std::move(desc);
  ++this->TablesVersion;
  return true;
}
//------------------------------------------------------------------------------
std::string TransferFunctionTables::EmptyFunctions(int numChannels) const
{
  std::ostringstream msg;
  for (int c = 0; c < numChannels && c < static_cast<int>(this->Functions.size()); ++c)
  {
    const ChannelFunctions& f = this->Functions[size_t(c)];
    auto* rgb = vtkColorTransferFunction::SafeDownCast(f.Color);
    auto* gray = vtkPiecewiseFunction::SafeDownCast(f.Color);
    const bool noColor = (rgb && rgb->GetSize() == 0) || (gray && gray->GetSize() == 0);
    const bool noOpacity = f.Opacity && f.Opacity->GetSize() == 0;
    if (noOpacity)
    {
      msg << "Channel " << c << "'s scalar opacity function has no points: the channel is transparent. ";
    }
    else if (noColor)
    {
      msg << "Channel " << c << "'s colour function has no points: the channel is black. ";
    }
  }
  std::string text = msg.str();
  if (!text.empty())
  {
    text += "Add points (AddPoint, AddRGBPoint) to show it.";
  }
  return text;
}
} // namespace adapter
} // namespace mcvol
