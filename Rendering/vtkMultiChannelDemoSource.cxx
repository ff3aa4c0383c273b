// SPDX-License-Identifier: BSD-3-Clause
#include "vtkMultiChannelDemoSource.h"

#include "vtkColorTransferFunction.h"
#include "vtkDataArray.h"
#include "vtkDataObject.h"
#include "vtkErrorCode.h"
#include "vtkImageData.h"
#include "vtkInformation.h"
#include "vtkInformationDoubleVectorKey.h"
#include "vtkInformationInformationVectorKey.h"
#include "vtkInformationVector.h"
#include "vtkNew.h"
#include "vtkObjectFactory.h"
#include "vtkPiecewiseFunction.h"
#include "vtkPointData.h"
#include "vtkSmartPointer.h"
#include "vtkStreamingDemandDrivenPipeline.h"
#include "vtkType.h"

#include "VTK/ScalarTypeMap.h"

#include "mcvol/DemoData.h"
#include "mcvol/ray/Types.h"

#include <algorithm>
#include <cmath>
#include <array>
#include <cstdint>
#include <cstring>
#include <exception>
#include <string>
#include <vector>

namespace
{
/// Copies planar channels into one interleaved array (T: a type of the
/// element size; the bytes are moved, not converted).
template <typename T>
void interleave(const mcvol::DemoVolume& v, void* dst, vtkIdType voxels)
{
  const int n = v.numChannels();
  T* out = static_cast<T*>(dst);
  for (int c = 0; c < n; ++c)
  {
    const T* src = reinterpret_cast<const T*>(v.channels[static_cast<size_t>(c)].data());
    for (vtkIdType i = 0; i < voxels; ++i)
    {
      out[i * n + c] = src[i];
    }
  }
}

const std::vector<std::string>& datasetNames()
{
  static const std::vector<std::string> names = mcvol::demoNames();
  return names;
}
} // namespace

struct vtkMultiChannelDemoSource::vtkInternals
{
  // Set by RequestInformation: the parameters are unusable.
  bool BadParameters = false;
  // Metadata of the last successful output.
  bool Valid = false;
  std::vector<std::string> Names;
  std::vector<std::array<float, 2>> Ranges;
  std::vector<mcvol::DemoTransferFunction> TransferFunctions;
  double SpacingScale = 1.0;
};

vtkStandardNewMacro(vtkMultiChannelDemoSource);

//------------------------------------------------------------------------------
vtkMultiChannelDemoSource::vtkMultiChannelDemoSource()
  : Internals(new vtkInternals)
{
  this->SetNumberOfInputPorts(0);
  this->SetDataset("cosmology");
}

//------------------------------------------------------------------------------
vtkMultiChannelDemoSource::~vtkMultiChannelDemoSource()
{
  this->SetDataset(nullptr);
}

//------------------------------------------------------------------------------
int vtkMultiChannelDemoSource::GetNumberOfDatasets()
{
  return static_cast<int>(datasetNames().size());
}

//------------------------------------------------------------------------------
const char* vtkMultiChannelDemoSource::GetDatasetName(int index)
{
  const auto& names = datasetNames();
  if (index < 0 || index >= static_cast<int>(names.size()))
  {
    return nullptr;
  }
  return names[static_cast<size_t>(index)].c_str();
}

namespace
{
/// Stores `range` as the cached range and finite range of a one-component
/// array (what vtkDataArray::GetRange and GetFiniteRange return until the
/// array is modified).
void CacheRange(vtkDataArray* array, const double range[2])
{
  if (!array || array->GetNumberOfComponents() != 1)
  {
    return;
  }
  for (vtkInformationInformationVectorKey* key : { vtkDataArray::PER_COMPONENT(), vtkDataArray::PER_FINITE_COMPONENT() })
  {
    vtkNew<vtkInformationVector> ranges;
    ranges->SetNumberOfInformationObjects(1);
    ranges->GetInformationObject(0)->Set(vtkDataArray::COMPONENT_RANGE(), range, 2);
    array->GetInformation()->Set(key, ranges);
  }
}
}

