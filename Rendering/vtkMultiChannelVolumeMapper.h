// SPDX-License-Identifier: BSD-3-Clause
/**
 * @class   vtkMultiChannelVolumeMapper
 * @brief   Progressive Monte Carlo volume mapper for N-channel image data.
 *
 * vtkMultiChannelVolumeMapper renders a vtkImageData whose point data holds N
 * scalar channels (1 to 32), each with its own colour and opacity transfer
 * function, by multi-density Woodcock (delta) tracking (Sahistan et al.). It
 * runs on NVIDIA GPUs (CUDA) or on the CPU (OpenMP); SetBackend picks the
 * backend: Auto (default) takes CUDA when this build has the CUDA backend and
 * a usable device, otherwise the CPU; GetBackendReport() says which and why.
 * With the CUDA backend the channels are uploaded once per data change, the
 * macrocell and majorant grids are built on the GPU (one channel's majorants
 * when its transfer function changes) and the image comes back once per
 * render.
 *
 * Rendering is progressive: every Render() adds SamplesPerPixel samples per
 * pixel to a running mean, which is drawn over the frame. The mean starts over
 * whenever anything that changes the image changes: the camera, the volume's
 * matrix, the input data, the vtkVolumeProperty or any transfer function, a
 * parameter of this mapper, the viewport size, or the depth of the opaque
 * geometry drawn before the volume (rays stop at that depth, so geometry
 * inside the volume occludes it correctly). Rendering again with nothing
 * changed refines the image; GetTotalSamples() says how far.
 *
 * Channels: by default the components of the point scalars (as selected with
 * SetScalarMode/SelectScalarArray) are the channels. Alternatively list N
 * single-component point arrays with AddChannelArray(). Supported types are
 * unsigned char, short, unsigned short, float and double; the data is read in
 * place, never copied. Cell data is not supported.
 *
 * Transfer functions: channel i < 4 takes its colour (RGB or gray), scalar
 * opacity and opacity unit distance from the vtkVolumeProperty's component i,
 * as VTK's other mappers do with IndependentComponentsOn (the default).
 * SetChannelColor,
 * SetChannelScalarOpacity and SetChannelScalarOpacityUnitDistance override
 * the property for one channel; channels 4 and above (vtkVolumeProperty holds
 * at most VTK_MAX_VRCOMP = 4) must be given both functions this way. Each
 * function is sampled over the channel's finite data range.
 *
 * Dependent components (vtkVolumeProperty::IndependentComponentsOff(), VTK's
 * convention) render one pre-classified RGBA volume: with 4 components RGB
 * come from components 0-2 (unsigned char: value / 255; other types: each
 * component scaled over its finite range to [0, 1], as VTK's GPU ray caster
 * does, a constant component clamped to [0, 1]) and the opacity from
 * component 3 through the scalar opacity function of component 0; with 2
 * components the colour is component 0 through the colour function and the
 * opacity component 1 through the scalar opacity function (both of
 * component 0; the mapper's SetChannelColor/SetChannelScalarOpacity/
 * SetChannelScalarOpacityUnitDistance of channel 0 override them). Each
 * voxel's opacity a becomes the extinction -ln(1 - min(a, 1 - 2^-20)) / unit
 * distance and its colour is stored extinction-weighted; sampling then
 * interpolates extinction and extinction-weighted colour (Kraus and Buerger,
 * Sec. 3.3). The mapper keeps the classified copy (16 bytes a voxel,
 * GetClassifiedMemory()) and rebuilds it only when the data, the functions'
 * values or the unit distance change (GetNumberOfClassifications()). NaN
 * voxels are transparent. ChannelBlendMode and mix weights do not matter
 * for the one channel; lighting works as for scalar channels; importance
 * functions are ignored (there is no scalar to look them up by). One
 * component renders as with IndependentComponentsOn; 3 components, or
 * channel arrays listed with AddChannelArray, are an error.
 *
 * Levels of detail (SetLevelOfDetail: 0 full resolution, the default; L > 0
 * a pre-classified copy with every axis halved L times; -1 automatic by the
 * pixel footprint) trade resolution for speed and memory, and
 * SetMemoryBudget makes a volume that does not fit render from the finest
 * level that does (GetLevelOfDetailReport() says which and why).
 *
 * How channels combine is SetChannelBlendMode (density, max, mix, composite).
 * This is separate from, and ignores, vtkVolumeMapper::SetBlendMode.
 * The vtkVolumeProperty's interpolation type (nearest, linear, or cubic
 * with SetInterpolationTypeToCubic) selects the sampling, and ShadeOn()
 * lights the volume with the renderer's lights
 * (Documentation/user-guide/lighting.md). Cropping, clipping planes, gradient opacity, 2D transfer
 * functions and vtkVolumeMapper::SetBlendMode are not used: a render with
 * any of them set warns once, naming them (GetIgnoredSettings()).
 *
 * Bad input (no input, no scalars, an unsupported type, an empty extent, more
 * than 32 channels, a channel without transfer functions) is reported with
 * vtkErrorMacro and nothing is drawn.
 *
 * @sa vtkVolumeMapper vtkVolumeProperty vtkFixedPointVolumeRayCastMapper
 */

#ifndef vtkMultiChannelVolumeMapper_h
#define vtkMultiChannelVolumeMapper_h

#include "mcvolRenderingMonteCarloModule.h" // For export macro
#include "vtkVolumeMapper.h"

#include <memory> // For std::unique_ptr
#include <string> // For std::string

#ifndef __VTK_WRAP__
namespace mcvol
{
class Accumulator;
struct Camera;
struct RenderSettings;
class Renderer;
class Scene;
}
#endif

class vtkColorTransferFunction;
class vtkMultiProcessController;
class vtkFloatArray;
class vtkImageData;
class vtkPiecewiseFunction;
class vtkRenderer;
class vtkVolume;
class vtkWindow;

class MCVOLRENDERINGMONTECARLO_EXPORT vtkMultiChannelVolumeMapper : public vtkVolumeMapper
{
public:
  static vtkMultiChannelVolumeMapper* New();
  vtkTypeMacro(vtkMultiChannelVolumeMapper, vtkVolumeMapper);
  void PrintSelf(ostream& os, vtkIndent indent) override;

  enum ChannelLimits
  {
    /// Most channels a volume may have.
    MAX_CHANNELS = 32
  };

  enum ChannelBlendModes
  {
    MC_DENSITY_BLEND = 0,
    MC_MAX_BLEND = 1,
    MC_MIX_BLEND = 2,
    MC_COMPOSITE_BLEND = 3
  };

  ///@{
  /**
   * How the channels combine (Sahistan et al., Sections 4.1, 4.2):
   * - MC_DENSITY_BLEND (default): extinctions add; a collision picks a channel
   *   in proportion to its extinction (physically based).
   * - MC_MAX_BLEND: at each point only the channel of largest extinction.
   * - MC_MIX_BLEND: max extinction, colour mixed with the channels' weights
   *   (SetMixWeight).
   * - MC_COMPOSITE_BLEND: each channel rendered alone and the images added.
   * Named "ChannelBlendMode" so as not to clash with vtkVolumeMapper's
   * BlendMode (composite/MIP/...), which this mapper ignores.
   */
  vtkSetClampMacro(ChannelBlendMode, int, MC_DENSITY_BLEND, MC_COMPOSITE_BLEND);
  vtkGetMacro(ChannelBlendMode, int);
  void SetChannelBlendModeToDensity() { this->SetChannelBlendMode(MC_DENSITY_BLEND); }
  void SetChannelBlendModeToMax() { this->SetChannelBlendMode(MC_MAX_BLEND); }
  void SetChannelBlendModeToMix() { this->SetChannelBlendMode(MC_MIX_BLEND); }
  void SetChannelBlendModeToComposite() { this->SetChannelBlendMode(MC_COMPOSITE_BLEND); }
  const char* GetChannelBlendModeAsString();
  ///@}

  enum TrackingMethods
  {
    ONE_DDA = 0,
    N_DDA = 1
  };

  ///@{
  /**
   * Macrocell traversal: ONE_DDA (default) walks one DDA over the macrocells,
   * and in each cell every channel takes Woodcock steps with its own majorant;
   * N_DDA walks one DDA per channel (Sahistan et al., Sections 4.5 and 4.4).
   * Both give the same image in expectation.
   */
  vtkSetClampMacro(TrackingMethod, int, ONE_DDA, N_DDA);
  vtkGetMacro(TrackingMethod, int);
  void SetTrackingMethodToOneDDA() { this->SetTrackingMethod(ONE_DDA); }
  void SetTrackingMethodToNDDA() { this->SetTrackingMethod(N_DDA); }
  const char* GetTrackingMethodAsString();
  ///@}

