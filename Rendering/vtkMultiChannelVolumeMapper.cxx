// SPDX-License-Identifier: BSD-3-Clause
#include "vtkMultiChannelVolumeMapper.h"

#include "vtkCamera.h"
#include "vtkColorTransferFunction.h"
#include "vtkDataArray.h"
#include "vtkFloatArray.h"
#include "vtkImageData.h"
#include "vtkLight.h"
#include "vtkLightCollection.h"
#include "vtkMath.h"
#include "vtkMatrix3x3.h"
#include "vtkMatrix4x4.h"
#include "vtkNew.h"
#include "vtkObjectFactory.h"
#include "vtkOpenGLQuadHelper.h"
#include "vtkOpenGLRenderWindow.h"
#include "vtkOpenGLShaderCache.h"
#include "vtkOpenGLState.h"
#include "vtkPiecewiseFunction.h"
#include "vtkPointData.h"
#include "vtkRenderer.h"
#include "vtkShaderProgram.h"
#include "vtkSmartPointer.h"
#include "vtkTextureObject.h"
#include "vtkVolume.h"
#include "vtkVolumeProperty.h"

#include "vtk_glew.h" // For GL enums

#include "mcvol/Renderer.h"
#include "mcvol/Scene.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstring>
#include <exception>
#include <limits>
#include <sstream>
#include <string>
#include <vector>

namespace
{
constexpr int kTableSize = 1024;
constexpr int kMaxChannels = vtkMultiChannelVolumeMapper::MAX_CHANNELS;
static_assert(kMaxChannels == mcvol::kMaxChannels, "channel limits of mapper and core differ");

bool toScalarType(int vtkType, mcvol::ScalarType& out)
{
  switch (vtkType)
  {
    case VTK_UNSIGNED_CHAR:
      out = mcvol::ScalarType::UInt8;
      return true;
    case VTK_SHORT:
      out = mcvol::ScalarType::Int16;
      return true;
    case VTK_UNSIGNED_SHORT:
      out = mcvol::ScalarType::UInt16;
      return true;
    case VTK_FLOAT:
      out = mcvol::ScalarType::Float32;
      return true;
    case VTK_DOUBLE:
      out = mcvol::ScalarType::Float64;
      return true;
    default:
      return false;
  }
}

/// Everything that decides which transfer-function table a channel gets; a
/// channel's table is rebuilt (and only its majorants) when this changes.
struct ChannelTFState
{
  bool Valid = false;
  vtkObject* Color = nullptr; // vtkColorTransferFunction or gray vtkPiecewiseFunction
  bool Gray = false;
  vtkMTimeType ColorMTime = 0;
  vtkPiecewiseFunction* Opacity = nullptr;
  vtkMTimeType OpacityMTime = 0;
  double UnitDistance = 0.0;
  double Range[2] = { 0.0, 0.0 };

  bool operator==(const ChannelTFState& o) const
  {
    return this->Valid == o.Valid && this->Color == o.Color && this->Gray == o.Gray &&
      this->ColorMTime == o.ColorMTime && this->Opacity == o.Opacity && this->OpacityMTime == o.OpacityMTime &&
      this->UnitDistance == o.UnitDistance && this->Range[0] == o.Range[0] && this->Range[1] == o.Range[1];
  }
  bool operator!=(const ChannelTFState& o) const { return !(*this == o); }
};

/// Everything whose change invalidates the accumulated image.
struct AccumulationKey
{
  vtkMTimeType MapperMTime = 0;
  vtkMTimeType PropertyMTime = 0;
  vtkMTimeType DataMTime = 0;
  vtkMTimeType LightsMTime = 0; ///< the renderer's lights (lighting only)
  unsigned long long TablesVersion = 0; ///< transfer-function tables
  int Width = 0;
  int Height = 0;
  double InvViewProj[16] = {};
  double WorldToIndex[12] = {};
  const mcvol::Renderer* Renderer = nullptr;

  bool operator==(const AccumulationKey& o) const
  {
    return this->MapperMTime == o.MapperMTime && this->TablesVersion == o.TablesVersion &&
      this->PropertyMTime == o.PropertyMTime &&
      this->DataMTime == o.DataMTime && this->LightsMTime == o.LightsMTime && this->Width == o.Width &&
      this->Height == o.Height &&
      std::equal(std::begin(this->InvViewProj), std::end(this->InvViewProj), std::begin(o.InvViewProj)) &&
      std::equal(std::begin(this->WorldToIndex), std::end(this->WorldToIndex), std::begin(o.WorldToIndex)) &&
      this->Renderer == o.Renderer;
  }
};
} // namespace

struct vtkMultiChannelVolumeMapper::vtkInternals
{
  mcvol::Scene Scene;
  mcvol::Accumulator Accum;
  std::unique_ptr<mcvol::Renderer> Renderer;
  int RendererBackend = -1; // the Backend value Renderer was created for
  bool RendererFailed = false;

  // User settings kept here so the header needs no STL containers of VTK types.
  std::vector<std::string> ChannelArrayNames;
  std::array<vtkSmartPointer<vtkColorTransferFunction>, kMaxChannels> Colors;
  std::array<vtkSmartPointer<vtkPiecewiseFunction>, kMaxChannels> Opacities;
  std::array<double, kMaxChannels> UnitDistances{};
  std::array<double, kMaxChannels> MixWeights;
  std::array<double, kMaxChannels> Albedo;
  std::array<double, kMaxChannels> Anisotropy;

  // What the Scene holds now.
  bool VolumeSet = false;
  std::array<mcvol::ChannelSource, kMaxChannels> Sources{};
  std::vector<vtkSmartPointer<vtkDataArray>> Arrays; // keeps the channel data alive
  vtkMTimeType DataMTime = 0;                        // of the arrays: their values
  vtkMTimeType ImageMTime = 0;                       // of the image: its values or its geometry
  std::array<double, 15> Geometry{};                 // origin, spacing, direction of ImageMTime
  std::array<std::array<double, 2>, kMaxChannels> Ranges{};
  std::array<ChannelTFState, kMaxChannels> TF{};
  // The tables last given to the Scene, and a counter bumped whenever one
  // really changes: a function whose time moves but whose values do not
  // (ParaView's lookup tables are touched on every render while they colour
  // something) neither rebuilds the grids nor restarts the image.
  std::array<mcvol::TransferFunctionDesc, kMaxChannels> Tables{};
  unsigned long long TablesVersion = 0;

  // Accumulation state.
  bool HaveKey = false;
  bool ResetRequested = false;
  // The input image of the last render (compared, never dereferenced).
  const void* LastImage = nullptr;
  // Samples per pixel of the batch being traced (0: SamplesPerPixel).
  int BatchSamples = 0;
  AccumulationKey Key;
  std::vector<float> Depth;
  std::vector<float> LastDepth;