//------------------------------------------------------------------------------
int vtkMultiChannelDemoSource::RequestInformation(
  vtkInformation*, vtkInformationVector**, vtkInformationVector* outputVector)
{
  vtkInformation* outInfo = outputVector->GetInformationObject(0);
  vtkInternals& in = *this->Internals;
  in.BadParameters = true;
  in.Valid = false;
  const int emptyExtent[6] = { 0, -1, 0, -1, 0, -1 };
  outInfo->Set(vtkStreamingDemandDrivenPipeline::WHOLE_EXTENT(), emptyExtent, 6);

  const std::string name = this->Dataset ? this->Dataset : "";
  const bool allZero = this->Dimensions[0] == 0 && this->Dimensions[1] == 0 && this->Dimensions[2] == 0;
  if (!allZero)
  {
    for (int a = 0; a < 3; ++a)
    {
      if (this->Dimensions[a] < 1 || this->Dimensions[a] > 8192)
      {
        vtkErrorMacro("Dimensions must each be in [1, 8192] (or all 0 for the default), not "
          << this->Dimensions[0] << " x " << this->Dimensions[1] << " x " << this->Dimensions[2]);
        this->SetErrorCode(vtkErrorCode::UserError);
        return 1;
      }
    }
  }

  std::array<int, 3> dims{};
  int numChannels = 0;
  int scalarType = VTK_FLOAT;
  double spacing[3] = { 1, 1, 1 };
  try
  {
    dims = allZero ? mcvol::demoDefaultDims(name)
                   : std::array<int, 3>{ this->Dimensions[0], this->Dimensions[1], this->Dimensions[2] };
    // A one-voxel probe gives the type, channel count and spacing cheaply.
    const mcvol::DemoVolume probe = mcvol::makeDemo(name, { 1, 1, 1 }, this->NumberOfChannels);
    numChannels = probe.numChannels();
    scalarType = mcvol::adapter::ToVTKScalarType(probe.type);
    std::copy(probe.spacing, probe.spacing + 3, spacing);
  }
  catch (const std::exception& e)
  {
    vtkErrorMacro("Cannot generate dataset '" << name << "': " << e.what());
    this->SetErrorCode(vtkErrorCode::UserError);
    return 1;
  }

  const int extent[6] = { 0, dims[0] - 1, 0, dims[1] - 1, 0, dims[2] - 1 };
  const double origin[3] = { 0, 0, 0 };
  outInfo->Set(vtkStreamingDemandDrivenPipeline::WHOLE_EXTENT(), extent, 6);
  outInfo->Set(vtkDataObject::SPACING(), spacing, 3);
  outInfo->Set(vtkDataObject::ORIGIN(), origin, 3);
  // Every voxel is a function of its indices alone, so a piece (an MPI rank's
  // extent) is generated without the rest of the volume.
  outInfo->Set(vtkAlgorithm::CAN_PRODUCE_SUB_EXTENT(), 1);
  const bool interleaved = this->Interleaved || !this->SeparateArrays;
  if (interleaved)
  {
    vtkDataObject::SetPointDataActiveScalarInfo(outInfo, scalarType, numChannels);
  }
  in.BadParameters = false;
  this->SetErrorCode(vtkErrorCode::NoError);
  return 1;
}

