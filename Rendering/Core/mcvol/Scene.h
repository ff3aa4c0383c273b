// SPDX-License-Identifier: BSD-3-Clause
#pragma once

#include "mcvol/ray/SceneView.h"
#include "mcvol/ray/Types.h"

#include <array>
#include <cstddef>
#include <cstdint>
#include <vector>

namespace mcvol
{
/**
 * Where one channel's voxels live: value of voxel v is data[v * stride].
 *
 * format Extinction (pre-classified): voxel v is the 4 float32
 * values data[v * stride + 0..3] = (sigma, sigma r, sigma g, sigma b), sigma
 * the extinction per world unit (as a transfer-function table holds it) and
 * (r, g, b) linear RGB in [0, 1]. type must be Float32, stride (in floats) at
 * least 4 (4: packed RGBA-like quadruples), offset 0; or type Float16: 4
 * binary16 values per voxel (stride in halves, at least 4), each multiplied
 * by `scale` when read (the pyramid levels' half-precision layout,
 * PyramidLevel::toHalfPrecision). Such a channel needs no
 * transfer function (one set anyway is kept but never read) and carries no
 * importance. Values are sanitised per voxel when read, never rejected
 * (the data are not scanned at setVolume): a negative sigma is clamped to 0
 * (the voxel is transparent and its colour ignored), sigma above 1e30 is
 * clamped to 1e30, and each sigma*c to [0, sigma]. A NaN in any of the four
 * values makes the channel transparent wherever that voxel is read (the
 * scalar NaN rule).
 */
struct ChannelSource
{
  const void* data = nullptr;
  ScalarType type = ScalarType::Float32;
  int64_t stride = 1; ///< in elements; N for the components of an interleaved array
  /// Float64 only: subtracted in double before a value becomes float, so data
  /// far from zero (1e9 + [0, 500]) keeps its resolution. Set it near the
  /// data (its minimum, say); transfer-function ranges stay in data units.
  double offset = 0.0;
  /// Last, so that aggregate initialisers { data, type, stride, offset } keep working.
  ChannelFormat format = ChannelFormat::Scalar;
  /// Float16 Extinction channels only (finite, > 0): the factor every
  /// stored value is multiplied by, so that a level's extinctions use
  /// binary16's range whatever their units. 1 for every other channel.
  double scale = 1.0;
};

/**
 * One channel's transfer function, sampled at `opacity.size()` evenly spaced
 * scalars over [scalarMin, scalarMax] (values outside clamp to the ends).
 * Opacity is VTK's: the opacity accumulated over `unitDistance` world units.
 */
struct TransferFunctionDesc
{
  double scalarMin = 0.0; ///< data units (the channel's offset is taken off)
  double scalarMax = 1.0;
  std::vector<float> rgb;     ///< 3 * K linear RGB in [0,1]
  std::vector<float> opacity; ///< K opacities in [0,1]
  float unitDistance = 1.f;   ///< world units, > 0
};

/**
 * Opacity 1 would be infinite extinction. Opacities are clamped to
 * kMaxOpacity = 1 - 2^-20 first, so an "opaque" transfer function lets
 * 2^-20 (about 1e-6) of the light through one unit distance: sigma is then
 * 13.86 / unitDistance, finite, and indistinguishable from opaque in 8-bit
 * images.
 */
constexpr float kMaxOpacity = 1.f - 0x1p-20f;

/// VTK's ScalarOpacityUnitDistance meaning: sigma = -ln(1 - a) / u.
float opacityToExtinction(float opacity, float unitDistance);

/// One light, in world space.
struct LightDesc
{
  bool point = false;             ///< false: directional
  double vector[3] = { 0, 0, 1 }; ///< directional: direction towards the light; point: position
  double color[3] = { 1, 1, 1 };
  double intensity = 1.0;
};

/**
 * What the scene asks of lighting. With no light and no ambient,
 * rendering is pure emission-absorption and none of it costs anything.
 */
struct LightingDesc
{
  std::vector<LightDesc> lights;
  double ambient[3] = { 0, 0, 0 }; ///< environment radiance from every direction
  std::vector<float> albedo;       ///< per channel, [0, 1] (missing: 0.5)
  std::vector<float> anisotropy;   ///< per channel, (-1, 1) (missing: 0)
  bool shadows = true;
  bool deltaShadows = false; ///< delta tracking instead of ratio tracking
  /**
   * Cached shadows (mcvol/ray/ShadowCache.h): each directional light's
   * transmittance is computed once on a grid of nodes `cacheSpacing` voxels
   * apart ([0.5, 64]) and interpolated, instead of a shadow ray per
   * scattering event. Biased (shadow edges finer than the spacing blur)
   * and much cheaper; the grid is rebuilt when the data, a transfer
   * function, the blend or a light's direction changes. Point lights, the
   * ambient light, post-render compositing, a piece of a split volume
   * (setOutside) and light rays under the visibility optimization keep
   * their tracked shadow rays. False (default): every shadow is tracked.
   */
  bool cacheShadows = false;
  float cacheSpacing = 2.f;
  int maxDepth = 1;          ///< scattering events per path (1 = single scattering)
  bool gradientShading = false;
  float shininess = 32.f;
  /// Next-event estimation towards one light per scattering event, chosen
  /// with probability proportional to its radiance (r + g + b of colour
  /// times intensity) and weighted by 1 / probability: the same expectation
  /// as sampling every light, for one shadow ray instead of one per light.
  /// False (default): every light, one shadow ray each.
  bool sampleOneLight = false;
  /// The expected-value estimator's scattering vertex (traceLitExpected()):
  /// a camera ray whose scattering weight W (the light it scatters, at most
  /// 1) is below this keeps its vertex with probability W / this. Smaller
  /// spends more shadow rays on thin rays for less noise; 1 about the
  /// collision estimator's shadow rays. (0, 1].
  float scatterRoulette = 0.5f;
};

/**
 * Visibility optimization (Lerzer and Dachsbacher). Each channel's importance function is
 * a table over the same value range as its transfer-function table (same
 * size); an empty table means the channel carries no importance. Values are
 * clamped to [0, 1] and snapped to the levels 0, 1/4, 1/2, 3/4, 1: the paper's
 * importance is a step function with a few distinct values (Sec. 4.2), and
 * few levels keep the per-ray segment lists short.
 */
struct ImportanceDesc
{
  bool enabled = false;
  std::vector<std::vector<float>> tables; ///< per channel; missing or empty: none
  double p = 1.0;                         ///< deviation weight (> 0)
  double q = 70.0;                        ///< occlusion weight (>= 0)
  double r = 30.0;                        ///< clutter weight (>= 0)
  double lambda = 1.0;                    ///< emphasis (>= 0)
  double mergeDistance = 0.0;             ///< d in normalised ray units (the volume spans 2); 0: two strata
  int samplesPerPass = 32;                ///< 1 .. kMaxImportanceSamples
  int refinePasses = 4;                   ///< passes that refine a pixel's segments (>= 1)
  bool lightRays = true;                  ///< optimize the rays to the lights too (Sec. 5.3)
  int lightRaySamples = 200;              ///< samples of each light ray's list (2 .. 4096)
  /// Which end of a light ray Eq. 7's x (where K starts) is: false (default)
  /// the scattering vertex, the ray's origin, as on a camera ray: an
  /// occluder between an important vertex and the light is weighted by r;
  /// true the light, read as the viewer: that occluder is weighted by q
  /// (Documentation/user-guide/visibility.md compares the two).
  bool lightRaysFromLight = false;
};

/// Snaps an importance value to the levels of ImportanceDesc.
float snapImportance(float v);

/// Memory of the acceleration structures, for the benchmark (paper Table 1).
struct MemoryStats
{
  size_t dataBytes = 0;
  size_t macrocellBytes = 0;
  size_t majorantBytes = 0;
  size_t tableBytes = 0;
};

/// An identity that copies do not share (a copied Scene or Accumulator is a
/// new object for the device caches keyed on it).
struct ObjectId
{
  ObjectId();
  ObjectId(const ObjectId&);
  ObjectId& operator=(const ObjectId&);
  uint64_t value = 0;
};

/**
 * Host-side owner of everything a render needs except the camera: the
 * channels (not copied), transfer-function tables, the macrocell grid of
 * per-channel scalar ranges and the per-channel majorant grids.
 *
 * Changing one channel's transfer function rebuilds only that channel's
 * majorants; changing the data or the macrocell size rebuilds the ranges and
 * all majorants. Nothing is rebuilt until update().
 *
 * Bad arguments throw std::invalid_argument with a message naming the cause.
 */
class Scene
{
public:
  Scene();