  enum Estimators
  {
    COLLISION_ESTIMATOR = 0,
    EXPECTED_VALUE_ESTIMATOR = 1,
    UNBIASED_MARCH_ESTIMATOR = 2,
    AUTOMATIC_ESTIMATOR = 3
  };

  ///@{
  /**
   * What each unlit camera ray scores. EXPECTED_VALUE_ESTIMATOR (default)
   * scores every tentative collision of the blend's majorant with the
   * transmittance so far (ratio tracking of the emission) and stops by
   * Russian roulette; COLLISION_ESTIMATOR tracks to the first real collision
   * and scores its colour (the papers' estimator; TrackingMethod then picks
   * 1-DDA or N-DDA). UNBIASED_MARCH_ESTIMATOR marches each non-empty
   * macrocell in jittered strata (MarchSamplesPerVoxel per voxel) and
   * weights the emission by an unbiased power-series transmittance
   * (Kettunen et al. 2021): about twice a ray march's samples per frame and
   * far less noise per frame; sooner than expected value to a given error on
   * dense data such as microscopy stacks, later on sparse, thin data
   * (Documentation/performance.md). Its samples are not bounded (a sample
   * may be negative), their mean is. All three are unbiased; the
   * expected-value estimator reaches a given error several times sooner than
   * the collision estimator (Documentation/performance.md). Lit volumes
   * (ShadeOn) take the expected-value estimator of lit camera rays (the
   * emission weighted as above, the scattered light and its shadow rays at
   * one real collision per path) or the collision estimator; the unbiased
   * march lights nothing and uses the collision estimator there. The
   * composite blend mode and the visibility optimization always use the
   * collision estimator. A change restarts the progressive image.
   *
   * AUTOMATIC_ESTIMATOR picks, per scene, the one of expected value and the
   * unbiased march at 1/16 to 4 strata per voxel (MarchSamplesPerVoxel
   * is then not used; with PixelJitter off, each rate with and without
   * control variates, see MarchControlVariates, and a rate between two
   * where the lower needs two samples and the higher one) whose predicted
   * time to the target is lowest, from a
   * small pilot image of each at the first render of the data and transfer
   * functions (mcvol::chooseEstimator, Rendering/Core/mcvol/
   * EstimatorChoice.h), aiming at TargetError where one is set, else at
   * 35 dB PSNR (RMSE 0.0178). The cost is a model of the work the render counts,
   * fitted per backend, not the pilot's wall time, so that a fixed seed gives
   * the same choice and image on a backend whatever the load. The choice is
   * kept while the camera, the window size and the level of detail change,
   * and made again when the data, a transfer function, the blend mode, the
   * lighting, the backend, the seed, MinimumSamplesPerVoxel, TargetError,
   * PixelJitter or MarchControlVariates changes. The pilots cost about a
   * frame or two once per choice (Documentation/performance.md).
   * GetChosenEstimatorAsString() says what was chosen and
   * GetEstimatorReport() why. When a choice is made again (after an edit)
   * on the CUDA backend, the render's first batch is rendered with the
   * previous choice's estimator while the pilots run, and kept where the
   * same estimator is chosen (mcvol::ChoiceAhead; the image is the same as
   * without, and the report says whether it was kept). A lit volume takes
   * the expected-value estimator without pilots (it reached 35 dB sooner
   * than the collision estimator on every lit benchmark scene,
   * Documentation/performance.md).
   */
  vtkSetClampMacro(Estimator, int, COLLISION_ESTIMATOR, AUTOMATIC_ESTIMATOR);
  vtkGetMacro(Estimator, int);
  void SetEstimatorToCollision() { this->SetEstimator(COLLISION_ESTIMATOR); }
  void SetEstimatorToExpectedValue() { this->SetEstimator(EXPECTED_VALUE_ESTIMATOR); }
  void SetEstimatorToUnbiasedMarch() { this->SetEstimator(UNBIASED_MARCH_ESTIMATOR); }
  void SetEstimatorToAutomatic() { this->SetEstimator(AUTOMATIC_ESTIMATOR); }
  const char* GetEstimatorAsString();
  /**
   * The estimator the last render's camera rays used: "Collision",
   * "ExpectedValue", "UnbiasedMarch(R)" with R strata per voxel (the plain
   * strata) or "UnbiasedMarch(R, control variates)"; under
   * AUTOMATIC_ESTIMATOR the choice made. Composite blending and the
   * visibility optimization report "Collision" whatever is set, lit volumes
   * "Collision" for the unbiased march. "none" before the first render.
   */
  const char* GetChosenEstimatorAsString();
  ///@{
  /**
   * Interactive renders (the user moving the camera). VTK's interactors raise
   * the render window's DesiredUpdateRate while the user drags and set it
   * back to the still rate when the drag ends, which renders once more; a
   * render whose window's DesiredUpdateRate is at least InteractiveUpdateRate
   * (default 1, vtkSmartVolumeMapper's rule and default) is interactive.
   * SetInteractiveRendering(1) makes every render interactive and 0 none;
   * -1 (default) asks the window. The ParaView representation sets 1 for
   * the renders ParaView makes with its level of detail, -1 otherwise.
   *
   * What changes: under AUTOMATIC_ESTIMATOR, an interactive render takes the
   * expected-value estimator where the choice's sample is predicted to cost
   * more than expected value's (one sample of the unbiased march costs
   * several expected-value samples), so the camera moves at expected
   * value's frame rate; the first still render restarts the image with the
   * choice, which then converges at its own speed. Nothing changes for an
   * estimator set by hand.
   * Setting InteractiveRendering does not restart the image by itself.
   */
  void SetInteractiveRendering(int mode) { this->InteractiveRendering = mode < -1 ? -1 : (mode > 1 ? 1 : mode); }
  vtkGetMacro(InteractiveRendering, int);
  /// Clamped to [0.0, VTK_DOUBLE_MAX]; NaN is an error (the value stays).
  virtual void SetInteractiveUpdateRate(double value);
  vtkGetMacro(InteractiveUpdateRate, double);
  /// Whether the last render was interactive (see SetInteractiveRendering).
  vtkGetMacro(LastRenderInteractive, bool);
  ///@}
  /// The automatic choice's pilots, one line per candidate (estimated
  /// variance, modelled cost per sample, their product; the chosen one
  /// marked) and their time; a sentence when no choice was made.
  const char* GetEstimatorReport();
  /// Automatic choices that rendered pilots so far (a choice is kept while
  /// only the camera moves; tests count on it).
  int GetNumberOfEstimatorChoices();

  /**
   * The VTK settings the last render found set and did not use, separated by
   * "; " (empty when none): cropping, clipping planes,
   * vtkVolumeMapper::SetBlendMode other than composite (the channels combine
   * by SetChannelBlendMode), a gradient opacity function that is enabled and
   * not constant 1 (per property component), 2D transfer functions. The
   * render warns when this text changes to a non-empty one, so a setting
   * left on warns once, not at every frame.
   */
  const char* GetIgnoredSettings();
  ///@}

  ///@{
  /**
   * Expected-value estimator: the fewest tentative collisions per voxel
   * length along a ray in every macrocell that is not empty (default 0: as
   * many as the majorant gives). Any value keeps the image unbiased (ratio
   * tracking needs only a collision rate at least the extinction); more
   * collisions in optically thin cells sample thin, faint structures more
   * often, at more cost per sample (Documentation/performance.md). No
   * effect on the collision estimator. A change
   * restarts the progressive image.
   */
  /// Clamped to [0.0, 1e6]; NaN is an error (the value stays).
  virtual void SetMinimumSamplesPerVoxel(double value);
  vtkGetMacro(MinimumSamplesPerVoxel, double);
  ///@}

  ///@{
  /**
   * Unbiased-march estimator: strata per voxel length along a ray in every
   * macrocell that is not empty (default 2, the ray marcher's default step
   * of half a voxel; 1 and 3 reach a given error later on the microscopy
   * scene, Documentation/performance.md). Clamped to [0.01, 1024]. No effect
   * on the other
   * estimators. A change restarts the progressive image.
   */
  /// Clamped to [0.01, 1024.0]; NaN is an error (the value stays).
  virtual void SetMarchSamplesPerVoxel(double value);
  vtkGetMacro(MarchSamplesPerVoxel, double);
  ///@}