//------------------------------------------------------------------------------
int vtkMultiChannelDemoSource::RequestData(vtkInformation*, vtkInformationVector**, vtkInformationVector* outputVector)
{
  vtkInformation* outInfo = outputVector->GetInformationObject(0);
  vtkImageData* output = vtkImageData::GetData(outInfo);
  vtkInternals& in = *this->Internals;
  in.Valid = false;
  in.Names.clear();
  in.Ranges.clear();
  in.TransferFunctions.clear();
  output->Initialize();
  if (in.BadParameters)
  {
    return 1; // reported by RequestInformation; the output stays empty
  }

  const std::string name = this->Dataset ? this->Dataset : "";
  int whole[6];
  outInfo->Get(vtkStreamingDemandDrivenPipeline::WHOLE_EXTENT(), whole);
  std::array<int, 6> extent = { whole[0], whole[1], whole[2], whole[3], whole[4], whole[5] };
  if (outInfo->Has(vtkStreamingDemandDrivenPipeline::UPDATE_EXTENT()))
  {
    outInfo->Get(vtkStreamingDemandDrivenPipeline::UPDATE_EXTENT(), extent.data());
  }
  if (extent[1] < extent[0] || extent[3] < extent[2] || extent[5] < extent[4])
  {
    return 1; // an empty piece (more ranks than slabs): nothing to generate
  }
  mcvol::DemoVolume v;
  try
  {
    v = mcvol::makeDemoPiece(name, { whole[1] + 1, whole[3] + 1, whole[5] + 1 }, this->NumberOfChannels, extent);
  }
  catch (const std::exception& e)
  {
    vtkErrorMacro("Cannot generate dataset '" << name << "': " << e.what());
    this->SetErrorCode(vtkErrorCode::UserError);
    return 1;
  }

  const int* d = v.dims;
  output->SetExtent(extent.data());
  output->SetSpacing(v.spacing);
  output->SetOrigin(0, 0, 0);

  const vtkIdType voxels = static_cast<vtkIdType>(d[0]) * d[1] * d[2];
  const int n = v.numChannels();
  const int type = mcvol::adapter::ToVTKScalarType(v.type);
  const size_t elem = static_cast<size_t>(mcvol::scalarTypeSize(v.type));
  const bool interleaved = this->Interleaved || !this->SeparateArrays;

  if (this->SeparateArrays)
  {
    for (int c = 0; c < n; ++c)
    {
      vtkSmartPointer<vtkDataArray> a = vtk::TakeSmartPointer(vtkDataArray::CreateDataArray(type));
      a->SetName(v.channelNames[static_cast<size_t>(c)].c_str());
      a->SetNumberOfComponents(1);
      a->SetNumberOfTuples(voxels);
      std::memcpy(a->GetVoidPointer(0), v.channels[static_cast<size_t>(c)].data(), static_cast<size_t>(voxels) * elem);
      output->GetPointData()->AddArray(a);
    }
  }
  if (interleaved)
  {
    vtkSmartPointer<vtkDataArray> a = vtk::TakeSmartPointer(vtkDataArray::CreateDataArray(type));
    a->SetName("channels");
    a->SetNumberOfComponents(n);
    a->SetNumberOfTuples(voxels);
    for (int c = 0; c < n; ++c)
    {
      a->SetComponentName(c, v.channelNames[static_cast<size_t>(c)].c_str());
    }
    switch (elem)
    {
      case 1:
        interleave<uint8_t>(v, a->GetVoidPointer(0), voxels);
        break;
      case 2:
        interleave<uint16_t>(v, a->GetVoidPointer(0), voxels);
        break;
      case 4:
        interleave<uint32_t>(v, a->GetVoidPointer(0), voxels);
        break;
      default:
        interleave<uint64_t>(v, a->GetVoidPointer(0), voxels);
        break;
    }
    output->GetPointData()->SetScalars(a);
  }

  in.Names = v.channelNames;
  in.TransferFunctions = v.transferFunctions;
  for (int c = 0; c < n; ++c)
  {
    in.Ranges.push_back(v.range(c));
  }
  // ParaView computes every array's range and finite range (single-threaded
  // in its Debian build) before a source's first frame: minutes for the
  // billions of voxels of one rank's piece of a large volume. The generated
  // values are finite and their ranges known, so the arrays carry them in
  // the range cache VTK consults (dropped by any later Modified()).
  if (this->SeparateArrays)
  {
    for (int c = 0; c < n; ++c)
    {
      const double r[2] = { in.Ranges[static_cast<size_t>(c)][0], in.Ranges[static_cast<size_t>(c)][1] };
      CacheRange(output->GetPointData()->GetArray(v.channelNames[static_cast<size_t>(c)].c_str()), r);
    }
  }
  in.SpacingScale = std::min({ v.spacing[0], v.spacing[1], v.spacing[2] });
  in.Valid = true;
  return 1;
}

//------------------------------------------------------------------------------
bool vtkMultiChannelDemoSource::UpdateForQuery()
{
  this->Update();
  return this->Internals->Valid;
}

//------------------------------------------------------------------------------
int vtkMultiChannelDemoSource::GetNumberOfOutputChannels()
{
  return this->UpdateForQuery() ? static_cast<int>(this->Internals->Names.size()) : 0;
}

