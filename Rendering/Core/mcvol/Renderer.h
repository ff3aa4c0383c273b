// SPDX-License-Identifier: BSD-3-Clause
#pragma once

#include "mcvol/ray/Importance.h"
#include "mcvol/Pyramid.h"
#include "mcvol/Scene.h"
#include "mcvol/ray/Types.h"

#include <algorithm>
#include <cstddef>
#include <cstdint>
#include <memory>
#include <string>
#include <vector>

namespace mcvol
{
struct MarchSettings; // MarchSetup.h
struct MarchCounters; // RayMarch.h

/**
 * Camera of one render. Rays are built by unprojecting pixel positions with
 * invViewProj (row-major, normalised device coordinates in [-1,1]^3 to world,
 * homogeneous), which serves perspective and parallel projection alike.
 * worldToIndex maps world points to continuous voxel indices (voxel i at i).
 */
struct Camera
{
  int width = 0;
  int height = 0;
  double invViewProj[16] = { 1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1 };
  double worldToIndex[12] = { 1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0 };
  /// Span of the sub-pixel jitter (RenderSettings::jitterPixels) in pixels,
  /// centred on the pixel: 1 (default) covers the pixel. The automatic
  /// estimator choice renders a small image of the view whose pixels each
  /// stand for s x s of the image's, with 1/s, so that its rays jitter over
  /// an image pixel's footprint, as the image's do (EstimatorChoice.h).
  float jitterScale = 1.f;
};

struct RenderSettings
{
  int samplesPerPixel = 1; ///< added to the accumulation per render
  uint32_t seed = 0;
  Tracker tracker = Tracker::OneDDA;
  bool jitterPixels = true; ///< sub-pixel jitter (anti-aliasing)
  /// Where the samples' leading decisions draw their numbers (Types.h,
  /// Sequence.h). Sobol by default: lower error at every sample count
  /// (Documentation/performance.md).
  Sampler sampler = Sampler::Sobol;
  /// What an unlit camera ray scores (Types.h). ExpectedValue by default:
  /// less time to a given error on every benchmark dataset
  /// (Documentation/performance.md).
  Estimator estimator = Estimator::ExpectedValue;
  /// Expected-value estimator: tentative collisions at least this many per
  /// voxel length along a ray (voxelRate()) in every macrocell that is not
  /// empty, where the majorant alone would place fewer. Unbiased for any
  /// value (ratio tracking needs only a rate at least the extinction); more
  /// samples in optically thin cells cost time and lower the noise of thin,
  /// bright structures. 0: the majorant alone.
  float minSamplesPerVoxel = 0.f;
  /// Unbiased-march estimator (Estimator::UnbiasedMarch): strata per voxel
  /// length along a ray in every macrocell that is not empty (each also at
  /// least kMarchMajorantStrata per unit of majorant optical depth), like
  /// the ray marcher's samples per voxel. Must be positive and finite.
  float marchSamplesPerVoxel = 2.f;
  /// Unbiased-march estimator at pixel centres (jitterPixels off) from
  /// kMarchControlVariateRate strata per voxel: take control variates
  /// (trackControlMarch(), less noise per sample for about 1.4x the time).
  /// Off keeps the plain strata there, for comparison (mcvol-bench
  /// --pixel-centres measures both). Both backends follow it.
  bool marchControlVariates = true;
  /// The strata per voxel from which marchControlVariates applies:
  /// kMarchControlVariateRate by default, the rule both backends follow
  /// when the estimator is set by hand. The automatic choice
  /// (chooseEstimator()) offers each march rate at pixel centres both with
  /// and without control variates, and sets 0 here (with
  /// marchControlVariates on) for a chosen control-variate rate below 1, or
  /// marchControlVariates off for chosen plain strata at 1 or more. Must be
  /// at least 0 and finite.
  float marchControlVariatesFrom = kMarchControlVariateRate;
  /// Device backends: copy the accumulated image into the Accumulator at the
  /// end of render(). false leaves it on the device (the frame may still be
  /// running when render() returns) until readBack() or the next render with
  /// readBack on; the Accumulator's sample count is updated either way and it
  /// is marked pendingOnDevice(). The device holds one image: rendering
  /// another Accumulator replaces it, after which readBack() or render() of
  /// the first throws std::logic_error instead of returning a stale image.
  bool readBack = true;
  /// Device backends: copy the error estimate's even half back with the
  /// image (default). false copies the image alone and marks the half
  /// evenPendingOnDevice() until readBackEven(): a renderer that draws every
  /// frame and asks for the estimate now and then halves its read-back.
  bool readBackEven = true;
};

/// Work counters a render adds up (tests read them; the benchmark prints them).
struct RenderCounters
{
  uint64_t rays = 0;
  uint64_t ddaSteps = 0;            ///< macrocells visited, summed over traversals
  uint64_t tentativeCollisions = 0; ///< Woodcock steps that landed inside a cell
  uint64_t realCollisions = 0;
  uint64_t channelSamples = 0; ///< channel values interpolated
  // Lighting: zero for every effect that is off.
  uint64_t scatteringEvents = 0;
  uint64_t shadowRays = 0;
  uint64_t gradientEvaluations = 0;
  // Visibility optimization: zero when it is off.
  uint64_t importanceSamples = 0; ///< importance evaluations (refinement and collisions)
};

/**
 * Running mean of premultiplied RGBA per pixel. Each render adds K samples
 * per pixel; reset() starts over (the caller resets when the image changes).
 * The mean is float (rgba()); beside it the host backend keeps each pixel's
 * sum of samples in double (sums()), to which every sample is added, so the
 * image keeps converging past 2^24 samples per pixel and does not depend on
 * how the samples were batched.
 *
 * Error estimate (on by default, errorEstimation()): a second running mean
 * holds only the samples of even per-pixel index (half A; the odd ones, half
 * B, are what the full mean holds beside them). Both halves are unbiased
 * estimates of the pixel with independent noise, so their difference
 * measures the noise of the full mean without any reference; see
 * estimatedMSE(). Samples are numbered per pixel, so, like the image, the
 * halves do not depend on how the samples were batched.
 */
class Accumulator
{
public:
  void resize(int width, int height);
  void reset();
  int width() const { return this->Width; }
  int height() const { return this->Height; }
  /// Samples per pixel accumulated so far.
  uint32_t samples() const { return this->Samples; }
  /// The host image. After reset() its zeros are written on first access
  /// (see hostClearPending()): a device backend that starts the image on the
  /// device never pays for clearing the host copy.
  const float* rgba() const
  {
    this->settle();
    return this->RGBA.data();
  }
  float* rgba()
  {
    this->settle();
    return this->RGBA.data();
  }
  /**
   * For a backend about to overwrite every value of the host image (or of
   * the even half, nullptr when there is none), e.g. a read-back: the
   * pointer without writing the pending zeros first. The caller must write
   * all of it.
   */
  float* rgbaForOverwrite();
  float* evenRGBAForOverwrite();
  /// True while reset() has not yet written the host image's zeros: they are
  /// written by the first rgba()/evenRGBA()/estimatedMSE() (not thread-safe
  /// against concurrent first accesses; backends take the pointer once).
  bool hostClearPending() const { return this->ClearRGBA || this->ClearEven; }
  /// Called by backends after adding `k` samples per pixel. `sumsKept`:
  /// the backend updated sums() (and evenSums()) with them; otherwise the
  /// sums are derived from the mean again when next asked for.
  void addSamples(uint32_t k, bool sumsKept = false)
  {
    this->Samples += k;
    this->SumsValid = this->SumsValid && sumsKept;
  }
  /**
   * Each pixel's sum of its samples() samples, RGBA in double, for a
   * backend to continue (Integrator.h, loadSum() and storeSum()). When the
   * mean was last written by other means (rgbaForOverwrite(), addSamples()
   * without sumsKept), the sums are rebuilt from it first: mean x samples,
   * which carries the mean's float rounding. Not read at 0 samples.
   */
  double* sums();
  /// The even half's sums (as sums(), for evenRGBA()), or nullptr when
  /// evenRGBA() is.
  double* evenSums();