  enum MarchControlVariatesModes
  {
    MARCH_CONTROL_VARIATES_NEVER = 0,
    MARCH_CONTROL_VARIATES_BY_RATE = 1,
    MARCH_CONTROL_VARIATES_ALWAYS = 2
  };

  ///@{
  /**
   * Unbiased-march estimator with PixelJitter off (rays through the pixel
   * centres): whether it takes control variates (a trapezoid march through
   * every stratum's ends composited exactly, chance left only the residual;
   * more time per sample for much less noise after one sample;
   * Documentation/performance.md). BY_RATE (default): from 1 stratum per voxel
   * (mcvol::kMarchControlVariateRate), the plain strata below. NEVER: the
   * plain strata at every rate. ALWAYS: control variates at every rate.
   * With jittered pixels the march always takes the plain strata.
   * Under AUTOMATIC_ESTIMATOR, BY_RATE offers every candidate rate both ways
   * and the choice decides; NEVER and ALWAYS fix the variant. A change
   * restarts the progressive image.
   */
  vtkSetClampMacro(MarchControlVariates, int, MARCH_CONTROL_VARIATES_NEVER, MARCH_CONTROL_VARIATES_ALWAYS);
  vtkGetMacro(MarchControlVariates, int);
  void SetMarchControlVariatesToNever() { this->SetMarchControlVariates(MARCH_CONTROL_VARIATES_NEVER); }
  void SetMarchControlVariatesToByRate() { this->SetMarchControlVariates(MARCH_CONTROL_VARIATES_BY_RATE); }
  void SetMarchControlVariatesToAlways() { this->SetMarchControlVariates(MARCH_CONTROL_VARIATES_ALWAYS); }
  ///@}

  enum SampleSequences
  {
    INDEPENDENT_SEQUENCE = 0,
    SOBOL_SEQUENCE = 1
  };

  ///@{
  /**
   * Where each pixel's samples draw the random numbers of their leading
   * decisions (sub-pixel position, the camera ray's first free flights and
   * tentative collisions, lit: its scatter test and ambient direction):
   * SOBOL_SEQUENCE (default) from Owen-scrambled Sobol' points with
   * per-pixel index shuffling (Burley 2020), INDEPENDENT_SEQUENCE from the
   * pseudo-random stream like the rest of each path. Both are unbiased and
   * reproducible for a fixed Seed whatever the thread count; the Sobol'
   * points lower the error at a given sample count. A change restarts the
   * progressive image.
   */
  vtkSetClampMacro(SampleSequence, int, INDEPENDENT_SEQUENCE, SOBOL_SEQUENCE);
  vtkGetMacro(SampleSequence, int);
  void SetSampleSequenceToIndependent() { this->SetSampleSequence(INDEPENDENT_SEQUENCE); }
  void SetSampleSequenceToSobol() { this->SetSampleSequence(SOBOL_SEQUENCE); }
  const char* GetSampleSequenceAsString();
  ///@}

  ///@{
  /**
   * Samples per pixel added by each Render() (default 1, 1..4096).
   */
  vtkSetClampMacro(SamplesPerPixel, int, 1, 4096);
  vtkGetMacro(SamplesPerPixel, int);
  ///@}

  ///@{
  /**
   * Time-budgeted progression: with a budget > 0 (seconds), each Render()
   * traces as many samples per pixel as fit in it, from the measured cost of
   * the previous batches (a moving average, kept when the image restarts:
   * a moved camera costs about what the last view did), at least 1 and at
   * most 4096; the first batch ever has SamplesPerPixel samples. 0 (the
   * default): SamplesPerPixel every render. MaximumTotalSamples still caps
   * the total. The image after a given number of samples is the same
   * whatever the batches (samples are numbered per pixel), up to float
   * rounding of the running mean. GetLastSamplesPerRender() gives the last
   * batch. The budget covers tracing, not drawing or uploads.
   */
  /// Clamped to [0.0, 3600.0]; NaN is an error (the value stays).
  virtual void SetInteractiveFrameTime(double value);
  vtkGetMacro(InteractiveFrameTime, double);
  vtkGetMacro(LastSamplesPerRender, int);
  ///@}

  ///@{
  /**
   * Progressive refinement (default on): every Render() with nothing changed
   * adds SamplesPerPixel samples to the running mean. Off, the image is
   * traced once per change, with SamplesPerPixel samples, and redrawn as it
   * is otherwise (the same seed gives the same image).
   */
  vtkSetMacro(Progressive, bool);
  vtkGetMacro(Progressive, bool);
  vtkBooleanMacro(Progressive, bool);
  ///@}

  ///@{
  /**
   * Largest number of samples per pixel the running mean accumulates
   * (default 0: no limit). Once reached, Render() redraws the image without
   * tracing; IsConverged() says so. The last batch is cut so that the total
   * is exactly this number.
   */
  vtkSetClampMacro(MaximumTotalSamples, int, 0, VTK_INT_MAX);
  vtkGetMacro(MaximumTotalSamples, int);
  ///@}

  enum TransferFunctionRangeModes
  {
    DATA_RANGE = 0,
    FUNCTION_RANGE = 1
  };
  ///@{
  /**
   * Range over which each channel's transfer functions are tabulated:
   * DATA_RANGE (default) the channel's finite data range, clipped to the
   * functions' own range when the functions clamp (beyond it the table
   * would hold only their end values: the same image, with the entries where
   * the functions change, so a few outliers in 16-bit data do not coarsen
   * the table); FUNCTION_RANGE the union of the colour, opacity and (with
   * the visibility optimization on) importance functions' own ranges
   * (values beyond it take the end values, as VTK's clamped functions do). Use
   * FUNCTION_RANGE when the same functions must give the same table on data
   * split over several processes (the ParaView plugin does).
   */
  vtkSetClampMacro(TransferFunctionRangeMode, int, DATA_RANGE, FUNCTION_RANGE);
  vtkGetMacro(TransferFunctionRangeMode, int);
  ///@}

  enum ErrorEstimateLimits
  {
    /// Samples per pixel the image must have before TargetError can stop
    /// it: with fewer, the halves of the estimate are too short for a lucky
    /// start (all early samples alike) not to stop it too soon.
    TARGET_ERROR_MINIMUM_SAMPLES = 16
  };

  ///@{
  /**
   * Estimated error of the current image: the root mean square, over pixels
   * and the premultiplied linear R, G and B in [0, 1] (as
   * GetAccumulatedImage() gives them, before 8-bit quantisation; alpha is
   * left out), of the difference between the image and the converged one it
   * estimates. Computed without a reference from two interleaved halves of
   * the samples (even and odd sample index; see mcvol::Accumulator::
   * estimatedMSE), it falls like 1/sqrt(GetTotalSamples()). -1 when there
   * is no estimate: fewer than 2 samples, no image yet, or the ray-marching
   * subclass (its image is traced once, deterministically). The mapper always
   * keeps the halves: one more float RGBA image and a few additions per
   * sample (Documentation/performance.md gives the cost).
   * GetEstimatedPSNR() is 20 log10(1 / RMSE) in dB (peak 1), 300 when the
   * estimate is exactly 0 (nothing visible), -1 when there is none.
   */
  double GetEstimatedError();
  double GetEstimatedPSNR();
  ///@}

  ///@{
  /**
   * Adaptive stopping: with a target > 0 (an RMSE, as GetEstimatedError),
   * the image is converged, and Render() redraws it without tracing, once
   * its estimated error is at most the target and it has at least
   * TARGET_ERROR_MINIMUM_SAMPLES samples per pixel. MaximumTotalSamples
   * still caps the total (whichever comes first). 0 (the default): off.
   * Like every mapper parameter, a new value restarts the image.
   */
  /// Clamped to [0.0, VTK_DOUBLE_MAX]; NaN is an error (the value stays).
  virtual void SetTargetError(double value);
  vtkGetMacro(TargetError, double);
  ///@}

  /**
   * True when another Render() would not trace: MaximumTotalSamples is
   * reached, the estimated error reached TargetError, or progressive
   * refinement is off and the image is traced, and nothing that resets the
   * image has changed since the last Render() (a change is only noticed at
   * the next Render()).
   */
  bool IsConverged();

