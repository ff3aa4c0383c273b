// SPDX-License-Identifier: BSD-3-Clause
#include "vtkMultiChannelVolumeRepresentation.h"

#include "ChannelDefaultRanges.h"

#include "vtkColorTransferFunction.h"
#include "vtkDataArray.h"
#include "vtkDiscretizableColorTransferFunction.h"
#include "vtkImageData.h"
#include "vtkInformation.h"
#include "vtkMultiChannelVolumeMapper.h"
#include "vtkMultiProcessController.h"
#include "vtkObjectFactory.h"
#include "vtkPVLODVolume.h"
#include "vtkPVRenderView.h"
#include "vtkPiecewiseFunction.h"
#include "vtkPointData.h"
#include "vtkRenderer.h"
#include "vtkScalarsToColors.h"
#include "vtkTextActor.h"
#include "vtkTextProperty.h"
#include "vtkVolumeProperty.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <sstream>

vtkStandardNewMacro(vtkMultiChannelVolumeRepresentation);

namespace
{
// The progress annotation. It sits in the view's non-composited renderer,
// which draws after the volume's renderer, and asks the representation for
// its words when it is drawn: the numbers describe the image under it, not
// the one before this render.
class vtkMultiChannelProgressText : public vtkTextActor
{
public:
  static vtkMultiChannelProgressText* New();
  vtkTypeMacro(vtkMultiChannelProgressText, vtkTextActor);

  vtkMultiChannelVolumeRepresentation* Owner = nullptr; // not counted: the owner holds this actor

  int RenderOpaqueGeometry(vtkViewport* viewport) override
  {
    const std::string text = this->Owner ? this->Owner->BuildProgressSummary() : std::string();
    if (text.empty())
    {
      return 0;
    }
    if (!this->GetInput() || text != this->GetInput())
    {
      this->SetInput(text.c_str());
    }
    return this->Superclass::RenderOpaqueGeometry(viewport);
  }
  int RenderOverlay(vtkViewport* viewport) override
  {
    return this->Owner && !this->Owner->BuildProgressSummary().empty() ? this->Superclass::RenderOverlay(viewport) : 0;
  }
};
vtkStandardNewMacro(vtkMultiChannelProgressText);
}

namespace
{
// Per-channel lists set by repeatable properties with use_index: entries not
// set take `fill`.
template <typename T>
void SetEntry(std::vector<T>& list, int index, T value, T fill)
{
  if (index < 0)
  {
    return;
  }
  if (static_cast<size_t>(index) >= list.size())
  {
    list.resize(static_cast<size_t>(index) + 1, fill);
  }
  list[index] = value;
}

template <typename T>
T EntryOr(const std::vector<T>& list, int index, T fallback)
{
  return static_cast<size_t>(index) < list.size() ? list[index] : fallback;
}

// The mapper's importance levels (mcvol::snapImportance): anything that
// snaps to 0, NaN included, means the channel carries no importance.
double SnapImportanceLevel(double level)
{
  if (!(level > 0.0))
  {
    return 0.0;
  }
  return level >= 1.0 ? 1.0 : std::round(level * 4.0) / 4.0;
}

// Whether any control point of an importance function snaps to a level > 0
// (between points the function interpolates, so it never exceeds them).
bool CarriesImportance(vtkPiecewiseFunction* function)
{
  if (!function)
  {
    return false;
  }
  double node[4];
  for (int i = 0; i < function->GetSize(); ++i)
  {
    function->GetNodeValue(i, node);
    if (SnapImportanceLevel(node[1]) > 0.0)
    {
      return true;
    }
  }
  return false;
}

// Points the mapper at a point array by name, touching it only on a change
// (every touch would restart the image).
void SelectPointArray(vtkMultiChannelVolumeMapper* mapper, const std::string& name)
{
  const char* current = mapper->GetArrayName();
  if (mapper->GetScalarMode() != VTK_SCALAR_MODE_USE_POINT_FIELD_DATA ||
    mapper->GetArrayAccessMode() != VTK_GET_ARRAY_BY_NAME || !current || name != current)
  {
    mapper->SetScalarMode(VTK_SCALAR_MODE_USE_POINT_FIELD_DATA);
    mapper->SelectScalarArray(name.c_str());
  }
}
}

//------------------------------------------------------------------------------
vtkMultiChannelVolumeRepresentation::vtkMultiChannelVolumeRepresentation()
{
  // Replace the image volume representation's mapper; everything else (data
  // delivery, outline, ordered compositing) is the superclass's.
  auto mapper = vtkSmartPointer<vtkMultiChannelVolumeMapper>::New();
  // ParaView's transfer functions span the whole dataset's range, the same
  // on every rank; a piece's own data range is not (tables would differ).
  mapper->SetTransferFunctionRangeMode(vtkMultiChannelVolumeMapper::FUNCTION_RANGE);
  // Lighting across ranks gathers in ProcessViewRequest(REQUEST_RENDER),
  // never inside the mapper's render (see there).
  mapper->LightingStandInSynchronizedByCallerOn();
  this->VolumeMapper = mapper;
}

//------------------------------------------------------------------------------
vtkMultiChannelVolumeRepresentation::~vtkMultiChannelVolumeRepresentation()
{
  if (auto* text = vtkMultiChannelProgressText::SafeDownCast(this->ProgressActor))
  {
    text->Owner = nullptr;
  }
}

