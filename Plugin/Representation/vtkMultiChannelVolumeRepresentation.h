// SPDX-License-Identifier: BSD-3-Clause
/**
 * @class   vtkMultiChannelVolumeRepresentation
 * @brief   ParaView volume representation drawn by vtkMultiChannelVolumeMapper.
 *
 * The representation behind "Multi-Channel Volume (Monte Carlo)". It is
 * ParaView's image volume representation (data delivery, outline for ranks
 * without data, ordered compositing of the pieces in parallel) with its
 * mapper replaced by vtkMultiChannelVolumeMapper and N channels instead of
 * one coloured array.
 *
 * Channels come from a list of point arrays (ChannelSource ARRAYS, the
 * default) or from the components of one point array (COMPONENTS). Channel
 * i is coloured by the i-th lookup table added with AddChannelLookupTable
 * and made opaque by that lookup table's scalar opacity function (ParaView's
 * PVLookupTable proxies carry one); vtkSMMultiChannelVolumeRepresentationProxy
 * fills that list on the client from ParaView's per-array transfer functions.
 *
 * Every setter only forwards to the mapper: the mapper starts its running
 * mean over when a value really changes and not otherwise, so rendering again
 * with nothing changed refines the image.
 *
 * Levels of detail: LevelOfDetail is the mapper's level for still renders
 * (0 full resolution, L > 0, -1 automatic). While ParaView renders with its
 * level of detail (vtkPVRenderView::USE_LOD() in the render request: an
 * interactive render, camera dragging, when the view's LOD threshold is
 * reached; set the view's LODThreshold to 0 to always use it), the mapper
 * renders InteractiveLevelOfDetail instead (default 1: 1/8 of the voxels;
 * -1 automatic; 0: the still level, no LOD), reading the nearest voxel
 * (InteractiveInterpolation). The first still render after
 * the interaction (the refinement timer's, pqMultiChannelRefinement) goes
 * back to the still level, which restarts the image there, as any change of
 * level does, and refines it from then on.
 */
#ifndef vtkMultiChannelVolumeRepresentation_h
#define vtkMultiChannelVolumeRepresentation_h

#include "mcvolParaViewRepresentationModule.h" // For export macro
#include "vtkImageVolumeRepresentation.h"
#include "vtkSmartPointer.h" // For vtkSmartPointer

#include <string> // For std::string
#include <vector> // For std::vector

class vtkMultiChannelVolumeMapper;
class vtkPiecewiseFunction;
class vtkScalarsToColors;
class vtkTextActor;

class MCVOLPARAVIEWREPRESENTATION_EXPORT vtkMultiChannelVolumeRepresentation : public vtkImageVolumeRepresentation
{
public:
  static vtkMultiChannelVolumeRepresentation* New();
  vtkTypeMacro(vtkMultiChannelVolumeRepresentation, vtkImageVolumeRepresentation);
  void PrintSelf(ostream& os, vtkIndent indent) override;

  enum ChannelSources
  {
    ARRAYS = 0,
    COMPONENTS = 1
  };

  ///@{
  /**
   * Where the channels come from: the arrays listed with AddChannelArray
   * (ARRAYS) or the components of ChannelComponentsArray (COMPONENTS).
   */
  void SetChannelSource(int source);
  vtkGetMacro(ChannelSource, int);
  void AddChannelArray(const char* name);
  void RemoveAllChannelArrays();
  void SetChannelComponentsArray(const char* name);
  ///@}

  ///@{
  /**
   * Channel i's colour transfer function, whose scalar opacity function (a
   * vtkDiscretizableColorTransferFunction's) is the channel's opacity.
   */
  void AddChannelLookupTable(vtkScalarsToColors* lut);
  void RemoveAllChannelLookupTables();
  ///@}

  ///@{
  /**
   * Which of the added lookup tables channel i uses (an index into the list
   * in the order added). ParaView adds a repeatable proxy property's proxies
   * in the order of their global ids, without repeats, so the client proxy
   * sends the channel order separately.
   */
  void SetNumberOfChannelLookupTableIndices(int n);
  void SetChannelLookupTableIndex(int channel, int index);
  ///@}