  ///@{
  /**
   * Seed of the random sequences (default 0). The same seed, scene and
   * backend give the same image.
   */
  vtkSetMacro(Seed, unsigned int);
  vtkGetMacro(Seed, unsigned int);
  ///@}

  ///@{
  /**
   * Added to Seed when this process renders its own piece of a volume split
   * over processes (sort-last; default 0), so that the processes' estimates
   * of one pixel are independent: "front over back" is unbiased only for
   * independent estimates (E[(1 - a1) c2] = (1 - E[a1]) E[c2]). Not added
   * while the processes split the image (SplitImageWithExactStandIn), whose
   * pixels they do not share: the composite is then the single-process
   * image of Seed. ParaView's representation sets it per rank.
   */
  vtkSetMacro(ProcessSeedOffset, unsigned int);
  vtkGetMacro(ProcessSeedOffset, unsigned int);
  ///@}

  ///@{
  /**
   * Spread each pixel's Monte Carlo samples over the pixel's area
   * (anti-aliasing; default on). Off, every sample goes through the pixel
   * centre, as vtkMultiChannelRayMarchMapper's rays do: use it to compare the
   * two image for image.
   */
  vtkSetMacro(PixelJitter, bool);
  vtkGetMacro(PixelJitter, bool);
  vtkBooleanMacro(PixelJitter, bool);
  ///@}

  ///@{
  /**
   * Edge of a macrocell of the majorant grid, in voxels (default 8, 1..256).
   */
  vtkSetClampMacro(MacrocellSize, int, 1, 256);
  vtkGetMacro(MacrocellSize, int);
  ///@}

  enum Backends
  {
    BACKEND_AUTO = 0,
    BACKEND_CPU = 1,
    BACKEND_CUDA = 2
  };

  ///@{
  /**
   * Where rays are traced. BACKEND_AUTO (default) takes CUDA when a usable
   * device exists and the CPU otherwise; BACKEND_CUDA without a device is an
   * error (nothing drawn).
   */
  vtkSetClampMacro(Backend, int, BACKEND_AUTO, BACKEND_CUDA);
  vtkGetMacro(Backend, int);
  void SetBackendToAuto() { this->SetBackend(BACKEND_AUTO); }
  void SetBackendToCPU() { this->SetBackend(BACKEND_CPU); }
  void SetBackendToCUDA() { this->SetBackend(BACKEND_CUDA); }
  const char* GetBackendAsString();

  ///@{
  /**
   * The CUDA device to render on (default -1: the process's rank on its
   * node, from OMPI_COMM_WORLD_LOCAL_RANK, MPI_LOCALRANKID, MPI_LOCAL_RANK
   * or SLURM_LOCALID, modulo the visible devices, so that the ranks of
   * `mpiexec -n 2 pvbatch` on a two-GPU node take one GPU each; device 0
   * without MPI). CUDA_VISIBLE_DEVICES decides which devices are visible
   * and how they are numbered. GetBackendReport() names the device taken.
   */
  vtkSetClampMacro(CUDADevice, int, -1, 1023);
  vtkGetMacro(CUDADevice, int);
  ///@}
  ///@}

  /**
   * Name of the backend in use ("cpu", "cuda", ...): the one the last render
   * used, or the one SetBackend would pick now if none has rendered yet.
   * "none" when the requested backend is not available.
   */
  const char* GetActiveBackendName();

  /**
   * A sentence on the backend choice, e.g. "CUDA backend (auto: CUDA device
   * <device name>)" or "CPU backend (auto: no usable CUDA device
   * (...))", or the error when the requested backend is not available.
   */
  const char* GetBackendReport();

  ///@{
  /**
   * Lighting (with vtkVolumeProperty::ShadeOn(), VTK's convention; with
   * ShadeOff the volume is pure emission-absorption and none of this costs
   * anything). The renderer's switched-on lights are used (VTK creates a
   * headlight when the renderer has none, unless AutomaticLightCreationOff):
   * positional lights as point lights at their position, the others as
   * directional lights from their position towards their focal point, with
   * their intensity and diffuse colour. A real collision with channel c
   * scatters with probability ChannelAlbedo(c) (default 1) and otherwise
   * emits the channel's colour; scattering samples every light through a
   * shadow ray and the ambient radiance through the Henyey-Greenstein phase
   * function of anisotropy ChannelAnisotropy(c) (default 0).
   */
  void SetChannelAlbedo(int channel, double albedo);
  double GetChannelAlbedo(int channel);
  void SetChannelAnisotropy(int channel, double g);
  double GetChannelAnisotropy(int channel);
  /// Environment radiance arriving from every direction (default 0.2 grey).
  /// Each component finite and >= 0; anything else (NaN, Inf, negative) is
  /// refused with an error and the radiance stays.
  virtual void SetAmbientRadiance(double r, double g, double b);
  virtual void SetAmbientRadiance(const double rgb[3]) { this->SetAmbientRadiance(rgb[0], rgb[1], rgb[2]); }
  vtkGetVector3Macro(AmbientRadiance, double);
  /**
   * CACHED_SHADOWS: each directional light's transmittance is computed once
   * on a grid of nodes ShadowCacheSpacing voxels apart and interpolated,
   * instead of a shadow ray per scattering event: a shadowed frame costs
   * about what a frame without shadows costs, for a bias (shadow edges
   * finer than the spacing blur) that Documentation/performance.md
   * measures. The grid is rebuilt when the data, a transfer function, the
   * blend or a light's direction changes (a light that follows the camera:
   * every camera move). Point lights and the ambient light keep ratio
   * tracking, as do post-render composite blending, light rays under the
   * visibility optimization and a piece rendered sort-last across
   * processes (GetIgnoredSettings names the first two). The ray-marching
   * mapper looks up the same grid.
   */
  enum ShadowModes
  {
    NO_SHADOWS = 0,
    RATIO_TRACKING_SHADOWS = 1, ///< smooth transmittance (default)
    DELTA_TRACKING_SHADOWS = 2, ///< binary, as Sahistan et al.'s viewer
    CACHED_SHADOWS = 3          ///< a grid of transmittance per light (biased, fast)
  };
  vtkSetClampMacro(ShadowMode, int, NO_SHADOWS, CACHED_SHADOWS);
  vtkGetMacro(ShadowMode, int);
  /// Node spacing of the CACHED_SHADOWS grid, voxels: clamped to [0.5, 64],
  /// default 2. Smaller is sharper and costs more memory (4 bytes a node,
  /// per directional light) and time per rebuild. NaN is an error (the
  /// value stays).
  virtual void SetShadowCacheSpacing(double voxels);
  vtkGetMacro(ShadowCacheSpacing, double);
  /// Scattering events per path: 1 is single scattering (default).
  vtkSetClampMacro(MaxScatteringDepth, int, 1, 1024);
  vtkGetMacro(MaxScatteringDepth, int);
  /// The Blinn-Phong term on the extinction gradient (Lerzer and Dachsbacher), default off.
  vtkSetMacro(GradientShading, bool);
  vtkGetMacro(GradientShading, bool);
  vtkBooleanMacro(GradientShading, bool);
  /// Clamped to [0.0, 1e4]; NaN is an error (the value stays).
  virtual void SetShininess(double value);
  vtkGetMacro(Shininess, double);
  ///@}

  ///@{
  /**
   * How the renderer's lights enter. LightIntensityScale multiplies every
   * light's intensity (default 1: physical units, in which an isotropic
   * scatterer under a light of intensity 4 pi reflects about the light's
   * colour). Programs whose lights are set up for surface shading, where
   * intensity 1 means "full brightness", scale by 4 pi; the ParaView
   * representation does (its property Light Intensity Scale). Both mappers
   * apply it, so they keep agreeing.
   *
   * LightSampling: ALL_LIGHTS (default) traces one shadow ray per light at
   * every scattering event; ONE_LIGHT traces one, towards a light chosen
   * with probability proportional to its radiance and weighted by the
   * inverse of that probability. Both are unbiased and converge to the same
   * image; ONE_LIGHT costs one light's time per sample whatever the number
   * of lights (ParaView's light kit has five), for somewhat more noise per
   * sample where lights cast different shadows. The ray-marching mapper
   * always sums every light (it is deterministic).
   */
  virtual void SetLightIntensityScale(double value);
  vtkGetMacro(LightIntensityScale, double);
  enum LightSamplingModes
  {
    ALL_LIGHTS = 0,
    ONE_LIGHT = 1
  };
  vtkSetClampMacro(LightSampling, int, ALL_LIGHTS, ONE_LIGHT);
  vtkGetMacro(LightSampling, int);
  void SetLightSamplingToAllLights() { this->SetLightSampling(ALL_LIGHTS); }
  void SetLightSamplingToOneLight() { this->SetLightSampling(ONE_LIGHT); }
  ///@}

