// SPDX-License-Identifier: BSD-3-Clause
#include "vtkSMMultiChannelVolumeRepresentationProxy.h"

#include "vtkCommand.h"
#include "vtkDataObject.h"
#include "vtkObjectFactory.h"
#include "vtkPVArrayInformation.h"
#include "vtkPVDataInformation.h"
#include "vtkSMOutputPort.h"
#include "vtkSMPVRepresentationProxy.h"
#include "vtkSMProperty.h"
#include "vtkSMPropertyHelper.h"
#include "vtkSMProxyProperty.h"
#include "vtkSMSessionProxyManager.h"
#include "vtkSMTransferFunctionManager.h"
#include "vtkSMTransferFunctionProxy.h"
#include "vtkSMViewProxy.h"

#include "vtkPVDataSetAttributesInformation.h"
#include "vtkSMStringVectorProperty.h"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <map>
#include <sstream>
#include <utility>

vtkStandardNewMacro(vtkSMMultiChannelVolumeRepresentationProxy);

namespace
{
// mcvol-render's default channels (Wrapping/Python/mcvol/scenefile/assemble.py,
// default_channels): one colour per channel, warm white for a channel alone.
const double kChannelColors[][3] = { { 0.2, 1.0, 0.3 }, { 1.0, 0.25, 0.9 }, { 0.25, 0.7, 1.0 },
  { 1.0, 0.85, 0.2 }, { 1.0, 0.35, 0.2 }, { 0.6, 0.4, 1.0 }, { 0.3, 1.0, 0.9 }, { 1.0, 1.0, 1.0 } };
constexpr int kNumChannelColors = sizeof(kChannelColors) / sizeof(kChannelColors[0]);
const double kChannelAlone[3] = { 1.0, 0.92, 0.82 };
// Opacity at the top of the range per this many of the smallest voxel spacings.
constexpr double kDefaultOpacity = 0.3;
constexpr double kDefaultOpacityVoxels = 4.0;
// Below this fraction of the robust range a channel is transparent (background).
constexpr double kDefaultThreshold = 0.15;
const char* const kRepresentationName = "Multi-Channel Volume (Monte Carlo)";
const char* const kDisplayPrefix = "mcvol_display/";
constexpr int kMaxChannels = 32;

bool IsChannelProperty(const char* name)
{
  return name &&
    (!strcmp(name, "ChannelArrays") || !strcmp(name, "ChannelComponentsArray") ||
      !strcmp(name, "ChannelSource"));
}
}

//------------------------------------------------------------------------------
vtkSMMultiChannelVolumeRepresentationProxy::vtkSMMultiChannelVolumeRepresentationProxy() = default;
vtkSMMultiChannelVolumeRepresentationProxy::~vtkSMMultiChannelVolumeRepresentationProxy()
{
  if (this->ObservedView)
  {
    this->ObservedView->RemoveObserver(this->ViewObserver);
  }
}

//------------------------------------------------------------------------------
void vtkSMMultiChannelVolumeRepresentationProxy::ViewUpdated(vtkSMProxy* view)
{
  this->Superclass::ViewUpdated(view);
  if (view == this->ObservedView)
  {
    return;
  }
  if (this->ObservedView)
  {
    this->ObservedView->RemoveObserver(this->ViewObserver);
  }
  this->ObservedView = view;
  this->ViewObserver =
    view ? view->AddObserver(vtkCommand::EndEvent, this, &vtkSMMultiChannelVolumeRepresentationProxy::ViewRendered) : 0;
}

//------------------------------------------------------------------------------
void vtkSMMultiChannelVolumeRepresentationProxy::ViewRendered()
{
  if (this->ObjectsCreated)
  {
    this->UpdatePropertyInformation();
  }
}

//------------------------------------------------------------------------------
std::string vtkSMMultiChannelVolumeRepresentationProxy::ChannelFunctionName(const char* array, int component)
{
  return std::string(array ? array : "") + ":" + std::to_string(component);
}