  // Drawing.
  vtkSmartPointer<vtkTextureObject> Texture;
  std::unique_ptr<vtkOpenGLQuadHelper> Quad;

  // Backing store for GetActiveBackendName and GetBackendReport.
  std::string BackendName = "none";
  std::string BackendReport = "no backend chosen yet";
  std::string BackendWhy; // from Renderer::create when Renderer was made

  vtkInternals()
  {
    this->MixWeights.fill(1.0);
    this->Albedo.fill(1.0);
    this->Anisotropy.fill(0.0);
  }

  void ForgetVolume()
  {
    this->VolumeSet = false;
    this->Arrays.clear();
    for (auto& tf : this->TF)
    {
      tf = ChannelTFState();
    }
    for (auto& table : this->Tables)
    {
      table = mcvol::TransferFunctionDesc();
      table.rgb.clear();
    }
    ++this->TablesVersion;
  }
};

vtkStandardNewMacro(vtkMultiChannelVolumeMapper);

//------------------------------------------------------------------------------
vtkMultiChannelVolumeMapper::vtkMultiChannelVolumeMapper()
  : Internals(new vtkInternals)
{
}

//------------------------------------------------------------------------------
vtkMultiChannelVolumeMapper::~vtkMultiChannelVolumeMapper() = default;

//------------------------------------------------------------------------------
vtkMTimeType vtkMultiChannelVolumeMapper::GetMTime()
{
  vtkMTimeType mtime = this->Superclass::GetMTime();
  for (int c = 0; c < kMaxChannels; ++c)
  {
    if (this->Internals->Colors[c])
    {
      mtime = std::max(mtime, this->Internals->Colors[c]->GetMTime());
    }
    if (this->Internals->Opacities[c])
    {
      mtime = std::max(mtime, this->Internals->Opacities[c]->GetMTime());
    }
  }
  return mtime;
}

//------------------------------------------------------------------------------
const char* vtkMultiChannelVolumeMapper::GetChannelBlendModeAsString()
{
  switch (this->ChannelBlendMode)
  {
    case MC_DENSITY_BLEND:
      return "Density";
    case MC_MAX_BLEND:
      return "Max";
    case MC_MIX_BLEND:
      return "Mix";
    case MC_COMPOSITE_BLEND:
      return "Composite";
    default:
      return "Unknown";
  }
}

//------------------------------------------------------------------------------
const char* vtkMultiChannelVolumeMapper::GetTrackingMethodAsString()
{
  return this->TrackingMethod == N_DDA ? "N-DDA" : "1-DDA";
}

//------------------------------------------------------------------------------
const char* vtkMultiChannelVolumeMapper::GetBackendAsString()
{
  switch (this->Backend)
  {
    case BACKEND_CPU:
      return "CPU";
    case BACKEND_CUDA:
      return "CUDA";
    default:
      return "Auto";
  }
}

//------------------------------------------------------------------------------
bool vtkMultiChannelVolumeMapper::TraceImage(const mcvol::Scene& scene, const mcvol::Camera& camera, const float* depth,
  mcvol::Renderer* renderer, mcvol::Accumulator& accum, std::string& error)
{
  if (!renderer)
  {
    error = "no rendering backend";
    return false;
  }
  mcvol::RenderSettings settings;
  settings.samplesPerPixel = this->Internals->BatchSamples > 0 ? this->Internals->BatchSamples : this->SamplesPerPixel;
  settings.seed = this->Seed;
  settings.tracker = this->TrackingMethod == N_DDA ? mcvol::Tracker::NDDA : mcvol::Tracker::OneDDA;
  settings.jitterPixels = this->PixelJitter;
  try
  {
    renderer->render(scene, camera, settings, depth, accum);
  }
  catch (const std::exception& e)
  {
    error = e.what();
    return false;
  }
  return true;
}

//------------------------------------------------------------------------------
bool vtkMultiChannelVolumeMapper::UsesRenderBackend()
{
  return true;
}

//------------------------------------------------------------------------------
const char* vtkMultiChannelVolumeMapper::GetActiveBackendName()
{
  vtkInternals& in = *this->Internals;
  if (!this->UsesRenderBackend())
  {
    in.BackendName = "cpu";
  }
  else if (in.RendererBackend != this->Backend)
  {
    // Not rendered with this setting yet: say what create() would pick.
    std::string why;
    if (this->Backend == BACKEND_CPU || !mcvol::Renderer::cudaAvailable(&why))
    {
      in.BackendName = this->Backend == BACKEND_CUDA ? "none" : "cpu";
    }
    else
    {
      in.BackendName = "cuda";
    }
  }
  else
  {
    in.BackendName = in.Renderer ? in.Renderer->name() : "none";
  }
  return in.BackendName.c_str();
}

//------------------------------------------------------------------------------
const char* vtkMultiChannelVolumeMapper::GetBackendReport()
{
  vtkInternals& in = *this->Internals;
  if (!this->UsesRenderBackend())
  {
    in.BackendReport = "CPU ray marcher (the reference; no Monte Carlo backend is used)";
    return in.BackendReport.c_str();
  }
  if (in.RendererBackend == this->Backend)
  {
    in.BackendReport = in.Renderer ? in.BackendWhy : "unavailable: " + in.BackendWhy;
    return in.BackendReport.c_str();
  }
  // Not rendered with this setting yet: what create() would say (without
  // creating a renderer).
  std::string why;
  const bool cuda = mcvol::Renderer::cudaAvailable(&why);
  switch (this->Backend)
  {
    case BACKEND_CPU:
      in.BackendReport = "CPU backend (requested)";
      break;
    case BACKEND_CUDA:
      in.BackendReport =
        cuda ? "CUDA backend (requested; " + why + ")" : "unavailable: the CUDA backend was requested but " + why;
      break;
    default:
      in.BackendReport = cuda ? "CUDA backend (auto: " + why + ")" : "CPU backend (auto: " + why + ")";
      break;
  }
  return in.BackendReport.c_str();
}

//------------------------------------------------------------------------------
void vtkMultiChannelVolumeMapper::SetMixWeight(int channel, double weight)
{
  if (channel < 0 || channel >= kMaxChannels)
  {
    vtkErrorMacro("SetMixWeight: channel " << channel << " is outside [0, " << kMaxChannels << ").");
    return;
  }
  if (!(weight >= 0.0) || !std::isfinite(weight))
  {
    vtkErrorMacro("SetMixWeight: weight " << weight << " of channel " << channel << " must be finite and >= 0.");
    return;
  }
  if (this->Internals->MixWeights[channel] != weight)
  {
    this->Internals->MixWeights[channel] = weight;
    this->Modified();
  }
}