  ///@{
  /**
   * Weight of a channel in MC_MIX_BLEND (default 1, >= 0). Weights are
   * normalised to sum 1; all zero means equal weights.
   */
  void SetMixWeight(int channel, double weight);
  double GetMixWeight(int channel);
  ///@}

  enum MixColorModes
  {
    MIX_AVERAGE = 0,
    MIX_EQUATION_10 = 1
  };

  ///@{
  /**
   * The colour of MC_MIX_BLEND at a point (extinction is max_n sigma_n either
   * way):
   * - MIX_AVERAGE (default): sum_n w_n sigma_n c_n / sum_n w_n sigma_n, the
   *   weighted average of the colours of the channels present there. A
   *   channel alone keeps its full colour whatever the number of channels.
   * - MIX_EQUATION_10: sum_n w_n sigma_n c_n / max_n sigma_n with the weights
   *   normalised to sum 1, as Sahistan et al. publish it. With N equal
   *   weights a channel alone shows 1/N of its colour.
   * Both are the same where the present channels have equal extinction and
   * their weights sum to 1. The ray-marching mapper follows the same setting
   * (with opacities in place of extinctions in its opacity model).
   */
  vtkSetClampMacro(MixColorMode, int, MIX_AVERAGE, MIX_EQUATION_10);
  vtkGetMacro(MixColorMode, int);
  void SetMixColorModeToAverage() { this->SetMixColorMode(MIX_AVERAGE); }
  void SetMixColorModeToEquation10() { this->SetMixColorMode(MIX_EQUATION_10); }
  ///@}

  ///@{
  /**
   * Reconstruction between voxels:
   * - -1 (default): the vtkVolumeProperty's interpolation type, as VTK's own
   *   mappers use it;
   * - VTK_NEAREST_INTERPOLATION, VTK_LINEAR_INTERPOLATION: override it;
   * - VTK_CUBIC_INTERPOLATION: the uniform cubic B-spline over 4x4x4
   *   voxels, for scalar and pre-classified channels on both backends. It is
   *   smooth (no trilinear creases) and approximating: it blurs detail of
   *   about one voxel. Each sample reads 8x the voxels of trilinear (on the
   *   GPU, 8 hardware trilinear fetches), so it costs more.
   * VTK 9.1's vtkVolumeProperty clamps its type to linear, so the cubic
   * choice is kept here; a property that says VTK_CUBIC_INTERPOLATION (VTK
   * 9.2) is honoured too. The ray-marching mapper's opacity compositing model
   * has no cubic variant: it reports an error and draws nothing.
   */
  vtkSetClampMacro(InterpolationType, int, -1, VTK_CUBIC_INTERPOLATION);
  vtkGetMacro(InterpolationType, int);
  void SetInterpolationTypeToProperty() { this->SetInterpolationType(-1); }
  void SetInterpolationTypeToNearest() { this->SetInterpolationType(VTK_NEAREST_INTERPOLATION); }
  void SetInterpolationTypeToLinear() { this->SetInterpolationType(VTK_LINEAR_INTERPOLATION); }
  void SetInterpolationTypeToCubic() { this->SetInterpolationType(VTK_CUBIC_INTERPOLATION); }
  ///@}

  ///@{
  /**
   * View-dependent visibility optimization (Lerzer and Dachsbacher, EG 2025):
   * what is important shows through what lies in front of it and is not
   * drowned by clutter behind it. Each channel may carry an importance
   * function of its interpolated value (nullptr: none); the importance of a
   * point is the maximum over channels, values snapped to 0, 1/4, 1/2, 3/4
   * and 1. A channel may carry importance while its opacity is zero (a label
   * or mask channel). Along every camera ray the extinction becomes
   * mu' = p mu / (p + (1 - g)^(2 lambda) h), h = (r - q) K(y) + q K(z), K the
   * integral of the squared importance (paper Eq. 7-8, distances in units
   * of half the volume's largest extent); every channel's extinction is
   * scaled alike, so colours keep their proportions in every blend mode.
   * Off by default; off, or no importance anywhere, renders exactly the
   * unoptimized image at no cost. Both backends, and the ray-marching
   * reference (with sums for the integrals, paper Sec. 6.2). With ShadeOn,
   * every ray to a light is optimized too (OptimizeLightRays, Sec. 5.3-5.4)
   * through a fresh list of LightRayImportanceSamples samples.
   */
  vtkSetMacro(VisibilityOptimization, bool);
  vtkGetMacro(VisibilityOptimization, bool);
  vtkBooleanMacro(VisibilityOptimization, bool);
  void SetChannelImportance(int channel, vtkPiecewiseFunction* importance);
  vtkPiecewiseFunction* GetChannelImportance(int channel);
  /// p: deviation from the data's extinction (> 0, default 1).
  /// Clamped to [1e-6, 1e12]; NaN is an error (the value stays).
  virtual void SetDeviationWeight(double value);
  vtkGetMacro(DeviationWeight, double);
  /// q: occlusion by what lies in front (default 70).
  /// Clamped to [0.0, 1e12]; NaN is an error (the value stays).
  virtual void SetOcclusionWeight(double value);
  vtkGetMacro(OcclusionWeight, double);
  /// r: clutter behind (default 30).
  /// Clamped to [0.0, 1e12]; NaN is an error (the value stays).
  virtual void SetClutterWeight(double value);
  vtkGetMacro(ClutterWeight, double);
  /// lambda: emphasis of important regions (default 1).
  /// Clamped to [0.0, 1e3]; NaN is an error (the value stays).
  virtual void SetImportanceEmphasis(double value);
  vtkGetMacro(ImportanceEmphasis, double);
  /// Merge distance d of the per-ray segment lists, in the same units
  /// (0, the default: two strata of a pass).
  /// Clamped to [0.0, 1e6]; NaN is an error (the value stays).
  virtual void SetImportanceMergeDistance(double value);
  vtkGetMacro(ImportanceMergeDistance, double);
  /// Stratified importance samples per camera ray and refinement pass
  /// (1-64, default 32); the first 4 renders of an image refine.
  vtkSetClampMacro(ImportanceSamples, int, 1, 64);
  vtkGetMacro(ImportanceSamples, int);
  /// Optimize the rays to the lights as well (default on; lit scenes only).
  vtkSetMacro(OptimizeLightRays, bool);
  vtkGetMacro(OptimizeLightRays, bool);
  vtkBooleanMacro(OptimizeLightRays, bool);
  /// Stratified importance samples of each light ray's list (2-4096,
  /// default 200, Lerzer and Dachsbacher's).
  vtkSetClampMacro(LightRayImportanceSamples, int, 2, 4096);
  vtkGetMacro(LightRayImportanceSamples, int);
  /// Bytes of the per-pixel segment lists (16 segments of 16 bytes per
  /// pixel, allocated when the optimization first runs), and how many
  /// pixel refinements were dropped because a list was full.
  double GetImportanceMemory();
  double GetImportanceOverflows();
  ///@}

  ///@{
  /**
   * Dependent components (IndependentComponentsOff): how many times the
   * mapper classified the input into its RGBA copy since it was created
   * (once per change of the data, the functions' values or the unit
   * distance; re-renders and camera moves classify nothing), and the bytes
   * of that copy (16 per voxel; 0 when the input is not classified).
   */
  int GetNumberOfClassifications();
  double GetClassifiedMemory();
  ///@}

  enum LevelOfDetailModes
  {
    /// SetLevelOfDetail(LEVEL_OF_DETAIL_AUTOMATIC): the footprint rule.
    LEVEL_OF_DETAIL_AUTOMATIC = -1
  };

  enum LevelOfDetailFilters
  {
    LOD_FILTER_BOX2 = 0,
    LOD_FILTER_BOX4 = 1,
    LOD_FILTER_BSPLINE = 2
  };