//------------------------------------------------------------------------------
std::vector<std::string> vtkSMMultiChannelVolumeRepresentationProxy::GetChannelFunctionNames()
{
  std::vector<std::string> names;
  if (!this->GetProperty("ChannelSource") ||
    vtkSMPropertyHelper(this, "ChannelSource").GetNumberOfElements() < 1)
  {
    return names;
  }
  const int source = vtkSMPropertyHelper(this, "ChannelSource").GetAsInt();
  if (source == 1)
  {
    vtkSMPropertyHelper arrayHelper(this, "ChannelComponentsArray");
    const char* array = arrayHelper.GetNumberOfElements() > 0 ? arrayHelper.GetAsString() : nullptr;
    vtkSMOutputPort* port = vtkSMPropertyHelper(this, "Input", true).GetAsOutputPort();
    vtkPVArrayInformation* info = (array && *array && port)
      ? port->GetDataInformation()->GetArrayInformation(array, vtkDataObject::POINT)
      : nullptr;
    const int components = info ? info->GetNumberOfComponents() : 0;
    for (int k = 0; k < components; ++k)
    {
      names.push_back(ChannelFunctionName(array, k));
    }
  }
  else
  {
    vtkSMPropertyHelper arrays(this, "ChannelArrays");
    for (unsigned int i = 0; i < arrays.GetNumberOfElements(); ++i)
    {
      const char* name = arrays.GetAsString(i);
      if (name && *name)
      {
        names.emplace_back(name);
      }
    }
  }
  return names;
}

//------------------------------------------------------------------------------
int vtkSMMultiChannelVolumeRepresentationProxy::UpdateChannelLookupTables()
{
  vtkSMSessionProxyManager* pxm = this->GetSessionProxyManager();
  if (!pxm || !this->GetProperty("ChannelLookupTables") || this->InUpdate)
  {
    return 0;
  }
  this->InUpdate = true;
  const std::vector<std::string> names = this->GetChannelFunctionNames();
  const int source = vtkSMPropertyHelper(this, "ChannelSource").GetAsInt();
  vtkSMPropertyHelper componentsHelper(this, "ChannelComponentsArray");
  const char* componentsArray =
    componentsHelper.GetNumberOfElements() > 0 ? componentsHelper.GetAsString() : nullptr;

  vtkNew<vtkSMTransferFunctionManager> manager;
  this->DefaultRanges.clear();
  this->DefaultRangesFetched = false;
  std::vector<vtkSMProxy*> luts;
  for (size_t c = 0; c < names.size(); ++c)
  {
    const std::string& name = names[c];
    const bool existed = pxm->GetProxy("lookup_tables", (name + ".PVLookupTable").c_str()) != nullptr;
    vtkSMProxy* lut = manager->GetColorTransferFunction(name.c_str(), pxm);
    vtkSMProxy* pwf = manager->GetOpacityTransferFunction(name.c_str(), pxm);
    if (!lut)
    {
      continue;
    }
    if (pwf && !vtkSMPropertyHelper(lut, "ScalarOpacityFunction", true).GetAsProxy())
    {
      vtkSMPropertyHelper(lut, "ScalarOpacityFunction").Set(pwf);
      lut->UpdateVTKObjects();
    }
    if (!existed && pwf)
    {
      const bool components = source == 1;
      this->ApplyDefaultFunctions(lut, pwf, components ? componentsArray : name.c_str(),
        components ? static_cast<int>(c) : 0, static_cast<int>(c), static_cast<int>(names.size()));
    }
    luts.push_back(lut);
  }
  vtkSMProxyProperty* prop = vtkSMProxyProperty::SafeDownCast(this->GetProperty("ChannelLookupTables"));
  prop->SetProxies(static_cast<unsigned int>(luts.size()), luts.data());
  this->SyncLookupTableIndices();
  if (this->ObjectsCreated)
  {
    this->UpdateProperty("ChannelLookupTables");
    this->UpdateProperty("ChannelLookupTableIndices");
  }
  this->InUpdate = false;
  return static_cast<int>(luts.size());
}

//------------------------------------------------------------------------------
bool vtkSMMultiChannelVolumeRepresentationProxy::DefaultRange(const char* array, int component, double range[2])
{
  if (!this->DefaultRangesFetched)
  {
    // Computed where the data is (vtkMultiChannelVolumeRepresentation::
    // GetChannelDefaultRanges), once per update of the channel list.
    this->DefaultRangesFetched = true;
    vtkSMProperty* prop = this->GetProperty("ChannelDefaultRanges");
    if (prop && this->ObjectsCreated)
    {
      // Computed on every server process together (the whole data set's
      // ranges under MPI), from the updated input: the channels may be
      // chosen before the first render.
      this->UpdatePipeline();
      this->InvokeCommand("ComputeChannelDefaultRanges");
      this->UpdatePropertyInformation(prop);
      const char* text = vtkSMPropertyHelper(prop).GetNumberOfElements() > 0
        ? vtkSMPropertyHelper(prop).GetAsString()
        : nullptr;
      std::istringstream lines(text ? text : "");
      std::string line;
      while (std::getline(lines, line))
      {
        const size_t a = line.find('\t'), b = line.find('\t', a + 1), c = line.find('\t', b + 1);
        if (a == std::string::npos || b == std::string::npos || c == std::string::npos)
        {
          continue;
        }
        const std::string key = line.substr(0, b);
        this->DefaultRanges[key] = { std::stod(line.substr(b + 1, c - b - 1)), std::stod(line.substr(c + 1)) };
      }
    }
  }
  const auto it = this->DefaultRanges.find(std::string(array ? array : "") + "\t" + std::to_string(component));
  if (it == this->DefaultRanges.end())
  {
    return false;
  }
  range[0] = it->second.first;
  range[1] = it->second.second;
  return std::isfinite(range[0]) && std::isfinite(range[1]) && range[0] <= range[1];
}