  /**
   * Keep the even-sample mean the error estimate needs (default on: one more
   * RGBA float image, and four additions per even sample). Turned on while
   * an image holds samples, the estimate is unavailable until reset() or
   * resize() (the earlier samples were not split); off frees the buffer.
   */
  void setErrorEstimation(bool on);
  bool errorEstimation() const { return this->EstimateError; }
  /// Running mean of the samples of even per-pixel index (RGBA as rgba()),
  /// or nullptr when the estimate is off or unavailable for this image:
  /// backends then skip the split.
  float* evenRGBA()
  {
    this->settle();
    return this->EvenValid ? this->Even.data() : nullptr;
  }
  const float* evenRGBA() const
  {
    this->settle();
    return this->EvenValid ? this->Even.data() : nullptr;
  }
  /// Whether evenRGBA() would return an image, without touching it (device
  /// backends ask this to decide whether to keep the split).
  bool hasEven() const { return this->EvenValid; }
  /// Samples of even index among the first n of a pixel: 0, 2, 4, ... < n.
  static uint32_t evenSamples(uint32_t n) { return (n + 1u) / 2u; }

  /**
   * Estimated mean squared error of the image against its expectation (the
   * converged image), averaged over pixels and the premultiplied R, G and B
   * (alpha is left out, as the accuracy benchmarks score images: it is the
   * coverage, not a colour, and would dilute the estimate with the often
   * noiseless background). Negative when it cannot be estimated: fewer than
   * 2 samples, estimation off or turned on mid-image, or the latest image
   * still on a device (readBack off). Exactly 0 for an image whose samples
   * all agree (e.g. nothing visible).
   *
   * Derivation, per pixel and colour channel: with N samples of variance
   * s^2, half A holds nA = ceil(N/2) of them (mean mA) and half B the
   * nB = floor(N/2) others (mB). The halves are independent, so
   * E[(mA - mB)^2] = s^2 (1/nA + 1/nB) = s^2 N / (nA nB), and the full mean
   * m = (nA mA + nB mB) / N has variance s^2 / N = E[(mA - mB)^2] nA nB / N^2
   * (a quarter of it when nA = nB). mB is not stored: it follows from m, and
   * mA - mB = N (mA - m) / nB, so the estimate is (nA / nB) (mA - m)^2:
   * no cancellation of large sums, only of two means of float rounding
   * (~1e-7 relative), far below any noise worth measuring. The per-pixel
   * estimate has few degrees of freedom, but the average over the image has
   * many: it is a good estimate of the image's MSE.
   */
  double estimatedMSE() const;
  /// Unique per Accumulator object (copies get their own): device backends
  /// key their copy of the image on it.
  uint64_t id() const { return this->Id.value; }
  /// True while the latest image exists only on a device
  /// (RenderSettings::readBack = false): rgba() is stale until readBack().
  bool pendingOnDevice() const { return this->Pending; }
  void setPendingOnDevice(bool pending) { this->Pending = pending; }
  /// The even half is still on the device (RenderSettings::readBackEven
  /// false): estimatedMSE() is unavailable until Renderer::readBackEven().
  bool evenPendingOnDevice() const { return this->EvenPending; }
  void setEvenPendingOnDevice(bool pending) { this->EvenPending = pending; }

