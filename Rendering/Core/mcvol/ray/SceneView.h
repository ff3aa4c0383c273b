// SPDX-License-Identifier: BSD-3-Clause
#pragma once

#include "mcvol/ray/Macros.h"
#include "mcvol/ray/Types.h"
#include "mcvol/ray/Vec.h"

#include <cstdint>

namespace mcvol
{
/**
 * Plain data the per-ray code reads, written down once for both backends
 * (like OSPRay's *Shared.h). Pointers are host pointers on the CPU backend and
 * device pointers in the copy the CUDA backend uploads.
 */
struct ChannelView
{
  const void* data = nullptr;
  int64_t stride = 1; ///< elements between consecutive voxels
  ScalarType type = ScalarType::Float32;
  /// Float64 scalars: subtracted before conversion to float. Float16
  /// pre-classified channels (host only; the CUDA backend widens them to
  /// float32): the factor their values are multiplied by (ChannelSource::scale).
  double offset = 0.0;
  /// CUDA backend only: a 3D texture object (cudaTextureObject_t) holding the
  /// same voxels, sampled with hardware filtering instead of `data`; 0 = none.
  unsigned long long texture = 0;
  /// CUDA backend only: when `data` is null, a point-filtered 3D texture
  /// holding the voxels (the channel is held once, as a texture), read voxel
  /// by voxel by fetchVoxel(); voxelTextureDims are the grid's x and y sizes.
  unsigned long long voxelTexture = 0;
  int voxelTextureDims[2] = { 0, 0 };
  /// Texture reads of integer data come back normalised (uint8 / 255 ...);
  /// this factor restores data units.
  float textureScale = 1.f;
  /// Extinction: 4 float32 per voxel (sigma, sigma r, sigma g, sigma b),
  /// sampled by sampleClassified (in software, or from a float4 texture of
  /// the sanitised voxels that the CUDA backend may hold instead of `data`).
  ChannelFormat format = ChannelFormat::Scalar;
};

struct VolumeView
{
  int dims[3] = { 0, 0, 0 };
  int numChannels = 0;
  ChannelView channels[kMaxChannels];
  /// Index-space box the volume occupies: [0, dim-1] per axis, except that an
  /// axis with a single voxel gets [-0.5, 0.5] (one spacing of thickness); a
  /// level of detail's is level 0's box (Scene::setIndexBounds), up to half
  /// a voxel wider, where sampling clamps to the outer voxels.
  Vec3f boxLo;
  Vec3f boxHi;
  /// Nearest-voxel instead of trilinear sampling (vtkVolumeProperty's
  /// VTK_NEAREST_INTERPOLATION).
  bool nearest = false;
  /// Cubic B-spline instead of trilinear sampling (Interpolation::Cubic;
  /// never together with nearest). Sampled out of line
  /// (sampleChannelCubic, sampleClassifiedCubic).
  bool cubic = false;
};

/// Transfer-function tables: per channel K texels of (r, g, b, extinction).
struct TableView
{
  int size = 0; ///< K >= 2
  const float* texels = nullptr;
  float scalarMin[kMaxChannels]; ///< table start minus the channel's offset
  float scale[kMaxChannels];     ///< (K - 1) / (max - min), always finite
};

/// Regular grid of macrocells in index space; majorants[cell * N + n].
struct GridView
{
  int dims[3] = { 0, 0, 0 };
  Vec3f lo;
  Vec3f cellSize;
  Vec3f invCellSize;
  int numChannels = 0;
  const float* majorants = nullptr;
};

struct BlendView
{
  BlendMode mode = BlendMode::Density;
  float mixWeights[kMaxChannels]; ///< sum to 1
  /// Mix colour: divided by sum_n w_n sigma_n (true: the weighted average of
  /// the channels present, a lone channel keeps its colour) or by
  /// max_n sigma_n (false: Eq. 10, a lone channel shows w_n of its colour).
  bool mixAverage = true;
};

/// Most lights a scene may have.
constexpr int kMaxLights = 8;

/**
 * Lighting. enabled is false for pure emission-absorption, and
 * then nothing below is read: the backends run the unlit kernels.
 */
struct LightingView
{
  bool enabled = false;
  int numLights = 0;
  int lightType[kMaxLights];       ///< 0: directional, 1: point
  Vec3f lightVector[kMaxLights];   ///< directional: unit world direction towards the light; point: world position
  Vec3f lightRadiance[kMaxLights]; ///< colour times intensity (point lights: at unit distance)
  /// Next-event estimation towards one light per scattering event
  /// (LightingDesc::sampleOneLight, with more than one light): light l is
  /// the first whose lightCdf[l] exceeds a uniform number, and is weighted
  /// by 1 / lightPdf[l]. Lights of zero radiance have lightPdf 0 and are
  /// never chosen; the last light with radiance has lightCdf 1.
  bool sampleOneLight = false;
  float lightCdf[kMaxLights];
  float lightPdf[kMaxLights];
  Vec3f ambient;                   ///< radiance arriving from every direction (an environment)
  float albedo[kMaxChannels];      ///< share of a channel's real collisions that scatter
  float anisotropy[kMaxChannels];  ///< Henyey-Greenstein g per channel
  bool shadows = true;             ///< trace shadow rays (else transmittance 1)
  int shadowEstimator = 0;         ///< ShadowEstimator: 0 ratio, 1 delta
  int maxDepth = 1;                ///< scattering events per path (1: single scattering)
  float scatterRoulette = 0.5f;    ///< LightingDesc::scatterRoulette
  bool gradientShading = false;    ///< Blinn-Phong on the extinction gradient (Lerzer and Dachsbacher)
  float shininess = 32.f;
  /**
   * Cached shadows (LightingDesc::cacheShadows; mcvol/ray/ShadowCache.h):
   * the transmittance towards each directional light on a grid of nodes
   * aligned with the light, looked up by a shadow ray instead of tracked.
   * Set per render by the backend: shadowCache[l] is light l's grid of
   * nodes (a host or a device address), null where its shadow rays are
   * tracked (a point light, no cache asked for, a piece of a split volume,
   * post-render compositing, or the visibility optimization of light
   * rays), and cacheFrame[l] and cacheDims[l] place its nodes
   * (ShadowCacheFrame::write()): in the view, so that the GPU's lookups
   * read them from the kernel's constant parameters.
   */
  bool cacheShadows = false;
  float cacheSpacing = 2.f; ///< asked-for node spacing, voxels
  const float* shadowCache[kMaxLights] = {};
  float cacheFrame[kMaxLights][12];
  int cacheDims[kMaxLights][3];
  /// Every light's shadow is looked up and there is no ambient light: no
  /// shadow ray is tracked, and the radiance scattered at a point is a
  /// function of the point (localLighting()).
  bool cachedOnly = false;
  /// Set per render by the backend from the camera: world-to-index linear
  /// part (row-major), its inverse, and the translation.
  float toIndex[9];
  float toWorld[9];
  Vec3f indexOffset;
};

/**
 * Visibility optimization (Lerzer and Dachsbacher; mcvol/ray/Importance.h). enabled is false
 * when the optimization is off or no channel carries importance anywhere,
 * and then nothing below is read: tracking is exactly the unoptimized code.
 */
struct ImportanceView
{
  bool enabled = false;
  int numChannels = 0;          ///< channels with an importance function
  int channels[kMaxChannels];   ///< which (opacity may be zero there)
  const float* table = nullptr; ///< [channel][TableView::size] snapped importance, over the TF table's range
  float p = 1.f;                ///< deviation weight
  float q = 70.f;               ///< occlusion weight
  float r = 30.f;               ///< clutter weight
  float twoLambda = 2.f;        ///< 2 lambda, the emphasis exponent of (1 - g)
  float mergeDistance = 0.f;    ///< d in normalised ray units; 0: two strata
  int samplesPerPass = 32;      ///< stratified samples per refinement pass
  int refinePasses = 4;         ///< one uniform, then adaptive passes
  bool lightRays = true;        ///< optimize every connection to a light too (Sec. 5.3-5.4)
  int lightRaySamples = 200;    ///< stratified samples of a light ray's fresh list
  /// A light ray's K runs from the light (ImportanceDesc::lightRaysFromLight)
  /// instead of from the scattering vertex.
  bool lightRaysFromLight = false;
  /// Set per render by the backend from the camera: world length of one
  /// normalised ray unit (half the volume's largest world extent), inverse.
  float invLengthUnit = 1.f;
};

/// Strata per voxel from which the unbiased march takes control variates
/// (SceneView::marchControlVariates, trackControlMarch()) when the camera
/// rays go through the pixel centres (RenderSettings::jitterPixels off).
/// Where strata resolve the voxels, a trapezoid march through their
/// boundaries is close to the integral and the residual left to chance is
/// small: at 1 per voxel one sample at pixel centres has several dB less
/// noise than with the plain strata, for about 1.4x the time. With jittered
/// pixels the noise of the pixel footprint, which the control variates leave
/// alone, dominates, and they take longer to a given error than the plain
/// strata. Below 1 per voxel they can still need fewer samples, but the thin
/// data sets' low rates (1/16 to 1/8 per voxel) reach 35 dB in one plain
/// frame, where the control variates would only add cost; so the rule for a
/// rate set by hand starts at 1. The automatic choice offers every rate both
/// ways at pixel centres (RenderSettings::marchControlVariatesFrom 0 for a
/// chosen control-variate rate below 1) and takes them below 1 where they
/// pay (Documentation/performance.md gives the figures).
constexpr float kMarchControlVariateRate = 1.f;

struct SceneView
{
  VolumeView volume;
  TableView tables;
  GridView grid;
  BlendView blend;
  /// Channels whose majorant is non-zero somewhere; the others are never
  /// traversed (a channel with zero opacity costs nothing).
  int numActive = 0;
  int active[kMaxChannels];
  /// Upper limit on any channel's extinction (world units^-1), set per render
  /// by the backend from the camera's worldToIndex (extinctionLimit()). It
  /// keeps the number of null collisions in a macrocell bounded when a
  /// transfer function is opaque over a tiny unit distance.
  float sigmaLimit = 3.4e38f;
  /// Lowest rate of tentative collisions (world units^-1) the expected-value
  /// estimator uses in a non-empty macrocell, set per render by the backend
  /// (RenderSettings::minSamplesPerVoxel times voxelRate()); 0: off.
  float minRate = 0.f;
  /// Strata per unit length (world units^-1) of the unbiased-march
  /// estimator in a non-empty macrocell, set per render by the backend
  /// (RenderSettings::marchSamplesPerVoxel times voxelRate()).
  float marchRate = 1.f;
  /// The unbiased march takes its control variates (trackControlMarch())
  /// instead of the plain strata: set per render by the backend
  /// (marchControlVariates()) where RenderSettings::marchSamplesPerVoxel >=
  /// kMarchControlVariateRate and the pixels are not jittered. The kernels
  /// choose by it (unlitEstimator() code 3: a kernel instance of its own on
  /// the GPU, so the plain strata's kernels carry none of its code).
  bool marchControlVariates = false;
  LightingView lighting;
  ImportanceView importance;
  /**
   * Lit rendering of one piece of a volume split over processes (ParaView,
   * MPI): a stand-in for the whole volume (Scene::setOutside), which the
   * parts of light paths beyond this piece's box are traced through: the
   * rest of every shadow ray and, with multiple scattering, a scattered ray
   * that leaves the piece (the path then continues in the stand-in).
   * Camera rays never enter it. Null (the default, and always unlit): the
   * piece is the whole volume, and no lighting code reads what follows.
   * Set per render by the backend (a host pointer on the CPU, a device
   * pointer on CUDA) to a view of its own whose lighting and blend are this
   * view's, mapped to the stand-in's index space, and whose `outside` is
   * null.
   */
  const SceneView* outside = nullptr;
  /// This view's index point p is the stand-in's p * outsideScale +
  /// outsideOffset (per axis); index directions scale by outsideScale.
  Vec3f outsideScale = Vec3f(1.f, 1.f, 1.f);
  Vec3f outsideOffset;
  /**
   * The stand-in holds this piece exactly (Scene::setOutside's `exact`):
   * a light path moves into it at its first vertex (litPathFrom()), so
   * every shadow ray and scattered ray is one march through the whole
   * volume and the kernels need no second march (kStandInCode).
   */
  bool outsideExact = false;
};

/// The view a light path runs in (litPathFrom()): s's exact stand-in
/// (SceneView::outsideExact), else s. A GPU kernel takes it as a parameter
/// of its own, so that its reads stay constant-bank operands as s's do.
MCVOL_FUNC const SceneView& lightView(const SceneView& s)
{
  return s.outside && s.outsideExact ? *s.outside : s;
}

/// An index point of view s in its stand-in's index space (SceneView::outside).
MCVOL_FUNC Vec3f toOutside(const SceneView& s, Vec3f p)
{
  return Vec3f(p.x * s.outsideScale.x + s.outsideOffset.x, p.y * s.outsideScale.y + s.outsideOffset.y,
    p.z * s.outsideScale.z + s.outsideOffset.z);
}

/// An index direction of view s in its stand-in's index space.
MCVOL_FUNC Vec3f toOutsideDirection(const SceneView& s, Vec3f d)
{
  return Vec3f(d.x * s.outsideScale.x, d.y * s.outsideScale.y, d.z * s.outsideScale.z);
}

/**
 * A view of one of s's active channels alone, its stand-in of the other
 * pieces (SceneView::outside) carrying the same one channel: lit
 * post-render composite lights each channel alone, in both mappers.
 * Not copyable: the view points at its own stand-in copy.
 */
struct OneChannelView
{
  SceneView view;
  SceneView standIn;
  MCVOL_FUNC explicit OneChannelView(const SceneView& s)
    : view(s)
  {
    view.numActive = 1;
    if (s.outside)
    {
      standIn = *s.outside;
      standIn.numActive = 1;
      view.outside = &standIn;
    }
  }
  OneChannelView(const OneChannelView&) = delete;
  OneChannelView& operator=(const OneChannelView&) = delete;
  /// The view of channel n alone.
  MCVOL_FUNC const SceneView& alone(int n)
  {
    view.active[0] = n;
    standIn.active[0] = n;
    return view;
  }
};
} // namespace mcvol