//------------------------------------------------------------------------------
const char* vtkMultiChannelDemoSource::GetChannelName(int channel)
{
  if (!this->UpdateForQuery() || channel < 0 || channel >= static_cast<int>(this->Internals->Names.size()))
  {
    return nullptr;
  }
  return this->Internals->Names[static_cast<size_t>(channel)].c_str();
}

//------------------------------------------------------------------------------
bool vtkMultiChannelDemoSource::GetChannelRange(int channel, double range[2])
{
  if (!this->UpdateForQuery() || channel < 0 || channel >= static_cast<int>(this->Internals->Ranges.size()))
  {
    return false;
  }
  range[0] = this->Internals->Ranges[static_cast<size_t>(channel)][0];
  range[1] = this->Internals->Ranges[static_cast<size_t>(channel)][1];
  return true;
}

//------------------------------------------------------------------------------
bool vtkMultiChannelDemoSource::GetSuggestedTransferFunction(
  int channel, vtkColorTransferFunction* color, vtkPiecewiseFunction* opacity, double* unitDistance)
{
  // The output's own range; the overload reports a failed update or a bad
  // channel.
  double range[2] = { 0.0, 0.0 };
  const vtkInternals& in = *this->Internals;
  if (this->UpdateForQuery() && channel >= 0 && channel < static_cast<int>(in.Ranges.size()))
  {
    range[0] = in.Ranges[static_cast<size_t>(channel)][0];
    range[1] = in.Ranges[static_cast<size_t>(channel)][1];
  }
  return this->GetSuggestedTransferFunction(channel, range, color, opacity, unitDistance);
}

//------------------------------------------------------------------------------
bool vtkMultiChannelDemoSource::GetSuggestedTransferFunction(int channel, const double range[2],
  vtkColorTransferFunction* color, vtkPiecewiseFunction* opacity, double* unitDistance)
{
  if (!this->UpdateForQuery())
  {
    vtkErrorMacro("No suggested transfer function: the source has no valid output.");
    return false;
  }
  const vtkInternals& in = *this->Internals;
  if (channel < 0 || channel >= static_cast<int>(in.TransferFunctions.size()))
  {
    vtkErrorMacro("Channel " << channel << " out of range [0, " << in.TransferFunctions.size() << ")");
    return false;
  }
  if (!std::isfinite(range[0]) || !std::isfinite(range[1]) || range[1] < range[0])
  {
    vtkErrorMacro("The range [" << range[0] << ", " << range[1] << "] is not a finite interval.");
    return false;
  }
  const mcvol::DemoTransferFunction& tf = in.TransferFunctions[static_cast<size_t>(channel)];
  const double lo = range[0];
  double span = range[1] - lo;
  if (!(span > 0))
  {
    span = 1.0; // constant channel: keep the points distinct
  }
  if (color)
  {
    color->RemoveAllPoints();
    for (const auto& p : tf.color)
    {
      color->AddRGBPoint(lo + span * p[0], p[1], p[2], p[3]);
    }
  }
  if (opacity)
  {
    opacity->RemoveAllPoints();
    for (const auto& p : tf.opacity)
    {
      opacity->AddPoint(lo + span * p[0], p[1]);
    }
  }
  if (unitDistance)
  {
    *unitDistance = double(tf.unitDistance) * in.SpacingScale;
  }
  return true;
}

//------------------------------------------------------------------------------
double vtkMultiChannelDemoSource::GetSuggestedUnitDistance(int channel)
{
  double u = 0.0;
  return this->GetSuggestedTransferFunction(channel, nullptr, nullptr, &u) ? u : 0.0;
}

//------------------------------------------------------------------------------
void vtkMultiChannelDemoSource::PrintSelf(ostream& os, vtkIndent indent)
{
  this->Superclass::PrintSelf(os, indent);
  os << indent << "Dataset: " << (this->Dataset ? this->Dataset : "(none)") << "\n";
  os << indent << "Dimensions: " << this->Dimensions[0] << " " << this->Dimensions[1] << " " << this->Dimensions[2]
     << "\n";
  os << indent << "NumberOfChannels: " << this->NumberOfChannels << "\n";
  os << indent << "Interleaved: " << (this->Interleaved ? "On" : "Off") << "\n";
  os << indent << "SeparateArrays: " << (this->SeparateArrays ? "On" : "Off") << "\n";
}