  /// dims: voxels per axis (each >= 1). The data must outlive the Scene.
  /// Each channel's format (ChannelSource::format) may be Scalar or
  /// Extinction, mixed freely.
  void setVolume(const int dims[3], int numChannels, const ChannelSource* channels);
  /// Marks the data as changed (same pointers, new values).
  void dataModified();
  /**
   * The box rays are clipped to, in continuous voxel indices (lo, hi per
   * axis). By default, and again after setVolume(), it is [0, dims - 1] per
   * axis, [-0.5, 0.5] on an axis of one voxel: the volume's bounds. A level
   * of detail takes level 0's bounds in its own index space
   * (PyramidLevel::indexBounds), so that every level covers the same world
   * box; points between its outer voxels and the box read the outer voxels
   * (sampling clamps to the grid, as it does everywhere). Each side may
   * reach at most half a voxel past the outer voxels. Throws
   * std::invalid_argument for a non-finite or empty box, one that reaches
   * further, or no volume.
   */
  void setIndexBounds(const double lo[3], const double hi[3]);
  void setTransferFunction(int channel, const TransferFunctionDesc& tf);
  /// Macrocell edge in voxels (>= 1).
  void setMacrocellSize(int voxels);
  void setBlendMode(BlendMode mode);
  /// Reconstruction filter between voxels (default Linear). Switching to or
  /// from Cubic rebuilds the macrocell ranges at the next update(): the
  /// cubic footprint is one voxel wider (cellVoxelBounds' apron). Throws
  /// std::invalid_argument for a value outside the enum.
  void setInterpolation(Interpolation interpolation);
  Interpolation interpolation() const { return this->InterpolationType; }
  /// Nearest-voxel sampling (true) or trilinear (false); kept for callers
  /// that know only the two (setInterpolation(Nearest or Linear)).
  void setNearestInterpolation(bool nearest)
  {
    this->setInterpolation(nearest ? Interpolation::Nearest : Interpolation::Linear);
  }
  /// Non-negative weights, one per channel; normalised to sum 1 (Eq. 10).
  /// All zero means equal weights.
  void setMixWeights(const float* weights, int count);
  /// Mix colour (BlendView::mixAverage): true (default) the weighted average
  /// of the channels present at a point; false Eq. 10 as published.
  void setMixAverage(bool average) { this->View.blend.mixAverage = average; }
  /// Lights and scattering (throws std::invalid_argument on bad values).
  void setLighting(const LightingDesc& lighting);
  bool lit() const { return this->View.lighting.enabled; }
  /// Importance functions and weights (throws std::invalid_argument on bad
  /// values, a table whose size differs from the channel's colour table, or
  /// a non-empty table for a pre-classified (Extinction) channel, which has
  /// no scalar to look importance up by; update() checks that again).
  void setImportance(const ImportanceDesc& importance);
  /// Whether rendering runs the visibility optimization.
  bool optimized() const { return this->View.importance.enabled; }

