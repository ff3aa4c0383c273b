// SPDX-License-Identifier: BSD-3-Clause
#include "vtkMultiChannelVolumeMapper.h"

#include "vtkCamera.h"
#include "vtkColorTransferFunction.h"
#include "vtkDataArray.h"
#include "vtkFloatArray.h"
#include "vtkImageData.h"
#include "vtkMath.h"
#include "vtkMatrix3x3.h"
#include "vtkMatrix4x4.h"
#include "vtkCommunicator.h"
#include "vtkMultiProcessController.h"
#include "vtkObjectFactory.h"
#include "vtkOpenGLRenderWindow.h"
#include "vtkPiecewiseFunction.h"
#include "vtkRenderWindow.h"
#include "vtkRenderer.h"
#include "vtkSmartPointer.h"
#include "vtkVolume.h"
#include "vtkVolumeProperty.h"

#include "VTK/Accumulation.h"
#include "mcvol/EstimatorChoice.h"
#include "VTK/ChannelBinding.h"
#include "VTK/DependentComponents.h"
#include "VTK/FrameCompositor.h"
#include "VTK/LevelOfDetail.h"
#include "VTK/RenderBackend.h"
#include "VTK/Settings.h"
#include "VTK/StandIn.h"
#include "VTK/TransferFunctionTables.h"
#include "VTK/View.h"

#include "mcvol/RenderSetup.h"
#include "mcvol/DeviceRenderer.h"
#include "mcvol/Renderer.h"
#include "mcvol/Scene.h"

#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <exception>
#include <sstream>
#include <string>
#include <vector>

namespace
{
constexpr int kMaxChannels = vtkMultiChannelVolumeMapper::MAX_CHANNELS;
static_assert(kMaxChannels == mcvol::kMaxChannels, "channel limits of mapper and core differ");
static_assert(vtkMultiChannelVolumeMapper::kSplitImageStripeRows == mcvol::kSplitImageStripeRows,
  "split-image stripes of mapper and core differ");

/// What a render's levels of detail depend on: the channels (their data and
/// values), the transfer-function tables (scalar channels), the filter and
/// whether the channels are summed.
mcvol::adapter::LevelOfDetailCache::Key LevelKey(const mcvol::adapter::BoundChannels& channels, bool classified,
  unsigned long long tablesVersion, int filter, bool summed, bool halfPrecision)
{
  mcvol::adapter::LevelOfDetailCache::Key key;
  key.Sources.assign(channels.Sources.begin(), channels.Sources.begin() + channels.Count);
  std::copy(channels.Dims, channels.Dims + 3, key.Dims);
  key.DataMTime = channels.DataMTime;
  // Dependent components: the classified copy's time already covers its
  // functions; scalar channels: the tables given to level 0's Scene.
  key.TablesVersion = classified ? 0 : tablesVersion;
  key.Filter = filter;
  key.Summed = summed;
  key.HalfPrecision = halfPrecision;
  return key;
}
} // namespace

/**
 * The mapper's state: the user's per-channel settings, and one object per
 * stage of Render() (each in Rendering/VTK/; Documentation/design.md, "Render()
 * as a pipeline").
 */
struct vtkMultiChannelVolumeMapper::vtkInternals
{
  // User settings kept here so the header needs no STL containers of VTK types.
  std::vector<std::string> ChannelArrayNames;
  mcvol::adapter::ChannelFunctionOverrides Functions;
  std::array<double, kMaxChannels> MixWeights;
  std::array<double, kMaxChannels> Albedo;
  std::array<double, kMaxChannels> Anisotropy;

  // The core's view of the volume and the image being accumulated.
  mcvol::Scene Scene;
  mcvol::Accumulator Accum;

  // The stages' state.
  mcvol::adapter::ChannelData Data;
  mcvol::adapter::DependentClassifier Dependent; // IndependentComponentsOff
  mcvol::adapter::TransferFunctionTables Tables;
  mcvol::adapter::RenderBackend Backend;
  mcvol::adapter::Accumulation Accumulation;
  mcvol::adapter::FrameCompositor Compositor;
  // Levels of detail: the levels built, and the Scene that renders one
  // (its own, so that level 0's Scene keeps its grids for the way back).
  mcvol::adapter::LevelOfDetailCache Levels;
  mcvol::Scene LevelScene;
  unsigned long long LevelSceneVersion = 0; // the level LevelScene holds (0: none)
  std::string LevelReport = "no render yet";
  std::string LevelWarning; // the last case warned about (warned once)
  std::string IgnoredSettings; // GetIgnoredSettings(): the last render's
  // Lighting across processes: the stand-in of the whole volume, and the
  // processes it is gathered from (null: the global controller).
  mcvol::adapter::StandIn StandIn;
  /// This render traces the exact stand-in for its share of the image
  /// (SplitImageWithExactStandIn): this process's index among SplitRanks.
  bool SplitImage = false;
  int SplitRank = 0;
  int SplitRanks = 1;
  std::string StandInReport;
  vtkSmartPointer<vtkMultiProcessController> Controller;
  std::vector<float> Depth; // this render's depth buffer (reused storage)

  // Samples per pixel of the batch being traced (0: SamplesPerPixel).
  int BatchSamples = 0;
  // The image's estimated MSE (negative: none), computed when first asked
  // for after a trace or restart (EstimateCurrent false).
  double EstimatedMSE = -1.0;
  bool EstimateCurrent = false;
  // Seconds per sample, for InteractiveFrameTime: [1] for the interactive
  // renders that keep expected value (InteractiveKeepsExpectedValue), [0]
  // for the others, so that a switch does not budget one estimator's frame
  // with the other's cost.
  mcvol::adapter::SampleCost Cost[2];

  // AUTOMATIC_ESTIMATOR: the choice and what it was made for (the camera,
  // the window size and the level of detail are left out: the choice is
  // kept while they change).
  struct ChoiceKey
  {
    unsigned long long TablesVersion = 0;
    vtkMTimeType DataMTime = 0;
    const mcvol::Renderer* Backend = nullptr;
    int Blend = -1;
    bool Lit = false;
    bool Optimized = false;
    unsigned int Seed = 0;
    double MinimumSamplesPerVoxel = 0.0;
    double TargetError = 0.0;
    bool PixelJitter = true;
    int MarchControlVariates = -1;
    bool operator==(const ChoiceKey& o) const
    {
      return this->TablesVersion == o.TablesVersion && this->DataMTime == o.DataMTime &&
        this->Backend == o.Backend && this->Blend == o.Blend && this->Lit == o.Lit &&
        this->Optimized == o.Optimized && this->Seed == o.Seed &&
        this->MinimumSamplesPerVoxel == o.MinimumSamplesPerVoxel && this->TargetError == o.TargetError &&
        this->PixelJitter == o.PixelJitter && this->MarchControlVariates == o.MarchControlVariates;
    }
  };
  bool ChoiceValid = false;
  ChoiceKey ChoiceMadeFor;
  mcvol::EstimatorChoice Choice;
  std::string ChoiceReport = "no automatic choice made yet";
  // The last CheckScale error GetBounds() reported (each cause once).
  std::string ScaleError;
  std::string ChosenEstimator = "none"; // backing store of GetChosenEstimatorAsString
  int Choices = 0;                      // choices that rendered pilots
  // This render's batch was rendered during the choice's pilots and kept
  // (mcvol::ChoiceAhead): TraceBatch() renders it no more.
  bool BatchRenderedAhead = false;

  // Backing store for GetActiveBackendName and GetBackendReport.
  std::string BackendName = "none";
  std::string BackendReport = "no backend chosen yet";

  vtkInternals()
  {
    this->MixWeights.fill(1.0);
    this->Albedo.fill(1.0);
    this->Anisotropy.fill(0.0);
  }