  ///@{
  /**
   * Levels of detail (Kraus and Buerger, "Interpolating and
   * Downsampling RGBA Volume Data", Sec. 4). Level 0 (the default) renders
   * the data as they are. Level L > 0 renders a pre-classified copy of the
   * volume with every axis halved L times: each scalar channel goes through
   * the same transfer-function table level 0 uses, into extinction and
   * extinction-weighted colour (sigma, sigma r, sigma g, sigma b), and that
   * is downsampled (extinction, never opacity, is averaged: a thin opaque
   * wall keeps its opacity). The level is built by streaming level 0 z-slab
   * by z-slab (the full-resolution classified volume is never allocated),
   * then kept until the data, a transfer function, the volume property's
   * functions or unit distance, the filter or the channel grouping change;
   * camera moves and progressive renders reuse it
   * (GetNumberOfLevelOfDetailBuilds()). A change of the level restarts the
   * progressive image.
   *
   * Channel grouping: with MC_DENSITY_BLEND the channels are summed into
   * one pre-classified channel (Eq. 6/7: extinctions and extinction-
   * weighted colours add, so this is the density blend exactly at the
   * voxels), unless the volume is lit with per-channel albedos or
   * anisotropies that differ (a sum would lose which channel scatters how).
   * The other blend modes (max, mix, composite) need each channel's own
   * extinction: every channel gets its own pre-classified channel (16 bytes
   * a voxel each at the level). Dependent components
   * (IndependentComponentsOff) are one classified channel already.
   *
   * The level's voxel j along an axis sits, in level 0's index space, at
   * (2^L - 1) / 2 + 2^L j (cell-centred, Pyramid.h), and the rays are mapped
   * into the level's index space with that geometry, so a level-L image lines
   * up with level 0's; the level's box is (2^L - 1) / 2 level-0 voxels
   * smaller on each side (its outermost voxel centres).
   *
   * Values: 0 full resolution; L > 0 level L (above
   * GetNumberOfLevelsOfDetail() it is clamped to the coarsest level, with a
   * warning once and the reason in GetLevelOfDetailReport()); -1
   * (LEVEL_OF_DETAIL_AUTOMATIC) the footprint rule: L = floor(log2(f / s)),
   * clamped to [0, levels], f the world size of one pixel at the distance
   * from the camera to the centre of the volume's bounds (perspective:
   * 2 d tan(viewAngle / 2) / viewport height in pixels; parallel projection:
   * 2 parallelScale / height) and s the finest world spacing of level 0
   * (the image's spacing, direction and the volume's matrix included), so a
   * voxel of the chosen level covers about one pixel. Values below -1 are an
   * error and are ignored.
   *
   * Not at levels above 0: the visibility optimization (a pre-classified
   * channel has no scalar to look importance up by).
   */
  void SetLevelOfDetail(int level);
  vtkGetMacro(LevelOfDetail, int);
  /// Levels available above 0 for the current input (every axis halved
  /// until it is one voxel: 9 for 512^3); 0 without a valid image input.
  int GetNumberOfLevelsOfDetail();
  /// The level the last render used (0 before any render).
  vtkGetMacro(LastLevelOfDetail, int);
  /// One sentence on the last render's level and why: requested, clamped,
  /// the automatic footprint (with its numbers), or the memory fallback.
  const char* GetLevelOfDetailReport();
  ///@}

  ///@{
  /**
   * The downsampling filter of the levels (Kraus and Buerger, Sec. 4.2):
   * LOD_FILTER_BOX4 (default), the 4-tap box, the paper's recommended
   * compromise for trilinear sampling; LOD_FILTER_BOX2, the 2x2x2 box of
   * mipmaps; LOD_FILTER_BSPLINE, (13 19 19 13)/64, the paper's filter for
   * quadratic B-spline sampling. A
   * change rebuilds the levels.
   */
  vtkSetClampMacro(LevelOfDetailFilter, int, LOD_FILTER_BOX2, LOD_FILTER_BSPLINE);
  vtkGetMacro(LevelOfDetailFilter, int);
  void SetLevelOfDetailFilterToBox2() { this->SetLevelOfDetailFilter(LOD_FILTER_BOX2); }
  void SetLevelOfDetailFilterToBox4() { this->SetLevelOfDetailFilter(LOD_FILTER_BOX4); }
  void SetLevelOfDetailFilterToBSpline() { this->SetLevelOfDetailFilter(LOD_FILTER_BSPLINE); }
  const char* GetLevelOfDetailFilterAsString();
  ///@}

  ///@{
  /**
   * Levels L > 0 in half precision (default on): each pre-classified voxel
   * as 4 binary16 values times a power-of-two scale per level, 8 bytes
   * instead of 16 (relative error at most 2^-11 per value; the images
   * differ from float32 levels by far less than one 8-bit step). Halves the levels'
   * host memory on the CPU backend; the CUDA backend keeps float32 levels
   * whatever the setting (it holds float32 on the device). Level 0 is never
   * converted. A change rebuilds the levels (CPU).
   */
  vtkSetMacro(LevelOfDetailHalfPrecision, bool);
  vtkGetMacro(LevelOfDetailHalfPrecision, bool);
  vtkBooleanMacro(LevelOfDetailHalfPrecision, bool);
  ///@}

  ///@{
  /**
   * Memory budget of the volume in bytes (0, the default: no cap). Where the
   * level asked for (0, L or the automatic one) needs more, the finest
   * coarser level that fits is rendered instead, GetLevelOfDetailReport()
   * says so and a warning is given once per distinct case (not every frame);
   * where none fits, the coarsest level is rendered with that warning. What
   * counts is the volume as the backend holds it: level 0 the channels as
   * they are (native type; the CPU reads them in place, the CUDA backend
   * holds each channel once with float64 as float32; the classified copy
   * of dependent components is 16 bytes a voxel), a level L > 0 16 bytes a
   * voxel per pre-classified channel, or 8 with LevelOfDetailHalfPrecision
   * on the CPU (the CUDA backend holds 16). The streamed build's
   * working memory (a few slices, GetLastLevelOfDetailBuildMemory()) and the
   * acceleration grids are not counted. The CUDA device's free memory is not
   * queried (the backend API has no call for it): set the budget to what
   * the device can hold.
   */
  /// Clamped to [0.0, VTK_DOUBLE_MAX]; NaN is an error (the value stays).
  virtual void SetMemoryBudget(double value);
  vtkGetMacro(MemoryBudget, double);
  ///@}

  ///@{
  /**
   * The levels' cost: how many levels the mapper built since it was
   * created, the bytes of the levels it keeps, and the last build's seconds
   * and peak working memory (host bytes besides the level itself; with the
   * CUDA backend, which builds the levels of scalar channels on the GPU,
   * the device's peak, its copy of the channels and the level included).
   */
  int GetNumberOfLevelOfDetailBuilds();
  double GetLevelOfDetailMemory();
  double GetLastLevelOfDetailBuildTime();
  double GetLastLevelOfDetailBuildMemory();
  /// Pre-classified channels of the last render's level (1 when summed; 0
  /// at level 0).
  vtkGetMacro(LastLevelOfDetailChannels, int);
  ///@}

  enum LightingStandInLevels
  {
    /// SetLightingStandInLevel(STAND_IN_OFF): light paths end at the piece.
    STAND_IN_OFF = -1,
    /// SetLightingStandInLevel(STAND_IN_EXACT): the whole volume as stored.
    STAND_IN_EXACT = 0,
    /// SetLightingStandInLevel(STAND_IN_AUTOMATIC): the finest level whose
    /// stand-in fits LightingStandInMemoryLimit.
    STAND_IN_AUTOMATIC = -2
  };