  /**
   * Lit rendering of one piece of a volume split over processes: `outside`
   * stands in for the whole volume (every piece, this one included) along
   * the parts of light paths beyond this Scene's box (SceneView::outside:
   * the rest of each shadow ray and, with multiple scattering, scattered
   * rays that leave the piece). This Scene's index point p is the
   * stand-in's p * scale + offset, per axis. A render reads only the
   * stand-in's volume, tables, macrocells and majorants (it must be
   * updated, with host acceleration on, and have this Scene's number of
   * channels, or the render throws std::invalid_argument); lighting, blend
   * and every setting are this Scene's. Unlit renders ignore it. The
   * stand-in is not copied: it must outlive its use. Null (default) clears
   * it. Throws std::invalid_argument for this Scene itself, or a scale that
   * is not positive and finite or an offset that is not finite.
   *
   * `exact`: the stand-in holds this piece's voxels as they are, at this
   * Scene's resolution, classified through the same tables (an exact
   * stand-in: the whole volume). Light paths then continue in the stand-in
   * from their first vertex (SceneView::outsideExact): one march per
   * shadow ray instead of one in the piece and one beyond it, the same
   * expectation. Without it (a coarse stand-in), and under the visibility
   * optimization, the part of a light path inside the piece reads the
   * piece.
   */
  void setOutside(
    const Scene* outside, const double scale[3] = nullptr, const double offset[3] = nullptr, bool exact = false);
  const Scene* outside() const { return this->Outside; }
  bool outsideExact() const { return this->OutsideExact; }
  /// The map given to setOutside (scale 1, offset 0 without one).
  const double* outsideScale() const { return this->OutsideScale; }
  const double* outsideOffset() const { return this->OutsideOffset; }

