// SPDX-License-Identifier: BSD-3-Clause
//
// mcvol-bench: what the sections share (options, timing, the scene, the CSV
// rows). Each section is one function in its own Section*.cxx, declared in
// Sections.h; mcvol_bench.cxx runs them.

#pragma once

#include "BenchUtil.h"

#include "mcvol/CameraMath.h"
#include "mcvol/DemoData.h"
#include "mcvol/Renderer.h"
#ifdef MCVOL_WITH_CUDA
#include "mcvol/CUDARenderer.h"
#endif

#include <array>
#include <string>
#include <vector>

namespace mcvolbench
{
struct Options
{
  std::string dataset = "cosmology";
  std::array<int, 3> dims = { 256, 256, 256 };
  int channels = 0;
  int width = 512;
  int height = 512;
  int warmup = 3;
  int frames = 10;
  int macrocell = 8;
  int tableSize = 1024;
  mcvol::Backend backend = mcvol::Backend::CPU;
  std::vector<std::string> sections = { "trackers", "channels", "macrocell", "rebuild", "memory" };
  std::vector<int> channelCounts = { 1, 2, 4, 8, 12, 16 };
  std::vector<int> macrocellSizes = { 2, 4, 8, 16, 32, 64 };
  std::string csv;
  std::string label; ///< e.g. "NYX-like", printed with the dataset
  std::string sampling = "texture";
  bool generalKernels = false; ///< CUDA: the general kernels for plain scenes too
  bool inlineShadows = false;  ///< CUDA: shadow rays traced in the camera rays' kernel (no deferral)
  int deferredBatch = 0;       ///< CUDA: setDeferredBatch() (0: the renderer's default)
  float scatterRoulette = 0.f; ///< LightingDesc::scatterRoulette of the lit scenes (0: its default)
  float cacheSpacing = 0.f;    ///< --cached-shadows: LightingDesc::cacheSpacing of the lit scenes (0: tracked shadows)
  int blockX = 8;
  int blockY = 8;
  double psnr = 35.0;
  int referenceSpp = 2048;
  int pyramidLevels = 2; ///< section pyramid: levels 1..N timed (half precision for 1 and 2 only)
  int maxConvergeFrames = 4096;
  double density = 1.0; ///< divides every opacity unit distance (denser volumes)
  /// lightingPreset() name: the scene's lighting (the effects section sets
  /// its own)
  std::string lighting = "none";
  std::vector<std::string> samplers = { "independent", "sobol" }; ///< section sequences
  int sppMax = 256;                                               ///< section sequences
  std::vector<std::string> estimators = { "collision" };          ///< section sequences
  /// section converge: extra expected-value rows with these
  /// RenderSettings::minSamplesPerVoxel (none by default)
  std::vector<float> minSamplesPerVoxel;
  /// section converge: unbiased-march rows with these
  /// RenderSettings::marchSamplesPerVoxel (one at the default, 2)
  std::vector<float> marchSamplesPerVoxel = { 2.f };
  /// section converge: leave out the collision-estimator rows
  bool skipCollision = false;
  /// section converge: back-to-back frames timed per configuration
  int steadyFrames = 200;
  /// section converge: the automatic choice's cost model, 4 weights (per
  /// ray, DDA step, tentative collision, channel sample); empty: the
  /// backend's default (defaultCostModel())
  std::vector<double> costModel;
  /// section converge: only the automatic row (with the expected-value row,
  /// the reference for its gain)
  bool onlyAutomatic = false;
  /// section converge: the automatic choice tries every rate (its report
  /// then predicts each; the choice is the same or better)
  bool choiceAll = false;

  /// converge: also every configuration at pixel centres
  /// (RenderSettings::jitterPixels off), against a reference at pixel centres
  bool pixelCentres = false;
  bool centresOnly = false; ///< --centres-only: the pixel-centre rows alone
};

/// Prints every option with its help.
void usage();
/// Throws std::invalid_argument on a bad command line; --help prints usage() and exits.
Options parse(int argc, char** argv);
bool wants(const Options& o, const std::string& s);

/// A loaded dataset with its scene.
struct Setup
{
  mcvol::DemoVolume volume;
  std::vector<std::array<float, 2>> ranges;
  mcvol::Scene scene;

  /// Generates the dataset (kept for the next section when name, size and
  /// channel count are the same: large volumes take minutes) and configures
  /// a new scene over it.
  void load(const Options& o, int channels, int macrocell, bool hostAcceleration = true);
  std::string loadedKey; ///< what `volume` was generated from ("" after another section replaced it)

  /// A new scene over the first `channels` channels of the loaded volume (the
  /// channel sweep generates the largest count once).
  void configure(const Options& o, int channels, int macrocell, bool hostAcceleration);
};

struct FrameStats
{
  double medianMs = 0;
  double minMs = 0;
  double meanMs = 0;
  double readBackMs = 0; ///< median frame time with the image copied back (device backends)
  double tentativePerRay = 0;
  double ddaPerRay = 0;
  double scatterPerRay = 0;
  double shadowPerRay = 0;
  double gradientPerRay = 0;
  double alpha = 0;
};

mcvol::Camera benchCamera(const Options& o, const mcvol::Scene& scene);
/// The lit scenes' lighting: --lighting's preset, --scatter-roulette, and
/// with `cached` --cached-shadows (tracked shadows without it).
mcvol::LightingDesc benchLighting(const Options& o, int channels, bool cached = true);

/// Times frames of 1 spp. Device backends: render() + finish() per frame with
/// the image left on the device; then a few frames with it copied back.
/// Frame times at 1 spp with the given tracker; the collision estimator by
/// default (the trackers' estimator: the expected-value one makes a single
/// DDA whatever the tracker).
FrameStats timeFrames(const Options& o, mcvol::Renderer& r, const mcvol::Scene& scene, mcvol::Tracker tracker,
  mcvol::Estimator estimator = mcvol::Estimator::Collision);

/// PSNR (peak 1) of the premultiplied RGB (the image over black) against a reference.
double psnrOf(const mcvol::Accumulator& a, const std::vector<float>& ref);

/// A converged reference of the loaded scene: --reference-spp samples of
/// seed 12345 in batches of at most 64, read back; returns its RGBA image.
/// `rs` gives everything else (sampler, estimator; its seed and batch size
/// are set here).
std::vector<float> renderReference(const Options& o, mcvol::Renderer& r, const mcvol::Scene& scene,
  const mcvol::Camera& cam, mcvol::Accumulator& ref, mcvol::RenderSettings rs = mcvol::RenderSettings());

#ifdef MCVOL_WITH_CUDA
mcvol::CUDARenderer* asCuda(mcvol::Renderer& r);
#endif

std::string describe(const Options& o, const Setup& s);

/// What every section works with. One Setup serves all sections in turn, as
/// one renderer does.
struct Bench
{
  const Options& o;
  mcvol::Renderer& r;
  bool hostAccel;
  Setup s;
  std::vector<std::string> csv = { "section,dataset,channels,macrocell,tracker,backend,value,unit,extra" };

  Bench(const Options& options, mcvol::Renderer& renderer, bool hostAcceleration)
    : o(options)
    , r(renderer)
    , hostAccel(hostAcceleration)
  {
  }

  void row(const std::string& section, const std::string& ds, int ch, int mc, const std::string& tr, double value,
    const std::string& unit, const std::string& extra);
  /// Writes the CSV rows to --csv (nothing without it).
  void writeCsv() const;
};
} // namespace mcvolbench