  ///@{
  /**
   * Forwarded to vtkMultiChannelVolumeMapper.
   */
  void SetChannelBlendMode(int mode);
  void SetNumberOfMixWeights(int n);
  void SetMixWeight(int channel, double weight);
  void SetMixColorMode(int mode);
  void SetTrackingMethod(int method);
  void SetSampleSequence(int sequence);
  void SetEstimator(int estimator);
  /// vtkMultiChannelVolumeMapper::SetMinimumSamplesPerVoxel.
  void SetMinimumSamplesPerVoxel(double samples);
  /// vtkMultiChannelVolumeMapper::SetMarchSamplesPerVoxel.
  void SetMarchSamplesPerVoxel(double samples);
  /// vtkMultiChannelVolumeMapper::SetMarchControlVariates.
  void SetMarchControlVariates(int mode);
  /// vtkMultiChannelVolumeMapper::SetInterpolationType (-1: the volume property's).
  void SetMultiChannelInterpolation(int type);
  void SetSamplesPerRender(int spp);
  void SetInteractiveFrameTime(double seconds);
  void SetProgressiveRefinement(bool on);
  void SetMaximumTotalSamples(int total);
  void SetTargetError(double rmse);
  void SetMacrocellSize(int size);
  void SetBackend(int backend);
  void SetCUDADevice(int device);
  void SetSeed(int seed);
  void SetPixelJitter(bool on);
  void SetShadowMode(int mode);
  void SetShadowCacheSpacing(double voxels);
  void SetAmbientRadiance(double r, double g, double b);
  void SetMaxScatteringDepth(int depth);
  /// vtkMultiChannelVolumeMapper::SetLightingStandInLevel (lighting across
  /// ranks; default -2, automatic). Gathered in ProcessViewRequest's
  /// REQUEST_RENDER, which every rank runs. Off while any process holds an
  /// empty piece (the report says so): the stand-in is put together from
  /// every piece.
  void SetLightingStandInLevel(int level);
  /// vtkMultiChannelVolumeMapper::SetLightingStandInMemoryLimit, in MiB
  /// (the automatic level's limit per rank).
  void SetLightingStandInMemoryLimit(double mib);
  /// vtkMultiChannelVolumeMapper::SetSplitImageWithExactStandIn (default on).
  void SetSplitImageWithExactStandIn(bool on);
  double GetLightingStandInMemory();
  double GetLastLightingStandInGatherTime();
  const char* GetLightingStandInReport();
  void SetGradientShading(bool on);
  void SetShininess(double shininess);
  /// vtkMultiChannelVolumeMapper::SetLightIntensityScale (ParaView's default
  /// 4 pi, see the XML property Light Intensity Scale).
  void SetLightIntensityScale(double scale);
  /// vtkMultiChannelVolumeMapper::SetLightSampling.
  void SetLightSampling(int mode);
  void SetNumberOfChannelAlbedos(int n);
  void SetChannelAlbedo(int channel, double albedo);
  void SetNumberOfChannelAnisotropies(int n);
  void SetChannelAnisotropy(int channel, double g);
  void SetVisibilityOptimization(bool on);
  void SetDeviationWeight(double p);
  void SetOcclusionWeight(double q);
  void SetClutterWeight(double r);
  void SetImportanceEmphasis(double lambda);
  void SetImportanceMergeDistance(double d);
  void SetImportanceSamples(int n);
  void SetOptimizeLightRays(bool on);
  void SetLightRayImportanceSamples(int n);
  void SetLevelOfDetail(int level);
  void SetLevelOfDetailFilter(int filter);
  void SetLevelOfDetailHalfPrecision(bool on);
  /// Mebibytes (the mapper's SetMemoryBudget takes bytes); 0: no cap.
  void SetMemoryBudgetMiB(double mib);
  ///@}

  ///@{
  /**
   * The level the mapper renders while ParaView renders with its level of
   * detail (see the class description): L >= 1, -1 automatic, or 0 for the
   * still level.
   */
  void SetInteractiveLevelOfDetail(int level);
  vtkGetMacro(InteractiveLevelOfDetail, int);
  ///@}

  ///@{
  /**
   * How voxels are read while ParaView renders with its level of detail:
   * INTERACTIVE_NEAREST (default) the nearest voxel (one voxel read per
   * sample instead of trilinear's 8, which on the CPU mostly miss the
   * caches on large levels), INTERACTIVE_AS_STILL the still renders'
   * interpolation (SetMultiChannelInterpolation, or the volume property's).
   * Still renders always use the latter.
   */
  enum
  {
    INTERACTIVE_NEAREST = 0,
    INTERACTIVE_AS_STILL = 1
  };
  void SetInteractiveInterpolation(int mode);
  vtkGetMacro(InteractiveInterpolation, int);
  ///@}