//------------------------------------------------------------------------------
bool vtkMultiChannelVolumeRepresentation::AddToView(vtkView* view)
{
  vtkPVRenderView* rview = vtkPVRenderView::SafeDownCast(view);
  if (rview && rview->GetNonCompositedRenderer())
  {
    if (!this->ProgressActor)
    {
      auto text = vtkSmartPointer<vtkMultiChannelProgressText>::New();
      text->Owner = this;
      text->GetTextProperty()->SetFontSize(13);
      text->GetTextProperty()->SetJustificationToRight();
      text->GetTextProperty()->SetVerticalJustificationToTop();
      text->GetTextProperty()->SetColor(0.85, 0.85, 0.85);
      text->GetTextProperty()->SetShadow(1);
      text->GetPositionCoordinate()->SetCoordinateSystemToNormalizedViewport();
      text->SetPosition(0.99, 0.99);
      this->ProgressActor = text;
    }
    rview->GetNonCompositedRenderer()->AddActor2D(this->ProgressActor);
  }
  return this->Superclass::AddToView(view);
}

//------------------------------------------------------------------------------
bool vtkMultiChannelVolumeRepresentation::RemoveFromView(vtkView* view)
{
  vtkPVRenderView* rview = vtkPVRenderView::SafeDownCast(view);
  if (rview && rview->GetNonCompositedRenderer() && this->ProgressActor)
  {
    rview->GetNonCompositedRenderer()->RemoveActor2D(this->ProgressActor);
  }
  return this->Superclass::RemoveFromView(view);
}

//------------------------------------------------------------------------------
void vtkMultiChannelVolumeRepresentation::SetProgressAnnotation(bool on)
{
  if (this->ProgressAnnotation != on)
  {
    this->ProgressAnnotation = on;
    this->Modified();
  }
}

//------------------------------------------------------------------------------
std::string vtkMultiChannelVolumeRepresentation::BuildProgressSummary()
{
  if (!this->ProgressAnnotation || !this->GetVisibility())
  {
    return std::string();
  }
  if (!this->HoldsData())
  {
    // This process holds no data (the client of a pvserver): the server's
    // words, if the GUI has fetched them.
    return this->RemoteProgressSummary;
  }
  if (!this->ChannelStatus.empty())
  {
    return "Multi-Channel Volume: " + this->ChannelStatus;
  }
  vtkMultiChannelVolumeMapper* mapper = this->GetMultiChannelMapper();
  const int samples = mapper->GetTotalSamples();
  if (samples <= 0)
  {
    return std::string();
  }
  char line[128];
  const double psnr = mapper->GetEstimatedPSNR();
  const char* state = mapper->IsConverged() ? "converged" : "refining";
  if (psnr > 0.0)
  {
    std::snprintf(line, sizeof(line), "%d samples   %.1f dB   %s", samples, psnr, state);
  }
  else
  {
    std::snprintf(line, sizeof(line), "%d sample%s   %s", samples, samples == 1 ? "" : "s", state);
  }
  return line;
}

//------------------------------------------------------------------------------
const char* vtkMultiChannelVolumeRepresentation::GetProgressSummary()
{
  this->ProgressSummaryValue = this->BuildProgressSummary();
  return this->ProgressSummaryValue.c_str();
}

//------------------------------------------------------------------------------
vtkMultiChannelVolumeMapper* vtkMultiChannelVolumeRepresentation::GetMultiChannelMapper()
{
  return vtkMultiChannelVolumeMapper::SafeDownCast(this->VolumeMapper);
}

//------------------------------------------------------------------------------
void vtkMultiChannelVolumeRepresentation::SetChannelSource(int source)
{
  source = source == COMPONENTS ? COMPONENTS : ARRAYS;
  if (this->ChannelSource != source)
  {
    this->ChannelSource = source;
    this->Modified();
  }
}

//------------------------------------------------------------------------------
void vtkMultiChannelVolumeRepresentation::AddChannelArray(const char* name)
{
  if (name && *name)
  {
    this->ChannelArrays.emplace_back(name);
    this->Modified();
  }
}

//------------------------------------------------------------------------------
void vtkMultiChannelVolumeRepresentation::RemoveAllChannelArrays()
{
  if (!this->ChannelArrays.empty())
  {
    this->ChannelArrays.clear();
    this->Modified();
  }
}

//------------------------------------------------------------------------------
void vtkMultiChannelVolumeRepresentation::SetChannelComponentsArray(const char* name)
{
  const std::string value = name ? name : "";
  if (this->ChannelComponentsArray != value)
  {
    this->ChannelComponentsArray = value;
    this->Modified();
  }
}

//------------------------------------------------------------------------------
void vtkMultiChannelVolumeRepresentation::AddChannelLookupTable(vtkScalarsToColors* lut)
{
  this->ChannelLookupTables.emplace_back(lut);
  this->Modified();
}

//------------------------------------------------------------------------------
void vtkMultiChannelVolumeRepresentation::RemoveAllChannelLookupTables()
{
  if (!this->ChannelLookupTables.empty())
  {
    this->ChannelLookupTables.clear();
    this->Modified();
  }
}