  ///@{
  /**
   * Lighting across the pieces of a volume split over processes (ParaView's
   * pvserver or pvbatch under mpiexec: each process renders its piece, and
   * the pieces' images are composited in visibility order). Camera rays
   * stay in the piece; the part of a shadow ray beyond it, and with
   * MaxScatteringDepth > 1 a scattered ray that leaves it, go on through a
   * stand-in for the whole volume that every process gathers from all of
   * them, so that a piece casts its shadow onto another:
   *
   * - STAND_IN_EXACT (0): every channel's voxels at full
   *   resolution, as the data hold them (the whole data set's bytes on
   *   every process, plus its macrocells and majorants). The composited
   *   image equals the single-process one within the Monte Carlo error.
   *   Gathered again when the data change, not when a transfer function
   *   does.
   * - k > 0: the whole volume's extinction pyramid level k (each channel
   *   pre-classified and its extinction and extinction-weighted colour
   *   averaged over blocks of 2^k voxels a side, which keeps optical depth):
   *   16 bytes per channel and coarse voxel, 1/8^k of the voxels. Shadows
   *   across pieces are blurred over 2^k voxels. Gathered again when the
   *   data or a transfer function change.
   * - STAND_IN_AUTOMATIC (-2): the exact stand-in when the whole volume's
   *   voxels take at most LightingStandInMemoryLimit bytes (default 2 GiB),
   *   else the finest coarse level that does (GetLightingStandInReport()
   *   names it). ParaView's representation uses it by default.
   * - STAND_IN_OFF (-1, the default): no stand-in; shadows end at the
   *   piece's border (what every process sees of the others is empty space).
   *
   * Only lit renders (ShadeOn) at level of detail 0 use it; a single
   * process, or processes that each hold the whole volume, build nothing
   * and render exactly as without it. With more than one process (the
   * Controller's), every lit render is collective: each process must render
   * with this mapper in step. Off by default for that reason: a compositor
   * may skip a process whose piece is outside the view (IceT does), and the
   * others would then wait for it. Turn it on where every piece is rendered
   * every frame (the whole volume in view), or gather outside the render
   * (SetLightingStandInSynchronizedByCaller, as ParaView's representation
   * does). The exact level is the correct one; the coarse levels trade
   * accuracy of the shadows across pieces for memory
   * (Documentation/user-guide/cluster.md gives the figures).
   */
  vtkSetClampMacro(LightingStandInLevel, int, STAND_IN_AUTOMATIC, 16);
  vtkGetMacro(LightingStandInLevel, int);
  void SetLightingStandInLevelToOff() { this->SetLightingStandInLevel(STAND_IN_OFF); }
  void SetLightingStandInLevelToExact() { this->SetLightingStandInLevel(STAND_IN_EXACT); }
  void SetLightingStandInLevelToAutomatic() { this->SetLightingStandInLevel(STAND_IN_AUTOMATIC); }
  ///@}

  ///@{
  /**
   * With the exact stand-in (every process then holds the whole volume),
   * split the image instead of the volume (default on). Each process
   * renders the whole volume, its settings its own, for its share of the
   * image: rows in stripes of kSplitImageStripeRows, dealt to the
   * processes in turn, its other pixels left transparent, so that the
   * composite (in any order) holds every pixel once. Camera rays, shadow
   * rays and scattered rays all cross the whole volume, as in a
   * single-process render: each process traces about 1/N of the paths,
   * the paths a single process would trace, and the image equals the
   * single-process one within the Monte Carlo error. GetBounds() reports
   * the whole volume while it is on, so that a compositor that reads
   * back only the screen area of a process's bounds (IceT) takes every
   * stripe. Off: each process traces camera rays through its own piece
   * (sort-last), and their light paths continue in the stand-in; the
   * processes whose pieces are in front trace paths that the composite
   * hides. Coarse stand-ins always render sort-last.
   */
  vtkSetMacro(SplitImageWithExactStandIn, bool);
  vtkGetMacro(SplitImageWithExactStandIn, bool);
  vtkBooleanMacro(SplitImageWithExactStandIn, bool);
  /// Whether the last lit render split the image (SplitImageWithExactStandIn).
  bool GetLastRenderSplitImage();
  /// The seed the render traces with: Seed, plus ProcessSeedOffset unless
  /// the processes split the image.
  unsigned int EffectiveSeed();
  ///@}

  /// Rows per stripe of a split image (mcvol::kSplitImageStripeRows).
  static constexpr int kSplitImageStripeRows = 16;

  ///@{
  /**
   * Bytes the automatic stand-in may hold on each process (default 2^31, 2
   * GiB; its macrocells and majorants and, on the CUDA backend, its device
   * copy come on top). Clamped to [0, VTK_DOUBLE_MAX]; NaN is an error (the
   * value stays).
   */
  virtual void SetLightingStandInMemoryLimit(double bytes);
  vtkGetMacro(LightingStandInMemoryLimit, double);
  ///@}

  ///@{
  /**
   * The processes the stand-in is gathered from (default null: VTK's
   * global controller, vtkMultiProcessController::GetGlobalController(),
   * as parallel VTK filters use it). A controller of one process (or
   * none) means no stand-in.
   */
  void SetController(vtkMultiProcessController* controller);
  vtkMultiProcessController* GetController();
  ///@}

  ///@{
  /**
   * Who runs the stand-in's collective step (LightingStandInLevel not STAND_IN_OFF,
   * more than one process). Off (the default): Render() does, so every
   * process must render with this mapper in step. On: Render() never
   * communicates. It uses the stand-in gathered by the last
   * SynchronizeLightingStandIn(), which the caller makes on every process
   * before each render, in a pass that every process runs whether or not
   * the compositor then renders its piece. ParaView's representation does
   * this in its REQUEST_RENDER pass, so that a piece out of view (which
   * IceT does not render) holds up no other process.
   *
   * SynchronizeLightingStandIn() runs the stages of Render() that the
   * stand-in reads (channels, transfer functions, level of detail, scene)
   * for this renderer and volume, then the collective step: one AllReduce
   * that agrees whether every process can take part, one that decides
   * whether anything changed, and the gather when it did.
   */
  vtkSetMacro(LightingStandInSynchronizedByCaller, bool);
  vtkGetMacro(LightingStandInSynchronizedByCaller, bool);
  vtkBooleanMacro(LightingStandInSynchronizedByCaller, bool);
  void SynchronizeLightingStandIn(vtkRenderer* ren, vtkVolume* vol);
  ///@}

  ///@{
  /**
   * The stand-in's cost on this process: bytes held (its voxels, macrocells
   * and majorants; 0 without one), the seconds of its last gather (the
   * classification of a coarse level included), how many times it was
   * gathered, and one sentence on what it holds.
   */
  double GetLightingStandInMemory();
  double GetLastLightingStandInGatherTime();
  int GetNumberOfLightingStandInGathers();
  const char* GetLightingStandInReport();
  ///@}

  /**
   * Samples per pixel accumulated in the current image.
   */
  int GetTotalSamples();

  ///@{
  /**
   * What the backend holds on the GPU. GetDeviceMemory(): bytes of device
   * memory (channels, textures, grids, tables, images, and the stand-in for
   * lighting across ranks when it has one); 0 on the CPU, before
   * the first render and after ReleaseGraphicsResources().
   * GetNumberOfDataUploads(): channel copies to the GPU since the backend
   * was created (one per channel per data change: progressive renders,
   * camera moves, transfer-function edits and shallow copies of the same
   * arrays upload nothing); 0 on the CPU, which reads the data in place.
   */
  double GetDeviceMemory();
  int GetNumberOfDataUploads();
  ///@}

  ///@{
  /**
   * Seconds the last Render() spent tracing (on the GPU: the kernels and the
   * copy of the image back to the host) and drawing the image over the
   * framebuffer. The rest of a frame is VTK's own work and the stages that
   * check the input, tables and camera.
   */
  vtkGetMacro(LastTraceTime, double);
  vtkGetMacro(LastDrawTime, double);
  ///@}

  /**
   * Starts the accumulation over at the next Render().
   */
  void ResetAccumulation();

  ///@{
  /**
   * The accumulated image in full float precision, for measurements: linear
   * premultiplied RGB and alpha (the fraction of paths that collided), one
   * 4-component tuple per pixel of the viewport, rows from the bottom. It is
   * what Render() draws over the frame, before any 8-bit quantisation or
   * compositing over the background. Empty before the first render.
   */
  void GetAccumulatedImage(vtkFloatArray* rgba);
  int GetAccumulatedImageWidth();
  int GetAccumulatedImageHeight();
  ///@}

  ///@{
  /**
   * Named single-component point arrays used as the channels, in order,
   * instead of the components of the scalars. None listed (default): the
   * scalars' components are the channels.
   */
  void AddChannelArray(const char* name);
  void RemoveAllChannelArrays();
  int GetNumberOfChannelArrays();
  const char* GetChannelArray(int index);
  ///@}

  ///@{
  /**
   * Per-channel transfer functions that override the vtkVolumeProperty's for
   * that channel (nullptr: use the property's). Required for channels >= 4.
   * Channel must be in [0, 32).
   */
  void SetChannelColor(int channel, vtkColorTransferFunction* function);
  vtkColorTransferFunction* GetChannelColor(int channel);
  void SetChannelScalarOpacity(int channel, vtkPiecewiseFunction* function);
  vtkPiecewiseFunction* GetChannelScalarOpacity(int channel);
  ///@}