//------------------------------------------------------------------------------
void vtkSMMultiChannelVolumeRepresentationProxy::ApplyDefaultFunctions(
  vtkSMProxy* lut, vtkSMProxy* pwf, const char* array, int component, int channel, int channels)
{
  vtkSMOutputPort* port = vtkSMPropertyHelper(this, "Input", true).GetAsOutputPort();
  vtkPVDataInformation* data = port ? port->GetDataInformation() : nullptr;
  // The file's display of this channel (an OME-Zarr's omero colour and
  // window, an OME-TIFF's channel colours: mcvol_display/<array>, components
  // r, g, b, start, end, active for each component of the array; NaN where
  // the file gives none).
  double color[3], range[2] = { 0.0, 1.0 };
  bool window = false, haveRange = false, haveColor = false;
  vtkPVArrayInformation* values = data ? data->GetArrayInformation(array, vtkDataObject::POINT) : nullptr;
  vtkPVArrayInformation* display = (data && values && component >= 0)
    ? data->GetArrayInformation((std::string(kDisplayPrefix) + (array ? array : "")).c_str(), vtkDataObject::FIELD)
    : nullptr;
  if (display && display->GetNumberOfComponents() == 6 * values->GetNumberOfComponents() &&
    component < values->GetNumberOfComponents())
  {
    const int first = 6 * component;
    haveColor = true;
    for (int k = 0; k < 3; ++k)
    {
      const double* c = display->GetComponentRange(first + k);
      color[k] = c[0];
      haveColor = haveColor && std::isfinite(c[0]) && c[0] == c[1] && c[0] >= 0.0 && c[0] <= 1.0;
    }
    range[0] = display->GetComponentRange(first + 3)[0];
    range[1] = display->GetComponentRange(first + 4)[0];
    window = std::isfinite(range[0]) && std::isfinite(range[1]) && range[0] < range[1];
    haveRange = window;
  }
  if (!haveColor)
  {
    const double* rgb = channels == 1 ? kChannelAlone : kChannelColors[channel % kNumChannelColors];
    std::copy(rgb, rgb + 3, color);
  }
  if (!window)
  {
    range[0] = 0.0;
    range[1] = 1.0;
  }
  if (!haveRange)
  {
    haveRange = this->DefaultRange(array, component, range);
  }
  if (!haveRange && data)
  {
    vtkPVArrayInformation* info = data->GetArrayInformation(array, vtkDataObject::POINT);
    if (info)
    {
      info->GetComponentRange(component, range);
      haveRange = range[0] <= range[1];
    }
  }
  if (!haveRange)
  {
    range[0] = 0.0;
    range[1] = 1.0;
  }
  if (!(range[1] > range[0]))
  {
    range[1] = range[0] + 1.0; // a constant channel: keep the points apart
  }
  // Opacity 0.3 per 4 of the smallest voxel spacings at the top, as
  // mcvol-render's defaults, expressed for the representation's
  // ScalarOpacityUnitDistance u: 1 - (1 - 0.3)^(u / (4 s)).
  double spacing = 0.0;
  if (data)
  {
    const double* bounds = data->GetBounds();
    const int* extent = data->GetExtent();
    for (int k = 0; k < 3; ++k)
    {
      const int cells = extent[2 * k + 1] - extent[2 * k];
      const double s = cells > 0 ? (bounds[2 * k + 1] - bounds[2 * k]) / cells : 0.0;
      spacing = s > 0.0 && (spacing == 0.0 || s < spacing) ? s : spacing;
    }
  }
  const double unit = this->GetProperty("ScalarOpacityUnitDistance")
    ? vtkSMPropertyHelper(this, "ScalarOpacityUnitDistance").GetAsDouble()
    : 0.0;
  double top = kDefaultOpacity;
  if (spacing > 0.0 && unit > 0.0)
  {
    top = 1.0 - std::pow(1.0 - kDefaultOpacity, unit / (kDefaultOpacityVoxels * spacing));
  }
  const double rgbPoints[8] = { range[0], 0.35 * color[0], 0.35 * color[1], 0.35 * color[2], range[1],
    color[0], color[1], color[2] };
  vtkSMPropertyHelper(lut, "RGBPoints").Set(rgbPoints, 8);
  if (lut->GetProperty("AutomaticRescaleRangeMode"))
  {
    vtkSMPropertyHelper(lut, "AutomaticRescaleRangeMode").Set(-1); // keep the range: "Never"
  }
  if (lut->GetProperty("ScalarRangeInitialized"))
  {
    vtkSMPropertyHelper(lut, "ScalarRangeInitialized").Set(1);
  }
  // Transparent below the window's start (a file's display) or below 15 %
  // of the robust range (the background), then a ramp to the top.
  const double threshold = window ? range[0] : range[0] + kDefaultThreshold * (range[1] - range[0]);
  std::vector<double> points = { range[0], 0.0, 0.5, 0.0 };
  if (threshold > range[0])
  {
    points.insert(points.end(), { threshold, 0.0, 0.5, 0.0 });
  }
  points.insert(points.end(), { range[1], top, 0.5, 0.0 });
  vtkSMPropertyHelper(pwf, "Points").Set(points.data(), static_cast<unsigned int>(points.size()));
  if (pwf->GetProperty("ScalarRangeInitialized"))
  {
    vtkSMPropertyHelper(pwf, "ScalarRangeInitialized").Set(1);
  }
  lut->UpdateVTKObjects();
  pwf->UpdateVTKObjects();
}

