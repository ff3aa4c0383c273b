// SPDX-License-Identifier: BSD-3-Clause
#include "vtkMultiChannelProgressProbe.h"

#include "vtkMultiChannelVolumeRepresentation.h"
#include "vtkObjectFactory.h"

vtkStandardNewMacro(vtkMultiChannelProgressProbe);

//------------------------------------------------------------------------------
vtkMultiChannelProgressProbe::vtkMultiChannelProgressProbe() = default;

//------------------------------------------------------------------------------
vtkMultiChannelProgressProbe::~vtkMultiChannelProgressProbe() = default;

//------------------------------------------------------------------------------
void vtkMultiChannelProgressProbe::SetRepresentation(vtkMultiChannelVolumeRepresentation* representation)
{
  // No Modified(): the probe is read, never part of a pipeline.
  this->Representation = representation;
}

//------------------------------------------------------------------------------
int vtkMultiChannelProgressProbe::GetTotalSamples()
{
  return this->Representation ? this->Representation->GetTotalSamples() : -1;
}

//------------------------------------------------------------------------------
double vtkMultiChannelProgressProbe::GetEstimatedPSNR()
{
  return this->Representation ? this->Representation->GetEstimatedPSNR() : -1.0;
}

//------------------------------------------------------------------------------
int vtkMultiChannelProgressProbe::GetConverged()
{
  return this->Representation ? this->Representation->GetConverged() : 0;
}

//------------------------------------------------------------------------------
const char* vtkMultiChannelProgressProbe::GetProgressText()
{
  this->Text = this->Representation ? this->Representation->BuildProgressSummary() : std::string();
  return this->Text.c_str();
}

//------------------------------------------------------------------------------
const char* vtkMultiChannelProgressProbe::GetChannelStatus()
{
  return this->Representation ? this->Representation->GetChannelStatus() : "";
}

//------------------------------------------------------------------------------
void vtkMultiChannelProgressProbe::PrintSelf(ostream& os, vtkIndent indent)
{
  this->Superclass::PrintSelf(os, indent);
  os << indent << "Representation: " << this->Representation.GetPointer() << "\n";
}