//------------------------------------------------------------------------------
void vtkMultiChannelVolumeRepresentation::SetNumberOfChannelLookupTableIndices(int n)
{
  this->ChannelLookupTableIndices.assign(static_cast<size_t>(std::max(0, n)), -1);
  this->Modified();
}

void vtkMultiChannelVolumeRepresentation::SetChannelLookupTableIndex(int channel, int index)
{
  SetEntry(this->ChannelLookupTableIndices, channel, index, -1);
  this->Modified();
}

//------------------------------------------------------------------------------
void vtkMultiChannelVolumeRepresentation::SetChannelBlendMode(int mode)
{
  this->GetMultiChannelMapper()->SetChannelBlendMode(mode);
}

void vtkMultiChannelVolumeRepresentation::SetNumberOfMixWeights(int n)
{
  this->MixWeights.assign(static_cast<size_t>(std::max(0, n)), 1.0);
}

void vtkMultiChannelVolumeRepresentation::SetMixColorMode(int mode)
{
  this->GetMultiChannelMapper()->SetMixColorMode(mode);
}

void vtkMultiChannelVolumeRepresentation::SetMixWeight(int channel, double weight)
{
  SetEntry(this->MixWeights, channel, weight, 1.0);
}

void vtkMultiChannelVolumeRepresentation::SetTrackingMethod(int method)
{
  this->GetMultiChannelMapper()->SetTrackingMethod(method);
}

void vtkMultiChannelVolumeRepresentation::SetEstimator(int estimator)
{
  this->GetMultiChannelMapper()->SetEstimator(estimator);
}

void vtkMultiChannelVolumeRepresentation::SetMinimumSamplesPerVoxel(double samples)
{
  this->GetMultiChannelMapper()->SetMinimumSamplesPerVoxel(samples);
}

//------------------------------------------------------------------------------
void vtkMultiChannelVolumeRepresentation::SetMarchSamplesPerVoxel(double samples)
{
  this->GetMultiChannelMapper()->SetMarchSamplesPerVoxel(samples);
}

void vtkMultiChannelVolumeRepresentation::SetMarchControlVariates(int mode)
{
  this->GetMultiChannelMapper()->SetMarchControlVariates(mode);
}

void vtkMultiChannelVolumeRepresentation::SetMultiChannelInterpolation(int type)
{
  // The mapper checks the value; UpdateMapperParameters applies it to still
  // renders.
  vtkMultiChannelVolumeMapper* mapper = this->GetMultiChannelMapper();
  mapper->SetInterpolationType(type);
  if (this->StillInterpolation != mapper->GetInterpolationType())
  {
    this->StillInterpolation = mapper->GetInterpolationType();
    this->Modified();
  }
}

void vtkMultiChannelVolumeRepresentation::SetInteractiveInterpolation(int mode)
{
  if (mode != INTERACTIVE_NEAREST && mode != INTERACTIVE_AS_STILL)
  {
    vtkErrorMacro("InteractiveInterpolation " << mode << " is not a mode: 0 nearest, 1 as still renders.");
    return;
  }
  if (this->InteractiveInterpolation != mode)
  {
    this->InteractiveInterpolation = mode;
    this->Modified();
  }
}

void vtkMultiChannelVolumeRepresentation::SetSampleSequence(int sequence)
{
  this->GetMultiChannelMapper()->SetSampleSequence(sequence);
}

void vtkMultiChannelVolumeRepresentation::SetInteractiveFrameTime(double seconds)
{
  this->GetMultiChannelMapper()->SetInteractiveFrameTime(seconds);
}

void vtkMultiChannelVolumeRepresentation::SetSamplesPerRender(int spp)
{
  this->GetMultiChannelMapper()->SetSamplesPerPixel(spp);
}

void vtkMultiChannelVolumeRepresentation::SetProgressiveRefinement(bool on)
{
  this->GetMultiChannelMapper()->SetProgressive(on);
}

void vtkMultiChannelVolumeRepresentation::SetMaximumTotalSamples(int total)
{
  this->GetMultiChannelMapper()->SetMaximumTotalSamples(total);
}

void vtkMultiChannelVolumeRepresentation::SetTargetError(double rmse)
{
  this->GetMultiChannelMapper()->SetTargetError(rmse);
}

void vtkMultiChannelVolumeRepresentation::SetMacrocellSize(int size)
{
  this->GetMultiChannelMapper()->SetMacrocellSize(size);
}

void vtkMultiChannelVolumeRepresentation::SetBackend(int backend)
{
  this->GetMultiChannelMapper()->SetBackend(backend);
}

void vtkMultiChannelVolumeRepresentation::SetCUDADevice(int device)
{
  this->GetMultiChannelMapper()->SetCUDADevice(device);
}

void vtkMultiChannelVolumeRepresentation::SetSeed(int seed)
{
  this->Seed = static_cast<unsigned int>(seed);
  this->Modified();
}

void vtkMultiChannelVolumeRepresentation::SetPixelJitter(bool on)
{
  this->GetMultiChannelMapper()->SetPixelJitter(on);
}

void vtkMultiChannelVolumeRepresentation::SetShadowMode(int mode)
{
  this->GetMultiChannelMapper()->SetShadowMode(mode);
}

