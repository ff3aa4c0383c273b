// SPDX-License-Identifier: BSD-3-Clause
#pragma once

#include "mcvol/DeviceRenderer.h"

#include <cstdint>
#include <memory>
#include <string>
#include <vector>

namespace mcvol
{
/// Where the CUDA kernels read voxels from.
enum class CudaSampling : int
{
  Texture = 0, ///< 3D textures, hardware trilinear (or point) filtering
  Global = 1   ///< plain device arrays in the native type, the core's software interpolation
};

/// Device-side memory of a CUDA renderer (the paper's Table 1, on the GPU).
struct CudaMemoryStats
{
  size_t dataBytes = 0;       ///< channels held as dense arrays (native type; float64 stored as float32)
  size_t textureBytes = 0;    ///< channels held as 3D textures (each channel is held one way only)
  size_t macrocellBytes = 0;  ///< per-cell per-channel scalar ranges
  size_t majorantBytes = 0;   ///< per-cell per-channel majorants
  size_t imageBytes = 0;      ///< accumulation (with the error estimate's even half), depth and deferred shadow rays
  size_t levelInputBytes = 0; ///< classifyLevel()'s kept copies of its inputs (ClassifyInput::dataVersion)
};

/// What the renderer did to keep its device copies current (for tests).
struct CudaUpdateCounters
{
  uint64_t dataUploads = 0;           ///< channel uploads (one per channel per data change)
  uint64_t rangeBuilds = 0;           ///< macrocell-range builds (all channels)
  uint64_t majorantChannelBuilds = 0; ///< per-channel majorant builds
  uint64_t imageDownloads = 0;        ///< accumulated images copied to the host
  double lastMajorantMs = 0.0;        ///< GPU time of the last majorant rebuild (all channels it touched)
  double lastRangeMs = 0.0;           ///< GPU time of the last range build
  uint64_t textureFallbacks = 0;      ///< channels held as dense arrays for lack of room for a texture
  uint64_t levelInputUploads = 0;     ///< classifyLevel(): scalar channels copied to the device
  uint64_t levelBuilds = 0;           ///< classifyLevel() calls that built a level
  double lastLevelMs = 0.0;           ///< wall time of the last classifyLevel() (uploads and read-back included)
  size_t lastLevelPeakBytes = 0;      ///< device memory of the last classifyLevel() at its peak
  uint64_t shadowCaches = 0;          ///< cached shadows' grids filled (LightingDesc::cacheShadows)
};

/**
 * CUDA backend: the frame-level Renderer and the GPU-level DeviceRenderer.
 * Runs the core's per-pixel code (Integrator.h, Tracking.h: the same
 * functions as the CPU backend, compiled by nvcc) with one thread per pixel.
 * Keeps device copies of the channels, of the transfer-function tables, of
 * the macrocell ranges and majorants (built on the GPU from the device
 * copies; one channel's majorants rebuilt when its transfer function
 * changes) and of the accumulated image.
 *
 * Uploads follow the Scene's versions: voxels when contentVersion() changes,
 * ranges when dataVersion() changes (macrocell size), one channel's majorants
 * when channelTableVersion(n) changes. Scenes whose host acceleration is on
 * work too (the host grids are simply not used).
 *
 * All errors throw std::runtime_error with the CUDA error text.
 */
class CUDARenderer final : public DeviceRenderer
{
public:
  /// Selects device `device`, or defaultDevice() when negative (throws if
  /// it is not usable).
  explicit CUDARenderer(int device = 0);
  ~CUDARenderer() override;

  void render(const Scene& scene, const Camera& camera, const RenderSettings& settings, const float* depth,
    Accumulator& accum, RenderCounters* counters = nullptr) override;
  /// The ray-marching reference on the GPU (RayMarch.h, the per-ray code
  /// of the CPU march) over the same device copies as render(): nothing is
  /// uploaded twice. MarchSettings::deviceTextures picks the sampling path
  /// (software interpolation by default, whatever setSampling() says).
  void march(const Scene& scene, const Camera& camera, const MarchSettings& settings, const float* depth,
    Accumulator& accum, MarchCounters* counters = nullptr) override;
  const char* name() const override { return "cuda"; }
  /**
   * The pilots of chooseEstimator() with every sample of every job launched
   * at once, each replicate's sample k a one-sample render of its own (first
   * sample index k) into an image of its own, on streams that run
   * concurrently; the means are folded on the host. One after the other, a
   * pilot of a few dozen pixels leaves the GPU nearly idle, each render
   * bound by a ray's latency, and a choice takes dozens of them
   * (Documentation/performance.md). setConcurrentPilots(false) renders them
   * one after the other (Renderer::renderPilots), the benchmark's
   * comparison.
   */
  void renderPilots(const Scene& scene, const Camera& camera, std::vector<PilotJob>& jobs) override;
  bool rendersPilotsAtOnce() const override { return this->concurrentPilots(); }
  void setConcurrentPilots(bool on);
  bool concurrentPilots() const;
  void finish() override;
  void readBack(Accumulator& accum) override;
  void readBackEven(Accumulator& accum) override;

