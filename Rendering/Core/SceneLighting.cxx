// SPDX-License-Identifier: BSD-3-Clause
// Scene: checking the lights and scattering parameters into the LightingView.
#include "mcvol/Scene.h"
#include "mcvol/ray/ShadowCache.h"

#include <cmath>
#include <stdexcept>
#include <string>

namespace mcvol
{
void Scene::setLighting(const LightingDesc& d)
{
  LightingView& L = this->View.lighting;
  if (d.lights.size() > size_t(kMaxLights))
  {
    throw std::invalid_argument("mcvol: at most " + std::to_string(kMaxLights) + " lights are supported");
  }
  auto finite3 = [](const double* v) { return std::isfinite(v[0]) && std::isfinite(v[1]) && std::isfinite(v[2]); };
  bool anyLight = false;
  for (size_t l = 0; l < d.lights.size(); ++l)
  {
    const LightDesc& ld = d.lights[l];
    const double len =
      std::sqrt(ld.vector[0] * ld.vector[0] + ld.vector[1] * ld.vector[1] + ld.vector[2] * ld.vector[2]);
    if (!finite3(ld.vector) || !finite3(ld.color) || !std::isfinite(ld.intensity) || ld.intensity < 0 ||
      ld.color[0] < 0 || ld.color[1] < 0 || ld.color[2] < 0 || (!ld.point && !(len > 0)))
    {
      throw std::invalid_argument("mcvol: light " + std::to_string(l) +
        " needs a finite non-zero direction (or a position), a colour >= 0 and an intensity >= 0");
    }
    L.lightType[l] = ld.point ? 1 : 0;
    const double inv = ld.point ? 1.0 : 1.0 / len;
    L.lightVector[l] = Vec3f(float(ld.vector[0] * inv), float(ld.vector[1] * inv), float(ld.vector[2] * inv));
    L.lightRadiance[l] =
      Vec3f(float(ld.color[0] * ld.intensity), float(ld.color[1] * ld.intensity), float(ld.color[2] * ld.intensity));
    anyLight = anyLight || ld.intensity > 0;
  }
  if (!finite3(d.ambient) || d.ambient[0] < 0 || d.ambient[1] < 0 || d.ambient[2] < 0)
  {
    throw std::invalid_argument("mcvol: the ambient radiance must be finite and >= 0");
  }
  if (d.maxDepth < 1 || d.maxDepth > 1024)
  {
    throw std::invalid_argument("mcvol: the maximum scattering depth must be in [1, 1024]");
  }
  if (!(d.shininess >= 0.f) || !std::isfinite(d.shininess))
  {
    throw std::invalid_argument("mcvol: the shininess must be a finite number >= 0");
  }
  if (!(d.cacheSpacing >= kShadowCacheMinSpacing && d.cacheSpacing <= kShadowCacheMaxSpacing))
  {
    throw std::invalid_argument("mcvol: the shadow cache's node spacing must be in [0.5, 64] voxels");
  }
  if (!(d.scatterRoulette > 0.f && d.scatterRoulette <= 1.f))
  {
    throw std::invalid_argument("mcvol: the scattering vertex's roulette threshold must be in (0, 1]");
  }
  for (int n = 0; n < kMaxChannels; ++n)
  {
    const float a = size_t(n) < d.albedo.size() ? d.albedo[size_t(n)] : 0.5f;
    const float g = size_t(n) < d.anisotropy.size() ? d.anisotropy[size_t(n)] : 0.f;
    if (!(a >= 0.f && a <= 1.f) || !(g > -1.f && g < 1.f))
    {
      throw std::invalid_argument(
        "mcvol: channel " + std::to_string(n) + " needs an albedo in [0, 1] and an anisotropy in (-1, 1)");
    }
    L.albedo[n] = a;
    L.anisotropy[n] = g;
  }
  L.numLights = int(d.lights.size());
  // One light per scattering event: probabilities in proportion to each
  // light's radiance (at unit distance for point lights; any positive
  // choice is unbiased, this one sends the shadow ray where most light is).
  double total = 0.0;
  int lastLit = -1;
  for (int l = 0; l < L.numLights; ++l)
  {
    const Vec3f& e = L.lightRadiance[l];
    total += double(e.x) + double(e.y) + double(e.z);
    if (e.x + e.y + e.z > 0.f)
    {
      lastLit = l;
    }
  }
  L.sampleOneLight = d.sampleOneLight && L.numLights > 1 && total > 0.0;
  double running = 0.0;
  for (int l = 0; l < L.numLights; ++l)
  {
    const Vec3f& e = L.lightRadiance[l];
    const double share = total > 0.0 ? (double(e.x) + double(e.y) + double(e.z)) / total : 0.0;
    running += share;
    L.lightPdf[l] = float(share);
    L.lightCdf[l] = l >= lastLit ? 1.f : float(running);
  }
  L.ambient = Vec3f(float(d.ambient[0]), float(d.ambient[1]), float(d.ambient[2]));
  L.shadows = d.shadows;
  L.shadowEstimator = d.deltaShadows ? 1 : 0;
  L.cacheShadows = d.cacheShadows;
  L.cacheSpacing = d.cacheSpacing;
  L.maxDepth = d.maxDepth;
  L.scatterRoulette = d.scatterRoulette;
  L.gradientShading = d.gradientShading;
  L.shininess = d.shininess;
  L.enabled = anyLight || d.ambient[0] > 0 || d.ambient[1] > 0 || d.ambient[2] > 0;
}
} // namespace mcvol

namespace mcvol
{
void Scene::setOutside(const Scene* outside, const double scale[3], const double offset[3], bool exact)
{
  if (outside == this)
  {
    throw std::invalid_argument("mcvol: a Scene cannot be its own stand-in (setOutside)");
  }
  double sc[3] = { 1, 1, 1 }, off[3] = { 0, 0, 0 };
  for (int a = 0; a < 3; ++a)
  {
    sc[a] = scale ? scale[a] : 1.0;
    off[a] = offset ? offset[a] : 0.0;
    if (!(sc[a] > 0.0) || !std::isfinite(sc[a]) || !std::isfinite(off[a]))
    {
      throw std::invalid_argument(
        "mcvol: the stand-in's index map needs a positive, finite scale and a finite offset (setOutside)");
    }
  }
  this->Outside = outside;
  this->OutsideExact = outside && exact;
  for (int a = 0; a < 3; ++a)
  {
    this->OutsideScale[a] = outside ? sc[a] : 1.0;
    this->OutsideOffset[a] = outside ? off[a] : 0.0;
  }
}
} // namespace mcvol
