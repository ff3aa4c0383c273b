// SPDX-License-Identifier: BSD-3-Clause
#pragma once

#include "mcvol/Scene.h"

#include <cstddef>
#include <cstdint>
#include <functional>
#include <limits>
#include <vector>

namespace mcvol
{
/**
 * Extinction-based pyramids of pre-classified volumes (Kraus and
 * Buerger, "Interpolating and Downsampling RGBA Volume Data", Section 4).
 *
 * A pre-classified volume holds per voxel (sigma, sigma r, sigma g, sigma b)
 * as 4 floats: extinction per world unit and extinction-weighted linear RGB
 * (ChannelFormat::Extinction). A level halves every axis (ceil; an axis of 1
 * voxel stays 1) by filtering sigma and sigma*colour with a separable,
 * symmetric filter (Sec. 4.1: extinction, not opacity, is averaged, so a thin
 * opaque structure is blurred but keeps its opacity along rays through it).
 *
 * Alignment (cell-centred, like mipmaps): coarse voxel c along an axis is
 * centred between fine voxels 2c and 2c+1, so a level's spacing is twice the
 * finer one and its origin (world position of voxel 0) moves by half a finer
 * spacing. An axis of 1 voxel is not filtered: its spacing and origin stay.
 * A level's outer voxels therefore sit inside level 0's box (by a quarter of
 * a level-1 voxel, 3/8 of a level-2 voxel, ...): every level keeps level 0's
 * world box (PyramidLevel::bounds) and is rendered over it
 * (PyramidLevel::indexBounds, Scene::setIndexBounds), with the outer voxels
 * reaching the box, so a level covers what level 0 covers. Boundary: taps outside the finer grid are clamped to its edge voxel (a
 * constant volume stays constant everywhere, edges included); weights are
 * normalised (they sum to 1).
 */
enum class DownsampleFilter : int
{
  /// (1 1) / 2: the 2x2x2 box, the usual mipmap filter (paper Sec. 4.2:
  /// epsilon = 0.34, epsilon_0 = 0.14 against a convolution).
  Box2 = 0,
  /// (1 1 1 1) / 4: the paper's "4-tap box filter", its recommended
  /// compromise for data sampled by trilinear interpolation (epsilon =
  /// 0.057, epsilon_0 = 0.0093). The paper names it without listing
  /// weights; a box has equal ones.
  Box4 = 1,
  /// (13 19 19 13) / 64: Kraus' filter for data sampled by quadratic
  /// B-spline filtering (epsilon = 0.0276, epsilon_0 = 0.0027).
  BSpline = 2
};

const char* toString(DownsampleFilter f);

/// A filter's taps: coarse voxel c reads finer voxels 2c + first + k,
/// k < count, with weights w[k] (normalised: they sum to 1).
struct FilterTaps
{
  int count = 0;
  int first = 0;
  double w[4] = { 0, 0, 0, 0 };
};
FilterTaps filterTaps(DownsampleFilter f);

/// A pre-classified volume read in place: voxel v is voxels[v * stride +
/// 0..3] = (sigma, sigma r, sigma g, sigma b), x fastest.
struct ClassifiedVolumeView
{
  const float* voxels = nullptr;
  int64_t stride = 4; ///< floats between voxels (>= 4)
  int dims[3] = { 0, 0, 0 };
  double spacing[3] = { 1, 1, 1 }; ///< world units, > 0
  double origin[3] = { 0, 0, 0 };  ///< world position of voxel 0
};

/// One level of a pyramid: its own packed voxels (stride 4), float32 or,
/// after toHalfPrecision(), binary16.
struct PyramidLevel
{
  int level = 0; ///< 0 = full resolution
  int dims[3] = { 0, 0, 0 };
  double spacing[3] = { 1, 1, 1 };
  double origin[3] = { 0, 0, 0 };
  /// World box of level 0, which every level covers: level 0's outer voxel
  /// centres (origin .. origin + (dims - 1) spacing), half a spacing either
  /// side of the voxel on an axis of one voxel (the box Scene gives such an
  /// axis). NaN on a level made by hand (indexBounds then gives its own box).
  double boundsLo[3] = { kNoBounds, kNoBounds, kNoBounds };
  double boundsHi[3] = { kNoBounds, kNoBounds, kNoBounds };
  std::vector<float> voxels; ///< 4 floats per voxel (empty once half precision)
  /// After toHalfPrecision(): 4 binary16 values per voxel, each times halfScale.
  std::vector<uint16_t> halfVoxels;
  double halfScale = 1.0;