//------------------------------------------------------------------------------
void vtkSMMultiChannelVolumeRepresentationProxy::ChooseDefaultChannels()
{
  vtkSMSessionProxyManager* pxm = this->GetSessionProxyManager();
  vtkSMProxy* parent = this->GetParentProxy();
  if (this->DefaultChannelsChosen || this->InUpdate || !this->ObjectsCreated || (pxm && pxm->GetInLoadXMLState()) ||
    !parent || !parent->GetProperty("Representation") || !this->GetProperty("ChannelArrays"))
  {
    return;
  }
  const char* shown = vtkSMPropertyHelper(parent, "Representation").GetAsString();
  if (!shown || strcmp(shown, kRepresentationName) != 0)
  {
    return;
  }
  vtkSMOutputPort* port = vtkSMPropertyHelper(this, "Input", true).GetAsOutputPort();
  vtkPVDataInformation* data = port ? port->GetDataInformation() : nullptr;
  vtkPVDataSetAttributesInformation* points = data ? data->GetPointDataInformation() : nullptr;
  if (!points || points->GetNumberOfArrays() == 0)
  {
    return;
  }
  // Chosen once: what the user sets afterwards (an empty list included) stays.
  this->DefaultChannelsChosen = true;
  vtkSMPropertyHelper arrays(this, "ChannelArrays");
  vtkSMPropertyHelper componentsArray(this, "ChannelComponentsArray");
  // (ChannelComponentsArray holds its domain's first array by default: only
  // ChannelSource says whether the components were chosen.)
  if (arrays.GetNumberOfElements() > 0 || vtkSMPropertyHelper(this, "ChannelSource").GetAsInt() != 0)
  {
    return;
  }
  std::vector<std::string> all, displayed, active;
  std::string multi;
  int multiCount = 0;
  for (int i = 0; i < points->GetNumberOfArrays(); ++i)
  {
    vtkPVArrayInformation* info = points->GetArrayInformation(i);
    if (!info || !info->GetName())
    {
      continue;
    }
    const std::string name = info->GetName();
    if (info->GetNumberOfComponents() > 1)
    {
      multi = name;
      ++multiCount;
      continue;
    }
    all.push_back(name);
    vtkPVArrayInformation* display =
      data->GetArrayInformation((kDisplayPrefix + name).c_str(), vtkDataObject::FIELD);
    if (display && display->GetNumberOfComponents() == 6)
    {
      displayed.push_back(name);
      if (display->GetComponentRange(5)[0] > 0.5)
      {
        active.push_back(name);
      }
    }
  }
  if (all.empty() && multiCount == 1)
  {
    // One multi-component array (an OME-TIFF's channels, an RGB stack): its components.
    vtkSMPropertyHelper(this, "ChannelSource").Set(1);
    componentsArray.Set(multi.c_str());
  }
  else if (!all.empty())
  {
    // A file's active channels, else every single-component array.
    const std::vector<std::string>& chosen = !active.empty() ? active : (!displayed.empty() ? displayed : all);
    const size_t n = std::min<size_t>(chosen.size(), kMaxChannels);
    vtkSMPropertyHelper(this, "ChannelSource").Set(0);
    auto* list = vtkSMStringVectorProperty::SafeDownCast(this->GetProperty("ChannelArrays"));
    std::vector<std::string> values(chosen.begin(), chosen.begin() + static_cast<std::ptrdiff_t>(n));
    list->SetElements(values);
  }
}