//------------------------------------------------------------------------------
void vtkMultiChannelVolumeMapper::SetChannelAlbedo(int channel, double albedo)
{
  if (channel < 0 || channel >= kMaxChannels || !(albedo >= 0.0 && albedo <= 1.0))
  {
    vtkErrorMacro("SetChannelAlbedo: channel must be in [0, " << kMaxChannels << ") and the albedo in [0, 1].");
    return;
  }
  if (this->Internals->Albedo[channel] != albedo)
  {
    this->Internals->Albedo[channel] = albedo;
    this->Modified();
  }
}

//------------------------------------------------------------------------------
double vtkMultiChannelVolumeMapper::GetChannelAlbedo(int channel)
{
  return channel >= 0 && channel < kMaxChannels ? this->Internals->Albedo[channel] : 0.0;
}

//------------------------------------------------------------------------------
void vtkMultiChannelVolumeMapper::SetChannelAnisotropy(int channel, double g)
{
  if (channel < 0 || channel >= kMaxChannels || !(g > -1.0 && g < 1.0))
  {
    vtkErrorMacro("SetChannelAnisotropy: channel must be in [0, " << kMaxChannels << ") and g in (-1, 1).");
    return;
  }
  if (this->Internals->Anisotropy[channel] != g)
  {
    this->Internals->Anisotropy[channel] = g;
    this->Modified();
  }
}

//------------------------------------------------------------------------------
double vtkMultiChannelVolumeMapper::GetChannelAnisotropy(int channel)
{
  return channel >= 0 && channel < kMaxChannels ? this->Internals->Anisotropy[channel] : 0.0;
}

//------------------------------------------------------------------------------
double vtkMultiChannelVolumeMapper::GetMixWeight(int channel)
{
  if (channel < 0 || channel >= kMaxChannels)
  {
    vtkErrorMacro("GetMixWeight: channel " << channel << " is outside [0, " << kMaxChannels << ").");
    return 0.0;
  }
  return this->Internals->MixWeights[channel];
}

//------------------------------------------------------------------------------
int vtkMultiChannelVolumeMapper::GetTotalSamples()
{
  return static_cast<int>(this->Internals->Accum.samples());
}

//------------------------------------------------------------------------------
bool vtkMultiChannelVolumeMapper::IsConverged()
{
  const vtkInternals& in = *this->Internals;
  const long long total = static_cast<long long>(in.Accum.samples());
  if (!in.HaveKey || in.ResetRequested || total <= 0)
  {
    return false;
  }
  if (!this->Progressive)
  {
    return true;
  }
  return this->MaximumTotalSamples > 0 && total >= this->MaximumTotalSamples;
}

//------------------------------------------------------------------------------
void vtkMultiChannelVolumeMapper::GetAccumulatedImage(vtkFloatArray* rgba)
{
  if (!rgba)
  {
    return;
  }
  const mcvol::Accumulator& acc = this->Internals->Accum;
  const vtkIdType pixels = static_cast<vtkIdType>(acc.width()) * acc.height();
  rgba->SetNumberOfComponents(4);
  rgba->SetNumberOfTuples(pixels);
  if (pixels > 0)
  {
    std::copy(acc.rgba(), acc.rgba() + 4 * pixels, rgba->GetPointer(0));
  }
}

//------------------------------------------------------------------------------
int vtkMultiChannelVolumeMapper::GetAccumulatedImageWidth()
{
  return this->Internals->Accum.width();
}

//------------------------------------------------------------------------------
int vtkMultiChannelVolumeMapper::GetAccumulatedImageHeight()
{
  return this->Internals->Accum.height();
}

//------------------------------------------------------------------------------
void vtkMultiChannelVolumeMapper::ResetAccumulation()
{
  this->Internals->ResetRequested = true;
}

//------------------------------------------------------------------------------
void vtkMultiChannelVolumeMapper::AddChannelArray(const char* name)
{
  if (!name || !*name)
  {
    vtkErrorMacro("AddChannelArray: an array name is required.");
    return;
  }
  this->Internals->ChannelArrayNames.emplace_back(name);
  this->Modified();
}

//------------------------------------------------------------------------------
void vtkMultiChannelVolumeMapper::RemoveAllChannelArrays()
{
  if (!this->Internals->ChannelArrayNames.empty())
  {
    this->Internals->ChannelArrayNames.clear();
    this->Modified();
  }
}

//------------------------------------------------------------------------------
int vtkMultiChannelVolumeMapper::GetNumberOfChannelArrays()
{
  return static_cast<int>(this->Internals->ChannelArrayNames.size());
}

//------------------------------------------------------------------------------
const char* vtkMultiChannelVolumeMapper::GetChannelArray(int index)
{
  if (index < 0 || index >= this->GetNumberOfChannelArrays())
  {
    return nullptr;
  }
  return this->Internals->ChannelArrayNames[index].c_str();
}

//------------------------------------------------------------------------------
#define MCVOL_CHECK_CHANNEL(method, channel, ...)                                                                      \
  if ((channel) < 0 || (channel) >= kMaxChannels)                                                                      \
  {                                                                                                                    \
    vtkErrorMacro(method ": channel " << (channel) << " is outside [0, " << kMaxChannels << ").");                     \
    return __VA_ARGS__;                                                                                                \
  }

void vtkMultiChannelVolumeMapper::SetChannelColor(int channel, vtkColorTransferFunction* function)
{
  MCVOL_CHECK_CHANNEL("SetChannelColor", channel);
  if (this->Internals->Colors[channel] != function)
  {
    this->Internals->Colors[channel] = function;
    this->Modified();
  }
}

//------------------------------------------------------------------------------
vtkColorTransferFunction* vtkMultiChannelVolumeMapper::GetChannelColor(int channel)
{
  MCVOL_CHECK_CHANNEL("GetChannelColor", channel, nullptr);
  return this->Internals->Colors[channel];
}

//------------------------------------------------------------------------------
void vtkMultiChannelVolumeMapper::SetChannelScalarOpacity(int channel, vtkPiecewiseFunction* function)
{
  MCVOL_CHECK_CHANNEL("SetChannelScalarOpacity", channel);
  if (this->Internals->Opacities[channel] != function)
  {
    this->Internals->Opacities[channel] = function;
    this->Modified();
  }
}

//------------------------------------------------------------------------------
vtkPiecewiseFunction* vtkMultiChannelVolumeMapper::GetChannelScalarOpacity(int channel)
{
  MCVOL_CHECK_CHANNEL("GetChannelScalarOpacity", channel, nullptr);
  return this->Internals->Opacities[channel];
}