  // DeviceRenderer
  const uint8_t* displayImage(Accumulator& accum) override;
  bool hasDisplayImage() const override { return true; }
  bool buildsAccelerationOnDevice() const override { return true; }
  size_t deviceBytes() const override;
  uint64_t dataUploads() const override { return this->updateCounters().dataUploads; }
  /**
   * Whether the mapper builds levels of detail with classifyLevel() on the
   * device (the default: a rebuild after a transfer-function edit copies
   * nothing but the tables and runs far faster than the host build,
   * Documentation/performance.md). setDeviceLevels(false) builds them on the
   * host instead. classifyLevel() itself builds on the device whatever this
   * says (its tests call it directly).
   */
  bool buildsLevelsOnDevice() const override;
  void setDeviceLevels(bool on);
  /**
   * A pyramid level built on the device (CUDAPyramid.cu): the scalar
   * channels are copied to the device as they are (strided arrays whole,
   * float64 as float64: the renderer's own copies are converted or held as
   * textures and not reused), classified there with
   * classificationTable()'s tables and the host's arithmetic (the texel
   * coordinate in double, the interpolation in float, the inputs added in
   * order), and filtered along x (fused with the classification), y and z
   * in double, stored as float after each axis; a level L > 1 is level 1
   * downsampled again on the device. The result equals
   * classifyExtinctionLevel's (the same operations, rounded alike: the
   * kernels use explicitly rounded arithmetic, no fused multiply-add) and
   * is checked against it to 1e-5 relative (Testing/Core/
   * cuda_pyramid_test.cxx). Device memory at the peak (lastLevelPeakBytes):
   * the inputs plus the x-filtered level-0 volume (half of the level-0
   * float4 volume, 8 bytes a level-0 voxel), then that plus the xy-filtered
   * one (a quarter), then the level; the full-resolution float4 volume is
   * never held. For 4 float channels of 512^3: 2 GiB of inputs + 1 GiB +
   * 0.5 GiB. Inputs with a nonzero ClassifyInput::dataVersion stay on the
   * device for later calls (levelInputBytes), so a transfer-function edit
   * copies nothing but the tables, per channel or summed: a kept copy is
   * freed when the same host array comes with another key (new data), and
   * the least recently used ones while the kept copies would exceed half
   * the device's memory; releaseLevelInputs() frees them all.
   */
  PyramidLevel classifyLevel(const ClassifyInput* inputs, int numInputs, const int dims[3], const double spacing[3],
    const double origin[3], int level, DownsampleFilter filter, size_t* peakWorkBytes = nullptr) override;
  /// Frees classifyLevel()'s kept input copies.
  void releaseLevelInputs();

  /// Texture (default) or global-memory sampling; takes effect at the next render.
  void setSampling(CudaSampling s);
  CudaSampling sampling() const;
  /**
   * On by default: renders of plain scenes (scalar channels, linear or
   * nearest interpolation), unlit and lit, launch kernels compiled without the pre-classified
   * and cubic sampling (CUDALaunchPlain.cu): fewer registers per thread, so
   * more rays in flight and shorter frames. The image is the same either way
   * (CudaRender.PlainKernelsEqualGeneral). Off, for comparisons.
   */
  void setPlainKernels(bool on);
  bool plainKernels() const;
  /**
   * On by default: lit renders whose shadow rays can wait
   * (deferrableShadows(): shadows, single scattering, no stand-in of other
   * pieces) trace the camera rays first, queue the pixels whose path
   * scattered, and trace their shadow rays in a second kernel, in full
   * warps; otherwise the few threads of a warp that cast a shadow ray hold
   * up the rest. The image is the same either way
   * (CudaRender.DeferredShadowsEqualTraced); the queue takes
   * sizeof(DeferredShadows), 152 bytes, per pixel
   * (CudaMemoryStats::imageBytes). Off, for comparisons.
   */
  void setDeferredShadows(bool on);
  bool deferredShadows() const;
  /**
   * Samples per pixel one pair of deferred launches traces when a render
   * asks for several (default 4, at most 8): a launch lasts as long as its
   * longest paths, so a fuller launch finishes more samples in the same
   * time. The image is the one of a sample at a time
   * (CudaRender.DeferredBatchesEqualOneSampleAtATime); the queue then takes
   * that many entries per pixel, and the batch a float4 image per sample
   * (CudaMemoryStats::imageBytes), the queue within 1/16 of the device's
   * memory. Where few pixels can have rays (an image smaller than 1024^2,
   * a depth mask that leaves a split image's rows) a batch takes more, up
   * to a 1024^2 image's paths; 1 otherwise traces one sample per pair.
   */
  void setDeferredBatch(int samples);
  int deferredBatch() const;
  /// Threads per block (x, y) of the render kernel (default 8 x 8).
  void setBlockSize(int x, int y);

  CudaMemoryStats memory() const;
  const CudaUpdateCounters& updateCounters() const;
  /// The device's name, driver and runtime versions and SM count, e.g.
  /// "<name>, driver 12.8, runtime 13.0, 132 SMs".
  std::string deviceDescription() const;
  /// Copies channel n's device majorant grid (cells x 1) to the host, for tests.
  std::vector<float> downloadMajorants(int channel) const;
  /// The active-channel list the last update computed.
  std::vector<int> activeChannels() const;

  /// True if CUDA device `device` can run this build's kernels; `why` gets
  /// the reason when not (or the device's name when it can).
  static bool deviceUsable(std::string* why = nullptr, int device = 0);

  /// The device a process takes when none is named: its rank on this node
  /// (OMPI_COMM_WORLD_LOCAL_RANK, MPI_LOCALRANKID, MPI_LOCAL_RANK,
  /// SLURM_LOCALID, in that order) modulo the visible devices, so that the
  /// ranks of `mpiexec -n 2` on a two-GPU node take one GPU each; 0 without
  /// a rank. CUDA_VISIBLE_DEVICES decides which devices are visible. `how`
  /// (optional) says why this one.
  static int defaultDevice(std::string* how = nullptr);

private:
  struct Internal;
  std::unique_ptr<Internal> In;
};
} // namespace mcvol