//------------------------------------------------------------------------------
bool vtkSMMultiChannelVolumeRepresentationProxy::SyncLookupTableIndices()
{
  vtkSMProxyProperty* luts = vtkSMProxyProperty::SafeDownCast(this->GetProperty("ChannelLookupTables"));
  vtkSMProperty* indices = this->GetProperty("ChannelLookupTableIndices");
  if (!luts || !indices)
  {
    return false;
  }
  // The server receives the distinct proxies sorted by global id.
  std::vector<vtkTypeUInt32> ids;
  for (unsigned int i = 0; i < luts->GetNumberOfProxies(); ++i)
  {
    vtkSMProxy* lut = luts->GetProxy(i);
    ids.push_back(lut ? lut->GetGlobalID() : 0);
  }
  std::vector<vtkTypeUInt32> sorted(ids);
  sorted.erase(std::remove(sorted.begin(), sorted.end(), 0u), sorted.end());
  std::sort(sorted.begin(), sorted.end());
  sorted.erase(std::unique(sorted.begin(), sorted.end()), sorted.end());
  std::vector<int> order;
  for (vtkTypeUInt32 id : ids)
  {
    const auto it = std::lower_bound(sorted.begin(), sorted.end(), id);
    order.push_back(id != 0 && it != sorted.end() && *it == id ? static_cast<int>(it - sorted.begin()) : -1);
  }
  vtkSMPropertyHelper helper(indices);
  bool same = helper.GetNumberOfElements() == order.size();
  for (size_t i = 0; same && i < order.size(); ++i)
  {
    same = helper.GetAsInt(static_cast<unsigned int>(i)) == order[i];
  }
  if (!same)
  {
    helper.Set(order.data(), static_cast<unsigned int>(order.size()));
  }
  return !same;
}