void vtkMultiChannelVolumeRepresentation::SetShadowCacheSpacing(double voxels)
{
  this->GetMultiChannelMapper()->SetShadowCacheSpacing(voxels);
}

void vtkMultiChannelVolumeRepresentation::SetAmbientRadiance(double r, double g, double b)
{
  this->GetMultiChannelMapper()->SetAmbientRadiance(r, g, b);
}

void vtkMultiChannelVolumeRepresentation::SetMaxScatteringDepth(int depth)
{
  this->GetMultiChannelMapper()->SetMaxScatteringDepth(depth);
}

void vtkMultiChannelVolumeRepresentation::SetLightingStandInLevel(int level)
{
  this->LightingStandInLevel = level;
  this->GetMultiChannelMapper()->SetLightingStandInLevel(this->EmptyPieceSomewhere ? -1 : level);
}

//------------------------------------------------------------------------------
void vtkMultiChannelVolumeRepresentation::SetLightingStandInMemoryLimit(double mib)
{
  this->GetMultiChannelMapper()->SetLightingStandInMemoryLimit(mib * 1048576.0);
}

//------------------------------------------------------------------------------
void vtkMultiChannelVolumeRepresentation::SetSplitImageWithExactStandIn(bool on)
{
  this->GetMultiChannelMapper()->SetSplitImageWithExactStandIn(on);
}

//------------------------------------------------------------------------------
int vtkMultiChannelVolumeRepresentation::RequestData(
  vtkInformation* request, vtkInformationVector** inputVector, vtkInformationVector* outputVector)
{
  const int result = this->Superclass::RequestData(request, inputVector, outputVector);
  // The stand-in for lighting across ranks puts the whole volume together
  // from every process's piece (ProcessViewRequest gathers it), so with an
  // empty piece anywhere it stays off. Decided here, in the pipeline update
  // that every process runs, so that all agree.
  vtkMultiProcessController* controller = vtkMultiProcessController::GetGlobalController();
  int mine = this->HoldsData() ? 1 : 0;
  int all = mine;
  if (controller && controller->GetNumberOfProcesses() > 1)
  {
    controller->AllReduce(&mine, &all, 1, vtkCommunicator::MIN_OP);
  }
  this->EmptyPieceSomewhere = all == 0;
  this->SetLightingStandInLevel(this->LightingStandInLevel);
  return result;
}

double vtkMultiChannelVolumeRepresentation::GetLightingStandInMemory()
{
  return this->GetMultiChannelMapper()->GetLightingStandInMemory();
}

double vtkMultiChannelVolumeRepresentation::GetLastLightingStandInGatherTime()
{
  return this->GetMultiChannelMapper()->GetLastLightingStandInGatherTime();
}

const char* vtkMultiChannelVolumeRepresentation::GetLightingStandInReport()
{
  if (this->EmptyPieceSomewhere && this->LightingStandInLevel != vtkMultiChannelVolumeMapper::STAND_IN_OFF)
  {
    return "off: a process holds no piece of the data, and lighting across ranks needs every process to render";
  }
  return this->GetMultiChannelMapper()->GetLightingStandInReport();
}

void vtkMultiChannelVolumeRepresentation::SetGradientShading(bool on)
{
  this->GetMultiChannelMapper()->SetGradientShading(on);
}

void vtkMultiChannelVolumeRepresentation::SetShininess(double shininess)
{
  this->GetMultiChannelMapper()->SetShininess(shininess);
}

void vtkMultiChannelVolumeRepresentation::SetLightIntensityScale(double scale)
{
  this->GetMultiChannelMapper()->SetLightIntensityScale(scale);
}

void vtkMultiChannelVolumeRepresentation::SetLightSampling(int mode)
{
  this->GetMultiChannelMapper()->SetLightSampling(mode);
}

void vtkMultiChannelVolumeRepresentation::SetNumberOfChannelAlbedos(int n)
{
  this->Albedos.assign(static_cast<size_t>(std::max(0, n)), 1.0);
}

void vtkMultiChannelVolumeRepresentation::SetChannelAlbedo(int channel, double albedo)
{
  SetEntry(this->Albedos, channel, albedo, 1.0);
}

void vtkMultiChannelVolumeRepresentation::SetNumberOfChannelAnisotropies(int n)
{
  this->Anisotropies.assign(static_cast<size_t>(std::max(0, n)), 0.0);
}

void vtkMultiChannelVolumeRepresentation::SetChannelAnisotropy(int channel, double g)
{
  SetEntry(this->Anisotropies, channel, g, 0.0);
}

void vtkMultiChannelVolumeRepresentation::SetVisibilityOptimization(bool on)
{
  this->GetMultiChannelMapper()->SetVisibilityOptimization(on);
}

void vtkMultiChannelVolumeRepresentation::SetDeviationWeight(double p)
{
  this->GetMultiChannelMapper()->SetDeviationWeight(p);
}

void vtkMultiChannelVolumeRepresentation::SetOcclusionWeight(double q)
{
  this->GetMultiChannelMapper()->SetOcclusionWeight(q);
}

void vtkMultiChannelVolumeRepresentation::SetClutterWeight(double r)
{
  this->GetMultiChannelMapper()->SetClutterWeight(r);
}

void vtkMultiChannelVolumeRepresentation::SetImportanceEmphasis(double lambda)
{
  this->GetMultiChannelMapper()->SetImportanceEmphasis(lambda);
}