  ///@{
  /**
   * Opacity unit distance of one channel (world units), overriding the
   * vtkVolumeProperty's. 0 (default) means unset: the property's for channels
   * < 4, 1 for the others.
   */
  void SetChannelScalarOpacityUnitDistance(int channel, double distance);
  double GetChannelScalarOpacityUnitDistance(int channel);
  ///@}

  /**
   * Removes every per-channel transfer function and unit distance set on the
   * mapper.
   */
  void RemoveAllChannelTransferFunctions();

  /**
   * Number of channels of the last successful render (0 before or after a
   * failed one).
   */
  vtkGetMacro(NumberOfChannels, int);

  /**
   * How many channels' transfer-function tables the last render rebuilt
   * (only channels whose functions, unit distance or data range changed).
   */
  vtkGetMacro(LastTransferFunctionUpdates, int);

  /**
   * Includes the modification times of the per-channel transfer functions set
   * on the mapper.
   */
  vtkMTimeType GetMTime() override;

  /**
   * Bounds of the volume. An axis with a single voxel gets a thickness of one
   * spacing, centred on that voxel, as the renderer gives it.
   */
  double* GetBounds() VTK_SIZEHINT(6) override;
  void GetBounds(double bounds[6]) override { this->vtkVolumeMapper::GetBounds(bounds); }

  /**
   * WARNING: INTERNAL METHOD - NOT INTENDED FOR GENERAL USE
   * Renders the volume into the current viewport.
   */
  void Render(vtkRenderer* ren, vtkVolume* vol) override;

  /**
   * WARNING: INTERNAL METHOD - NOT INTENDED FOR GENERAL USE
   * Releases the OpenGL texture and shader used to draw the image.
   */
  void ReleaseGraphicsResources(vtkWindow* window) override;

protected:
  vtkMultiChannelVolumeMapper();
  ~vtkMultiChannelVolumeMapper() override;

#ifndef __VTK_WRAP__
  /**
   * Traces one render into `accum`, which was reset to zero samples whenever
   * the image changed. The Monte Carlo mapper adds SamplesPerPixel samples
   * with the chosen backend (`renderer`); vtkMultiChannelRayMarchMapper replaces it with
   * the deterministic ray march. Returns false and sets `error` on failure.
   */
  virtual bool TraceImage(const mcvol::Scene& scene, const mcvol::Camera& camera, const float* depth,
    mcvol::Renderer* renderer, mcvol::Accumulator& accum, std::string& error);
  /// The Monte Carlo settings of this render from the mapper's (the
  /// estimator as set: AUTOMATIC_ESTIMATOR's choice is applied by TraceImage).
  mcvol::RenderSettings MakeRenderSettings(const mcvol::Renderer& renderer);
  /// Whether rendering needs a backend (Backend); without one, TraceImage
  /// gets nullptr and the Scene keeps its host grids. Both mappers use one.
  virtual bool UsesRenderBackend();
  /// Whether each render adds Monte Carlo samples (batches, progressive
  /// refinement, the frame-time budget); false: the image is traced once
  /// per change (the ray-marching reference).
  virtual bool AddsSamples();
#endif

  int ChannelBlendMode = MC_DENSITY_BLEND;
  int MixColorMode = MIX_AVERAGE;
  int InterpolationType = -1; ///< -1: the property's
  int TrackingMethod = ONE_DDA;
  int SampleSequence = SOBOL_SEQUENCE;
  int Estimator = EXPECTED_VALUE_ESTIMATOR;
  double MinimumSamplesPerVoxel = 0.0;
  double MarchSamplesPerVoxel = 2.0;
  int MarchControlVariates = MARCH_CONTROL_VARIATES_BY_RATE;
  int InteractiveRendering = -1;
  double InteractiveUpdateRate = 1.0;
  bool LastRenderInteractive = false;
  int SamplesPerPixel = 1;
  double InteractiveFrameTime = 0.0;
  int LastSamplesPerRender = 0;
  unsigned int Seed = 0;
  unsigned int ProcessSeedOffset = 0;
  bool PixelJitter = true;
  double AmbientRadiance[3] = { 0.2, 0.2, 0.2 };
  int ShadowMode = RATIO_TRACKING_SHADOWS;
  double ShadowCacheSpacing = 2.0;
  int MaxScatteringDepth = 1;
  bool GradientShading = false;
  double Shininess = 32.0;
  double LightIntensityScale = 1.0;
  int LightSampling = ALL_LIGHTS;
  int MacrocellSize = 8;
  bool Progressive = true;
  int TransferFunctionRangeMode = DATA_RANGE;
  int MaximumTotalSamples = 0;
  double TargetError = 0.0;
  int Backend = BACKEND_AUTO;
  int CUDADevice = -1;
  double LastTraceTime = 0.0;
  double LastDrawTime = 0.0;
  bool VisibilityOptimization = false;
  double DeviationWeight = 1.0;
  double OcclusionWeight = 70.0;
  double ClutterWeight = 30.0;
  double ImportanceEmphasis = 1.0;
  double ImportanceMergeDistance = 0.0;
  int ImportanceSamples = 32;
  bool OptimizeLightRays = true;
  int LightRayImportanceSamples = 200;
  int NumberOfChannels = 0;
  int LastTransferFunctionUpdates = 0;
  int LevelOfDetail = 0;
  int LevelOfDetailFilter = LOD_FILTER_BOX4;
  bool LevelOfDetailHalfPrecision = true;
  double MemoryBudget = 0.0;
  int LastLevelOfDetail = 0;
  int LastLevelOfDetailChannels = 0;
  int LightingStandInLevel = STAND_IN_OFF;
  bool LightingStandInSynchronizedByCaller = false;
  bool SplitImageWithExactStandIn = true;
  double LightingStandInMemoryLimit = 2147483648.0;

private:
  vtkMultiChannelVolumeMapper(const vtkMultiChannelVolumeMapper&) = delete;
  void operator=(const vtkMultiChannelVolumeMapper&) = delete;

  struct vtkInternals;
  std::unique_ptr<vtkInternals> Internals;

  // The stages of Render(), in order; each works through one unit of
  // Rendering/VTK/ and reports its own errors (false ends the frame).
  struct RenderPass;
  bool BindChannels(RenderPass& pass);
  /// GetIgnoredSettings(): finds them, warns when they change.
  void ReportIgnoredSettings(vtkVolume* volume);
  bool ClassifyDependentComponents(RenderPass& pass);
  bool ResolveTransferFunctions(RenderPass& pass);
  bool EnsureBackend();
  bool ChooseLevelOfDetail(RenderPass& pass);
  bool UpdateScene(RenderPass& pass);
  /// Level > 0: the level's channels (built or cached) into LevelScene.
  bool UpdateLevelScene(RenderPass& pass);
  /// Whether the level sums the channels into one (density blend).
  bool SumsChannelsAtLevels(RenderPass& pass);
  /// Lit, split over processes: the stand-in of the other pieces. Its
  /// steps: STAND_IN_GATHER_AND_USE (collective, then used by this render),
  /// STAND_IN_GATHER (collective only: SynchronizeLightingStandIn) or
  /// STAND_IN_USE (no communication: LightingStandInSynchronizedByCaller).
  enum StandInStep
  {
    STAND_IN_GATHER_AND_USE,
    STAND_IN_GATHER,
    STAND_IN_USE
  };
  bool UpdateStandIn(RenderPass& pass, StandInStep step);
  /// The mapper's settings (blend, interpolation, lighting, importance) on
  /// the Scene a render traces, and its update().
  void ApplySceneSettings(RenderPass& pass, mcvol::Scene& scene);
  bool SetUpView(RenderPass& pass);
  void UpdateAccumulation(RenderPass& pass);
  /// AUTOMATIC_ESTIMATOR: the pilots, when the data, tables or settings the
  /// choice was made for changed.
  bool ChooseEstimator(RenderPass& pass);
  /// This render is interactive and AUTOMATIC_ESTIMATOR's choice costs more
  /// per sample than expected value: the render keeps expected value.
  bool InteractiveKeepsExpectedValue();
  bool TraceBatch(RenderPass& pass);
  /// Whether TargetError stops the current image (estimate at most the target).
  bool ReachedTargetError();
  void DrawImage(RenderPass& pass);
  /// Copies the accumulated float image to the host if it is still on the
  /// device (readers of the image call it; drawing does not need it).
  void ReadBackImage();
};

#endif