  /**
   * Whether update() builds the macrocell ranges and majorants on the host
   * (default true; the CPU backend reads them). A backend that builds its own
   * copies on the device (CUDA) turns it off so that no host time or memory
   * is spent on them; update() then only checks the input, samples the tables
   * and lays out the grid, and the per-channel versions below tell the
   * backend what to rebuild.
   */
  void setHostAcceleration(bool on);
  bool hostAcceleration() const { return this->HostAcceleration; }

  /// Builds what is out of date. Returns true if anything was rebuilt.
  bool update();

  int numChannels() const { return this->NumChannels; }
  const int* dims() const { return this->Dims; }
  int macrocellSize() const { return this->MacrocellSize; }
  BlendMode blendMode() const { return this->View.blend.mode; }
  const int* macrocellDims() const { return this->View.grid.dims; }
  /// Seconds spent in the last majorant (re)build, and how many channels it touched.
  double lastMajorantBuildSeconds() const { return this->LastMajorantSeconds; }
  int lastMajorantChannelsRebuilt() const { return this->LastMajorantChannels; }
  double lastMacrocellBuildSeconds() const { return this->LastMacrocellSeconds; }
  MemoryStats memory() const;
  /// Increments whenever update() changes anything a backend caches.
  uint64_t dataVersion() const { return this->DataVersion; }
  uint64_t tableVersion() const { return this->TableVersion; }
  /// Unique per Scene object (copies get their own), for device caches.
  uint64_t id() const { return this->Id.value; }
  /// Increments when the voxels change (setVolume, dataModified), not when
  /// only the macrocell size does.
  uint64_t contentVersion() const { return this->ContentVersion; }
  /// Increments when channel n's transfer function is set.
  uint64_t channelTableVersion(int n) const { return this->ChannelTableVersion[size_t(n)]; }
  /// The channels as given to setVolume (a device backend uploads them).
  const ChannelSource& channel(int n) const { return this->Channels[size_t(n)]; }

  /// The plain view the per-ray code reads (valid after update()).
  const SceneView& view() const { return this->View; }

  /// Host copies a backend uploads (the CUDA backend mirrors them).
  const std::vector<float>& macrocellRanges() const { return this->Ranges; }
  const std::vector<float>& majorants() const { return this->Majorants; }
  const std::vector<float>& tables() const { return this->Tables; }
  /// Snapped importance tables [channel][K] (the view's importance.table).
  const std::vector<float>& importanceTables() const { return this->ImportanceTables; }

private:
  void layoutGrid();
  void rebuildMacrocells();
  void rebuildMajorants(int channel);
  void refreshView(bool majorantsChanged);
  void refreshImportance();

  int Dims[3] = { 0, 0, 0 };
  int NumChannels = 0;
  const Scene* Outside = nullptr;
  double OutsideScale[3] = { 1, 1, 1 };
  double OutsideOffset[3] = { 0, 0, 0 };
  bool OutsideExact = false;
  std::array<ChannelSource, kMaxChannels> Channels{};
  std::array<bool, kMaxChannels> HasTF{};
  std::array<bool, kMaxChannels> MajorantDirty{};
  ObjectId Id;
  bool MacrocellsDirty = true;
  bool HostAcceleration = true;
  bool HasIndexBounds = false; ///< setIndexBounds() since setVolume()
  double IndexBoundsLo[3] = { 0, 0, 0 };
  double IndexBoundsHi[3] = { 0, 0, 0 };
  uint64_t ContentVersion = 0;
  std::array<uint64_t, kMaxChannels> ChannelTableVersion{};
  int MacrocellSize = 8;
  Interpolation InterpolationType = Interpolation::Linear;
  std::array<float, kMaxChannels> MixWeights{};

  std::vector<float> Tables; ///< [channel][K][4]: r, g, b, extinction
  ImportanceDesc Importance;
  std::vector<float> ImportanceTables; ///< [channel][K], snapped
  std::vector<float> Ranges;           ///< [cell][channel][2]: min, max
  std::vector<float> Majorants;        ///< [cell][channel]
  SceneView View;
  double LastMajorantSeconds = 0.0;
  int LastMajorantChannels = 0;
  double LastMacrocellSeconds = 0.0;
  uint64_t DataVersion = 0;
  uint64_t TableVersion = 0;
};
} // namespace mcvol
