// SPDX-License-Identifier: BSD-3-Clause
//
// mcvol-sampling-figures: Kraus and Buerger's ("Interpolating and
// Downsampling RGBA Volume Data", 2008) figures, made by mcvol's ray marcher
// (RayMarch.h) with its two compositing models, opacity-based and
// extinction-based sampling (Compositing::Opacity, Compositing::Extinction):
//
//   fig4.ppm   paper Fig. 4: the opacity alpha_ray a ray integrates through a
//              one-voxel wall of extinction tau_max (interpolated between
//              vertices, as in the paper's Fig. 1), against the sampling
//              distance d = d' (horizontal, 0.1 .. 2 voxels) and the sample
//              lattice's offset r from the wall's vertex (vertical, 0 .. 1
//              of d); one panel per tau_max = 1, 2, 4, 8, opacity-based
//              sampling on the top row, extinction-based on the bottom. Every
//              deviation from alpha_exact = 1 - exp(-tau_max) is a sampling
//              error: red where alpha_ray is above it, blue below, white
//              exact; full colour at +-0.25.
//   fig7.ppm   paper Fig. 7: scattered opaque voxels rendered with opacity-
//              based (left) and extinction-based (right) sampling at d = 0.8.
//   levels.ppm a thin structure (a one-voxel wall seen at a grazing angle)
//              at levels 0 to 3 (left to right) of the extinction pyramid
//              (top) and of opacity averaging (bottom), box4 filter, every
//              level rendered over level 0's box (Sec. 4).
//
// It prints the largest deviation per tau_max and model over 0.5 <= d <= 1
// (the interactive range the paper points at) and over 1 < d <= 1.5, as a
// Markdown table. Benchmarks/plots/sampling_figures.sh turns the PPMs into the PNGs
// of Documentation/images/.
//
//   mcvol-sampling-figures [--out DIR]

#include "mcvol/CameraMath.h"
#include "mcvol/MarchSetup.h"
#include "mcvol/Pyramid.h"
#include "mcvol/RayMarcher.h"
#include "mcvol/Scene.h"
#include "mcvol/ray/RayMarch.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <stdexcept>
#include <string>
#include <vector>