//------------------------------------------------------------------------------
void vtkMultiChannelVolumeMapper::SetChannelScalarOpacityUnitDistance(int channel, double distance)
{
  MCVOL_CHECK_CHANNEL("SetChannelScalarOpacityUnitDistance", channel);
  if (!(distance >= 0.0) || !std::isfinite(distance))
  {
    vtkErrorMacro(
      "SetChannelScalarOpacityUnitDistance: distance " << distance << " must be finite and > 0 (0 unsets it).");
    return;
  }
  if (this->Internals->UnitDistances[channel] != distance)
  {
    this->Internals->UnitDistances[channel] = distance;
    this->Modified();
  }
}

//------------------------------------------------------------------------------
double vtkMultiChannelVolumeMapper::GetChannelScalarOpacityUnitDistance(int channel)
{
  MCVOL_CHECK_CHANNEL("GetChannelScalarOpacityUnitDistance", channel, 0.0);
  return this->Internals->UnitDistances[channel];
}

#undef MCVOL_CHECK_CHANNEL

//------------------------------------------------------------------------------
void vtkMultiChannelVolumeMapper::RemoveAllChannelTransferFunctions()
{
  bool changed = false;
  for (int c = 0; c < kMaxChannels; ++c)
  {
    changed = changed || this->Internals->Colors[c] || this->Internals->Opacities[c] ||
      this->Internals->UnitDistances[c] != 0.0;
    this->Internals->Colors[c] = nullptr;
    this->Internals->Opacities[c] = nullptr;
    this->Internals->UnitDistances[c] = 0.0;
  }
  if (changed)
  {
    this->Modified();
  }
}

//------------------------------------------------------------------------------
double* vtkMultiChannelVolumeMapper::GetBounds()
{
  // Like vtkAbstractVolumeMapper: bring the input up to date first (the
  // renderer asks for bounds before anything has rendered).
  if (this->GetNumberOfInputConnections(0) == 0)
  {
    vtkMath::UninitializeBounds(this->Bounds);
    return this->Bounds;
  }
  this->GetInputAlgorithm()->Update();
  vtkImageData* image = vtkImageData::SafeDownCast(this->GetInput());
  if (!image)
  {
    // No image: the base class gives the default (or a non-image's) bounds.
    return this->Superclass::GetBounds();
  }
  int extent[6];
  image->GetExtent(extent);
  if (extent[0] > extent[1] || extent[2] > extent[3] || extent[4] > extent[5])
  {
    vtkMath::UninitializeBounds(this->Bounds);
    return this->Bounds;
  }
  // Index box of the voxels; a single-voxel axis is one spacing thick (the
  // renderer does the same, so a slice or a lone voxel stays visible).
  double lo[3], hi[3];
  for (int a = 0; a < 3; ++a)
  {
    const double pad = extent[2 * a] == extent[2 * a + 1] ? 0.5 : 0.0;
    lo[a] = extent[2 * a] - pad;
    hi[a] = extent[2 * a + 1] + pad;
  }
  for (int a = 0; a < 3; ++a)
  {
    this->Bounds[2 * a] = VTK_DOUBLE_MAX;
    this->Bounds[2 * a + 1] = -VTK_DOUBLE_MAX;
  }
  for (int corner = 0; corner < 8; ++corner)
  {
    const double ijk[3] = { (corner & 1) ? hi[0] : lo[0], (corner & 2) ? hi[1] : lo[1], (corner & 4) ? hi[2] : lo[2] };
    double xyz[3];
    image->TransformContinuousIndexToPhysicalPoint(ijk, xyz);
    for (int a = 0; a < 3; ++a)
    {
      this->Bounds[2 * a] = std::min(this->Bounds[2 * a], xyz[a]);
      this->Bounds[2 * a + 1] = std::max(this->Bounds[2 * a + 1], xyz[a]);
    }
  }
  return this->Bounds;
}

//------------------------------------------------------------------------------
void vtkMultiChannelVolumeMapper::ReleaseGraphicsResources(vtkWindow* window)
{
  if (this->Internals->Quad)
  {
    this->Internals->Quad->ReleaseGraphicsResources(window);
    this->Internals->Quad.reset();
  }
  if (this->Internals->Texture)
  {
    this->Internals->Texture->ReleaseGraphicsResources(window);
    this->Internals->Texture = nullptr;
  }
  // A device backend holds the data (twice, with textures) and the grids in
  // GPU memory: give them back too; the next render uploads again.
  vtkInternals& in = *this->Internals;
  if (in.Renderer && in.Renderer->buildsAccelerationOnDevice())
  {
    in.Renderer.reset();
    in.RendererBackend = -1;
    in.HaveKey = false;
  }
}

