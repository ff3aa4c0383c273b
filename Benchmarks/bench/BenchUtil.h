// SPDX-License-Identifier: BSD-3-Clause
//
// What the benchmark programs share besides their options: timing, image
// error, the demo datasets' transfer functions, scenes over pre-classified
// grids, and writing result files.

#pragma once

#include "mcvol/DemoData.h"
#include "mcvol/Pyramid.h"
#include "mcvol/Renderer.h"

#include <array>
#include <chrono>
#include <cstddef>
#include <memory>
#include <string>
#include <vector>

namespace mcvolbench
{
using Clock = std::chrono::steady_clock;

/// Seconds since t0.
double seconds(Clock::time_point t0);
/// Milliseconds since t0.
double msSince(Clock::time_point t0);
double median(std::vector<double> v);

/// Whether `list` holds `s` (a section name among --sections).
bool contains(const std::vector<std::string>& list, const std::string& s);

struct ImageError
{
  double rmse = 0;
  double psnr = 0;
};

/// RMSE and PSNR (peak 1; 300 dB for equal images) of the premultiplied RGB,
/// each value clipped to [0, 1], of `pixels` RGBA pixels against a reference:
/// how the accuracy and levels-of-detail studies score images.
ImageError clippedRgbError(const float* rgba, const float* ref, size_t pixels);

/// Channel n's transfer function as the benchmarks sample it: `tableSize`
/// entries over the channel's `range`, opacity unit distance one voxel
/// (spacing[0]) divided by `density`.
mcvol::TransferFunctionDesc demoTransferFunction(
  const mcvol::DemoVolume& v, int n, const std::array<float, 2>& range, int tableSize = 1024, double density = 1.0);

/// The lit scenes the benchmarks measure, by name:
///   none      no light (emission-absorption)
///   shadows   one directional light (intensity 4, from (1, 2, 1.5)) with
///             ratio-tracking shadows; albedo 0.8, anisotropy 0.3
///   ambient   shadows plus ambient radiance 0.2
///   multiple  ambient plus multiple scattering (up to 8 events per path)
/// scatterRoulette > 0 sets LightingDesc::scatterRoulette.
/// Throws std::invalid_argument on another name.
mcvol::LightingDesc lightingPreset(const std::string& name, int channels, float scatterRoulette = 0.f);
/// The names lightingPreset() takes, for help texts.
constexpr const char* kLightingPresets = "none|shadows|ambient|multiple";

/// `cam` (a camera of level 0, whose origin is 0) with the world-to-index map
/// of a grid of this spacing and origin, so that every pyramid level is seen
/// through the same rays.
mcvol::Camera forGrid(mcvol::Camera cam, const double spacing[3], const double origin[3]);

/// A scene over one pre-classified grid: one Extinction channel, density blend.
std::unique_ptr<mcvol::Scene> classifiedScene(
  const mcvol::ClassifiedVolumeView& v, int macrocell = 8, bool hostAcceleration = true);

/// Writes `lines` to `path`, one a line (nothing where it cannot be opened).
void writeLines(const std::string& path, const std::vector<std::string>& lines);
} // namespace mcvolbench