  /**
   * Notes whether this render uses ParaView's level of detail
   * (REQUEST_RENDER with vtkPVRenderView::USE_LOD()) before the superclass
   * hands the mapper its parameters.
   */
  int ProcessViewRequest(
    vtkInformationRequestKey* request_type, vtkInformation* inInfo, vtkInformation* outInfo) override;

  ///@{
  /**
   * Per-channel importance of the visibility optimization as a step in data
   * units: channel c carries importance level L (snapped to 0, 1/4, 1/2,
   * 3/4, 1) where its value is >= threshold T, and 0 below. A channel
   * carries no importance unless both lists have an entry for it, the
   * snapped level is > 0 and the threshold is finite (NaN: none). Missing
   * levels are 0 so that setting thresholds alone never makes a channel
   * important by accident.
   */
  void SetNumberOfChannelImportanceLevels(int n);
  void SetChannelImportanceLevel(int channel, double level);
  void SetNumberOfChannelImportanceThresholds(int n);
  void SetChannelImportanceThreshold(int channel, double threshold);
  ///@}

  ///@{
  /**
   * Per-channel importance as a function of the channel's value (data
   * units), edited in ParaView like an opacity function: properties
   * "Channel 1 Importance" ... "Channel 8 Importance". A function whose
   * values all snap to 0 (the default: 0 everywhere) leaves the channel to
   * the level/threshold lists above; one that reaches 0.125 or more is handed
   * to the mapper (vtkMultiChannelVolumeMapper::SetChannelImportance, which
   * snaps it to 0, 1/4, 1/2, 3/4, 1) and wins over the lists.
   */
  static constexpr int NUMBER_OF_IMPORTANCE_FUNCTIONS = 8;
  void SetChannelImportanceFunction(int channel, vtkPiecewiseFunction* function);
  void SetChannelImportanceFunction1(vtkPiecewiseFunction* f) { this->SetChannelImportanceFunction(0, f); }
  void SetChannelImportanceFunction2(vtkPiecewiseFunction* f) { this->SetChannelImportanceFunction(1, f); }
  void SetChannelImportanceFunction3(vtkPiecewiseFunction* f) { this->SetChannelImportanceFunction(2, f); }
  void SetChannelImportanceFunction4(vtkPiecewiseFunction* f) { this->SetChannelImportanceFunction(3, f); }
  void SetChannelImportanceFunction5(vtkPiecewiseFunction* f) { this->SetChannelImportanceFunction(4, f); }
  void SetChannelImportanceFunction6(vtkPiecewiseFunction* f) { this->SetChannelImportanceFunction(5, f); }
  void SetChannelImportanceFunction7(vtkPiecewiseFunction* f) { this->SetChannelImportanceFunction(6, f); }
  void SetChannelImportanceFunction8(vtkPiecewiseFunction* f) { this->SetChannelImportanceFunction(7, f); }
  ///@}

  ///@{
  /**
   * Read back by the client (information properties).
   */
  int GetTotalSamples();
  /// The mapper's estimated RMSE and PSNR of the current image; -1 where
  /// there is none (no samples yet, or no data on this process).
  double GetEstimatedError();
  double GetEstimatedPSNR();
  int GetConverged();
  int GetNumberOfChannels();
  const char* GetBackendReport();
  /// The level of detail of the mapper's last render, and why.
  int GetLastLevelOfDetail();
  const char* GetLevelOfDetailReport();
  /// The estimator the last render used (the Automatic choice, e.g.
  /// "UnbiasedMarch(1)" or "UnbiasedMarch(0.75, control variates)";
  /// "ExpectedValue" in LOD renders where the choice costs more per sample;
  /// "Collision" for lit volumes).
  const char* GetChosenEstimator();
  const char* GetChannelStatus() { return this->ChannelStatus.c_str(); }
  /// The robust range of every point array and component of the input, as
  /// mcvol-render's "range": "auto" computes it, one line each
  /// ("name\tcomponent\tlo\thi"): where the client spreads a channel's
  /// default transfer functions when it first shows the channel. Under MPI
  /// the whole data set's, after ComputeChannelDefaultRanges(), which every
  /// process must call together (the proxy does, before it reads them).
  const char* GetChannelDefaultRanges();
  void ComputeChannelDefaultRanges();
  double GetImportanceMemory();
  double GetImportanceOverflows();
  ///@}

