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

#include <algorithm>
#include <cstring>

vtkStandardNewMacro(vtkSMMultiChannelVolumeRepresentationProxy);

namespace
{
// Distinct sequential presets for channels whose functions are new.
const char* const kChannelPresets[] = { "Reds", "Greens", "Blues", "Oranges", "Purples", "Greys" };
constexpr int kNumChannelPresets = sizeof(kChannelPresets) / sizeof(kChannelPresets[0]);

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
  vtkSMOutputPort* port = vtkSMPropertyHelper(this, "Input", true).GetAsOutputPort();

  vtkNew<vtkSMTransferFunctionManager> manager;
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
    if (!existed)
    {
      // A new channel: its own preset, fitted to the channel's data range.
      vtkSMTransferFunctionProxy::ApplyPreset(lut, kChannelPresets[c % kNumChannelPresets], false);
      double range[2] = { 0.0, 1.0 };
      bool haveRange = false;
      if (port)
      {
        const bool components = source == 1;
        vtkPVArrayInformation* info = port->GetDataInformation()->GetArrayInformation(
          components ? componentsArray : name.c_str(), vtkDataObject::POINT);
        if (info)
        {
          info->GetComponentRange(components ? static_cast<int>(c) : 0, range);
          haveRange = range[0] <= range[1];
        }
      }
      if (haveRange)
      {
        vtkSMTransferFunctionProxy::RescaleTransferFunction(lut, range, false);
        if (pwf)
        {
          vtkSMTransferFunctionProxy::RescaleTransferFunction(pwf, range, false);
        }
      }
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
