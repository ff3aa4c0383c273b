// SPDX-License-Identifier: BSD-3-Clause
#pragma once

#include "vtkType.h" // For vtkMTimeType

#include "mcvol/Renderer.h"

#include <vector>

namespace mcvol
{
namespace adapter
{
/**
 * Stage 6 of vtkMultiChannelVolumeMapper::Render: what resets the
 * progressive image, and how many samples this render adds to it.
 */

/// Everything whose change invalidates the accumulated image. The depth of
/// the opaque geometry counts too (compared separately, by value).
struct AccumulationKey
{
  vtkMTimeType MapperMTime = 0;         ///< the mapper's own parameters
  vtkMTimeType PropertyMTime = 0;       ///< the volume property's own settings
  vtkMTimeType DataMTime = 0;           ///< the channel arrays' values
  vtkMTimeType LightsMTime = 0;         ///< the renderer's lights (lighting only)
  unsigned long long TablesVersion = 0; ///< transfer-function tables
  int Width = 0;
  int Height = 0;
  double InvViewProj[16] = {};
  double WorldToIndex[12] = {};
  const Renderer* Backend = nullptr;
  /// The level of detail rendered (0: full resolution) and the version of
  /// that level's data (a rebuilt level is new data).
  int Level = 0;
  unsigned long long LevelVersion = 0;
  /// AUTOMATIC_ESTIMATOR's interactive renders, which may take another
  /// estimator than the still ones (vtkMultiChannelVolumeMapper::
  /// SetInteractiveRendering); false otherwise.
  bool InteractiveEstimator = false;

  bool operator==(const AccumulationKey& o) const;
};

/**
 * Whether the cameras of two NDC -> world matrices (AccumulationKey::
 * InvViewProj) trace the same rays in a width x height image: the corners of
 * the view frustum of `a`, projected by `b`, land within kSameRayPixels of
 * where they are in `a` and within kSameRayDepth in NDC depth. Cameras set
 * by different routes to the same view differ in the last bits
 * (vtkWindowToImageFilter's re-render recomputes the view angle through a
 * truncated pi: a relative 3e-8); such a difference moves no ray visibly and
 * keeps the image. Each render compares with the camera the image was
 * started with, so many small moves add up to a restart.
 */
constexpr double kSameRayPixels = 1e-3;
constexpr double kSameRayDepth = 1e-6;
bool SameRays(const double a[16], const double b[16], int width, int height);

/// The key of the image being accumulated, and the depth it was traced
/// against.
class Accumulation
{
public:
  /// Restarts `accum` (resized to the key's size) when the key, the depth or
  /// a requested reset says the image is stale. `depth` is this render's
  /// depth buffer; afterwards Depth() is the one to trace against.
  /// True when the image was restarted.
  bool Update(const AccumulationKey& key, std::vector<float>& depth, Accumulator& accum);

  /// The depth buffer the current image is traced against; null when the
  /// render had none (nothing but volumes: every ray reaches the far plane).
  const float* Depth() const { return this->LastDepth.empty() ? nullptr : this->LastDepth.data(); }

  /// The next render starts a new image (ResetAccumulation).
  void RequestReset() { this->ResetRequested = true; }
  /// The image is unusable (an error, or its backend was released).
  void Invalidate() { this->HaveKey = false; }
  /// Whether an image is being accumulated for an up-to-date key.
  bool IsCurrent() const { return this->HaveKey && !this->ResetRequested; }

private:
  bool HaveKey = false;
  bool ResetRequested = false;
  AccumulationKey Key;
  std::vector<float> LastDepth;
};

/**
 * The measured cost of a sample per pixel, for time-budgeted renders
 * (vtkMultiChannelVolumeMapper::SetInteractiveFrameTime): a moving average
 * of the last batches' seconds per sample, kept across image restarts (a
 * moved camera costs about what the last view did).
 */
class SampleCost
{
public:
  /// A batch of `samples` samples per pixel took `seconds`.
  void Record(int samples, double seconds);
  /// Samples per pixel that fit in `frameTime` seconds: at least 1, at most
  /// `cap`; `first` before anything was measured.
  int Budget(double frameTime, int first, int cap) const;

private:
  double SecondsPerSample = 0.0;
};

/// Samples per pixel this render traces: a batch of `samplesPerPixel`, none
/// more once a non-progressive image exists, and no more than what is left of
/// `maximumTotalSamples` (0: no limit). A mapper that does not add Monte
/// Carlo samples (`addsSamples` false: the ray march) decides for itself.
int SamplesThisRender(
  bool addsSamples, bool progressive, int samplesPerPixel, long long maximumTotalSamples, long long traced);
} // namespace adapter
} // namespace mcvol