  /// The Scene holds nothing the next render can reuse (after an error).
  void ForgetVolume()
  {
    this->Data.Forget();
    this->Tables.Forget();
    this->Levels.Clear();
    this->LevelSceneVersion = 0;
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
    if (this->Internals->Functions.Colors[c])
    {
      mtime = std::max(mtime, this->Internals->Functions.Colors[c]->GetMTime());
    }
    if (this->Internals->Functions.Opacities[c])
    {
      mtime = std::max(mtime, this->Internals->Functions.Opacities[c]->GetMTime());
    }
    if (this->Internals->Functions.Importance[c])
    {
      mtime = std::max(mtime, this->Internals->Functions.Importance[c]->GetMTime());
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
const char* vtkMultiChannelVolumeMapper::GetEstimatorAsString()
{
  return this->Estimator == COLLISION_ESTIMATOR ? "Collision"
    : this->Estimator == UNBIASED_MARCH_ESTIMATOR ? "UnbiasedMarch"
    : this->Estimator == AUTOMATIC_ESTIMATOR      ? "Automatic"
                                                  : "ExpectedValue";
}

//------------------------------------------------------------------------------
const char* vtkMultiChannelVolumeMapper::GetChosenEstimatorAsString()
{
  return this->Internals->ChosenEstimator.c_str();
}

//------------------------------------------------------------------------------
const char* vtkMultiChannelVolumeMapper::GetEstimatorReport()
{
  return this->Internals->ChoiceReport.c_str();
}

//------------------------------------------------------------------------------
const char* vtkMultiChannelVolumeMapper::GetIgnoredSettings()
{
  return this->Internals->IgnoredSettings.c_str();
}

namespace
{
/// Whether a gradient opacity function changes anything: some node below 1
/// or above (an empty function is taken as unset).
bool GradientOpacityHasEffect(vtkPiecewiseFunction* f)
{
  if (!f)
  {
    return false;
  }
  for (int i = 0; i < f->GetSize(); ++i)
  {
    double node[4];
    f->GetNodeValue(i, node);
    if (node[1] != 1.0)
    {
      return true;
    }
  }
  return false;
}
} // namespace

//------------------------------------------------------------------------------
void vtkMultiChannelVolumeMapper::ReportIgnoredSettings(vtkVolume* volume)
{
  std::vector<std::string> ignored;
  if (this->GetCropping())
  {
    ignored.emplace_back("cropping (SetCropping)");
  }
  if (this->GetNumberOfClippingPlanes() > 0)
  {
    ignored.emplace_back("clipping planes");
  }
  if (this->GetBlendMode() != vtkVolumeMapper::COMPOSITE_BLEND)
  {
    ignored.emplace_back(
      "vtkVolumeMapper::SetBlendMode (the channels combine by SetChannelBlendMode: density, max, mix or composite)");
  }
  if (this->ShadowMode == CACHED_SHADOWS && this->ChannelBlendMode == MC_COMPOSITE_BLEND)
  {
    ignored.emplace_back("cached shadows under post-render composite blending (its shadow rays are tracked)");
  }
  if (this->ShadowMode == CACHED_SHADOWS && this->VisibilityOptimization && this->OptimizeLightRays)
  {
    ignored.emplace_back("cached shadows with the visibility optimization of light rays (its light rays are tracked)");
  }
  vtkVolumeProperty* property = volume ? volume->GetProperty() : nullptr;
  if (property && property->GetTransferFunctionMode() == vtkVolumeProperty::TF_2D)
  {
    ignored.emplace_back("2D transfer functions (the 1D colour and scalar opacity functions are used)");
  }
  else if (property)
  {
    for (int c = 0; c < VTK_MAX_VRCOMP; ++c)
    {
      if (property->HasGradientOpacity(c) && !property->GetDisableGradientOpacity(c) &&
        GradientOpacityHasEffect(property->GetStoredGradientOpacity(c)))
      {
        ignored.emplace_back("the gradient opacity of component " + std::to_string(c));
      }
    }
  }
  std::string text;
  for (const std::string& s : ignored)
  {
    text += (text.empty() ? "" : "; ") + s;
  }
  vtkInternals& in = *this->Internals;
  if (text != in.IgnoredSettings)
  {
    in.IgnoredSettings = text;
    if (!text.empty())
    {
      vtkWarningMacro("Not supported by this mapper, so not used: " << text << ".");
    }
  }
}

//------------------------------------------------------------------------------
int vtkMultiChannelVolumeMapper::GetNumberOfEstimatorChoices()
{
  return this->Internals->Choices;
}

//------------------------------------------------------------------------------
const char* vtkMultiChannelVolumeMapper::GetSampleSequenceAsString()
{
  return this->SampleSequence == INDEPENDENT_SEQUENCE ? "Independent" : "Sobol";
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
mcvol::RenderSettings vtkMultiChannelVolumeMapper::MakeRenderSettings(const mcvol::Renderer& renderer)
{
  mcvol::RenderSettings settings;
  settings.samplesPerPixel = this->Internals->BatchSamples > 0 ? this->Internals->BatchSamples : this->SamplesPerPixel;
  settings.seed = this->EffectiveSeed();
  settings.tracker = this->TrackingMethod == N_DDA ? mcvol::Tracker::NDDA : mcvol::Tracker::OneDDA;
  settings.jitterPixels = this->PixelJitter;
  settings.readBackEven = false; // GetEstimatedError() reads it back when asked
  // A device backend keeps the image on the device: DrawImage() copies an
  // 8-bit display image (a quarter of the float image), and the float image
  // comes back only when asked (GetAccumulatedImage, GetEstimatedError).
  settings.readBack = !(renderer.device() && renderer.device()->hasDisplayImage());
  settings.sampler = this->SampleSequence == INDEPENDENT_SEQUENCE ? mcvol::Sampler::Independent : mcvol::Sampler::Sobol;
  // AUTOMATIC_ESTIMATOR: expected value until the choice is made.
  settings.estimator = this->Estimator == COLLISION_ESTIMATOR ? mcvol::Estimator::Collision
    : this->Estimator == UNBIASED_MARCH_ESTIMATOR             ? mcvol::Estimator::UnbiasedMarch
                                                              : mcvol::Estimator::ExpectedValue;
  settings.minSamplesPerVoxel = float(this->MinimumSamplesPerVoxel);
  settings.marchSamplesPerVoxel = float(this->MarchSamplesPerVoxel);
  settings.marchControlVariates = this->MarchControlVariates != MARCH_CONTROL_VARIATES_NEVER;
  settings.marchControlVariatesFrom =
    this->MarchControlVariates == MARCH_CONTROL_VARIATES_ALWAYS ? 0.f : mcvol::kMarchControlVariateRate;
  return settings;
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
  mcvol::RenderSettings settings = this->MakeRenderSettings(*renderer);
  vtkInternals& in = *this->Internals;
  // Interactive renders keep expected value (MakeRenderSettings' estimator
  // under AUTOMATIC_ESTIMATOR) where the choice's sample costs more.
  if (this->Estimator == AUTOMATIC_ESTIMATOR && in.ChoiceValid && !this->InteractiveKeepsExpectedValue())
  {
    settings.estimator = in.Choice.settings.estimator;
    settings.marchSamplesPerVoxel = in.Choice.settings.marchSamplesPerVoxel;
    settings.marchControlVariates = in.Choice.settings.marchControlVariates;
    settings.marchControlVariatesFrom = in.Choice.settings.marchControlVariatesFrom;
  }
  const mcvol::Estimator used = mcvol::effectiveEstimator(scene, settings);
  in.ChosenEstimator = mcvol::estimatorName(used, settings.marchSamplesPerVoxel,
    used == mcvol::Estimator::UnbiasedMarch && mcvol::marchControlVariates(settings, camera));
  try
  {
    renderer->render(scene, camera, settings, depth, accum);
    if (!settings.readBack)
    {
      // Wait for the kernel: the trace time feeds the frame-time budget
      // (SetInteractiveFrameTime), which must see the render's real cost.
      renderer->finish();
    }
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
bool vtkMultiChannelVolumeMapper::AddsSamples()
{
  return true;
}

//------------------------------------------------------------------------------
const char* vtkMultiChannelVolumeMapper::GetActiveBackendName()
{
  vtkInternals& in = *this->Internals;
  in.BackendName = in.Backend.ActiveName(this->UsesRenderBackend(), this->Backend);
  return in.BackendName.c_str();
}

//------------------------------------------------------------------------------
const char* vtkMultiChannelVolumeMapper::GetBackendReport()
{
  vtkInternals& in = *this->Internals;
  in.BackendReport = in.Backend.Report(this->UsesRenderBackend(), this->Backend);
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
void vtkMultiChannelVolumeMapper::SetChannelImportance(int channel, vtkPiecewiseFunction* importance)
{
  if (channel < 0 || channel >= kMaxChannels)
  {
    vtkErrorMacro("SetChannelImportance: channel " << channel << " is outside [0, " << kMaxChannels << ").");
    return;
  }
  if (this->Internals->Functions.Importance[channel] != importance)
  {
    this->Internals->Functions.Importance[channel] = importance;
    this->Modified();
  }
}

//------------------------------------------------------------------------------
vtkPiecewiseFunction* vtkMultiChannelVolumeMapper::GetChannelImportance(int channel)
{
  return channel >= 0 && channel < kMaxChannels ? this->Internals->Functions.Importance[channel].Get() : nullptr;
}

//------------------------------------------------------------------------------
double vtkMultiChannelVolumeMapper::GetImportanceMemory()
{
  return static_cast<double>(this->Internals->Accum.importancePoolIfAny().bytes());
}

//------------------------------------------------------------------------------
double vtkMultiChannelVolumeMapper::GetImportanceOverflows()
{
  return static_cast<double>(this->Internals->Accum.importancePoolIfAny().overflows);
}

//------------------------------------------------------------------------------
double vtkMultiChannelVolumeMapper::GetDeviceMemory()
{
  const mcvol::Renderer* renderer = this->Internals->Backend.Get();
  return renderer && renderer->device() ? static_cast<double>(renderer->device()->deviceBytes()) : 0.0;
}

//------------------------------------------------------------------------------
int vtkMultiChannelVolumeMapper::GetNumberOfDataUploads()
{
  const mcvol::Renderer* renderer = this->Internals->Backend.Get();
  return renderer && renderer->device() ? static_cast<int>(renderer->device()->dataUploads()) : 0;
}

//------------------------------------------------------------------------------
int vtkMultiChannelVolumeMapper::GetNumberOfClassifications()
{
  return this->Internals->Dependent.Classifications();
}

//------------------------------------------------------------------------------
double vtkMultiChannelVolumeMapper::GetClassifiedMemory()
{
  return static_cast<double>(this->Internals->Dependent.Bytes());
}

//------------------------------------------------------------------------------
void vtkMultiChannelVolumeMapper::SetLevelOfDetail(int level)
{
  if (level < LEVEL_OF_DETAIL_AUTOMATIC)
  {
    vtkErrorMacro(
      "SetLevelOfDetail: " << level << " is not a level: 0 is full resolution, L > 0 level L, -1 automatic.");
    return;
  }
  if (this->LevelOfDetail != level)
  {
    this->LevelOfDetail = level;
    this->Modified();
  }
}

//------------------------------------------------------------------------------
int vtkMultiChannelVolumeMapper::GetNumberOfLevelsOfDetail()
{
  if (this->GetNumberOfInputConnections(0) == 0)
  {
    return 0;
  }
  this->GetInputAlgorithm()->Update();
  vtkImageData* image = vtkImageData::SafeDownCast(this->GetInput());
  if (!image)
  {
    return 0;
  }
  int extent[6];
  image->GetExtent(extent);
  const int dims[3] = { extent[1] - extent[0] + 1, extent[3] - extent[2] + 1, extent[5] - extent[4] + 1 };
  if (dims[0] < 1 || dims[1] < 1 || dims[2] < 1)
  {
    return 0;
  }
  return mcvol::maxPyramidLevels(dims);
}

//------------------------------------------------------------------------------
const char* vtkMultiChannelVolumeMapper::GetLevelOfDetailReport()
{
  return this->Internals->LevelReport.c_str();
}

//------------------------------------------------------------------------------
const char* vtkMultiChannelVolumeMapper::GetLevelOfDetailFilterAsString()
{
  return mcvol::toString(static_cast<mcvol::DownsampleFilter>(this->LevelOfDetailFilter));
}

//------------------------------------------------------------------------------
int vtkMultiChannelVolumeMapper::GetNumberOfLevelOfDetailBuilds()
{
  return this->Internals->Levels.Builds();
}

//------------------------------------------------------------------------------
double vtkMultiChannelVolumeMapper::GetLevelOfDetailMemory()
{
  return static_cast<double>(this->Internals->Levels.Bytes());
}

//------------------------------------------------------------------------------
double vtkMultiChannelVolumeMapper::GetLastLevelOfDetailBuildTime()
{
  return this->Internals->Levels.LastBuildSeconds();
}

//------------------------------------------------------------------------------
double vtkMultiChannelVolumeMapper::GetLastLevelOfDetailBuildMemory()
{
  return static_cast<double>(this->Internals->Levels.LastWorkBytes());
}

//------------------------------------------------------------------------------
int vtkMultiChannelVolumeMapper::GetTotalSamples()
{
  return static_cast<int>(this->Internals->Accum.samples());
}

//------------------------------------------------------------------------------
double vtkMultiChannelVolumeMapper::GetEstimatedError()
{
  vtkInternals& in = *this->Internals;
  if (!in.EstimateCurrent)
  {
    // One pass over the image (a few ms at 1080p); kept until the next trace.
    // A device backend copies the image and its even half only now (not
    // every frame).
    this->ReadBackImage();
    if (in.Accum.evenPendingOnDevice() && in.Backend.Get())
    {
      try
      {
        in.Backend.Get()->readBackEven(in.Accum);
      }
      catch (const std::exception& e)
      {
        vtkWarningMacro("The error estimate could not be read back: " << e.what());
      }
    }
    in.EstimatedMSE = in.Accum.estimatedMSE();
    in.EstimateCurrent = true;
  }
  return in.EstimatedMSE >= 0.0 ? std::sqrt(in.EstimatedMSE) : -1.0;
}

//------------------------------------------------------------------------------
double vtkMultiChannelVolumeMapper::GetEstimatedPSNR()
{
  const double rmse = this->GetEstimatedError();
  if (rmse < 0.0)
  {
    return -1.0;
  }
  // 300 dB for a noiseless image, as the accuracy benchmark scores one.
  return rmse > 0.0 ? std::min(300.0, -20.0 * std::log10(rmse)) : 300.0;
}

//------------------------------------------------------------------------------
bool vtkMultiChannelVolumeMapper::ReachedTargetError()
{
  if (!(this->TargetError > 0.0) || this->Internals->Accum.samples() < TARGET_ERROR_MINIMUM_SAMPLES)
  {
    return false;
  }
  const double rmse = this->GetEstimatedError();
  return rmse >= 0.0 && rmse <= this->TargetError;
}

//------------------------------------------------------------------------------
bool vtkMultiChannelVolumeMapper::IsConverged()
{
  const vtkInternals& in = *this->Internals;
  const long long total = static_cast<long long>(in.Accum.samples());
  if (!in.Accumulation.IsCurrent() || total <= 0)
  {
    return false;
  }
  if (!this->Progressive)
  {
    return true;
  }
  if (this->AddsSamples() && this->ReachedTargetError())
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
  this->ReadBackImage();
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
  this->Internals->Accumulation.RequestReset();
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
  if (this->Internals->Functions.Colors[channel] != function)
  {
    this->Internals->Functions.Colors[channel] = function;
    this->Modified();
  }
}

//------------------------------------------------------------------------------
vtkColorTransferFunction* vtkMultiChannelVolumeMapper::GetChannelColor(int channel)
{
  MCVOL_CHECK_CHANNEL("GetChannelColor", channel, nullptr);
  return this->Internals->Functions.Colors[channel];
}

//------------------------------------------------------------------------------
void vtkMultiChannelVolumeMapper::SetChannelScalarOpacity(int channel, vtkPiecewiseFunction* function)
{
  MCVOL_CHECK_CHANNEL("SetChannelScalarOpacity", channel);
  if (this->Internals->Functions.Opacities[channel] != function)
  {
    this->Internals->Functions.Opacities[channel] = function;
    this->Modified();
  }
}

//------------------------------------------------------------------------------
vtkPiecewiseFunction* vtkMultiChannelVolumeMapper::GetChannelScalarOpacity(int channel)
{
  MCVOL_CHECK_CHANNEL("GetChannelScalarOpacity", channel, nullptr);
  return this->Internals->Functions.Opacities[channel];
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
  if (this->Internals->Functions.UnitDistances[channel] != distance)
  {
    this->Internals->Functions.UnitDistances[channel] = distance;
    this->Modified();
  }
}

//------------------------------------------------------------------------------
double vtkMultiChannelVolumeMapper::GetChannelScalarOpacityUnitDistance(int channel)
{
  MCVOL_CHECK_CHANNEL("GetChannelScalarOpacityUnitDistance", channel, 0.0);
  return this->Internals->Functions.UnitDistances[channel];
}

#undef MCVOL_CHECK_CHANNEL

//------------------------------------------------------------------------------
void vtkMultiChannelVolumeMapper::RemoveAllChannelTransferFunctions()
{
  bool changed = false;
  for (int c = 0; c < kMaxChannels; ++c)
  {
    changed = changed || this->Internals->Functions.Colors[c] || this->Internals->Functions.Opacities[c] ||
      this->Internals->Functions.UnitDistances[c] != 0.0;
    this->Internals->Functions.Colors[c] = nullptr;
    this->Internals->Functions.Opacities[c] = nullptr;
    this->Internals->Functions.UnitDistances[c] = 0.0;
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
  if (this->SplitImageWithExactStandIn && this->Internals->StandIn.IsExact())
  {
    // A split image covers the whole volume's screen area on every process
    // (the compositor reads back only the area of these bounds).
    std::copy_n(this->Internals->StandIn.WholeExtent(), 6, extent);
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
  // A volume VTK's camera cannot show is culled before Render() could say
  // why: say it here, once per cause.
  std::string error;
  if (!mcvol::adapter::CheckScale(image->GetSpacing(), this->Bounds, error) &&
    error != this->Internals->ScaleError)
  {
    vtkErrorMacro(<< error);
  }
  this->Internals->ScaleError = error;
  return this->Bounds;
}

//------------------------------------------------------------------------------
void vtkMultiChannelVolumeMapper::ReleaseGraphicsResources(vtkWindow* window)
{
  vtkInternals& in = *this->Internals;
  in.Compositor.ReleaseGraphicsResources(window);
  // The image still on the device comes back first: GetAccumulatedImage
  // after a release (vtkRenderWindow::RemoveRenderer releases) returns it,
  // as on the CPU.
  this->ReadBackImage();
  // A device backend holds the data (twice, with textures) and the grids in
  // GPU memory: give them back too; the next render uploads again.
  if (in.Backend.ReleaseDevice())
  {
    in.Accumulation.Invalidate();
    in.ChoiceValid = false; // a new backend object may reuse the address
  }
}

//------------------------------------------------------------------------------
/// What one Render() call works on, handed from stage to stage.
struct vtkMultiChannelVolumeMapper::RenderPass
{
  vtkRenderer* Renderer = nullptr;
  vtkVolume* Volume = nullptr;
  vtkImageData* Image = nullptr;
  vtkVolumeProperty* Property = nullptr;
  mcvol::adapter::BoundChannels Channels;
  mcvol::adapter::ChannelFunctionSet Functions;
  /// IndependentComponentsOff: Channels is the one pre-classified channel.
  bool Classified = false;
  /// The level of detail rendered, whether its channels are summed, its
  /// data (level > 0), and the Scene traced (level 0's or the level's).
  int Level = 0;
  bool SumChannels = false;
  /// Levels L > 0 converted to half precision: LevelOfDetailHalfPrecision
  /// on a backend that reads them in place (the CPU). The CUDA backend
  /// holds float32 on the device whatever the host keeps, so there the
  /// conversion would only add time to every rebuild.
  bool HalfLevels = false;
  const mcvol::adapter::LevelOfDetailCache::Level* LevelData = nullptr;
  mcvol::Scene* Scene = nullptr;
  vtkMTimeType LightsMTime = 0;
  mcvol::adapter::Viewport Viewport;
  vtkOpenGLRenderWindow* Window = nullptr;
  mcvol::Camera Camera;
};

//------------------------------------------------------------------------------
void vtkMultiChannelVolumeMapper::Render(vtkRenderer* ren, vtkVolume* vol)
{
  this->NumberOfChannels = 0;
  this->LastTransferFunctionUpdates = 0;
  if (!ren || !vol)
  {
    return;
  }
  // Each stage reports its own error and returns false to end the frame.
  RenderPass pass;
  pass.Renderer = ren;
  pass.Volume = vol;
  {
    // This render's kind (SetInteractiveRendering), read by the stages.
    vtkRenderWindow* window = ren->GetRenderWindow();
    this->LastRenderInteractive = this->InteractiveRendering == 1 ||
      (this->InteractiveRendering == -1 && window &&
        window->GetDesiredUpdateRate() >= this->InteractiveUpdateRate);
  }
  this->ReportIgnoredSettings(vol); // VTK settings this mapper does not use: warned once
  if (!this->BindChannels(pass) ||              // input image -> channels read in place
    !this->ClassifyDependentComponents(pass) || // IndependentComponentsOff: RGBA -> one classified channel
    !this->ResolveTransferFunctions(pass) ||    // VTK functions of each channel
    !this->EnsureBackend() ||                   // CPU or CUDA renderer
    !this->ChooseLevelOfDetail(pass) ||         // level asked for, automatic, or the one that fits
    !this->UpdateScene(pass) ||                 // volume, tables, grids, settings, lights
    !this->UpdateStandIn(pass,                  // lit, split over processes: the other pieces
      this->LightingStandInSynchronizedByCaller ? STAND_IN_USE : STAND_IN_GATHER_AND_USE) ||
    !this->SetUpView(pass))                     // camera rays, depth of opaque geometry
  {
    return;
  }
  this->UpdateAccumulation(pass); // restart the image if anything changed
  if (!this->TraceBatch(pass))    // add this render's samples
  {
    return;
  }
  this->NumberOfChannels = pass.Channels.Count;
  this->LastLevelOfDetail = pass.Level;
  this->LastLevelOfDetailChannels = pass.LevelData ? static_cast<int>(pass.LevelData->Channels.size()) : 0;
  this->DrawImage(pass); // the mean so far, over the framebuffer
}

//------------------------------------------------------------------------------
bool vtkMultiChannelVolumeMapper::BindChannels(RenderPass& pass)
{
  vtkDataSet* dataSet = nullptr;
  if (this->GetNumberOfInputConnections(0) > 0)
  {
    this->GetInputAlgorithm()->Update();
    dataSet = this->GetInput();
  }
  if (!dataSet)
  {
    vtkErrorMacro("No input: set a vtkImageData with SetInputData or SetInputConnection.");
    return false;
  }
  pass.Image = vtkImageData::SafeDownCast(dataSet);
  if (!pass.Image)
  {
    vtkErrorMacro(
      "Input is a " << dataSet->GetClassName() << "; vtkMultiChannelVolumeMapper renders vtkImageData only.");
    return false;
  }
  mcvol::adapter::ChannelSelection selection;
  selection.ArrayNames = &this->Internals->ChannelArrayNames;
  selection.ScalarMode = this->ScalarMode;
  selection.ArrayAccessMode = this->ArrayAccessMode;
  selection.ArrayId = this->ArrayId;
  selection.ArrayName = this->ArrayName;
  std::string error;
  if (!mcvol::adapter::BindChannels(pass.Image, selection, pass.Channels, error))
  {
    vtkErrorMacro(<< error);
    return false;
  }
  return true;
}

//------------------------------------------------------------------------------
bool vtkMultiChannelVolumeMapper::ClassifyDependentComponents(RenderPass& pass)
{
  vtkVolumeProperty* property = pass.Volume->GetProperty();
  // One channel is the same whether its components are dependent or not.
  if (!property || property->GetIndependentComponents() || pass.Channels.Count == 1)
  {
    return true;
  }
  std::string error;
  if (!this->Internals->ChannelArrayNames.empty())
  {
    vtkErrorMacro("IndependentComponentsOff needs the dependent components in one 2- or 4-component scalar array; "
                  "the mapper lists "
      << this->Internals->ChannelArrayNames.size()
      << " channel arrays (RemoveAllChannelArrays, or use IndependentComponentsOn).");
    return false;
  }
  // Channel 0's functions (the mapper's own where set, else the property's
  // component 0, VTK's convention for dependent components).
  mcvol::adapter::ChannelFunctionSet functions;
  if (pass.Channels.Count == 2 || pass.Channels.Count == 4)
  {
    if (!mcvol::adapter::ResolveChannelFunctions(this->Internals->Functions, property, 1, functions, error))
    {
      vtkErrorMacro(<< error);
      return false;
    }
  }
  if (!this->Internals->Dependent.Update(pass.Image, functions[0], pass.Channels, error))
  {
    vtkErrorMacro(<< error);
    return false;
  }
  pass.Classified = true;
  return true;
}

//------------------------------------------------------------------------------
bool vtkMultiChannelVolumeMapper::ResolveTransferFunctions(RenderPass& pass)
{
  pass.Property = pass.Volume->GetProperty();
  std::string error;
  if (!mcvol::adapter::ResolveChannelFunctions(
        this->Internals->Functions, pass.Property, pass.Channels.Count, pass.Functions, error))
  {
    vtkErrorMacro(<< error);
    return false;
  }
  if (this->VisibilityOptimization && !pass.Classified)
  {
    for (int c = 0; c < pass.Channels.Count; ++c)
    {
      pass.Functions[c].Importance = this->Internals->Functions.Importance[c];
    }
  }
  return true;
}

//------------------------------------------------------------------------------
bool vtkMultiChannelVolumeMapper::EnsureBackend()
{
  std::string error;
  this->Internals->Backend.SetCudaDevice(this->CUDADevice);
  if (!this->Internals->Backend.Ensure(this->UsesRenderBackend(), this->Backend, error))
  {
    vtkErrorMacro(<< error);
    return false;
  }
  return true;
}

//------------------------------------------------------------------------------
bool vtkMultiChannelVolumeMapper::UpdateScene(RenderPass& pass)
{
  vtkInternals& in = *this->Internals;
  const int numChannels = pass.Channels.Count;
  try
  {
    // A device backend builds macrocells and majorants itself from its own
    // copy of the data; the host then spends neither time nor memory on them.
    mcvol::Renderer* renderer = in.Backend.Get();
    const bool hostAcceleration =
      !renderer || !renderer->device() || !renderer->device()->buildsAccelerationOnDevice();
    in.Scene.setHostAcceleration(hostAcceleration);
    in.Data.Update(in.Scene, pass.Image, pass.Channels, [&in] { in.Tables.Forget(); });
    if (pass.Classified)
    {
      // The classified channel reads no table; its changes reach the Scene
      // (dataModified) and the image (DataMTime) as new data.
      this->LastTransferFunctionUpdates = 0;
    }
    else
    {
      // The Scene reads the arrays again: the classified copy can go.
      in.Dependent.Release();
      this->LastTransferFunctionUpdates = in.Tables.Update(in.Scene, pass.Functions, numChannels,
        this->TransferFunctionRangeMode == FUNCTION_RANGE, [&in](int c) { return in.Data.Range(c); });
      // Visibility optimization: importance over the colour tables' ranges
      // (before the levels, which key on the tables' version).
      in.Tables.UpdateImportance(in.Functions, numChannels);
      if (this->LastTransferFunctionUpdates > 0)
      {
        const std::string empty = in.Tables.EmptyFunctions(numChannels);
        if (!empty.empty())
        {
          vtkWarningMacro(<< empty);
        }
      }
    }

    // Level 0 renders the Scene of the data; a level L > 0 its own Scene of
    // pre-classified channels (level 0's grids are not built meanwhile).
    pass.Scene = &in.Scene;
    if (pass.Level > 0)
    {
      this->UpdateLevelScene(pass);
      in.LevelScene.setHostAcceleration(hostAcceleration);
    }
    else
    {
      // Levels kept for interaction stay while they are current; stale ones
      // (new data or functions) would be rebuilt anyway: free them now.
      in.Levels.DropIfStale(
        LevelKey(pass.Channels, pass.Classified, in.Tables.Version(), this->LevelOfDetailFilter, pass.SumChannels,
          pass.HalfLevels));
    }
    this->ApplySceneSettings(pass, *pass.Scene);
  }
  catch (const std::exception& e)
  {
    vtkErrorMacro(
      "Could not set up the volume" << (pass.Level > 0 ? " at its level of detail" : "") << ": " << e.what());
    in.ForgetVolume();
    in.Accumulation.Invalidate();
    in.ChoiceValid = false;
    return false;
  }
  return true;
}

//------------------------------------------------------------------------------
void vtkMultiChannelVolumeMapper::ApplySceneSettings(RenderPass& pass, mcvol::Scene& scene)
{
  vtkInternals& in = *this->Internals;
  const int sceneChannels = scene.numChannels();

  // The Scene's setters are cheap and rebuild nothing unless a value
  // changed (a new macrocell size marks the grids for update()).
  scene.setMacrocellSize(this->MacrocellSize);
  scene.setBlendMode(static_cast<mcvol::BlendMode>(this->ChannelBlendMode));
  // The mapper's interpolation type, else vtkVolumeProperty's, as VTK's own
  // mappers use it (a change resets the accumulation through the mapper's
  // or the property's MTime).
  const int interpolation =
    this->InterpolationType >= 0 ? this->InterpolationType : pass.Property->GetInterpolationType();
  scene.setInterpolation(interpolation == VTK_NEAREST_INTERPOLATION ? mcvol::Interpolation::Nearest
      : interpolation == VTK_CUBIC_INTERPOLATION                       ? mcvol::Interpolation::Cubic
                                                                       : mcvol::Interpolation::Linear);
  std::array<float, kMaxChannels> weights{};
  for (int c = 0; c < sceneChannels; ++c)
  {
    weights[c] = static_cast<float>(in.MixWeights[c]);
  }
  scene.setMixWeights(weights.data(), sceneChannels);
  scene.setMixAverage(this->MixColorMode == MIX_AVERAGE);
  // Lighting: only with ShadeOn (the lights' state joins the reset key).
  // Summed channels are summed only when their albedos and anisotropies
  // agree (SumsChannelsAtLevels), so channel 0's stand for all.
  mcvol::adapter::LightingSettings lighting;
  lighting.AmbientRadiance = this->AmbientRadiance;
  lighting.Albedo = in.Albedo.data();
  lighting.Anisotropy = in.Anisotropy.data();
  lighting.Shadows = this->ShadowMode != NO_SHADOWS;
  lighting.DeltaShadows = this->ShadowMode == DELTA_TRACKING_SHADOWS;
  lighting.CacheShadows = this->ShadowMode == CACHED_SHADOWS;
  lighting.CacheSpacing = this->ShadowCacheSpacing;
  lighting.MaxScatteringDepth = this->MaxScatteringDepth;
  lighting.GradientShading = this->GradientShading;
  lighting.Shininess = this->Shininess;
  mcvol::LightingDesc lights =
    mcvol::adapter::CollectLighting(pass.Renderer, pass.Property, lighting, sceneChannels, pass.LightsMTime);
  // Where the renderer's lights enter the physics: their scale (ParaView's
  // lights are meant for surface shading) and how many a scattering event
  // samples. The ray marcher sums every light whatever LightSampling says.
  for (mcvol::LightDesc& light : lights.lights)
  {
    light.intensity *= this->LightIntensityScale;
  }
  lights.sampleOneLight = this->LightSampling == ONE_LIGHT;
  scene.setLighting(lights);
  mcvol::ImportanceDesc importance;
  // A pre-classified channel (dependent components, or any level above 0)
  // has no scalar to look importance up by.
  importance.enabled = this->VisibilityOptimization && pass.Level == 0;
  if (importance.enabled && !pass.Classified)
  {
    importance.tables = in.Tables.ImportanceTables();
  }
  importance.p = this->DeviationWeight;
  importance.q = this->OcclusionWeight;
  importance.r = this->ClutterWeight;
  importance.lambda = this->ImportanceEmphasis;
  importance.mergeDistance = this->ImportanceMergeDistance;
  importance.samplesPerPass = this->ImportanceSamples;
  importance.lightRays = this->OptimizeLightRays;
  importance.lightRaySamples = this->LightRayImportanceSamples;
  scene.setImportance(importance);
  scene.update();
}

//------------------------------------------------------------------------------
bool vtkMultiChannelVolumeMapper::UpdateStandIn(RenderPass& pass, StandInStep step)
{
  vtkInternals& in = *this->Internals;
  if (step != STAND_IN_GATHER)
  {
    in.Scene.setOutside(nullptr);
    in.SplitImage = false;
  }
  vtkMultiProcessController* controller =
    in.Controller ? in.Controller.Get() : vtkMultiProcessController::GetGlobalController();
  // The same on every process (the settings and lights are), so that all
  // take part in the gather or none does.
  const bool wanted = this->LightingStandInLevel != STAND_IN_OFF && pass.Scene && pass.Scene->lit() && controller &&
    controller->GetNumberOfProcesses() > 1;
  if (!wanted)
  {
    if (in.StandIn.Builds() > 0)
    {
      in.StandIn.Release();
    }
    return true;
  }
  mcvol::adapter::StandIn::Input input;
  input.Piece = &in.Scene;
  pass.Image->GetExtent(input.Extent);
  pass.Image->GetOrigin(input.Origin);
  pass.Image->GetSpacing(input.Spacing);
  input.DataMTime = pass.Channels.DataMTime;
  input.TablesVersion = in.Tables.Version();
  if (!pass.Classified)
  {
    for (int c = 0; c < pass.Channels.Count; ++c)
    {
      input.Functions.push_back(&in.Tables.Table(c));
    }
  }
  input.Level = this->LightingStandInLevel;
  input.MemoryLimit = this->LightingStandInMemoryLimit;
  input.MacrocellSize = this->MacrocellSize;
  input.Interp = in.Scene.interpolation();
  // A split image renders the exact stand-in as its Scene: a backend that
  // builds its grids on the device needs no host copy of them.
  input.HostAcceleration = in.Scene.hostAcceleration() || !this->SplitImageWithExactStandIn;
  try
  {
    bool changed = false;
    double scale[3], offset[3];
    mcvol::Scene* standIn = nullptr;
    switch (step)
    {
      case STAND_IN_GATHER:
        in.StandIn.Synchronize(controller, input, changed);
        break;
      case STAND_IN_USE:
        standIn = in.StandIn.Use(input, changed, scale, offset);
        break;
      default:
        standIn = in.StandIn.Update(controller, input, changed, scale, offset);
        break;
    }
    if (changed)
    {
      in.Accumulation.RequestReset();
    }
    // Levels of detail above 0 render the piece alone.
    if (standIn && pass.Level == 0 && in.StandIn.IsExact() && this->SplitImageWithExactStandIn)
    {
      // Every process holds the whole volume: each traces it, with this
      // mapper's settings, for its stripes of the image.
      this->ApplySceneSettings(pass, *standIn);
      pass.Scene = standIn;
      in.SplitImage = true;
      in.SplitRank = controller->GetLocalProcessId();
      in.SplitRanks = controller->GetNumberOfProcesses();
    }
    else if (standIn && pass.Level == 0)
    {
      in.Scene.setOutside(standIn, scale, offset, in.StandIn.IsExact());
    }
  }
  catch (const std::exception& e)
  {
    vtkErrorMacro("Could not gather the stand-in for lighting across processes: " << e.what());
    in.StandIn.Release();
    return false;
  }
  return true;
}

//------------------------------------------------------------------------------
void vtkMultiChannelVolumeMapper::SynchronizeLightingStandIn(vtkRenderer* ren, vtkVolume* vol)
{
  vtkMultiProcessController* controller = this->Internals->Controller
    ? this->Internals->Controller.Get()
    : vtkMultiProcessController::GetGlobalController();
  // The same on every process, so that all return here or none does.
  if (this->LightingStandInLevel == STAND_IN_OFF || !controller || controller->GetNumberOfProcesses() < 2)
  {
    return;
  }
  RenderPass pass;
  pass.Renderer = ren;
  pass.Volume = vol;
  // Render()'s stages up to the stand-in, so that its input is the next
  // render's. A process whose stages fail (its error reported) keeps all
  // the others out of the gather: they agree first.
  int ready = ren && vol && this->BindChannels(pass) && this->ClassifyDependentComponents(pass) &&
      this->ResolveTransferFunctions(pass) && this->EnsureBackend() && this->ChooseLevelOfDetail(pass) &&
      this->UpdateScene(pass)
    ? 1
    : 0;
  int all = 0;
  controller->AllReduce(&ready, &all, 1, vtkCommunicator::MIN_OP);
  if (all)
  {
    this->UpdateStandIn(pass, STAND_IN_GATHER);
  }
}

//------------------------------------------------------------------------------
void vtkMultiChannelVolumeMapper::SetController(vtkMultiProcessController* controller)
{
  if (this->Internals->Controller.Get() != controller)
  {
    this->Internals->Controller = controller;
    this->Modified();
  }
}

//------------------------------------------------------------------------------
vtkMultiProcessController* vtkMultiChannelVolumeMapper::GetController()
{
  return this->Internals->Controller.Get();
}

//------------------------------------------------------------------------------
double vtkMultiChannelVolumeMapper::GetLightingStandInMemory()
{
  return static_cast<double>(this->Internals->StandIn.Bytes());
}

//------------------------------------------------------------------------------
double vtkMultiChannelVolumeMapper::GetLastLightingStandInGatherTime()
{
  return this->Internals->StandIn.LastGatherSeconds();
}

//------------------------------------------------------------------------------
int vtkMultiChannelVolumeMapper::GetNumberOfLightingStandInGathers()
{
  return this->Internals->StandIn.Builds();
}

//------------------------------------------------------------------------------
const char* vtkMultiChannelVolumeMapper::GetLightingStandInReport()
{
  vtkInternals& in = *this->Internals;
  in.StandInReport = in.StandIn.Report();
  if (in.SplitImage)
  {
    in.StandInReport += "; the processes split the image (" + std::to_string(in.SplitRanks) + " processes, stripes of " +
      std::to_string(kSplitImageStripeRows) + " rows)";
  }
  return in.StandInReport.c_str();
}

//------------------------------------------------------------------------------
bool vtkMultiChannelVolumeMapper::GetLastRenderSplitImage()
{
  return this->Internals->SplitImage;
}

//------------------------------------------------------------------------------
unsigned int vtkMultiChannelVolumeMapper::EffectiveSeed()
{
  return this->Seed + (this->Internals->SplitImage ? 0u : this->ProcessSeedOffset);
}

//------------------------------------------------------------------------------
bool vtkMultiChannelVolumeMapper::SumsChannelsAtLevels(RenderPass& pass)
{
  if (pass.Classified || pass.Channels.Count < 2 || this->ChannelBlendMode != MC_DENSITY_BLEND)
  {
    return false;
  }
  vtkVolumeProperty* property = pass.Volume->GetProperty();
  if (property && property->GetShade())
  {
    // Lit: a collision scatters with its channel's albedo and phase
    // function; a sum keeps only one of each.
    const vtkInternals& in = *this->Internals;
    for (int c = 1; c < pass.Channels.Count; ++c)
    {
      if (in.Albedo[c] != in.Albedo[0] || in.Anisotropy[c] != in.Anisotropy[0])
      {
        return false;
      }
    }
  }
  return true;
}

//------------------------------------------------------------------------------
bool vtkMultiChannelVolumeMapper::ChooseLevelOfDetail(RenderPass& pass)
{
  vtkInternals& in = *this->Internals;
  pass.SumChannels = this->SumsChannelsAtLevels(pass);
  const int outChannels = pass.SumChannels ? 1 : pass.Channels.Count;
  mcvol::adapter::LevelPolicy policy;
  policy.Requested = this->LevelOfDetail;
  policy.MemoryBudget = this->MemoryBudget;
  // The CUDA backend copies the channels (float64 as float32).
  policy.DeviceCopy = in.Backend.ActiveName(this->UsesRenderBackend(), this->Backend) == "cuda";
  pass.HalfLevels = this->LevelOfDetailHalfPrecision && !policy.DeviceCopy;
  policy.HalfPrecision = pass.HalfLevels;

  // Level 0's voxel size in world units per axis: spacing, direction and
  // the volume's matrix.
  double worldSpacing[3] = { 1.0, 1.0, 1.0 };
  double footprint = 0.0;
  if (this->LevelOfDetail == LEVEL_OF_DETAIL_AUTOMATIC)
  {
    vtkMatrix4x4* prop = pass.Volume->GetMatrix();
    vtkMatrix3x3* direction = pass.Image->GetDirectionMatrix();
    const double* spacing = pass.Image->GetSpacing();
    for (int a = 0; a < 3; ++a)
    {
      double w[3] = { 0.0, 0.0, 0.0 };
      for (int r = 0; r < 3; ++r)
      {
        for (int k = 0; k < 3; ++k)
        {
          w[r] += prop->GetElement(r, k) * direction->GetElement(k, a) * spacing[a];
        }
      }
      worldSpacing[a] = vtkMath::Norm(w);
    }
    // The world size of one pixel where the volume is.
    const mcvol::adapter::Viewport viewport = mcvol::adapter::GetViewport(pass.Renderer);
    vtkCamera* camera = pass.Renderer->GetActiveCamera();
    const int pixels = camera->GetUseHorizontalViewAngle() ? viewport.Width : viewport.Height;
    double bounds[6];
    pass.Volume->GetBounds(bounds);
    const double centre[3] = { 0.5 * (bounds[0] + bounds[1]), 0.5 * (bounds[2] + bounds[3]),
      0.5 * (bounds[4] + bounds[5]) };
    if (pixels < 1)
    {
      footprint = 0.0;
    }
    else if (camera->GetParallelProjection())
    {
      footprint = 2.0 * camera->GetParallelScale() / pixels;
    }
    else
    {
      const double d = std::sqrt(vtkMath::Distance2BetweenPoints(camera->GetPosition(), centre));
      footprint = 2.0 * d * std::tan(vtkMath::RadiansFromDegrees(camera->GetViewAngle()) / 2.0) / pixels;
    }
  }
  mcvol::adapter::LevelChoice choice;
  try
  {
    choice = mcvol::adapter::ChooseLevel(policy, pass.Channels, outChannels, footprint, worldSpacing);
  }
  catch (const std::exception& e)
  {
    vtkErrorMacro("Could not choose the level of detail: " << e.what());
    return false;
  }
  pass.Level = choice.Level;
  in.LevelReport = choice.Report;
  if (choice.Level > 0 && this->VisibilityOptimization)
  {
    in.LevelReport += "; the visibility optimization is off at levels above 0";
  }
  if (choice.Clamped || choice.Fallback)
  {
    // Once per case, not every frame (a progressive image renders many).
    std::ostringstream key;
    key << this->LevelOfDetail << " " << choice.Wanted << " " << choice.Level << " " << this->MemoryBudget << " "
        << policy.DeviceCopy;
    if (key.str() != in.LevelWarning)
    {
      in.LevelWarning = key.str();
      vtkWarningMacro("Level of detail: " << in.LevelReport);
    }
  }
  else
  {
    in.LevelWarning.clear();
  }
  return true;
}

//------------------------------------------------------------------------------
bool vtkMultiChannelVolumeMapper::UpdateLevelScene(RenderPass& pass)
{
  vtkInternals& in = *this->Internals;
  const mcvol::adapter::LevelOfDetailCache::Key key =
    LevelKey(pass.Channels, pass.Classified, in.Tables.Version(), this->LevelOfDetailFilter, pass.SumChannels,
      pass.HalfLevels);
  std::vector<const mcvol::TransferFunctionDesc*> tables;
  if (!pass.Classified)
  {
    for (int c = 0; c < pass.Channels.Count; ++c)
    {
      tables.push_back(&in.Tables.Table(c));
    }
  }
  // Scalar channels' levels are built on the backend's device where it
  // builds them there (CUDA), so that editing a function at a coarse level
  // stays interactive; on the host otherwise.
  const mcvol::adapter::LevelOfDetailCache::Level& level =
    in.Levels.Get(key, pass.Level, pass.Channels, tables, in.Backend.Get() ? in.Backend.Get()->device() : nullptr);
  pass.LevelData = &level;
  if (level.Version != in.LevelSceneVersion)
  {
    std::vector<mcvol::ChannelSource> sources;
    for (const mcvol::PyramidLevel& channel : level.Channels)
    {
      sources.push_back(channel.source());
    }
    in.LevelScene.setVolume(level.Channels[0].dims, static_cast<int>(sources.size()), sources.data());
    // Rendered over level 0's box, so that the level covers what level 0
    // covers (its outer voxels sit inside that box).
    double lo[3], hi[3];
    level.Channels[0].indexBounds(lo, hi);
    in.LevelScene.setIndexBounds(lo, hi);
    in.LevelSceneVersion = level.Version;
  }
  pass.Scene = &in.LevelScene;
  return true;
}

//------------------------------------------------------------------------------
bool vtkMultiChannelVolumeMapper::SetUpView(RenderPass& pass)
{
  pass.Viewport = mcvol::adapter::GetViewport(pass.Renderer);
  if (pass.Viewport.Width < 1 || pass.Viewport.Height < 1)
  {
    return false;
  }
  pass.Window = vtkOpenGLRenderWindow::SafeDownCast(pass.Renderer->GetRenderWindow());
  if (!pass.Window)
  {
    vtkErrorMacro("vtkMultiChannelVolumeMapper draws with OpenGL and needs a "
                  "vtkOpenGLRenderWindow.");
    return false;
  }
  // GetBounds() checks the volume's scale and reports a problem once.
  this->GetBounds();
  if (!this->Internals->ScaleError.empty())
  {
    return false;
  }
  std::string error;
  vtkInternals& in = *this->Internals;
  // A split image traces the whole volume (the pieces share origin and
  // spacing: the stand-in's gather checks it).
  if (!mcvol::adapter::ComputeCamera(pass.Renderer, pass.Volume, pass.Image,
        in.SplitImage ? in.StandIn.WholeExtent() : pass.Channels.Extent, pass.Viewport, pass.Camera, error))
  {
    vtkErrorMacro(<< error);
    return false;
  }
  if (pass.LevelData)
  {
    // Rays into the level's index space, so that its image lines up with
    // level 0's.
    mcvol::adapter::ApplyToCamera(pass.LevelData->Channels[0], pass.Camera);
  }
  std::vector<float>& depth = in.Depth;
  if (!mcvol::adapter::HasOpaqueGeometry(pass.Renderer))
  {
    // Nothing but volumes: the depth buffer is all "far". No buffer at all
    // (an empty one: Depth() is null and the backends take every ray to the
    // far plane) skips the read-back, the per-frame fill and comparison of
    // a full-window buffer, and a device backend's depth copy.
    depth.clear();
  }
  else if (!mcvol::adapter::ReadDepth(pass.Window, pass.Viewport, depth))
  {
    vtkWarningMacro("Could not read the depth buffer; geometry will not occlude the volume.");
  }
  if (in.SplitImage)
  {
    // The other processes' stripes: depth 0, geometry at the near plane.
    mcvol::maskSplitImageRows(depth, pass.Viewport.Width, pass.Viewport.Height, in.SplitRanks, in.SplitRank);
  }
  return true;
}

//------------------------------------------------------------------------------
void vtkMultiChannelVolumeMapper::UpdateAccumulation(RenderPass& pass)
{
  vtkInternals& in = *this->Internals;
  mcvol::adapter::AccumulationKey key;
  // The mapper's own parameters; the transfer functions count through the
  // tables they produce (their version), not through their times.
  key.MapperMTime = this->Superclass::GetMTime();
  key.TablesVersion = in.Tables.Version();
  // The property's own settings (shading, interpolation, which functions it
  // holds); the values of its functions count through the tables.
  key.PropertyMTime = pass.Property ? pass.Property->vtkObject::GetMTime() : 0;
  // The arrays' times (marked when values were written in place); geometry
  // reaches the key through WorldToIndex.
  key.DataMTime = pass.Channels.DataMTime;
  key.LightsMTime = pass.LightsMTime;
  key.Width = pass.Viewport.Width;
  key.Height = pass.Viewport.Height;
  std::copy(std::begin(pass.Camera.invViewProj), std::end(pass.Camera.invViewProj), key.InvViewProj);
  std::copy(std::begin(pass.Camera.worldToIndex), std::end(pass.Camera.worldToIndex), key.WorldToIndex);
  key.Backend = in.Backend.Get();
  key.Level = pass.Level;
  key.LevelVersion = pass.LevelData ? pass.LevelData->Version : 0;
  // An interactive render that takes another estimator than the still ones
  // (under the choice made so far; a new choice comes with new data or
  // settings, which restart the image anyway).
  key.InteractiveEstimator = this->InteractiveKeepsExpectedValue();
  if (in.Accumulation.Update(key, in.Depth, in.Accum))
  {
    in.EstimateCurrent = false;
  }
}

//------------------------------------------------------------------------------
bool vtkMultiChannelVolumeMapper::InteractiveKeepsExpectedValue()
{
  const vtkInternals& in = *this->Internals;
  return this->Estimator == AUTOMATIC_ESTIMATOR && this->LastRenderInteractive && in.ChoiceValid && in.Choice.applies &&
    in.Choice.chosen > 0 &&
    in.Choice.trials[size_t(in.Choice.chosen)].costPerSample > in.Choice.trials[0].costPerSample;
}

//------------------------------------------------------------------------------
bool vtkMultiChannelVolumeMapper::ChooseEstimator(RenderPass& pass)
{
  vtkInternals& in = *this->Internals;
  if (this->Estimator != AUTOMATIC_ESTIMATOR || !this->AddsSamples() || !in.Backend.Get())
  {
    return true;
  }
  const mcvol::Scene& scene = *pass.Scene;
  vtkInternals::ChoiceKey key;
  key.TablesVersion = in.Tables.Version();
  key.DataMTime = pass.Channels.DataMTime;
  key.Backend = in.Backend.Get();
  key.Blend = static_cast<int>(scene.blendMode());
  key.Lit = scene.lit();
  key.Optimized = scene.optimized();
  key.Seed = this->EffectiveSeed();
  key.MinimumSamplesPerVoxel = this->MinimumSamplesPerVoxel;
  key.TargetError = this->TargetError;
  key.PixelJitter = this->PixelJitter;
  key.MarchControlVariates = this->MarchControlVariates;
  if (in.ChoiceValid && in.ChoiceMadeFor == key)
  {
    return true;
  }
  mcvol::RenderSettings base = this->MakeRenderSettings(*in.Backend.Get());
  mcvol::EstimatorChoiceSettings settings;
  if (this->TargetError > 0.0)
  {
    // Aim at the image's own target (an RMSE over premultiplied RGB, as the
    // choice's MSE is).
    settings.targetMSE = this->TargetError * this->TargetError;
  }
  // The previous choice's candidates go into the first round of pilots on
  // a backend that renders a round at once (after a transfer-function edit
  // the search likely reaches them again): fewer rounds, the same choice.
  if (in.Choice.applies)
  {
    settings.hint = in.Choice.hint();
  }
  // There, this render's batch also goes to the device first, with the
  // previous choice's estimator: it runs beside the pilots (a round is a few
  // thousand long rays, bound by one's latency) and is the image's first
  // batch where the choice is the same again, else it is dropped
  // (mcvol::ChoiceAhead). Still renders of a new image only: an interactive
  // one may take expected value instead of the choice.
  mcvol::Renderer& renderer = *in.Backend.Get();
  mcvol::ChoiceAhead ahead;
  const bool renderAhead = in.Choice.applies && renderer.rendersPilotsAtOnce() && !this->LastRenderInteractive &&
    in.Accum.samples() == 0 && in.BatchSamples > 0;
  if (renderAhead)
  {
    ahead.candidate = in.Choice.chosenCandidate();
    ahead.accum = &in.Accum;
    ahead.depth = in.Accumulation.Depth();
  }
  in.BatchRenderedAhead = false;
  try
  {
    in.Choice = renderAhead ? mcvol::chooseEstimator(renderer, scene, pass.Camera, base, settings, ahead)
                            : mcvol::chooseEstimator(renderer, scene, pass.Camera, base, settings);
  }
  catch (const std::exception& e)
  {
    vtkErrorMacro("Automatic estimator choice failed: " << e.what());
    in.ChoiceValid = false;
    if (renderAhead)
    {
      in.Accum.reset(); // frames rendered ahead, if any, are not the image's
    }
    return false;
  }
  in.ChoiceValid = true;
  in.ChoiceMadeFor = key;
  in.BatchRenderedAhead = ahead.kept;
  in.ChoiceReport = in.Choice.report();
  if (ahead.rendered)
  {
    in.ChoiceReport += std::string("the first ") + std::to_string(in.BatchSamples) +
      " samples per pixel, rendered during the pilots with the previous choice's " +
      mcvol::estimatorName(ahead.candidate.estimator, ahead.candidate.marchSamplesPerVoxel,
        ahead.candidate.controlVariates) +
      (ahead.kept ? ": kept\n" : ": dropped (another estimator was chosen)\n");
  }
  in.Choices += in.Choice.applies ? 1 : 0;
  return true;
}

//------------------------------------------------------------------------------
bool vtkMultiChannelVolumeMapper::TraceBatch(RenderPass& pass)
{
  // Progressive refinement adds a batch up to MaximumTotalSamples; without it
  // the image is traced once per change. The ray-marching subclass decides
  // for itself (it traces once per change).
  vtkInternals& in = *this->Internals;
  const bool budgeted = this->InteractiveFrameTime > 0.0 && this->AddsSamples();
  mcvol::adapter::SampleCost& cost = in.Cost[this->InteractiveKeepsExpectedValue() ? 1 : 0];
  const int wanted =
    budgeted ? cost.Budget(this->InteractiveFrameTime, this->SamplesPerPixel, 4096) : this->SamplesPerPixel;
  int batch = mcvol::adapter::SamplesThisRender(this->AddsSamples(), this->Progressive, wanted,
    this->MaximumTotalSamples, static_cast<long long>(in.Accum.samples()));
  // Adaptive stopping: once the estimate reached TargetError, redraw only.
  if (batch > 0 && this->AddsSamples() && this->ReachedTargetError())
  {
    batch = 0;
  }
  if (batch <= 0)
  {
    this->LastTraceTime = 0.0;
    return true;
  }
  std::string error;
  in.BatchSamples = batch;
  // The automatic estimator's pilots (once per data and transfer functions)
  // before the timer: the frame-time budget measures samples, not pilots.
  if (!this->ChooseEstimator(pass))
  {
    in.BatchSamples = 0;
    in.Accumulation.Invalidate();
    return false;
  }
  // A batch rendered beside the pilots and kept (ChooseEstimator) is this
  // render's: not traced again, and its time is the pilots' wall time, not a
  // sample cost for the budget.
  const bool ahead = in.BatchRenderedAhead;
  in.BatchRenderedAhead = false;
  const auto start = std::chrono::steady_clock::now();
  const bool ok = ahead ||
    this->TraceImage(*pass.Scene, pass.Camera, in.Accumulation.Depth(), in.Backend.Get(), in.Accum, error);
  if (ahead)
  {
    in.ChosenEstimator = in.Choice.chosenName();
  }
  const double traced = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  this->LastTraceTime = ahead ? in.Choice.seconds : traced;
  in.EstimateCurrent = false;
  if (ok && !ahead && this->AddsSamples())
  {
    cost.Record(batch, traced);
  }
  in.BatchSamples = 0;
  this->LastSamplesPerRender = ok ? batch : 0;
  if (!ok)
  {
    vtkErrorMacro("Rendering failed: " << error);
    in.Accumulation.Invalidate();
    return false;
  }
  return true;
}

//------------------------------------------------------------------------------
void vtkMultiChannelVolumeMapper::ReadBackImage()
{
  vtkInternals& in = *this->Internals;
  if (!in.Accum.pendingOnDevice() || !in.Backend.Get())
  {
    return;
  }
  try
  {
    in.Backend.Get()->readBack(in.Accum);
  }
  catch (const std::exception& e)
  {
    vtkWarningMacro("The accumulated image could not be read back from the device: " << e.what());
  }
}

//------------------------------------------------------------------------------
void vtkMultiChannelVolumeMapper::DrawImage(RenderPass& pass)
{
  const auto start = std::chrono::steady_clock::now();
  std::string error;
  vtkInternals& in = *this->Internals;
  // A device backend's image is drawn from its 8-bit display copy; the
  // float image is drawn where it is on the host (the CPU, or read back).
  const unsigned char* display = nullptr;
  if (in.Accum.pendingOnDevice() && in.Backend.Get() && in.Backend.Get()->device())
  {
    try
    {
      display = in.Backend.Get()->device()->displayImage(in.Accum);
    }
    catch (const std::exception& e)
    {
      vtkErrorMacro("The image could not be copied from the device: " << e.what());
      return;
    }
  }
  const bool drawn = display
    ? in.Compositor.Draw(pass.Window, pass.Viewport.Width, pass.Viewport.Height, display, error)
    : in.Compositor.Draw(pass.Window, pass.Viewport.Width, pass.Viewport.Height, in.Accum.rgba(), error);
  if (!drawn)
  {
    vtkErrorMacro(<< error);
  }
  this->LastDrawTime = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
}

//------------------------------------------------------------------------------
void vtkMultiChannelVolumeMapper::PrintSelf(ostream& os, vtkIndent indent)
{
  this->Superclass::PrintSelf(os, indent);
  vtkInternals& in = *this->Internals;
  os << indent << "ChannelBlendMode: " << this->GetChannelBlendModeAsString() << "\n";
  os << indent << "MixColorMode: " << (this->MixColorMode == MIX_AVERAGE ? "Average" : "Equation10") << "\n";
  os << indent << "InterpolationType: "
     << (this->InterpolationType < 0                               ? "Property"
            : this->InterpolationType == VTK_NEAREST_INTERPOLATION ? "Nearest"
            : this->InterpolationType == VTK_LINEAR_INTERPOLATION  ? "Linear"
                                                                   : "Cubic")
     << "\n";
  os << indent << "TrackingMethod: " << this->GetTrackingMethodAsString() << "\n";
  os << indent << "SampleSequence: " << this->GetSampleSequenceAsString() << "\n";
  os << indent << "Estimator: " << this->GetEstimatorAsString() << " (last used: " << in.ChosenEstimator << ")\n";
  os << indent << "MinimumSamplesPerVoxel: " << this->MinimumSamplesPerVoxel << "\n";
  os << indent << "MarchSamplesPerVoxel: " << this->MarchSamplesPerVoxel << "\n";
  os << indent << "MarchControlVariates: " << this->MarchControlVariates << "\n";
  os << indent << "InteractiveRendering: " << this->InteractiveRendering
     << " (update rate " << this->InteractiveUpdateRate << "; last render "
     << (this->LastRenderInteractive ? "interactive" : "still") << ")\n";
  os << indent << "SamplesPerPixel: " << this->SamplesPerPixel << "\n";
  os << indent << "InteractiveFrameTime: " << this->InteractiveFrameTime << "\n";
  os << indent << "Progressive: " << this->Progressive << "\n";
  os << indent
     << "TransferFunctionRangeMode: " << (this->TransferFunctionRangeMode == FUNCTION_RANGE ? "function" : "data")
     << "\n";
  os << indent << "MaximumTotalSamples: " << this->MaximumTotalSamples << "\n";
  os << indent << "TargetError: " << this->TargetError << "\n";
  os << indent << "Seed: " << this->Seed << "\n";
  os << indent << "ProcessSeedOffset: " << this->ProcessSeedOffset << "\n";
  os << indent << "PixelJitter: " << this->PixelJitter << "\n";
  os << indent << "MacrocellSize: " << this->MacrocellSize << "\n";
  os << indent << "Backend: " << this->GetBackendAsString() << "\n";
  os << indent << "CUDADevice: " << this->CUDADevice << (this->CUDADevice < 0 ? " (by local MPI rank)" : "") << "\n";
  os << indent << "ActiveBackend: " << in.Backend.PrintName(this->Backend) << "\n";
  os << indent << "TotalSamples: " << in.Accum.samples() << "\n";
  os << indent << "DeviceMemory: " << this->GetDeviceMemory() << " bytes\n";
  os << indent << "NumberOfDataUploads: " << this->GetNumberOfDataUploads() << "\n";
  os << indent << "LastTraceTime: " << this->LastTraceTime << "\n";
  os << indent << "LastDrawTime: " << this->LastDrawTime << "\n";
  os << indent << "EstimatedError: " << this->GetEstimatedError() << "\n";
  os << indent << "NumberOfChannels: " << this->NumberOfChannels << "\n";
  os << indent << "LastTransferFunctionUpdates: " << this->LastTransferFunctionUpdates << "\n";
  os << indent << "NumberOfClassifications: " << in.Dependent.Classifications() << "\n";
  os << indent << "ClassifiedMemory: " << in.Dependent.Bytes() << " bytes\n";
  os << indent << "LevelOfDetail: " << this->LevelOfDetail
     << (this->LevelOfDetail == LEVEL_OF_DETAIL_AUTOMATIC ? " (automatic)" : "") << "\n";
  os << indent << "LevelOfDetailFilter: " << this->GetLevelOfDetailFilterAsString() << "\n";
  os << indent << "LightingStandInLevel: " << this->LightingStandInLevel
     << (this->LightingStandInLevel == STAND_IN_AUTOMATIC ? " (automatic)"
           : this->LightingStandInLevel < 0               ? " (off)"
           : this->LightingStandInLevel == 0              ? " (exact)"
                                                          : " (coarse)")
     << "\n";
  os << indent << "LightingStandInMemoryLimit: " << this->LightingStandInMemoryLimit << "\n";
  os << indent << "LightingStandInSynchronizedByCaller: " << this->LightingStandInSynchronizedByCaller << "\n";
  os << indent << "SplitImageWithExactStandIn: " << (this->SplitImageWithExactStandIn ? "On" : "Off") << "\n";
  os << indent << "LevelOfDetailHalfPrecision: " << (this->LevelOfDetailHalfPrecision ? "On" : "Off") << "\n";
  os << indent << "MemoryBudget: " << this->MemoryBudget << " bytes" << (this->MemoryBudget > 0.0 ? "" : " (no cap)")
     << "\n";
  os << indent << "LastLevelOfDetail: " << this->LastLevelOfDetail << "\n";
  os << indent << "LevelOfDetailReport: " << in.LevelReport << "\n";
  os << indent << "NumberOfLevelOfDetailBuilds: " << in.Levels.Builds() << "\n";
  os << indent << "LevelOfDetailMemory: " << in.Levels.Bytes() << " bytes\n";
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
  os << indent << "VisibilityOptimization: " << this->VisibilityOptimization << "\n";
  os << indent << "DeviationWeight: " << this->DeviationWeight << "\n";
  os << indent << "OcclusionWeight: " << this->OcclusionWeight << "\n";
  os << indent << "ClutterWeight: " << this->ClutterWeight << "\n";
  os << indent << "ImportanceEmphasis: " << this->ImportanceEmphasis << "\n";
  os << indent << "ImportanceMergeDistance: " << this->ImportanceMergeDistance << "\n";
  os << indent << "ImportanceSamples: " << this->ImportanceSamples << "\n";
  os << indent << "OptimizeLightRays: " << this->OptimizeLightRays << "\n";
  os << indent << "LightRayImportanceSamples: " << this->LightRayImportanceSamples << "\n";
  os << indent << "ChannelImportance:";
  for (int c = 0; c < kMaxChannels; ++c)
  {
    if (in.Functions.Importance[c])
    {
      os << " " << c << ": " << in.Functions.Importance[c].Get();
    }
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
    const mcvol::adapter::ChannelFunctionOverrides& f = in.Functions;
    if (f.Colors[c] || f.Opacities[c] || f.UnitDistances[c] != 0.0)
    {
      os << indent << "Channel " << c << ": Color " << f.Colors[c].Get() << ", ScalarOpacity " << f.Opacities[c].Get()
         << ", ScalarOpacityUnitDistance " << f.UnitDistances[c] << "\n";
    }
  }
}

//------------------------------------------------------------------------------
void vtkMultiChannelVolumeMapper::SetInteractiveUpdateRate(double value)
{
  mcvol::adapter::SetClamped(this, "SetInteractiveUpdateRate", value, 0.0, VTK_DOUBLE_MAX, this->InteractiveUpdateRate);
}

//------------------------------------------------------------------------------
void vtkMultiChannelVolumeMapper::SetMinimumSamplesPerVoxel(double value)
{
  mcvol::adapter::SetClamped(this, "SetMinimumSamplesPerVoxel", value, 0.0, 1e6, this->MinimumSamplesPerVoxel);
}

//------------------------------------------------------------------------------
void vtkMultiChannelVolumeMapper::SetMarchSamplesPerVoxel(double value)
{
  mcvol::adapter::SetClamped(this, "SetMarchSamplesPerVoxel", value, 0.01, 1024.0, this->MarchSamplesPerVoxel);
}

//------------------------------------------------------------------------------
void vtkMultiChannelVolumeMapper::SetInteractiveFrameTime(double value)
{
  mcvol::adapter::SetClamped(this, "SetInteractiveFrameTime", value, 0.0, 3600.0, this->InteractiveFrameTime);
}

//------------------------------------------------------------------------------
void vtkMultiChannelVolumeMapper::SetTargetError(double value)
{
  mcvol::adapter::SetClamped(this, "SetTargetError", value, 0.0, VTK_DOUBLE_MAX, this->TargetError);
}

//------------------------------------------------------------------------------
void vtkMultiChannelVolumeMapper::SetShininess(double value)
{
  mcvol::adapter::SetClamped(this, "SetShininess", value, 0.0, 1e4, this->Shininess);
}

//------------------------------------------------------------------------------
void vtkMultiChannelVolumeMapper::SetShadowCacheSpacing(double voxels)
{
  mcvol::adapter::SetClamped(this, "SetShadowCacheSpacing", voxels, 0.5, 64.0, this->ShadowCacheSpacing);
}

//------------------------------------------------------------------------------
void vtkMultiChannelVolumeMapper::SetLightIntensityScale(double value)
{
  mcvol::adapter::SetClamped(this, "SetLightIntensityScale", value, 0.0, 1e6, this->LightIntensityScale);
}

//------------------------------------------------------------------------------
void vtkMultiChannelVolumeMapper::SetDeviationWeight(double value)
{
  mcvol::adapter::SetClamped(this, "SetDeviationWeight", value, 1e-6, 1e12, this->DeviationWeight);
}

//------------------------------------------------------------------------------
void vtkMultiChannelVolumeMapper::SetOcclusionWeight(double value)
{
  mcvol::adapter::SetClamped(this, "SetOcclusionWeight", value, 0.0, 1e12, this->OcclusionWeight);
}

//------------------------------------------------------------------------------
void vtkMultiChannelVolumeMapper::SetClutterWeight(double value)
{
  mcvol::adapter::SetClamped(this, "SetClutterWeight", value, 0.0, 1e12, this->ClutterWeight);
}

//------------------------------------------------------------------------------
void vtkMultiChannelVolumeMapper::SetImportanceEmphasis(double value)
{
  mcvol::adapter::SetClamped(this, "SetImportanceEmphasis", value, 0.0, 1e3, this->ImportanceEmphasis);
}

//------------------------------------------------------------------------------
void vtkMultiChannelVolumeMapper::SetImportanceMergeDistance(double value)
{
  mcvol::adapter::SetClamped(this, "SetImportanceMergeDistance", value, 0.0, 1e6, this->ImportanceMergeDistance);
}

//------------------------------------------------------------------------------
void vtkMultiChannelVolumeMapper::SetMemoryBudget(double value)
{
  mcvol::adapter::SetClamped(this, "SetMemoryBudget", value, 0.0, VTK_DOUBLE_MAX, this->MemoryBudget);
}

//------------------------------------------------------------------------------
void vtkMultiChannelVolumeMapper::SetLightingStandInMemoryLimit(double bytes)
{
  mcvol::adapter::SetClamped(
    this, "SetLightingStandInMemoryLimit", bytes, 0.0, VTK_DOUBLE_MAX, this->LightingStandInMemoryLimit);
}

//------------------------------------------------------------------------------
void vtkMultiChannelVolumeMapper::SetAmbientRadiance(double r, double g, double b)
{
  const double rgb[3] = { r, g, b };
  for (double v : rgb)
  {
    if (!(v >= 0.0) || !std::isfinite(v))
    {
      vtkErrorMacro("SetAmbientRadiance: (" << r << ", " << g << ", " << b
                                            << ") must be finite and >= 0; the radiance stays.");
      return;
    }
  }
  if (this->AmbientRadiance[0] != r || this->AmbientRadiance[1] != g || this->AmbientRadiance[2] != b)
  {
    std::copy(rgb, rgb + 3, this->AmbientRadiance);
    this->Modified();
  }
}