  /**
   * The visibility optimization's per-pixel segment lists (Sec. 5.1,
   * Lerzer and Dachsbacher), kept across renders with the image and cleared
   * with it by reset() and resize(): a pool of kImportanceCapacity segments
   * per pixel, a count and the ray's integral K(z) per pixel. Allocated on
   * first use only.
   */
  struct ImportancePool
  {
    std::vector<ImportanceSegment> segments; ///< [pixel][kImportanceCapacity]
    std::vector<uint8_t> counts;             ///< segments in use per pixel
    std::vector<float> totals;               ///< K over the whole ray per pixel
    int passes = 0;                          ///< refinement passes done
    uint64_t overflows = 0;                  ///< pixel passes and light-ray lists dropped for lack of room
    size_t deviceBytes = 0;                  ///< the device backend's copy (its lists live there)
    size_t bytes() const
    {
      return segments.size() * sizeof(ImportanceSegment) + counts.size() + totals.size() * sizeof(float) + deviceBytes;
    }
  };
  /// The pool, sized to the image (the host lists are allocated on the first
  /// call; a device backend keeps its lists on the device and asks for the
  /// bookkeeping only, `hostLists` false).
  ImportancePool& importancePool(bool hostLists = true);
  const ImportancePool& importancePoolIfAny() const { return this->Importance; }

private:
  void settle() const
  {
    if (this->ClearRGBA || this->ClearEven)
    {
      this->clearHost();
    }
  }
  void clearHost() const;