//------------------------------------------------------------------------------
void vtkSMMultiChannelVolumeRepresentationProxy::ShowActiveChannel()
{
  vtkSMProperty* active = this->GetProperty("ActiveChannel");
  if (!active || this->InUpdate || vtkSMPropertyHelper(active).GetNumberOfElements() < 1)
  {
    return;
  }
  const int channel = vtkSMPropertyHelper(this, "ActiveChannel").GetAsInt();
  vtkSMPropertyHelper luts(this, "ChannelLookupTables");
  const std::vector<std::string> names = this->GetChannelFunctionNames();
  if (channel < 0)
  {
    return;
  }
  if (static_cast<unsigned int>(channel) >= luts.GetNumberOfElements() ||
    static_cast<size_t>(channel) >= names.size())
  {
    vtkWarningMacro("Edit Channel " << channel << ": there " << (names.size() == 1 ? "is " : "are ")
                                    << names.size() << " channel" << (names.size() == 1 ? "" : "s")
                                    << " (0 is the first); the colour map editor is left as it is.");
    return;
  }
  vtkSMProxy* lut = luts.GetAsProxy(static_cast<unsigned int>(channel));
  vtkSMProxy* pwf = lut ? vtkSMPropertyHelper(lut, "ScalarOpacityFunction", true).GetAsProxy() : nullptr;
  if (!lut)
  {
    return;
  }
  // Set them on the composite representation ParaView shows (its shared
  // properties are linked from the other subproxies to this one, not back).
  vtkSMProxy* target = this->GetParentProxy() ? this->GetParentProxy() : this;
  vtkSMProxy* previous =
    target->GetProperty("LookupTable") ? vtkSMPropertyHelper(target, "LookupTable", true).GetAsProxy() : nullptr;
  this->InUpdate = true;

  // The colour map editor edits the representation's LookupTable, and only
  // while it colours by an array (Solid Color shows "Array Name: <none>"):
  // colour by the channel's array. A component channel colours by its array
  // with the channel's own functions, which pick that component, so that
  // the editor's "rescale to data range" and the scalar bar take the
  // component's range.
  const bool components = vtkSMPropertyHelper(this, "ChannelSource").GetAsInt() == 1;
  std::string arrayName = names[static_cast<size_t>(channel)];
  if (components)
  {
    vtkSMPropertyHelper componentsHelper(this, "ChannelComponentsArray");
    arrayName = componentsHelper.GetNumberOfElements() > 0 && componentsHelper.GetAsString()
      ? componentsHelper.GetAsString()
      : "";
    if (lut->GetProperty("VectorMode") && lut->GetProperty("VectorComponent"))
    {
      vtkSMPropertyHelper(lut, "VectorMode").Set(1); // vtkScalarsToColors::COMPONENT
      vtkSMPropertyHelper(lut, "VectorComponent").Set(channel);
      lut->UpdateVTKObjects();
    }
  }
  if (!arrayName.empty() && target->GetProperty("ColorArrayName"))
  {
    vtkSMPropertyHelper(target, "ColorArrayName").SetInputArrayToProcess(vtkDataObject::POINT, arrayName.c_str());
  }
  if (target->GetProperty("LookupTable"))
  {
    vtkSMPropertyHelper(target, "LookupTable").Set(lut);
  }
  if (pwf && target->GetProperty("ScalarOpacityFunction"))
  {
    vtkSMPropertyHelper(target, "ScalarOpacityFunction").Set(pwf);
  }
  if (target->GetObjectsCreated())
  {
    target->UpdateVTKObjects();
  }

  // The scalar bar follows the edited channel: where the view shows the
  // previous channel's bar (or this channel's), it shows this channel's.
  vtkSMViewProxy* view = vtkSMViewProxy::FindView(target);
  if (view)
  {
    const bool previousShown =
      previous && previous != lut && vtkSMTransferFunctionProxy::IsScalarBarVisible(previous, view);
    const bool shown = vtkSMTransferFunctionProxy::IsScalarBarVisible(lut, view);
    if (previousShown)
    {
      if (vtkSMProxy* bar = vtkSMTransferFunctionProxy::FindScalarBarRepresentation(previous, view))
      {
        vtkSMPropertyHelper(bar, "Visibility").Set(0);
        bar->UpdateVTKObjects();
      }
    }
    if (previousShown || shown)
    {
      // ParaView titles it: the array's name, and a component channel's
      // component name or number.
      vtkSMPVRepresentationProxy::SetScalarBarVisibility(target, view, true);
    }
  }
  this->InUpdate = false;
}

//------------------------------------------------------------------------------
void vtkSMMultiChannelVolumeRepresentationProxy::SetPropertyModifiedFlag(const char* name, int flag)
{
  this->Superclass::SetPropertyModifiedFlag(name, flag);
  // Nothing to do while the definition is read (ObjectsCreated is 0 until
  // the proxy exists on the processes) or while a state file is loaded.
  vtkSMSessionProxyManager* pxm = this->GetSessionProxyManager();
  const bool loading = pxm && pxm->GetInLoadXMLState();
  if (loading || this->InUpdate || !flag || !this->ObjectsCreated)
  {
    return;
  }
  if (IsChannelProperty(name))
  {
    this->UpdateChannelLookupTables();
  }
  else if (name && !strcmp(name, "ChannelLookupTables"))
  {
    // Set directly (Python): keep the channel order in step.
    this->InUpdate = true;
    if (this->SyncLookupTableIndices())
    {
      this->UpdateProperty("ChannelLookupTableIndices");
    }
    this->InUpdate = false;
  }
  else if (name && !strcmp(name, "ActiveChannel"))
  {
    this->ShowActiveChannel();
  }
}

//------------------------------------------------------------------------------
void vtkSMMultiChannelVolumeRepresentationProxy::UpdateVTKObjects()
{
  // Shown as the Multi-Channel Volume for the first time with no channels:
  // the file's channels, or the components of a lone multi-component array.
  this->ChooseDefaultChannels();
  // Every push carries the channel order of the lookup tables as they are now
  // (after a state file is loaded the proxies have new global ids).
  this->SyncLookupTableIndices();
  this->Superclass::UpdateVTKObjects();
}

//------------------------------------------------------------------------------
void vtkSMMultiChannelVolumeRepresentationProxy::PrintSelf(ostream& os, vtkIndent indent)
{
  this->Superclass::PrintSelf(os, indent);
}