//------------------------------------------------------------------------------
void vtkMultiChannelVolumeMapper::Render(vtkRenderer* ren, vtkVolume* vol)
{
  vtkInternals& in = *this->Internals;
  this->NumberOfChannels = 0;
  this->LastTransferFunctionUpdates = 0;
  if (!ren || !vol)
  {
    return;
  }

  // ---- Input --------------------------------------------------------------
  vtkDataSet* dataSet = nullptr;
  if (this->GetNumberOfInputConnections(0) > 0)
  {
    this->GetInputAlgorithm()->Update();
    dataSet = this->GetInput();
  }
  if (!dataSet)
  {
    vtkErrorMacro("No input: set a vtkImageData with SetInputData or SetInputConnection.");
    return;
  }
  vtkImageData* image = vtkImageData::SafeDownCast(dataSet);
  if (!image)
  {
    vtkErrorMacro(
      "Input is a " << dataSet->GetClassName() << "; vtkMultiChannelVolumeMapper renders vtkImageData only.");
    return;
  }
  int extent[6];
  image->GetExtent(extent);
  int dims[3];
  for (int a = 0; a < 3; ++a)
  {
    dims[a] = extent[2 * a + 1] - extent[2 * a] + 1;
  }
  if (dims[0] < 1 || dims[1] < 1 || dims[2] < 1)
  {
    vtkErrorMacro("Input image has an empty extent (" << extent[0] << " " << extent[1] << " " << extent[2] << " "
                                                      << extent[3] << " " << extent[4] << " " << extent[5] << ").");
    return;
  }
  const vtkIdType numPoints = image->GetNumberOfPoints();

  // ---- Channels -----------------------------------------------------------
  std::vector<vtkDataArray*> arrays; // one per channel
  std::vector<int> components;       // component of that array
  if (!in.ChannelArrayNames.empty())
  {
    for (const std::string& name : in.ChannelArrayNames)
    {
      vtkDataArray* array = image->GetPointData()->GetArray(name.c_str());
      if (!array)
      {
        vtkErrorMacro("Channel array \"" << name << "\" is not a point data array of the input.");
        return;
      }
      if (array->GetNumberOfComponents() != 1)
      {
        vtkErrorMacro("Channel array \"" << name << "\" has " << array->GetNumberOfComponents()
                                         << " components; channel arrays must have one.");
        return;
      }
      arrays.push_back(array);
      components.push_back(0);
    }
  }
  else
  {
    int cellFlag = 0;
    vtkDataArray* scalars = vtkAbstractMapper::GetScalars(
      image, this->ScalarMode, this->ArrayAccessMode, this->ArrayId, this->ArrayName, cellFlag);
    if (!scalars)
    {
      vtkErrorMacro("Input has no point scalars to render (set them, select an array with "
                    "SelectScalarArray, or list channel arrays with AddChannelArray).");
      return;
    }
    if (cellFlag)
    {
      vtkErrorMacro("Scalars \"" << (scalars->GetName() ? scalars->GetName() : "")
                                 << "\" are cell data; only point data is supported.");
      return;
    }
    for (int c = 0; c < scalars->GetNumberOfComponents(); ++c)
    {
      arrays.push_back(scalars);
      components.push_back(c);
    }
  }
  const int numChannels = static_cast<int>(arrays.size());
  if (numChannels < 1 || numChannels > kMaxChannels)
  {
    vtkErrorMacro("The input has " << numChannels << " channels; 1 to " << kMaxChannels << " are supported.");
    return;
  }

  std::array<mcvol::ChannelSource, kMaxChannels> sources{};
  // The arrays' times say their values changed; the image's time also moves
  // when only its origin, spacing or direction do, which needs no rebuild
  // (those reach the renderer through worldToIndex).
  vtkMTimeType dataMTime = 0;
  vtkMTimeType lightsMTime = 0; // the lights, when lighting is on
  const vtkMTimeType imageMTime = image->GetMTime();
  std::array<double, 15> geometry;
  std::copy(image->GetOrigin(), image->GetOrigin() + 3, geometry.begin());
  std::copy(image->GetSpacing(), image->GetSpacing() + 3, geometry.begin() + 3);
  std::copy(image->GetDirectionMatrix()->GetData(), image->GetDirectionMatrix()->GetData() + 9, geometry.begin() + 6);
  for (int c = 0; c < numChannels; ++c)
  {
    vtkDataArray* array = arrays[c];
    const char* arrayName = array->GetName() ? array->GetName() : "(unnamed)";
    mcvol::ScalarType type;
    if (!toScalarType(array->GetDataType(), type))
    {
      vtkErrorMacro("Channel " << c << " (array \"" << arrayName << "\") has type " << array->GetDataTypeAsString()
                               << "; supported types are unsigned char, short, unsigned short, "
                                  "float and double.");
      return;
    }
    if (array->GetNumberOfTuples() != numPoints)
    {
      vtkErrorMacro("Channel " << c << " (array \"" << arrayName << "\") has " << array->GetNumberOfTuples()
                               << " tuples for " << numPoints << " points.");
      return;
    }
    if (!array->HasStandardMemoryLayout())
    {
      vtkErrorMacro("Channel " << c << " (array \"" << arrayName
                               << "\") is not a contiguous array of tuples (AOS); it cannot be "
                                  "read in place.");
      return;
    }
    const int numComponents = array->GetNumberOfComponents();
    sources[c].data = static_cast<const char*>(array->GetVoidPointer(0)) +
      static_cast<size_t>(components[c]) * static_cast<size_t>(array->GetDataTypeSize());
    sources[c].type = type;
    sources[c].stride = numComponents;
    dataMTime = std::max(dataMTime, array->GetMTime());
  }

  // ---- Transfer functions -------------------------------------------------
  vtkVolumeProperty* property = vol->GetProperty();
  std::array<ChannelTFState, kMaxChannels> tfState{};
  for (int c = 0; c < numChannels; ++c)
  {
    ChannelTFState& s = tfState[c];
    s.Valid = true;
    if (in.Colors[c])
    {
      s.Color = in.Colors[c];
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
    if (in.Opacities[c])
    {
      s.Opacity = in.Opacities[c];
    }
    else if (c < VTK_MAX_VRCOMP && property)
    {
      s.Opacity = property->GetScalarOpacity(c);
    }
    if (!s.Color || !s.Opacity)
    {
      vtkErrorMacro("Channel " << c << " has no " << (!s.Color ? "colour" : "scalar opacity")
                               << " transfer function: channels >= " << VTK_MAX_VRCOMP
                               << " need SetChannelColor and SetChannelScalarOpacity on the "
                                  "mapper.");
      return;
    }
    s.ColorMTime = s.Color->GetMTime();
    s.OpacityMTime = s.Opacity->GetMTime();
    s.UnitDistance = in.UnitDistances[c];
    if (!(s.UnitDistance > 0.0))
    {
      s.UnitDistance = (c < VTK_MAX_VRCOMP && property) ? property->GetScalarOpacityUnitDistance(c) : 1.0;
    }
    if (!(s.UnitDistance > 0.0) || !std::isfinite(s.UnitDistance))
    {
      vtkErrorMacro(
        "Channel " << c << " has opacity unit distance " << s.UnitDistance << "; it must be finite and > 0.");
      return;
    }
  }

  // ---- Backend ------------------------------------------------------------
  if (!this->UsesRenderBackend())
  {
    in.Renderer.reset();
    in.RendererBackend = -1;
  }
  else if (!in.Renderer || in.RendererBackend != this->Backend)
  {
    in.Renderer.reset();
    in.RendererBackend = this->Backend;
    try
    {
      in.Renderer = mcvol::Renderer::create(static_cast<mcvol::Backend>(this->Backend), &in.BackendWhy);
    }
    catch (const std::exception& e)
    {
      in.BackendWhy = e.what();
      vtkErrorMacro("Backend " << this->GetBackendAsString() << " is not available: " << e.what());
      return;
    }
    if (!in.Renderer)
    {
      vtkErrorMacro("No rendering backend could be created.");
      return;
    }
  }

  // ---- Scene: volume, ranges, tables, parameters --------------------------
  try
  {
    // A device backend builds macrocells and majorants itself from its own
    // copy of the data; the host then spends neither time nor memory on them.
    in.Scene.setHostAcceleration(!in.Renderer || !in.Renderer->buildsAccelerationOnDevice());
    bool volumeChanged =
      !in.VolumeSet || in.Scene.numChannels() != numChannels || !std::equal(dims, dims + 3, in.Scene.dims());
    for (int c = 0; c < numChannels && !volumeChanged; ++c)
    {
      volumeChanged = sources[c].data != in.Sources[c].data || sources[c].type != in.Sources[c].type ||
        sources[c].stride != in.Sources[c].stride;
    }
    // An image Modified() with the same geometry may mean values written in
    // place (users often call image->Modified() rather than the array's).
    // Only for the same image object: a new image holding the same arrays
    // (ParaView delivers a fresh shallow copy for every parallel render)
    // changed nothing the arrays' times would not show.
    const bool sameImage = in.LastImage == image;
    const bool imageValuesChanged = sameImage && imageMTime != in.ImageMTime && geometry == in.Geometry;
    in.LastImage = image;
    const bool dataChanged = volumeChanged || dataMTime != in.DataMTime || imageValuesChanged;
    in.ImageMTime = imageMTime;
    in.Geometry = geometry;
    if (imageValuesChanged && dataMTime == in.DataMTime)
    {
      // The arrays were not marked modified, so their cached ranges are
      // stale: mark them (what the writer should have done) and take the
      // new time, so the next render sees no change.
      for (vtkDataArray* a : arrays)
      {
        a->Modified();
        dataMTime = std::max(dataMTime, a->GetMTime());
      }
    }
    if (dataChanged)
    {
      in.DataMTime = dataMTime;
      for (int c = 0; c < numChannels; ++c)
      {
        // Finite range: NaN and Inf voxels must not stretch or poison the table.
        double range[2];
        arrays[c]->GetFiniteRange(range, components[c]);
        if (!(range[0] <= range[1]) || !std::isfinite(range[0]) || !std::isfinite(range[1]))
        {
          range[0] = 0.0; // no finite voxel at all
          range[1] = 1.0;
        }
        if (range[0] == range[1])
        {
          // A constant channel: centre its value in the table. (Ranges
          // narrower than float resolution are widened by the core.)
          const double pad = std::max(0.5, 1e-3 * std::abs(range[0]));
          range[0] -= pad;
          range[1] += pad;
        }
        in.Ranges[c] = { range[0], range[1] };
      }
    }
    // Double data is read relative to its minimum, so values far from zero
    // (1e9 + [0, 500]) keep their resolution when they become float.
    for (int c = 0; c < numChannels; ++c)
    {
      sources[c].offset = sources[c].type == mcvol::ScalarType::Float64 ? in.Ranges[c][0] : 0.0;
      volumeChanged = volumeChanged || sources[c].offset != in.Sources[c].offset;
    }
    if (volumeChanged)
    {
      in.ForgetVolume();
      in.Scene.setVolume(dims, numChannels, sources.data());
      in.VolumeSet = true;
      in.Sources = sources;
      in.Arrays.assign(arrays.begin(), arrays.end());
    }
    else if (dataChanged)
    {
      in.Scene.dataModified();
    }

    int updates = 0;
    std::vector<double> colors(3 * kTableSize);
    std::vector<float> gray(kTableSize);
    for (int c = 0; c < numChannels; ++c)
    {
      ChannelTFState& s = tfState[c];
      s.Range[0] = in.Ranges[c][0];
      s.Range[1] = in.Ranges[c][1];
      if (this->TransferFunctionRangeMode == FUNCTION_RANGE)
      {
        // The functions' own range (the same on every rank of a parallel
        // render); values beyond it take the end values, as VTK's clamped
        // functions do.
        double cr[2], orr[2];
        if (s.Gray)
        {
          static_cast<vtkPiecewiseFunction*>(s.Color)->GetRange(cr);
        }
        else
        {
          static_cast<vtkColorTransferFunction*>(s.Color)->GetRange(cr);
        }
        s.Opacity->GetRange(orr);
        const double lo = std::min(cr[0], orr[0]);
        const double hi = std::max(cr[1], orr[1]);
        if (std::isfinite(lo) && std::isfinite(hi) && lo < hi)
        {
          s.Range[0] = lo;
          s.Range[1] = hi;
        }
      }
      if (s == in.TF[c])
      {
        continue;
      }
      mcvol::TransferFunctionDesc desc;
      desc.scalarMin = static_cast<float>(s.Range[0]);
      desc.scalarMax = static_cast<float>(s.Range[1]);
      desc.unitDistance = static_cast<float>(s.UnitDistance);
      desc.rgb.resize(3 * kTableSize);
      desc.opacity.resize(kTableSize);
      if (s.Gray)
      {
        static_cast<vtkPiecewiseFunction*>(s.Color)->GetTable(s.Range[0], s.Range[1], kTableSize, gray.data());
        for (int i = 0; i < kTableSize; ++i)
        {
          desc.rgb[3 * i] = desc.rgb[3 * i + 1] = desc.rgb[3 * i + 2] = gray[i];
        }
      }
      else
      {
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
      in.TF[c] = s;
      const mcvol::TransferFunctionDesc& last = in.Tables[c];
      if (last.rgb == desc.rgb && last.opacity == desc.opacity && last.scalarMin == desc.scalarMin &&
        last.scalarMax == desc.scalarMax && last.unitDistance == desc.unitDistance)
      {
        continue;
      }
      in.Scene.setTransferFunction(c, desc);
      in.Tables[c] = std::move(desc);
      ++in.TablesVersion;
      ++updates;
    }
    this->LastTransferFunctionUpdates = updates;

    // The Scene's setters are cheap and rebuild nothing unless a value
    // changed (a new macrocell size marks the grids for update()).
    in.Scene.setMacrocellSize(this->MacrocellSize);
    in.Scene.setBlendMode(static_cast<mcvol::BlendMode>(this->ChannelBlendMode));
    // vtkVolumeProperty's interpolation type, as VTK's own mappers use it (a
    // property change resets the accumulation through its MTime).
    in.Scene.setNearestInterpolation(property->GetInterpolationType() == VTK_NEAREST_INTERPOLATION);
    std::array<float, kMaxChannels> weights{};
    for (int c = 0; c < numChannels; ++c)
    {
      weights[c] = static_cast<float>(in.MixWeights[c]);
    }
    in.Scene.setMixWeights(weights.data(), numChannels);
    // Lighting: only with ShadeOn (the lights' state joins the reset key).
    mcvol::LightingDesc lighting;
    lightsMTime = 0;
    if (property && property->GetShade())
    {
      vtkLightCollection* lights = ren->GetLights();
      lightsMTime = lights->GetMTime();
      vtkCollectionSimpleIterator it;
      lights->InitTraversal(it);
      while (vtkLight* light = lights->GetNextLight(it))
      {
        lightsMTime = std::max(lightsMTime, light->GetMTime());
        if (!light->GetSwitch() || lighting.lights.size() >= size_t(mcvol::kMaxLights))
        {
          continue;
        }
        mcvol::LightDesc ld;
        double pos[3], focal[3];
        light->GetTransformedPosition(pos);
        light->GetTransformedFocalPoint(focal);
        ld.point = light->GetPositional() != 0;
        for (int a = 0; a < 3; ++a)
        {
          ld.vector[a] = ld.point ? pos[a] : pos[a] - focal[a];
          ld.color[a] = light->GetDiffuseColor()[a];
        }
        ld.intensity = light->GetIntensity();
        lighting.lights.push_back(ld);
      }
      std::copy(this->AmbientRadiance, this->AmbientRadiance + 3, lighting.ambient);
      for (int c = 0; c < numChannels; ++c)
      {
        lighting.albedo.push_back(static_cast<float>(in.Albedo[c]));
        lighting.anisotropy.push_back(static_cast<float>(in.Anisotropy[c]));
      }
      lighting.shadows = this->ShadowMode != NO_SHADOWS;
      lighting.deltaShadows = this->ShadowMode == DELTA_TRACKING_SHADOWS;
      lighting.maxDepth = this->MaxScatteringDepth;
      lighting.gradientShading = this->GradientShading;
      lighting.shininess = static_cast<float>(this->Shininess);
    }
    in.Scene.setLighting(lighting);
    in.Scene.update();
  }
  catch (const std::exception& e)
  {
    vtkErrorMacro("Could not set up the volume: " << e.what());
    in.ForgetVolume();
    in.HaveKey = false;
    return;
  }

  // ---- Camera -------------------------------------------------------------
  int width = 0, height = 0, x0 = 0, y0 = 0;
  ren->GetTiledSizeAndOrigin(&width, &height, &x0, &y0);
  if (width < 1 || height < 1)
  {
    return;
  }
  vtkOpenGLRenderWindow* renWin = vtkOpenGLRenderWindow::SafeDownCast(ren->GetRenderWindow());
  if (!renWin)
  {
    vtkErrorMacro("vtkMultiChannelVolumeMapper draws with OpenGL and needs a "
                  "vtkOpenGLRenderWindow.");
    return;
  }

  mcvol::Camera camera;
  camera.width = width;
  camera.height = height;
  AccumulationKey key;
  {
    vtkCamera* cam = ren->GetActiveCamera();
    // World to normalised device coordinates, as vtkOpenGLCamera computes it.
    vtkMatrix4x4* worldToNDC = cam->GetCompositeProjectionTransformMatrix(ren->GetTiledAspectRatio(), -1, 1);
    vtkNew<vtkMatrix4x4> ndcToWorld;
    if (worldToNDC->Determinant() == 0.0)
    {
      vtkErrorMacro("The camera's projection is singular.");
      return;
    }
    vtkMatrix4x4::Invert(worldToNDC, ndcToWorld);

    // World -> volume model coordinates (the prop's matrix) -> physical image
    // coordinates -> continuous index, with voxel 0 at the extent's start.
    vtkMatrix4x4* propMatrix = vol->GetMatrix();
    if (propMatrix->Determinant() == 0.0)
    {
      vtkErrorMacro("The volume's matrix is singular (a zero scale?).");
      return;
    }
    const double* spacing = image->GetSpacing();
    if (!(spacing[0] != 0.0 && spacing[1] != 0.0 && spacing[2] != 0.0 && std::isfinite(spacing[0]) &&
          std::isfinite(spacing[1]) && std::isfinite(spacing[2])) ||
      image->GetDirectionMatrix()->Determinant() == 0.0)
    {
      vtkErrorMacro("The image's spacing (" << spacing[0] << ", " << spacing[1] << ", " << spacing[2]
                                            << ") or direction matrix is degenerate: every axis needs a non-zero, "
                                               "finite spacing and the directions must be independent.");
      return;
    }
    vtkNew<vtkMatrix4x4> worldToModel;
    vtkMatrix4x4::Invert(propMatrix, worldToModel);
    vtkNew<vtkMatrix4x4> worldToIndex;
    vtkMatrix4x4::Multiply4x4(image->GetPhysicalToIndexMatrix(), worldToModel, worldToIndex);
    for (int r = 0; r < 3; ++r)
    {
      for (int k = 0; k < 4; ++k)
      {
        double v = worldToIndex->GetElement(r, k);
        if (k == 3)
        {
          v -= extent[2 * r];
        }
        camera.worldToIndex[4 * r + k] = v;
      }
    }
    for (int r = 0; r < 4; ++r)
    {
      for (int k = 0; k < 4; ++k)
      {
        camera.invViewProj[4 * r + k] = ndcToWorld->GetElement(r, k);
      }
    }
  }

  // ---- Depth of the opaque geometry drawn so far --------------------------
  in.Depth.resize(static_cast<size_t>(width) * static_cast<size_t>(height));
  {
    if (renWin->GetZbufferData(x0, y0, x0 + width - 1, y0 + height - 1, in.Depth.data()) != VTK_OK)
    {
      vtkWarningMacro("Could not read the depth buffer; geometry will not occlude the volume.");
      std::fill(in.Depth.begin(), in.Depth.end(), 1.f);
    }
  }

  // ---- Accumulation reset -------------------------------------------------
  // The mapper's own parameters; the transfer functions count through the
  // tables they produce (TablesVersion), not through their times.
  key.MapperMTime = this->Superclass::GetMTime();
  key.TablesVersion = in.TablesVersion;
  // The property's own settings (shading, interpolation, which functions it
  // holds); the values of its functions count through TablesVersion.
  key.PropertyMTime = property ? property->vtkObject::GetMTime() : 0;
  // The arrays' times (marked above when values were written in place);
  // geometry reaches the key through WorldToIndex.
  key.DataMTime = dataMTime;
  key.LightsMTime = lightsMTime;
  key.Width = width;
  key.Height = height;
  std::copy(std::begin(camera.invViewProj), std::end(camera.invViewProj), key.InvViewProj);
  std::copy(std::begin(camera.worldToIndex), std::end(camera.worldToIndex), key.WorldToIndex);
  key.Renderer = in.Renderer.get();
  const bool depthChanged = in.LastDepth.size() != in.Depth.size() ||
    std::memcmp(in.LastDepth.data(), in.Depth.data(), in.Depth.size() * sizeof(float)) != 0;
  if (!in.HaveKey || !(key == in.Key) || depthChanged || in.ResetRequested || in.Accum.width() != width ||
    in.Accum.height() != height)
  {
    if (in.Accum.width() != width || in.Accum.height() != height)
    {
      in.Accum.resize(width, height);
    }
    in.Accum.reset();
    in.Key = key;
    in.HaveKey = true;
    in.ResetRequested = false;
    in.LastDepth.swap(in.Depth);
    in.Depth.resize(in.LastDepth.size());
  }

  // ---- Trace --------------------------------------------------------------
  // Progressive refinement adds a batch up to MaximumTotalSamples; without it
  // the image is traced once per change. The ray-marching subclass decides
  // for itself (it traces once per change).
  const long long traced = static_cast<long long>(in.Accum.samples());
  int batch = this->SamplesPerPixel;
  if (this->UsesRenderBackend())
  {
    if (!this->Progressive && traced > 0)
    {
      batch = 0;
    }
    else if (this->MaximumTotalSamples > 0)
    {
      batch = static_cast<int>(std::min<long long>(batch, std::max<long long>(0, this->MaximumTotalSamples - traced)));
    }
  }
  if (batch > 0)
  {
    std::string error;
    in.BatchSamples = batch;
    const bool ok = this->TraceImage(in.Scene, camera, in.LastDepth.data(), in.Renderer.get(), in.Accum, error);
    in.BatchSamples = 0;
    if (!ok)
    {
      vtkErrorMacro("Rendering failed: " << error);
      in.HaveKey = false;
      return;
    }
  }
  this->NumberOfChannels = numChannels;

  // ---- Draw the mean over the frame ---------------------------------------
  if (!in.Texture)
  {
    in.Texture = vtkSmartPointer<vtkTextureObject>::New();
  }
  in.Texture->SetContext(renWin);
  in.Texture->SetMinificationFilter(vtkTextureObject::Nearest);
  in.Texture->SetMagnificationFilter(vtkTextureObject::Nearest);
  in.Texture->SetWrapS(vtkTextureObject::ClampToEdge);
  in.Texture->SetWrapT(vtkTextureObject::ClampToEdge);
  if (!in.Texture->Create2DFromRaw(static_cast<unsigned int>(width), static_cast<unsigned int>(height), 4, VTK_FLOAT,
        const_cast<float*>(in.Accum.rgba())))
  {
    vtkErrorMacro("Could not upload the image to a float texture.");
    return;
  }

  if (!in.Quad)
  {
    // vtkOpenGLRenderUtilities' full-screen-quad template, filled in (that
    // header pulls in GLEW's).
    const char* fs = "//VTK::System::Dec\n"
                     "//VTK::Output::Dec\n"
                     "in vec2 texCoord;\n"
                     "uniform sampler2D mcvolImage;\n"
                     "void main()\n"
                     "{\n"
                     "  gl_FragData[0] = texture(mcvolImage, texCoord);\n"
                     "}\n";
    in.Quad.reset(new vtkOpenGLQuadHelper(renWin, nullptr, fs, nullptr));
  }
  else
  {
    renWin->GetShaderCache()->ReadyShaderProgram(in.Quad->Program);
  }
  if (!in.Quad->Program || !in.Quad->Program->GetCompiled())
  {
    vtkErrorMacro("Could not build the shader that draws the image.");
    return;
  }

  vtkOpenGLState* state = renWin->GetState();
  vtkOpenGLState::ScopedglEnableDisable blendSaver(state, GL_BLEND);
  vtkOpenGLState::ScopedglEnableDisable depthTestSaver(state, GL_DEPTH_TEST);
  vtkOpenGLState::ScopedglBlendFuncSeparate blendFuncSaver(state);
  vtkOpenGLState::ScopedglDepthMask depthMaskSaver(state);
  state->vtkglEnable(GL_BLEND);
  // The image is premultiplied: "over" is (ONE, ONE_MINUS_SRC_ALPHA).
  state->vtkglBlendFuncSeparate(GL_ONE, GL_ONE_MINUS_SRC_ALPHA, GL_ONE, GL_ONE_MINUS_SRC_ALPHA);
  state->vtkglDisable(GL_DEPTH_TEST);
  state->vtkglDepthMask(GL_FALSE);

  in.Texture->Activate();
  in.Quad->Program->SetUniformi("mcvolImage", in.Texture->GetTextureUnit());
  in.Quad->Render();
  in.Texture->Deactivate();
}

//------------------------------------------------------------------------------
void vtkMultiChannelVolumeMapper::PrintSelf(ostream& os, vtkIndent indent)
{
  this->Superclass::PrintSelf(os, indent);
  vtkInternals& in = *this->Internals;
  os << indent << "ChannelBlendMode: " << this->GetChannelBlendModeAsString() << "\n";
  os << indent << "TrackingMethod: " << this->GetTrackingMethodAsString() << "\n";
  os << indent << "SamplesPerPixel: " << this->SamplesPerPixel << "\n";
  os << indent << "Progressive: " << this->Progressive << "\n";
  os << indent << "TransferFunctionRangeMode: "
     << (this->TransferFunctionRangeMode == FUNCTION_RANGE ? "function" : "data") << "\n";
  os << indent << "MaximumTotalSamples: " << this->MaximumTotalSamples << "\n";
  os << indent << "Seed: " << this->Seed << "\n";
  os << indent << "PixelJitter: " << this->PixelJitter << "\n";
  os << indent << "MacrocellSize: " << this->MacrocellSize << "\n";
  os << indent << "Backend: " << this->GetBackendAsString() << "\n";
  os << indent
     << "ActiveBackend: " << (in.Renderer && in.RendererBackend == this->Backend ? in.Renderer->name() : "(none yet)")
     << "\n";
  os << indent << "TotalSamples: " << in.Accum.samples() << "\n";
  os << indent << "NumberOfChannels: " << this->NumberOfChannels << "\n";
  os << indent << "LastTransferFunctionUpdates: " << this->LastTransferFunctionUpdates << "\n";
  os << indent << "ChannelArrays:";
  if (in.ChannelArrayNames.empty())
  {
    os << " (none: the scalars' components)";
  }
  for (const std::string& name : in.ChannelArrayNames)
  {
    os << " \"" << name << "\"";
  }
  os << "\n";
  os << indent << "MixWeights:";
  for (int c = 0; c < kMaxChannels; ++c)
  {
    os << " " << in.MixWeights[c];
  }
  os << "\n";
  for (int c = 0; c < kMaxChannels; ++c)
  {
    if (in.Colors[c] || in.Opacities[c] || in.UnitDistances[c] != 0.0)
    {
      os << indent << "Channel " << c << ": Color " << in.Colors[c].Get() << ", ScalarOpacity " << in.Opacities[c].Get()
         << ", ScalarOpacityUnitDistance " << in.UnitDistances[c] << "\n";
    }
  }
}