void vtkMultiChannelVolumeRepresentation::SetImportanceMergeDistance(double d)
{
  this->GetMultiChannelMapper()->SetImportanceMergeDistance(d);
}

void vtkMultiChannelVolumeRepresentation::SetImportanceSamples(int n)
{
  this->GetMultiChannelMapper()->SetImportanceSamples(n);
}

void vtkMultiChannelVolumeRepresentation::SetOptimizeLightRays(bool on)
{
  this->GetMultiChannelMapper()->SetOptimizeLightRays(on);
}

void vtkMultiChannelVolumeRepresentation::SetLightRayImportanceSamples(int n)
{
  this->GetMultiChannelMapper()->SetLightRayImportanceSamples(n);
}

void vtkMultiChannelVolumeRepresentation::SetLevelOfDetail(int level)
{
  // Applied in UpdateMapperParameters, which knows whether this render uses
  // ParaView's level of detail.
  if (level < vtkMultiChannelVolumeMapper::LEVEL_OF_DETAIL_AUTOMATIC)
  {
    vtkErrorMacro("LevelOfDetail " << level << " is not a level: 0 full resolution, L > 0, -1 automatic.");
    return;
  }
  if (this->LevelOfDetail != level)
  {
    this->LevelOfDetail = level;
    this->Modified();
  }
}

void vtkMultiChannelVolumeRepresentation::SetInteractiveLevelOfDetail(int level)
{
  if (level < vtkMultiChannelVolumeMapper::LEVEL_OF_DETAIL_AUTOMATIC)
  {
    vtkErrorMacro("InteractiveLevelOfDetail " << level << " is not a level: L >= 1, -1 automatic, 0 the still level.");
    return;
  }
  if (this->InteractiveLevelOfDetail != level)
  {
    this->InteractiveLevelOfDetail = level;
    this->Modified();
  }
}

void vtkMultiChannelVolumeRepresentation::SetLevelOfDetailFilter(int filter)
{
  this->GetMultiChannelMapper()->SetLevelOfDetailFilter(filter);
}

void vtkMultiChannelVolumeRepresentation::SetLevelOfDetailHalfPrecision(bool on)
{
  this->GetMultiChannelMapper()->SetLevelOfDetailHalfPrecision(on);
}

void vtkMultiChannelVolumeRepresentation::SetMemoryBudgetMiB(double mib)
{
  this->GetMultiChannelMapper()->SetMemoryBudget(mib > 0.0 ? mib * 1048576.0 : 0.0);
}

int vtkMultiChannelVolumeRepresentation::GetLastLevelOfDetail()
{
  return this->GetMultiChannelMapper()->GetLastLevelOfDetail();
}

const char* vtkMultiChannelVolumeRepresentation::GetLevelOfDetailReport()
{
  this->LevelOfDetailReport = this->GetMultiChannelMapper()->GetLevelOfDetailReport();
  return this->LevelOfDetailReport.c_str();
}

//------------------------------------------------------------------------------
const char* vtkMultiChannelVolumeRepresentation::GetChosenEstimator()
{
  this->ChosenEstimator = this->GetMultiChannelMapper()->GetChosenEstimatorAsString();
  return this->ChosenEstimator.c_str();
}

//------------------------------------------------------------------------------
int vtkMultiChannelVolumeRepresentation::ProcessViewRequest(
  vtkInformationRequestKey* request_type, vtkInformation* inInfo, vtkInformation* outInfo)
{
  if (request_type == vtkPVView::REQUEST_RENDER())
  {
    // vtkPVRenderView sets USE_LOD for an interactive render when its LOD
    // threshold is reached; the superclass's REQUEST_RENDER then calls
    // UpdateMapperParameters.
    this->RenderingWithLOD =
      inInfo && inInfo->Has(vtkPVRenderView::USE_LOD()) && inInfo->Get(vtkPVRenderView::USE_LOD()) != 0;
  }
  if (!this->Superclass::ProcessViewRequest(request_type, inInfo, outInfo))
  {
    return 0;
  }
  if (request_type == vtkPVView::REQUEST_RENDER())
  {
    // Every rendering process runs this pass before IceT composites, also
    // one whose piece IceT then leaves out because it is outside the view.
    // The stand-in's collective step runs here, so no process waits inside
    // a render that another never starts.
    if (vtkPVRenderView* view = vtkPVRenderView::SafeDownCast(inInfo->Get(vtkPVView::VIEW())))
    {
      this->GetMultiChannelMapper()->SynchronizeLightingStandIn(view->GetRenderer(), this->Actor);
    }
  }
  return 1;
}

void vtkMultiChannelVolumeRepresentation::SetNumberOfChannelImportanceLevels(int n)
{
  this->ImportanceLevels.assign(static_cast<size_t>(std::max(0, n)), 0.0);
}

void vtkMultiChannelVolumeRepresentation::SetChannelImportanceLevel(int channel, double level)
{
  SetEntry(this->ImportanceLevels, channel, level, 0.0);
}

void vtkMultiChannelVolumeRepresentation::SetNumberOfChannelImportanceThresholds(int n)
{
  this->ImportanceThresholds.assign(static_cast<size_t>(std::max(0, n)), std::numeric_limits<double>::quiet_NaN());
}