  int Width = 0;
  int Height = 0;
  uint32_t Samples = 0;
  // reset() leaves the host zeros to the first access (mutable: const
  // accessors write them).
  mutable bool ClearRGBA = false;
  mutable bool ClearEven = false;
  bool Pending = false;
  bool EvenPending = false;
  ObjectId Id;
  mutable std::vector<float> RGBA;
  bool EstimateError = true;
  bool EvenValid = false; ///< Even holds the even samples of this image
  mutable std::vector<float> Even;
  std::vector<double> Sum;     ///< sums(), allocated on first use
  std::vector<double> EvenSum; ///< evenSums(), allocated on first use
  bool SumsValid = true;       ///< Sum and EvenSum hold the current samples' sums
  ImportancePool Importance;
};

/**
 * One candidate's pilot images for chooseEstimator() (EstimatorChoice.h):
 * two replicates of the view with independent scrambles (seeds), each
 * rendered to checkpoints.back() samples per pixel, and each replicate's
 * mean image after every checkpoint's samples.
 */
struct PilotJob
{
  /// The candidate's settings; their seed and samplesPerPixel are not used.
  RenderSettings settings;
  uint32_t seeds[2] = { 0u, 0u };
  /// Ascending sample counts (at least one), e.g. 1, 2, 4, 8.
  std::vector<int> checkpoints;
  /// Out: means[r][i], replicate r's image (premultiplied RGBA, the
  /// Accumulator's layout) after checkpoints[i] samples per pixel.
  std::vector<std::vector<float>> means[2];
  /// Out: the work counters of replicate 0's samples.
  RenderCounters counters;
};

class DeviceRenderer; // DeviceRenderer.h

/// Rows per stripe of a split image (processes that each hold the whole
/// volume render stripes of rows dealt to them in turn): a multiple of the
/// CUDA backend's block height, so that a block lies wholly inside or
/// outside a process's share and the threads of the others end at once.
constexpr int kSplitImageStripeRows = 16;

/**
 * The depth mask of process `rank` of `ranks` splitting a width x height
 * image: `depth` (resized to width x height, new values 1: nothing drawn)
 * gets 0 on the rows of the other processes' stripes, so that their camera
 * rays end before they start and those pixels stay transparent; this
 * process's rows keep their values (the depth of opaque geometry).
 */
inline void maskSplitImageRows(std::vector<float>& depth, int width, int height, int ranks, int rank)
{
  const size_t w = width > 0 ? size_t(width) : 0;
  depth.resize(w * size_t(height > 0 ? height : 0), 1.0f);
  for (int y = 0; y < height; ++y)
  {
    if ((y / kSplitImageStripeRows) % ranks != rank)
    {
      std::fill_n(depth.begin() + std::ptrdiff_t(w * size_t(y)), w, 0.0f);
    }
  }
}

/**
 * A backend: renders a Scene into an Accumulator, frame by frame. This is
 * the frame-level interface, what every backend does; a backend that
 * renders on a device (CUDA) adds the GPU-level interface, DeviceRenderer,
 * reached through device().
 *
 * A frame may still be running when render() returns (a device backend with
 * RenderSettings::readBack off): finish() waits for it and readBack() brings
 * its image to the host. A backend that renders on the host finishes every
 * frame before render() returns, and both calls return at once.
 *
 * The per-ray work is the core's (Integrator.h, RayMarch.h); the virtual
 * calls here are made once a frame, never per ray.
 */
class Renderer
{
public:
  virtual ~Renderer() = default;

