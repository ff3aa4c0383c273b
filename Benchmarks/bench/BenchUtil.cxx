// SPDX-License-Identifier: BSD-3-Clause

#include "BenchUtil.h"

#include <algorithm>
#include <cmath>
#include <fstream>
#include <stdexcept>

namespace mcvolbench
{
double seconds(Clock::time_point t0)
{
  return std::chrono::duration<double>(Clock::now() - t0).count();
}

double msSince(Clock::time_point t0)
{
  return 1e3 * seconds(t0);
}

double median(std::vector<double> v)
{
  std::sort(v.begin(), v.end());
  const size_t n = v.size();
  return n % 2 ? v[n / 2] : 0.5 * (v[n / 2 - 1] + v[n / 2]);
}

bool contains(const std::vector<std::string>& list, const std::string& s)
{
  return std::find(list.begin(), list.end(), s) != list.end();
}

ImageError clippedRgbError(const float* rgba, const float* ref, size_t pixels)
{
  double se = 0;
  for (size_t p = 0; p < pixels; ++p)
  {
    for (size_t c = 0; c < 3; ++c)
    {
      const double x = std::min(1.0, std::max(0.0, double(rgba[4 * p + c])));
      const double y = std::min(1.0, std::max(0.0, double(ref[4 * p + c])));
      se += (x - y) * (x - y);
    }
  }
  const double mse = se / double(3 * pixels);
  return { std::sqrt(mse), mse > 0 ? -10.0 * std::log10(mse) : 300.0 };
}

mcvol::TransferFunctionDesc demoTransferFunction(
  const mcvol::DemoVolume& v, int n, const std::array<float, 2>& range, int tableSize, double density)
{
  return mcvol::sampleTransferFunction(
    v.transferFunctions[size_t(n)], range[0], range[1], tableSize, v.spacing[0] / density);
}

mcvol::LightingDesc lightingPreset(const std::string& name, int channels, float scatterRoulette)
{
  if (name != "none" && name != "shadows" && name != "ambient" && name != "multiple")
  {
    throw std::invalid_argument(std::string("--lighting takes ") + kLightingPresets + ", not " + name);
  }
  mcvol::LightingDesc d;
  if (scatterRoulette > 0.f)
  {
    d.scatterRoulette = scatterRoulette;
  }
  if (name == "none")
  {
    return d;
  }
  mcvol::LightDesc sun;
  sun.vector[0] = 1;
  sun.vector[1] = 2;
  sun.vector[2] = 1.5;
  sun.intensity = 4.0;
  d.lights.push_back(sun);
  d.albedo.assign(size_t(channels), 0.8f);
  d.anisotropy.assign(size_t(channels), 0.3f);
  if (name != "shadows")
  {
    d.ambient[0] = d.ambient[1] = d.ambient[2] = 0.2;
  }
  if (name == "multiple")
  {
    d.maxDepth = 8;
  }
  return d;
}

mcvol::Camera forGrid(mcvol::Camera cam, const double spacing[3], const double origin[3])
{
  for (double& x : cam.worldToIndex)
  {
    x = 0.0;
  }
  for (int a = 0; a < 3; ++a)
  {
    cam.worldToIndex[a * 4 + a] = 1.0 / spacing[a];
    cam.worldToIndex[a * 4 + 3] = -origin[a] / spacing[a];
  }
  return cam;
}

std::unique_ptr<mcvol::Scene> classifiedScene(
  const mcvol::ClassifiedVolumeView& v, int macrocell, bool hostAcceleration)
{
  auto scene = std::make_unique<mcvol::Scene>();
  mcvol::ChannelSource src;
  src.data = v.voxels;
  src.type = mcvol::ScalarType::Float32;
  src.stride = v.stride;
  src.format = mcvol::ChannelFormat::Extinction;
  scene->setHostAcceleration(hostAcceleration);
  scene->setVolume(v.dims, 1, &src);
  scene->setMacrocellSize(macrocell);
  scene->setBlendMode(mcvol::BlendMode::Density);
  scene->update();
  return scene;
}

void writeLines(const std::string& path, const std::vector<std::string>& lines)
{
  std::ofstream f(path);
  for (const std::string& l : lines)
  {
    f << l << "\n";
  }
}
} // namespace mcvolbench