  static constexpr double kNoBounds = std::numeric_limits<double>::quiet_NaN();
  /// `bounds` in this level's continuous index space ((world - origin) /
  /// spacing per axis): the box to render the level over
  /// (Scene::setIndexBounds) so that it covers level 0's world box. Without
  /// bounds, the level's own box (as Scene makes it).
  void indexBounds(double lo[3], double hi[3]) const;
  size_t numVoxels() const { return size_t(this->dims[0]) * size_t(this->dims[1]) * size_t(this->dims[2]); }
  size_t bytes() const { return this->voxels.size() * sizeof(float) + this->halfVoxels.size() * sizeof(uint16_t); }
  bool halfPrecision() const { return !this->halfVoxels.empty(); }
  /// The float32 voxels; std::logic_error for a half-precision level.
  ClassifiedVolumeView view() const;
  /// A channel for Scene::setVolume (format Extinction, stride 4; float32,
  /// or float16 with `scale` = halfScale); the level must outlive the Scene.
  /// The caller's camera maps world to index with this level's spacing and
  /// origin.
  ChannelSource source() const;
  /**
   * Converts the level to half precision (8 bytes a voxel instead of 16,
   * for the memory budget) and frees the float32 voxels. Every value v is
   * stored as binary16(v / halfScale), rounded to nearest, with halfScale
   * the power of two that puts the level's largest value between 2^13 and
   * 2^14 (binary16's largest finite value is 65504): each value keeps a
   * relative error of at most 2^-11 down to 2^-28 of the largest, and
   * smaller ones an absolute error of at most 2^-39 of it (subnormals). A
   * NaN stays NaN; an infinite or negative value (which no build produces)
   * throws std::invalid_argument. Idempotent; an empty level stays empty.
   */
  void toHalfPrecision();
};

/// The world box of a volume of `dims`, `spacing` and `origin` as Scene
/// renders it: its outer voxel centres, and half a spacing either side on an
/// axis of one voxel.
void volumeBounds(const int dims[3], const double spacing[3], const double origin[3], double lo[3], double hi[3]);

/// The number of halvings after which every axis of `dims` is 1 (the most
/// levels a pyramid of them can have above level 0).
int maxPyramidLevels(const int dims[3]);

/**
 * One extinction-based downsampling step (Sec. 4.1): sigma and sigma*colour
 * filtered separably. Throws std::invalid_argument on bad input: no voxels,
 * a stride below 4, dims below 1, a spacing that is not positive and finite,
 * or a voxel whose sigma is negative, NaN or infinite or whose weighted
 * colour is NaN, infinite or negative (rejected, not clamped: a filter
 * would spread them into their neighbours).
 */
PyramidLevel downsampleExtinction(const ClassifiedVolumeView& fine, DownsampleFilter filter);

/// Levels 1..levels (in order) of the extinction-based pyramid over level 0;
/// levels in [0, maxPyramidLevels(dims)] (0 gives none). Same errors as
/// downsampleExtinction, and a level count out of range.
std::vector<PyramidLevel> buildExtinctionPyramid(
  const ClassifiedVolumeView& level0, int levels, DownsampleFilter filter = DownsampleFilter::Box4);

/**
 * The opacity-averaging baseline (Sec. 4.1, Fig. 3), for comparison only:
 * each finer voxel's opacity for the distance `step` (world units),
 * alpha = 1 - exp(-sigma step), and its opacity-weighted colour alpha c are
 * filtered; the coarse voxel's averaged opacity a is taken as the opacity
 * over `step`, so over its own doubled size it is 1 - (1 - a)^2 (the
 * opacity correction, Eq. 16), and it is stored back as extinction
 * sigma' = -ln(1 - a) / step with colour (alpha c) / a. (The transparency
 * 1 - alpha is what is filtered, which is the same average and keeps float
 * precision near alpha = 1; 1 - a is kept above 1e-30.) In the paper's example 4 voxels of tau = 4 and 4 of 0
 * average to a = 0.49, and 0.74 over the coarse voxel, where extinction
 * averaging keeps 0.98. It loses opacity in general.
 */
PyramidLevel downsampleOpacity(const ClassifiedVolumeView& fine, double step, DownsampleFilter filter);

/// Levels 1..levels of the opacity-averaging baseline, level l averaging
/// opacities for the step step0 * 2^(l-1) (the finer level's voxel size).
std::vector<PyramidLevel> buildOpacityPyramid(
  const ClassifiedVolumeView& level0, int levels, double step0, DownsampleFilter filter = DownsampleFilter::Box2);

/**
 * Pre-classifies one scalar channel through a transfer function into the
 * float4 layout, with the core's table semantics (TransferFunctionDesc:
 * K texels over [scalarMin, scalarMax], values outside clamped to the ends,
 * colour clamped to [0, 1], opacity for unitDistance turned into extinction
 * by opacityToExtinction, colour and extinction interpolated linearly
 * between texels as lookupTF does). `out` receives 4 floats per voxel at
 * out[v * outStride]; with `accumulate` the sample is added to what is
 * there, so classifying N channels into one array gives their density blend
 * (Eq. 6/7: extinctions and extinction-weighted colours add). A NaN scalar
 * gives a transparent voxel (0, 0, 0, 0); note that rendering the scalar
 * instead blanks the channel wherever its footprint reads the NaN. Float64
 * data use the source's offset as Scene does. Parallel over voxels
 * (OpenMP). Throws std::invalid_argument on a bad source or table.
 */
void classifyScalars(const ChannelSource& src, const int dims[3], const TransferFunctionDesc& tf, float* out,
  int64_t outStride = 4, bool accumulate = false);
/// Voxels per axis of pyramid level `level` (>= 0) over `dims`: every axis
/// halved (ceil) `level` times, an axis of 1 staying 1.
void levelDims(const int dims[3], int level, int out[3]);

/// Bytes of level `level` held as `channels` pre-classified channels of 4
/// floats per voxel (16 bytes a voxel and channel), or of 4 halves
/// (`halfPrecision`: 8 bytes, PyramidLevel::toHalfPrecision).
size_t levelBytes(const int dims[3], int level, int channels, bool halfPrecision = false);

/**
 * Streamed construction of one level (memory-aware): level `level` (1 ..
 * maxPyramidLevels(dims)) of the extinction-based pyramid over a level 0 of
 * `dims`, `spacing` and `origin` that is never held whole. `slice(z, out)`
 * writes level 0's z-slice z (dims[0] * dims[1] voxels of 4 floats, x
 * fastest) into `out`. Each slice is filtered along x and y at once, and
 * along z as soon as the filter's taps are in, through one stage per level:
 * a stage keeps only the few xy-filtered slices its z taps still need (4
 * for Box4 and BSpline, 2 for Box2). The level's z-slices are split into
 * chunks streamed in parallel (OpenMP), one thread per chunk: `slice` is
 * called from several threads at once (it must be thread-safe), in
 * increasing z within a chunk, and the few slices at a chunk's border that
 * both neighbours' taps read are asked for twice. Working memory is about
 * one level-0 slice plus 4 xy-filtered slices per stage and chunk, besides
 * the level itself; `peakWorkBytes` (optional) receives the largest
 * chunk's peak times the chunks that run at once (the output level
 * excluded). The result equals
 * buildExtinctionPyramid(level0, level, filter).back() exactly: the same
 * taps in the same order (x, y, then z) in double, stored as float after
 * each axis. Same errors as downsampleExtinction (bad geometry, a negative,
 * NaN or infinite value in a slice), and a level out of range.
 */
PyramidLevel streamExtinctionLevel(const int dims[3], const double spacing[3], const double origin[3], int level,
  DownsampleFilter filter, const std::function<void(int z, float* out)>& slice, size_t* peakWorkBytes = nullptr);

/// One scalar channel and the table that classifies it.
struct ClassifyInput
{
  ChannelSource source;
  const TransferFunctionDesc* tf = nullptr;
  /// Optional, for device backends (Renderer::classifyLevel): nonzero names
  /// the content of `source` (e.g. the data array's modification time), so
  /// a backend may keep its device copy of the channel between builds and
  /// reuse it while the source pointer, type, stride, dims and this version
  /// are the same (a transfer-function edit then uploads nothing). 0: the
  /// content is unknown and is copied every time. The caller must change it
  /// whenever the data change in place. The host build ignores it.
  uint64_t dataVersion = 0;
};

/**
 * streamExtinctionLevel over scalar channels classified slice by slice:
 * level 0's slice is the sum of classifyScalars of every input (their
 * density blend, Eq. 6/7: extinctions and extinction-weighted colours add);
 * one input gives that channel's own pre-classified level. The full-
 * resolution classified volume (16 bytes a voxel) is never allocated: the
 * working memory is one classified level-0 slice and the stages' slices.
 * Throws what classifyScalars and streamExtinctionLevel throw, and for no
 * inputs or a missing table.
 */
PyramidLevel classifyExtinctionLevel(const ClassifyInput* inputs, int numInputs, const int dims[3],
  const double spacing[3], const double origin[3], int level, DownsampleFilter filter, size_t* peakWorkBytes = nullptr);

/// A transfer function as classifyScalars reads it: per texel (r, g, b,
/// extinction), colour clamped to [0, 1] and extinction from
/// opacityToExtinction, 4 floats a texel; a scalar s (in data units, double)
/// is at texel coordinate (s - scalarMin) * scale, clamped to [0, K - 1].
struct ClassificationTable
{
  std::vector<float> texels; ///< 4 per texel
  size_t K = 0;
  double scalarMin = 0.0;
  double scale = 0.0;
};

/// The table classifyScalars and classifyExtinctionLevel build for `src`
/// and `tf` (for backends that classify elsewhere, e.g. on a device, with
/// the same numbers). Throws what classifyScalars throws for them.
ClassificationTable classificationTable(const ChannelSource& src, const TransferFunctionDesc& tf);
/// classificationTable() of each input, after classifyExtinctionLevel()'s
/// checks of them (at least one, each with data and a transfer function:
/// std::invalid_argument naming the channel).
std::vector<ClassificationTable> classificationTables(const ClassifyInput* inputs, int numInputs);

/// The geometry (level, dims, spacing, origin; no voxels) of level `level`
/// (1 .. maxPyramidLevels(dims)) over a level 0 of `dims`, `spacing` and
/// `origin`, as streamExtinctionLevel computes it; throws its errors for bad
/// geometry and a level out of range.
PyramidLevel pyramidLevelGeometry(const int dims[3], const double spacing[3], const double origin[3], int level);

/**
 * The automatic level of detail: the level whose voxels
 * are about one pixel, L = floor(log2(pixelFootprintWorld / min(spacing))),
 * clamped to [0, levels]. `pixelFootprintWorld` is the world size of one
 * pixel where the volume is (perspective: 2 d tan(viewAngle / 2) / height
 * in pixels, d the distance from the camera to the centre of the volume's
 * bounding box; parallel projection: 2 parallelScale / height), `spacing`
 * level 0's voxel size in world units per axis. A pixel smaller than twice
 * the finest voxel keeps level 0, since level 1's voxels would then be
 * larger than a pixel. Throws std::invalid_argument for a footprint that is
 * negative or NaN, a spacing that is not positive and finite, or levels < 0;
 * an infinite footprint gives `levels`.
 */
int chooseLevelOfDetail(double pixelFootprintWorld, const double spacing[3], int levels);
} // namespace mcvol