  virtual const char* name() const = 0;

  /// Adds settings.samplesPerPixel samples to every pixel of `accum` (which
  /// must be sized to the camera). depth: optional window depth in [0,1] per
  /// pixel (row-major from the bottom row, like glReadPixels); rays stop at
  /// that depth (opaque geometry already drawn). 1 means no geometry.
  virtual void render(const Scene& scene, const Camera& camera, const RenderSettings& settings, const float* depth,
    Accumulator& accum, RenderCounters* counters = nullptr) = 0;

  /**
   * The deterministic ray-marching reference (RayMarch.h) on this backend:
   * one ray through each pixel centre, the same per-ray code on every
   * backend. Replaces `accum`'s image (sized to the camera; its sample count
   * becomes 1) and copies it to the host before returning. Throws
   * std::invalid_argument for settings the reference does not render (the
   * same refusals on every backend: prepareMarch()).
   */
  virtual void march(const Scene& scene, const Camera& camera, const MarchSettings& settings, const float* depth,
    Accumulator& accum, MarchCounters* counters = nullptr) = 0;

  /**
   * Renders every job's pilot (PilotJob) into its `means` and `counters`.
   * Each replicate's images are what render() gives an Accumulator of its
   * own, reset and rendered in chunks up to each checkpoint with the
   * replicate's seed. The default does exactly that, job after job. A device
   * backend may run every job's samples at once: pilot images are a few
   * thousand pixels, too few to fill a GPU, so one after the other they cost
   * a ray's latency each (CUDARenderer: sample k of a replicate rendered
   * alone with first sample index k, the means folded on the host; equal to
   * the chunked renders up to float rounding). Unlit, unoptimized,
   * non-composite scenes only (those chooseEstimator() pilots).
   */
  virtual void renderPilots(const Scene& scene, const Camera& camera, std::vector<PilotJob>& jobs);
  /// True where renderPilots() renders its jobs at once, so that a round
  /// of several candidates costs about what one does (chooseEstimator()
  /// then renders ahead the candidates it will most likely reach).
  virtual bool rendersPilotsAtOnce() const { return false; }

  /// Waits until every render issued so far has finished.
  virtual void finish() {}
  /// Waits for the renders issued so far and copies the accumulated image
  /// into `accum` (see RenderSettings::readBack).
  virtual void readBack(Accumulator& accum) { (void)accum; }
  /// Copies the error estimate's even half of the image last rendered into
  /// `accum` (see RenderSettings::readBackEven).
  virtual void readBackEven(Accumulator& accum) { (void)accum; }

  /// The GPU-level interface (device residency, the display path, levels
  /// of detail built on the device), or nullptr for a backend that renders
  /// on the host (the CPU).
  virtual DeviceRenderer* device() { return nullptr; }
  virtual const DeviceRenderer* device() const { return nullptr; }

  /**
   * The backend `requested`: Auto takes CUDA when a usable device exists,
   * otherwise the CPU. Throws std::runtime_error naming the cause if the
   * requested backend is unavailable. `why` (optional) receives a sentence
   * on the choice made. `cudaDevice`: the CUDA device to use, or -1 for the
   * default (the process's local MPI rank modulo the visible devices; see
   * CUDARenderer::defaultDevice()).
   *
   * create() and cudaAvailable() are defined by the Backends layer
   * (Rendering/Backends, library mcvol::backends), the one place that knows
   * every backend.
   */
  static std::unique_ptr<Renderer> create(Backend requested, std::string* why = nullptr, int cudaDevice = -1);
  /// True if this build has the CUDA backend and CUDA device `cudaDevice`
  /// (-1: the default, as for create()) can run its kernels. `why`
  /// (optional) receives the reason when not, or the device when it can.
  static bool cudaAvailable(std::string* why = nullptr, int cudaDevice = -1);
};
} // namespace mcvol