void vtkMultiChannelVolumeRepresentation::SetChannelImportanceThreshold(int channel, double threshold)
{
  SetEntry(this->ImportanceThresholds, channel, threshold, std::numeric_limits<double>::quiet_NaN());
}

void vtkMultiChannelVolumeRepresentation::SetChannelImportanceFunction(int channel, vtkPiecewiseFunction* function)
{
  if (channel < 0 || channel >= NUMBER_OF_IMPORTANCE_FUNCTIONS)
  {
    vtkErrorMacro("importance function " << channel + 1 << " is outside 1.." << NUMBER_OF_IMPORTANCE_FUNCTIONS);
    return;
  }
  if (this->ImportanceFunctions[channel] != function)
  {
    this->ImportanceFunctions[channel] = function;
    this->MarkModified();
  }
}

//------------------------------------------------------------------------------
bool vtkMultiChannelVolumeRepresentation::HoldsData()
{
  // The client of a pvserver runs the pipeline on an empty image.
  vtkDataSet* data = vtkDataSet::SafeDownCast(this->Cache);
  return data && data->GetNumberOfPoints() > 0;
}

//------------------------------------------------------------------------------
int vtkMultiChannelVolumeRepresentation::GetTotalSamples()
{
  // -1: this process holds no data and renders none (the client of a
  // pvserver); the render server's image is not known here.
  if (!this->HoldsData())
  {
    return -1;
  }
  // Nothing is drawn while the channels are incomplete (ChannelStatus).
  return this->ChannelStatus.empty() ? this->GetMultiChannelMapper()->GetTotalSamples() : 0;
}

double vtkMultiChannelVolumeRepresentation::GetEstimatedError()
{
  // As GetTotalSamples: nothing known without data, nothing drawn while the
  // channels are incomplete.
  if (!this->HoldsData() || !this->ChannelStatus.empty())
  {
    return -1.0;
  }
  return this->GetMultiChannelMapper()->GetEstimatedError();
}

double vtkMultiChannelVolumeRepresentation::GetEstimatedPSNR()
{
  if (!this->HoldsData() || !this->ChannelStatus.empty())
  {
    return -1.0;
  }
  return this->GetMultiChannelMapper()->GetEstimatedPSNR();
}

int vtkMultiChannelVolumeRepresentation::GetConverged()
{
  if (!this->HoldsData())
  {
    return -1;
  }
  return this->GetMultiChannelMapper()->IsConverged() ? 1 : 0;
}

int vtkMultiChannelVolumeRepresentation::GetNumberOfChannels()
{
  return this->GetMultiChannelMapper()->GetNumberOfChannels();
}

double vtkMultiChannelVolumeRepresentation::GetImportanceMemory()
{
  return this->GetMultiChannelMapper()->GetImportanceMemory();
}

double vtkMultiChannelVolumeRepresentation::GetImportanceOverflows()
{
  return this->GetMultiChannelMapper()->GetImportanceOverflows();
}

const char* vtkMultiChannelVolumeRepresentation::GetBackendReport()
{
  this->BackendReport = this->GetMultiChannelMapper()->GetBackendReport();
  return this->BackendReport.c_str();
}