  ///@{
  /**
   * A small text in the view's upper right corner (default on; ParaView
   * puts the colour legend in the lower right and the orientation axes in
   * the lower left): the samples
   * per pixel, the estimated PSNR and "refining" or "converged", or why
   * nothing is drawn (ChannelStatus). It is read from the mapper as the
   * view draws its annotations, after the volume, so it describes the image
   * it sits on. A process that holds no data (the client of a pvserver)
   * shows the text it was last given by SetRemoteProgressSummary, which the
   * GUI reads from the server through vtkMultiChannelProgressProbe after
   * every render.
   */
  void SetProgressAnnotation(bool on);
  vtkGetMacro(ProgressAnnotation, bool);
  /// The annotation's text as it would be drawn now (empty when hidden).
  std::string BuildProgressSummary();
  /// The rendering process's text, for a copy that holds no data. Not a
  /// change of the representation: nothing restarts.
  void SetRemoteProgressSummary(const std::string& text) { this->RemoteProgressSummary = text; }
  const std::string& GetRemoteProgressSummary() const { return this->RemoteProgressSummary; }
  /// The same, for the information property ProgressText.
  const char* GetProgressSummary();
  ///@}

  vtkMultiChannelVolumeMapper* GetMultiChannelMapper();

protected:
  vtkMultiChannelVolumeRepresentation();
  ~vtkMultiChannelVolumeRepresentation() override;

  void UpdateMapperParameters() override;
  int RequestData(vtkInformation*, vtkInformationVector**, vtkInformationVector*) override;
  bool AddToView(vtkView* view) override;
  bool RemoveFromView(vtkView* view) override;
  void UpdateChannelImportance(int numChannels);
  /// Whether this process has data to render (not the client of a pvserver).
  bool HoldsData();

  int ChannelSource = ARRAYS;
  unsigned int Seed = 0;
  std::vector<std::string> ChannelArrays;
  std::string ChannelComponentsArray;
  std::vector<vtkSmartPointer<vtkScalarsToColors>> ChannelLookupTables;
  std::vector<int> ChannelLookupTableIndices;
  std::vector<double> MixWeights;
  std::vector<double> Albedos;
  std::vector<double> Anisotropies;
  std::vector<double> ImportanceLevels;
  std::vector<double> ImportanceThresholds;
  // Each channel keeps one function object for good, because the mapper
  // starts its image over when handed a different object; its points are
  // rewritten only when the values change (this runs before every render,
  // and every rewrite makes the mapper resample the function).
  struct ImportanceStep
  {
    vtkSmartPointer<vtkPiecewiseFunction> Function;
    double Level = 0.0;
    double Threshold = 0.0;
  };
  std::vector<ImportanceStep> ImportanceSteps;
  vtkSmartPointer<vtkPiecewiseFunction> ImportanceFunctions[NUMBER_OF_IMPORTANCE_FUNCTIONS];
  std::string ChannelStatus;
  std::string ChannelDefaultRanges;
  vtkMTimeType ChannelDefaultRangesTime = 0;
  bool ChannelDefaultRangesStale = true; ///< not computed yet
  std::string BackendReport;
  std::string LevelOfDetailReport;
  std::string ChosenEstimator;
  int LevelOfDetail = 0;
  int InteractiveLevelOfDetail = 1;
  int InteractiveInterpolation = INTERACTIVE_NEAREST;
  int StillInterpolation = -1; // SetMultiChannelInterpolation's (-1: the volume property's)
  bool RenderingWithLOD = false; // this render is one with ParaView's LOD
  bool ProgressAnnotation = true;
  int LightingStandInLevel = -2;    // as set (automatic); the mapper's is -1 while a piece is empty
  bool EmptyPieceSomewhere = false; // some process holds no data (RequestData)
  vtkSmartPointer<vtkTextActor> ProgressActor;
  std::string ProgressSummaryValue;
  std::string RemoteProgressSummary;

private:
  vtkMultiChannelVolumeRepresentation(const vtkMultiChannelVolumeRepresentation&) = delete;
  void operator=(const vtkMultiChannelVolumeRepresentation&) = delete;
};

#endif