namespace
{
struct Image
{
  int w = 0, h = 0;
  std::vector<unsigned char> rgb;
  Image(int width, int height)
    : w(width)
    , h(height)
    , rgb(size_t(width) * size_t(height) * 3, 255)
  {
  }
  void set(int x, int y, float r, float g, float b)
  {
    unsigned char* p = this->rgb.data() + (size_t(y) * size_t(this->w) + size_t(x)) * 3;
    p[0] = static_cast<unsigned char>(std::lround(255.f * std::min(std::max(r, 0.f), 1.f)));
    p[1] = static_cast<unsigned char>(std::lround(255.f * std::min(std::max(g, 0.f), 1.f)));
    p[2] = static_cast<unsigned char>(std::lround(255.f * std::min(std::max(b, 0.f), 1.f)));
  }
  void write(const std::string& path) const
  {
    FILE* f = std::fopen(path.c_str(), "wb");
    if (!f)
    {
      throw std::runtime_error("cannot write " + path);
    }
    std::fprintf(f, "P6\n%d %d\n255\n", this->w, this->h);
    std::fwrite(this->rgb.data(), 1, this->rgb.size(), f);
    std::fclose(f);
  }
};

/// Extinction linear in the scalar: 0 at 0, tau at 1 (unit distance 1), white.
mcvol::TransferFunctionDesc linearTF(double tau)
{
  mcvol::TransferFunctionDesc tf;
  tf.scalarMin = 0.f;
  tf.scalarMax = 1.f;
  tf.unitDistance = 1.f;
  tf.opacity = { 0.f, float(-std::expm1(-tau)) };
  tf.rgb = { 1.f, 1.f, 1.f, 1.f, 1.f, 1.f };
  return tf;
}

/// Paper Fig. 4: alpha_ray through a one-voxel wall (scalar 1 at x = 8 of a
/// 17-voxel line, 2 x 2 across) marched along +x at step d with lattice
/// offset r (phase), through the per-ray march of RayMarch.h.
double wallAlpha(const mcvol::Scene& scene, mcvol::Compositing model, double d, double r)
{
  mcvol::Camera cam;
  cam.width = cam.height = 1;
  mcvol::MarchSettings ms;
  ms.step = d;
  ms.terminateTransmittance = 0.f;
  ms.skipEmpty = false;
  ms.compositing = model;
  mcvol::SceneView s = scene.view();
  const mcvol::MarchParams mp = mcvol::prepareMarch(cam, ms, s);
  mcvol::MarchCounters mc;
  const mcvol::Vec3f o(0.f, 0.5f, 0.5f), dir(1.f, 0.f, 0.f);
  const float tmax = float(s.volume.boxHi.x - s.volume.boxLo.x);
  const mcvol::Vec4f c = mcvol::marchChannels<mcvol::BlendMode::Density>(
    s, mp, s.active, s.numActive, o, dir, tmax, float(r), mc);
  return c.a;
}

void diverging(float v, float& r, float& g, float& b)
{
  const float x = std::min(std::max(v / 0.25f, -1.f), 1.f);
  if (x >= 0.f)
  {
    r = 1.f;
    g = b = 1.f - 0.85f * x;
  }
  else
  {
    b = 1.f;
    r = g = 1.f + 0.85f * x;
  }
}

void figure4(const std::string& out)
{
  const int PW = 190, PH = 100, gap = 6; // panel: d = 0.1 .. 2 by 0.01, r = 0 .. 0.99
  const double taus[4] = { 1, 2, 4, 8 };
  Image img(4 * PW + 3 * gap, 2 * PH + gap);
  const int dims[3] = { 17, 2, 2 };
  std::vector<float> wall(17 * 2 * 2, 0.f);
  for (int k = 0; k < 2; ++k)
    for (int j = 0; j < 2; ++j)
      wall[size_t((k * 2 + j) * 17 + 8)] = 1.f;
  mcvol::ChannelSource src;
  src.data = wall.data();
  src.type = mcvol::ScalarType::Float32;
  std::printf("## Paper 001 Fig. 4: alpha_ray through a one-voxel wall, largest |alpha_ray - alpha_exact|\n\n");
  std::printf("| tau_max | alpha_exact | opacity-based, 0.5 <= d <= 1 | extinction-based, 0.5 <= d <= 1 | "
              "opacity-based, 1 < d <= 1.5 | extinction-based, 1 < d <= 1.5 |\n|---|---|---|---|---|---|\n");
  for (int t = 0; t < 4; ++t)
  {
    mcvol::Scene scene;
    scene.setVolume(dims, 1, &src);
    scene.setTransferFunction(0, linearTF(taus[t]));
    scene.setMacrocellSize(4);
    scene.update();
    const double exact = -std::expm1(-taus[t]);
    double worst[2][2] = { { 0, 0 }, { 0, 0 } }; // [model][0.5 <= d <= 1, 1 < d <= 1.5]
    for (int m = 0; m < 2; ++m)
    {
      const mcvol::Compositing model = m == 0 ? mcvol::Compositing::Opacity : mcvol::Compositing::Extinction;
      for (int x = 0; x < PW; ++x)
      {
        const double d = 0.1 + 0.01 * x;
        for (int y = 0; y < PH; ++y)
        {
          const double r = 0.01 * y;
          const double dev = wallAlpha(scene, model, d, r) - exact;
          float cr, cg, cb;
          diverging(float(dev), cr, cg, cb);
          img.set(t * (PW + gap) + x, m * (PH + gap) + (PH - 1 - y), cr, cg, cb);
          if (d >= 0.5 - 1e-9 && d <= 1.0 + 1e-9)
          {
            worst[m][0] = std::max(worst[m][0], std::fabs(dev));
          }
          else if (d > 1.0 + 1e-9 && d <= 1.5 + 1e-9)
          {
            worst[m][1] = std::max(worst[m][1], std::fabs(dev));
          }
        }
      }
    }
    std::printf("| %g | %.4f | %.4f | %.4f | %.4f | %.4f |\n", taus[t], exact, worst[0][0], worst[1][0], worst[0][1],
      worst[1][1]);
  }
  std::printf("\n");
  img.write(out + "/fig4.ppm");
}

/// An orbit view of a grid of `spacing`/`origin` (world = origin + spacing *
/// index) around level 0's volume of `dims0`.
mcvol::Camera viewOf(const int dims0[3], int W, int H, double az, double el, const double spacing[3],
  const double origin[3])
{
  const double one[3] = { 1, 1, 1 };
  mcvol::Camera c = mcvol::orbitCamera(dims0, one, W, H, az, el);
  for (double& x : c.worldToIndex)
  {
    x = 0.0;
  }
  for (int a = 0; a < 3; ++a)
  {
    c.worldToIndex[a * 4 + a] = 1.0 / spacing[a];
    c.worldToIndex[a * 4 + 3] = -origin[a] / spacing[a];
  }
  return c;
}

void blit(Image& img, const mcvol::Accumulator& acc, int x0, int y0)
{
  for (int y = 0; y < acc.height(); ++y)
  {
    for (int x = 0; x < acc.width(); ++x)
    {
      const float* p = acc.rgba() + (size_t(y) * size_t(acc.width()) + size_t(x)) * 4;
      // Premultiplied colour over black; image rows from the top.
      img.set(x0 + x, y0 + (acc.height() - 1 - y), p[0], p[1], p[2]);
    }
  }
}

void figure7(const std::string& out)
{
  const int n = 40, W = 256;
  const int dims[3] = { n, n, n };
  std::vector<float> v(size_t(n) * n * n, 0.f);
  uint64_t state = 12345;
  for (int i = 0; i < 60; ++i)
  {
    int c[3];
    for (int& x : c)
    {
      state = state * 6364136223846793005ull + 1442695040888963407ull;
      x = 4 + int((state >> 33) % uint64_t(n - 8));
    }
    v[(size_t(c[2]) * n + size_t(c[1])) * n + size_t(c[0])] = 1.f;
  }
  mcvol::ChannelSource src;
  src.data = v.data();
  src.type = mcvol::ScalarType::Float32;
  mcvol::Scene scene;
  scene.setVolume(dims, 1, &src);
  scene.setTransferFunction(0, linearTF(8.0));
  scene.setMacrocellSize(4);
  scene.update();
  Image img(2 * W + 6, W);
  const double one[3] = { 1, 1, 1 }, zero[3] = { 0, 0, 0 };
  const mcvol::Camera cam = viewOf(dims, W, W, 35, 25, one, zero);
  for (int m = 0; m < 2; ++m)
  {
    mcvol::MarchSettings ms;
    ms.step = 0.8;
    ms.terminateTransmittance = 0.f;
    ms.compositing = m == 0 ? mcvol::Compositing::Opacity : mcvol::Compositing::Extinction;
    mcvol::RayMarcher rm;
    mcvol::Accumulator acc;
    rm.render(scene, cam, ms, nullptr, acc);
    blit(img, acc, m * (W + 6), 0);
  }
  img.write(out + "/fig7.ppm");
}

void levels(const std::string& out)
{
  const int n = 48, W = 160, L = 3;
  const int dims[3] = { n, n, n };
  std::vector<float> v(size_t(n) * n * n * 4, 0.f);
  for (int k = 0; k < n; ++k)
    for (int j = 0; j < n; ++j)
    {
      float* x = v.data() + ((size_t(k) * n + size_t(j)) * n + 20) * 4; // the wall x = 20
      x[0] = 4.f;
      x[1] = 4.f * 1.f;
      x[2] = 4.f * 0.6f;
      x[3] = 4.f * 0.2f;
    }
  mcvol::ClassifiedVolumeView view;
  view.voxels = v.data();
  std::copy(dims, dims + 3, view.dims);
  const std::vector<mcvol::PyramidLevel> ext = mcvol::buildExtinctionPyramid(view, L);
  const std::vector<mcvol::PyramidLevel> opa = mcvol::buildOpacityPyramid(view, L, 1.0);
  Image img(4 * W + 3 * 6, 2 * W + 6);
  for (int row = 0; row < 2; ++row)
  {
    for (int l = 0; l <= L; ++l)
    {
      mcvol::PyramidLevel L0;
      const mcvol::PyramidLevel* lev = nullptr;
      if (l == 0)
      {
        std::copy(dims, dims + 3, L0.dims);
        L0.voxels = v;
        lev = &L0;
      }
      else
      {
        lev = &(row == 0 ? ext : opa)[size_t(l - 1)];
      }
      const mcvol::ChannelSource src = lev->source();
      mcvol::Scene scene;
      scene.setVolume(lev->dims, 1, &src);
      double lo[3], hi[3];
      lev->indexBounds(lo, hi);
      scene.setIndexBounds(lo, hi);
      scene.setMacrocellSize(4);
      scene.update();
      const mcvol::Camera cam = viewOf(dims, W, W, 62, 15, lev->spacing, lev->origin);
      mcvol::MarchSettings ms;
      ms.step = 0.25;
      ms.terminateTransmittance = 0.f;
      mcvol::RayMarcher rm;
      mcvol::Accumulator acc;
      rm.render(scene, cam, ms, nullptr, acc);
      blit(img, acc, l * (W + 6), row * (W + 6));
    }
  }
  img.write(out + "/levels.ppm");
}
} // namespace

int main(int argc, char** argv)
{
  std::string out = ".";
  for (int i = 1; i < argc; ++i)
  {
    const std::string a = argv[i];
    if (a == "--out" && i + 1 < argc)
    {
      out = argv[++i];
    }
    else if (a == "--help" || a == "-h")
    {
      std::printf("usage: mcvol-sampling-figures [--out DIR]\n"
                  "Writes fig4.ppm, fig7.ppm and levels.ppm (Kraus and Buerger's Fig. 4 and 7, and a thin\n"
                  "wall at levels 0-3) into DIR and prints Fig. 4's deviations as a Markdown table.\n");
      return 0;
    }
    else
    {
      std::fprintf(stderr, "mcvol-sampling-figures: unknown argument '%s' (--out DIR, --help)\n", a.c_str());
      return 2;
    }
  }
  try
  {
    figure4(out);
    figure7(out);
    levels(out);
  }
  catch (const std::exception& e)
  {
    std::fprintf(stderr, "mcvol-sampling-figures: %s\n", e.what());
    return 1;
  }
  return 0;
}