//------------------------------------------------------------------------------
void vtkMultiChannelVolumeRepresentation::UpdateMapperParameters()
{
  vtkMultiChannelVolumeMapper* mapper = this->GetMultiChannelMapper();
  vtkImageData* image = vtkImageData::SafeDownCast(this->Cache);
  this->Actor->SetMapper(mapper);

  // Each rank's piece gets its own random sequences. With the same seed on
  // every rank, a pixel's paths through the front and the back piece would
  // use the same numbers: the front's opacity and the back's colour would be
  // correlated, and "front over back" is unbiased only for independent
  // estimates (E[(1 - a1) c2] = (1 - E[a1]) E[c2]). The mapper leaves the
  // offset out while the ranks split the image, which share no pixel.
  vtkMultiProcessController* controller = vtkMultiProcessController::GetGlobalController();
  const unsigned int rank = controller ? static_cast<unsigned int>(controller->GetLocalProcessId()) : 0u;
  mapper->SetSeed(this->Seed);
  mapper->SetProcessSeedOffset(0x9E3779B9u * rank);

  // ---- Level of detail: coarser while ParaView renders with its LOD ------------
  // The mapper restarts the image only when the level really changes, so
  // every interactive frame stays at the interactive level and the first
  // still render goes back (and refines from there).
  const bool interactiveLevel = this->RenderingWithLOD && this->InteractiveLevelOfDetail != 0;
  mapper->SetLevelOfDetail(interactiveLevel ? this->InteractiveLevelOfDetail : this->LevelOfDetail);
  // The nearest voxel while dragging: on the CPU a trilinear sample of a
  // large level spends most of its time waiting for its 8 corners, and the
  // interaction's frames are coarse anyway. A change of interpolation
  // restarts the image, as the change of level does.
  const bool interactiveNearest = this->RenderingWithLOD && this->InteractiveInterpolation == INTERACTIVE_NEAREST;
  mapper->SetInterpolationType(interactiveNearest ? VTK_NEAREST_INTERPOLATION : this->StillInterpolation);
  // ParaView's LOD renders are its interactive ones: there the automatic
  // estimator keeps expected value's frame rate (the render window's update
  // rate decides the others).
  mapper->SetInteractiveRendering(this->RenderingWithLOD ? 1 : -1);

  // ---- Channels -------------------------------------------------------------
  int numChannels = 0;
  std::ostringstream status;
  if (this->ChannelSource == COMPONENTS)
  {
    mapper->RemoveAllChannelArrays();
    SelectPointArray(mapper, this->ChannelComponentsArray);
    vtkDataArray* array = (image && !this->ChannelComponentsArray.empty())
      ? image->GetPointData()->GetArray(this->ChannelComponentsArray.c_str())
      : nullptr;
    numChannels = array ? array->GetNumberOfComponents() : static_cast<int>(this->ChannelLookupTables.size());
    if (this->ChannelComponentsArray.empty())
    {
      status << "no channel array selected";
    }
    else if (image && !array)
    {
      status << "no point array named '" << this->ChannelComponentsArray << "'";
    }
  }
  else
  {
    bool same = mapper->GetNumberOfChannelArrays() == static_cast<int>(this->ChannelArrays.size());
    for (size_t i = 0; same && i < this->ChannelArrays.size(); ++i)
    {
      same = this->ChannelArrays[i] == mapper->GetChannelArray(static_cast<int>(i));
    }
    if (!same)
    {
      mapper->RemoveAllChannelArrays();
      for (const std::string& name : this->ChannelArrays)
      {
        mapper->AddChannelArray(name.c_str());
      }
    }
    numChannels = static_cast<int>(this->ChannelArrays.size());
    if (numChannels == 0)
    {
      status << "no channels selected";
    }
    else
    {
      // The mapper reads the listed arrays and ignores the scalars, but
      // vtkPVLODVolume only renders a volume mapper whose scalars it finds:
      // point it at the first channel (data without active scalars, such
      // as a file of separate arrays, would otherwise draw nothing).
      SelectPointArray(mapper, this->ChannelArrays[0]);
      // A multi-component array listed as one channel (an OME-TIFF's
      // channels): say how to render its components.
      for (const std::string& name : this->ChannelArrays)
      {
        vtkDataArray* array = image ? image->GetPointData()->GetArray(name.c_str()) : nullptr;
        if (array && array->GetNumberOfComponents() > 1)
        {
          status << "point array '" << name << "' has " << array->GetNumberOfComponents()
                 << " components: set Channels From to Components of One Array (ChannelSource 1) to render them "
                    "as channels";
          break;
        }
      }
    }
  }
  if (numChannels > vtkMultiChannelVolumeMapper::MAX_CHANNELS)
  {
    status << numChannels << " channels; at most " << int(vtkMultiChannelVolumeMapper::MAX_CHANNELS)
           << " are supported";
    numChannels = 0;
  }

  // ---- Transfer functions and per-channel parameters ---------------------------
  const double unitDistance = this->Property->GetScalarOpacityUnitDistance(0);
  for (int c = 0; c < numChannels; ++c)
  {
    // ParaView delivers a repeatable proxy property as a set, in the order of
    // the proxies' global ids and without repeats; the client sends which of
    // those lookup tables each channel uses.
    const int index = EntryOr(this->ChannelLookupTableIndices, c, -1);
    vtkScalarsToColors* lut = (index >= 0 && static_cast<size_t>(index) < this->ChannelLookupTables.size())
      ? this->ChannelLookupTables[index].Get()
      : nullptr;
    auto* color = vtkColorTransferFunction::SafeDownCast(lut);
    auto* discretizable = vtkDiscretizableColorTransferFunction::SafeDownCast(lut);
    vtkPiecewiseFunction* opacity = discretizable ? discretizable->GetScalarOpacityFunction() : nullptr;
    if (!color || !opacity)
    {
      if (status.tellp() == 0)
      {
        status << "channel " << c << " has no " << (color ? "opacity" : "colour") << " transfer function";
      }
      continue;
    }
    mapper->SetChannelColor(c, color);
    mapper->SetChannelScalarOpacity(c, opacity);
    mapper->SetChannelScalarOpacityUnitDistance(c, unitDistance);
    mapper->SetMixWeight(c, EntryOr(this->MixWeights, c, 1.0));
    mapper->SetChannelAlbedo(c, EntryOr(this->Albedos, c, 1.0));
    mapper->SetChannelAnisotropy(c, EntryOr(this->Anisotropies, c, 0.0));
  }

  this->UpdateChannelImportance(numChannels);

  this->ChannelStatus = status.str();
  // Volume mappers do not like inputs they cannot draw (as the superclass).
  this->Actor->SetVisibility(this->ChannelStatus.empty() && numChannels > 0);
}

