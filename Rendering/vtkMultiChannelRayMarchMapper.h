// SPDX-License-Identifier: BSD-3-Clause
/**
 * @class   vtkMultiChannelRayMarchMapper
 * @brief   Deterministic ray-marching reference for vtkMultiChannelVolumeMapper.
 *
 * Renders the same channels, transfer functions, extinction model and blend
 * modes as vtkMultiChannelVolumeMapper (it is one: everything about inputs,
 * channels, transfer functions, camera, depth and drawing is inherited), but
 * by marching each ray through the pixel centre at a fixed step instead of
 * Monte Carlo tracking. Each Monte Carlo blend mode
 * converges to the image this mapper gives for the same mode as its step
 * goes to zero, which makes it the reference of the image-regression tests
 * and of the accuracy-versus-time benchmark (Documentation/performance.md). Pre-classified
 * RGBA input (vtkVolumeProperty::IndependentComponentsOff) is classified by
 * the inherited stage exactly as for the Monte Carlo mapper.
 *
 * The image is computed once per change (anything that would reset the Monte
 * Carlo mapper's accumulation) and drawn again unchanged otherwise;
 * GetTotalSamples() is 1 once it exists. SamplesPerPixel, TrackingMethod,
 * PixelJitter, Progressive and InteractiveFrameTime do not apply; Seed sets
 * the jitter pattern.
 *
 * Backend (inherited: SetBackendToAuto/CPU/CUDA, GetActiveBackendName,
 * GetBackendReport) picks where the march runs, exactly as for the Monte
 * Carlo mapper: the CPU (OpenMP) or the GPU (CUDA), both running the same
 * per-ray code (RayMarch.h). BACKEND_AUTO (default) takes CUDA when a usable
 * device exists, like the Monte Carlo mapper, so that both are timed on the
 * same hardware; this is safe for a reference because the CUDA march reads
 * voxels with the core's software interpolation (not the hardware texture
 * filter the Monte Carlo renders use by default): its image equals the CPU
 * march's to float rounding (at most 1e-4 per component in the tests,
 * Testing/Core/cuda_march_test.cxx). BACKEND_CUDA without a device is an
 * error, nothing is drawn, and GetBackendReport() says why. Both backends
 * refuse the same settings (lit composite blending or opacity compositing,
 * a scattering depth above 1, the visibility optimization with opacity
 * compositing), with the same error.
 * GetLastTraceSeconds() includes the copy of the image back to the host.
 *
 * Two compositing models (Kraus and Buerger 2008):
 * - EXTINCTION_COMPOSITING (default): the channels' extinctions are
 *   interpolated and combined by the blend mode; each step's opacity is
 *   exactly 1 - exp(-sigma d). This is what the Monte Carlo mapper converges
 *   to.
 * - OPACITY_COMPOSITING: classic opacity-based sampling: per-voxel opacities
 *   corrected to the step, opacity-weighted colours, both interpolated, the
 *   channels' opacities summed (density) or compared (max, mix). It needs
 *   smaller steps for the same accuracy.
 */

#ifndef vtkMultiChannelRayMarchMapper_h
#define vtkMultiChannelRayMarchMapper_h

#include "mcvolRenderingMonteCarloModule.h" // For export macro
#include "vtkMultiChannelVolumeMapper.h"

class MCVOLRENDERINGMONTECARLO_EXPORT vtkMultiChannelRayMarchMapper : public vtkMultiChannelVolumeMapper
{
public:
  static vtkMultiChannelRayMarchMapper* New();
  vtkTypeMacro(vtkMultiChannelRayMarchMapper, vtkMultiChannelVolumeMapper);
  void PrintSelf(ostream& os, vtkIndent indent) override;

  ///@{
  /**
   * Distance between samples along a ray, in world units. 0 (default) means
   * the Nyquist rate of the paper: half the smallest voxel spacing.
   * GetLastStepSize() gives the step the last render used.
   */
  /// Clamped to [0.0, VTK_DOUBLE_MAX]; NaN is an error (the value stays).
  virtual void SetStepSize(double value);
  vtkGetMacro(StepSize, double);
  vtkGetMacro(LastStepSize, double);
  ///@}

  ///@{
  /**
   * Offsets each pixel's samples by a random fraction of a step (a hash of
   * the pixel and Seed, so the image is still deterministic), which turns
   * wood-grain artifacts of coarse steps into noise. Off by default.
   */
  vtkSetMacro(Jitter, bool);
  vtkGetMacro(Jitter, bool);
  vtkBooleanMacro(Jitter, bool);
  ///@}

  ///@{
  /**
   * Early ray termination: a ray stops once its transmittance falls below
   * this value (default 1e-4), so the image differs from the full march by at
   * most this much per pixel and component (composite blending: this much per
   * channel). 0 disables it.
   */
  /// Clamped to [0.0, 0.999]; NaN is an error (the value stays).
  virtual void SetTerminationTransmittance(double value);
  vtkGetMacro(TerminationTransmittance, double);
  ///@}

  ///@{
  /**
   * Skips macrocells (MacrocellSize) whose majorants are zero for every
   * channel. Exact: the image is the same either way. On by default.
   */
  vtkSetMacro(EmptySpaceSkipping, bool);
  vtkGetMacro(EmptySpaceSkipping, bool);
  vtkBooleanMacro(EmptySpaceSkipping, bool);
  ///@}

  enum CompositingModels
  {
    EXTINCTION_COMPOSITING = 0,
    OPACITY_COMPOSITING = 1
  };

  ///@{
  /** See the class description. */
  vtkSetClampMacro(CompositingModel, int, EXTINCTION_COMPOSITING, OPACITY_COMPOSITING);
  vtkGetMacro(CompositingModel, int);
  void SetCompositingModelToExtinction() { this->SetCompositingModel(EXTINCTION_COMPOSITING); }
  void SetCompositingModelToOpacity() { this->SetCompositingModel(OPACITY_COMPOSITING); }
  const char* GetCompositingModelAsString();
  ///@}

  /**
   * Samples evaluated by the last render that traced (empty-space skipping
   * and early termination lower it), and macrocells it skipped.
   */
  vtkGetMacro(LastSampleCount, double);
  vtkGetMacro(LastSkippedCells, double);

  /**
   * Seconds the last ray march took (0 when the last render only redrew).
   */
  vtkGetMacro(LastTraceSeconds, double);

protected:
  vtkMultiChannelRayMarchMapper();
  ~vtkMultiChannelRayMarchMapper() override;

#ifndef __VTK_WRAP__
  bool TraceImage(const mcvol::Scene& scene, const mcvol::Camera& camera, const float* depth, mcvol::Renderer* renderer,
    mcvol::Accumulator& accum, std::string& error) override;
  bool AddsSamples() override;
#endif

  double StepSize = 0.0;
  double LastStepSize = 0.0;
  bool Jitter = false;
  double TerminationTransmittance = 1e-4;
  bool EmptySpaceSkipping = true;
  int CompositingModel = EXTINCTION_COMPOSITING;
  double LastSampleCount = 0.0;
  double LastSkippedCells = 0.0;
  double LastTraceSeconds = 0.0;

private:
  vtkMultiChannelRayMarchMapper(const vtkMultiChannelRayMarchMapper&) = delete;
  void operator=(const vtkMultiChannelRayMarchMapper&) = delete;
};

#endif