//------------------------------------------------------------------------------
void vtkMultiChannelVolumeRepresentation::ComputeChannelDefaultRanges()
{
  // The input as the source produced it (the representation's own copy is
  // made only when the view updates). Under MPI every process runs this
  // command together (the proxy invokes it on all of them), so the ranges
  // are the whole data set's: every process and a single one spread the
  // default functions alike. Computed again only when an input changed.
  vtkImageData* image = this->GetNumberOfInputConnections(0) > 0
    ? vtkImageData::SafeDownCast(this->GetInputDataObject(0, 0))
    : nullptr;
  const vtkMTimeType time = image ? image->GetMTime() : 0;
  int changed = (time != this->ChannelDefaultRangesTime || this->ChannelDefaultRangesStale) ? 1 : 0;
  int anyChanged = changed;
  vtkMultiProcessController* controller = vtkMultiProcessController::GetGlobalController();
  if (controller && controller->GetNumberOfProcesses() > 1)
  {
    controller->AllReduce(&changed, &anyChanged, 1, vtkCommunicator::MAX_OP);
  }
  if (anyChanged)
  {
    this->ChannelDefaultRanges = mcvol::RobustRanges(image, controller);
    this->ChannelDefaultRangesTime = time;
    this->ChannelDefaultRangesStale = false;
  }
}

const char* vtkMultiChannelVolumeRepresentation::GetChannelDefaultRanges()
{
  // A single process computes them when asked; several wait for the
  // collective ComputeChannelDefaultRanges.
  vtkMultiProcessController* controller = vtkMultiProcessController::GetGlobalController();
  if (!controller || controller->GetNumberOfProcesses() <= 1)
  {
    this->ComputeChannelDefaultRanges();
  }
  return this->ChannelDefaultRanges.c_str();
}

//------------------------------------------------------------------------------
void vtkMultiChannelVolumeRepresentation::UpdateChannelImportance(int numChannels)
{
  vtkMultiChannelVolumeMapper* mapper = this->GetMultiChannelMapper();
  const double none = std::numeric_limits<double>::quiet_NaN();
  this->ImportanceSteps.resize(vtkMultiChannelVolumeMapper::MAX_CHANNELS);
  for (int c = 0; c < vtkMultiChannelVolumeMapper::MAX_CHANNELS; ++c)
  {
    // Entries past the channel list are ignored rather than kept on the
    // mapper, which would otherwise hold them for channels that come later.
    vtkPiecewiseFunction* function = c < NUMBER_OF_IMPORTANCE_FUNCTIONS ? this->ImportanceFunctions[c].Get() : nullptr;
    if (c < numChannels && CarriesImportance(function))
    {
      mapper->SetChannelImportance(c, function);
      continue;
    }
    const double level = c < numChannels ? SnapImportanceLevel(EntryOr(this->ImportanceLevels, c, 0.0)) : 0.0;
    const double threshold = EntryOr(this->ImportanceThresholds, c, none);
    if (level == 0.0 || !std::isfinite(threshold))
    {
      mapper->SetChannelImportance(c, nullptr);
      continue;
    }
    ImportanceStep& step = this->ImportanceSteps[c];
    if (!step.Function || step.Level != level || step.Threshold != threshold)
    {
      if (!step.Function)
      {
        step.Function = vtkSmartPointer<vtkPiecewiseFunction>::New();
      }
      // vtkPiecewiseFunction interpolates linearly between points and clamps
      // beyond them. A point at the largest double below the threshold makes
      // the ramp one ulp wide: exactly 0 below T and the level from T up.
      // The mapper samples it into its 1024-texel table over the channel's
      // transfer-function range, so the step is resolved to one texel.
      const double below = std::nextafter(threshold, -std::numeric_limits<double>::infinity());
      step.Function->RemoveAllPoints();
      if (std::isfinite(below))
      {
        step.Function->AddPoint(below, 0.0);
      }
      step.Function->AddPoint(threshold, level);
      step.Level = level;
      step.Threshold = threshold;
    }
    mapper->SetChannelImportance(c, step.Function);
  }
}

//------------------------------------------------------------------------------
void vtkMultiChannelVolumeRepresentation::PrintSelf(ostream& os, vtkIndent indent)
{
  this->Superclass::PrintSelf(os, indent);
  os << indent << "ChannelSource: " << (this->ChannelSource == COMPONENTS ? "components" : "arrays") << "\n";
  os << indent << "ChannelArrays:";
  for (const std::string& name : this->ChannelArrays)
  {
    os << " " << name;
  }
  os << "\n";
  os << indent << "ChannelComponentsArray: " << this->ChannelComponentsArray << "\n";
  os << indent << "ChannelLookupTables: " << this->ChannelLookupTables.size() << "\n";
  os << indent << "ChannelImportance (level, threshold):";
  for (size_t c = 0; c < std::max(this->ImportanceLevels.size(), this->ImportanceThresholds.size()); ++c)
  {
    os << " (" << EntryOr(this->ImportanceLevels, static_cast<int>(c), 0.0) << ", "
       << EntryOr(this->ImportanceThresholds, static_cast<int>(c), std::numeric_limits<double>::quiet_NaN()) << ")";
  }
  os << "\n";
  os << indent << "ChannelStatus: " << this->ChannelStatus << "\n";
  os << indent << "LevelOfDetail: " << this->LevelOfDetail << "\n";
  os << indent << "InteractiveLevelOfDetail: " << this->InteractiveLevelOfDetail << "\n";
  os << indent << "InteractiveInterpolation: "
     << (this->InteractiveInterpolation == INTERACTIVE_NEAREST ? "Nearest" : "AsStill") << "\n";
  os << indent << "StillInterpolation: " << this->StillInterpolation << "\n";
  os << indent << "RenderingWithLOD: " << this->RenderingWithLOD << "\n";
}
