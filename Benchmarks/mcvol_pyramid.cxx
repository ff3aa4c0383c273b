// SPDX-License-Identifier: BSD-3-Clause
//
// mcvol-pyramid: the image quality of levels of detail (Kraus and Buerger,
// "Interpolating and Downsampling RGBA Volume Data", Sections 3-4): the
// levels-of-detail part of the accuracy-versus-time study. VTK-free, CPU only (the GPU frame times of the levels
// are mcvol-bench --sections pyramid).
//
// Section "levels", per dataset (density blend, pre-classified by
// classifyScalars with accumulate = true, so level 0 is the classified
// full-resolution volume, one float4 channel):
//   - pyramids of levels 1..--levels with each filter (box2, box4, bspline),
//     extinction-based (buildExtinctionPyramid's steps) and the
//     opacity-averaging baseline (downsampleOpacity, opacity for one finer
//     voxel, as buildOpacityPyramid does) with the same filter;
//   - every level ray-marched (extinction compositing, a fine step of
//     --step-fraction of the level-0 voxel, no early termination) with its own
//     geometry (PyramidLevel spacing and origin, so it lines up with level 0)
//     and scored (RMSE, PSNR of the premultiplied RGB over black) against
//     (a) the full-resolution image and (b) the paper's criterion (Sec. 4.2):
//     the full-resolution volume blurred in extinction by the equivalent
//     convolution of that level's downsampling and reconstruction
//     (equivalentKernel(), pyramid/EquivalentKernel.h), rendered at full
//     resolution the same way;
//   - frame time per level (ray march at the level's own Nyquist step with
//     early termination; Monte Carlo 1-spp frames, the renderer's defaults),
//     memory per level and build time (classify, each downsampling step).
//   Datasets (pyramid/Datasets.h): the study's phantoms (figure3, microscopy, cosmology, weather at
//   their stored sizes), "wall" (a one-voxel wall of tau = 4 per voxel, the
//   paper's Sec. 3.6 / 4.1 case, facing the view), "wall-x" (the same wall
//   seen at a grazing angle) and "figure2" (the paper's Figure 2/3
//   example: every 2x2x2 block of a two-voxel slab holds 4 voxels of tau = 4
//   and 4 of tau = 0, checkered, so every axis ray through it meets one of
//   each: extinction averaging keeps alpha = 0.98 there, opacity averaging
//   gives 0.74).
//   The program exits 1 if on the wall the extinction-based pyramid is not
//   better than the opacity baseline at every level and filter, on both
//   criteria (the paper's claim, Sec. 4.1; the other datasets are reported).
//
// Section "far": the far-view aliasing case. A --far-edge^3 (256^3) volume
// with voxel-scale detail (makeFarVolume(): "ball", a dense ball of per-voxel
// random colour and density; "sheets", semi-transparent one-voxel sheets
// above the pixel rate) seen small (--far-size, its box's edge covering about
// --far-coverage pixels), scored against the pixel-footprint-averaged image
// (a ray march of --far-super^2 sub-pixel rays per pixel, box-filtered): ray
// march and Monte Carlo at every level, level 0 against the automatic level
// (autoLevel() below, the rule the mapper uses) and the level of lowest error.
//
// Output: Markdown tables on stdout; --csv FILE the rows
// section,dataset,filter,method,level,metric,value.

#include "bench/ArgParser.h"
#include "bench/BenchUtil.h"
#include "pyramid/Datasets.h"
#include "pyramid/EquivalentKernel.h"

#include "mcvol/CameraMath.h"
#include "mcvol/DemoData.h"
#include "mcvol/MarchSetup.h"
#include "mcvol/Pyramid.h"
#include "mcvol/RayMarcher.h"
#include "mcvol/Renderer.h"

#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <fstream>
#include <memory>
#include <sstream>
#include <stdexcept>
#include <string>
#include <vector>

#ifdef _OPENMP
#include <omp.h>
#endif

using namespace mcvolbench;

namespace
{
using mcvol::DownsampleFilter;

const double MiB = 1024.0 * 1024.0;

struct Options
{
  std::vector<std::string> datasets = { "figure3", "microscopy", "cosmology", "weather", "wall", "wall-x", "figure2" };
  std::vector<std::string> sections = { "levels", "far" };
  std::vector<std::string> farKinds = { "ball", "sheets" };
  std::array<int, 3> dims = { 0, 0, 0 }; ///< all zero: each dataset's default
  int width = 256;
  int height = 256;
  int levels = 3;
  double stepFraction = 8; ///< fine march step = level-0 voxel / this
  int reps = 3;
  int farEdge = 256;
  int farSize = 128;
  double farCoverage = 56; ///< pixels the far volume's edge covers
  int farSuper = 8;
  int farLevels = 4;
  std::string csv;
};

/// The options of mcvol-pyramid, stored into `o`.
ArgParser makeParser(Options& o)
{
  ArgParser p("mcvol-pyramid");
  p.add("--datasets", 1, "A,B,...",
     "levels: datasets (default figure3,microscopy,cosmology,weather,wall,wall-x,figure2)",
     [&](const Args& v) { o.datasets = splitList(v[0]); })
    .add("--sections", 1, "levels,far", "sections to run (default both)",
      [&](const Args& v) { o.sections = splitList(v[0]); })
    .add("--dims", 3, "X Y Z", "levels: volume size in voxels (default 0 0 0: each dataset's own)",
      [&](const Args& v)
      {
        for (size_t k = 0; k < 3; ++k)
          o.dims[k] = std::stoi(v[k]);
      })
    .add("--size", 2, "W H", "levels: image size in pixels (default 256 256)",
      [&](const Args& v)
      {
        o.width = std::stoi(v[0]);
        o.height = std::stoi(v[1]);
      })
    .add("--levels", 1, "L", "levels: pyramid levels 1..L (default 3)",
      [&](const Args& v) { o.levels = std::stoi(v[0]); })
    .add("--step-fraction", 1, "F", "levels: the scoring march's step is a level-0 voxel / F (default 8)",
      [&](const Args& v) { o.stepFraction = std::stod(v[0]); })
    .add("--reps", 1, "N", "frames timed per level; the median is reported (default 3)",
      [&](const Args& v) { o.reps = std::max(1, std::stoi(v[0])); })
    .add("--far-volumes", 1, "ball,sheets", "far: the volumes (default both)",
      [&](const Args& v) { o.farKinds = splitList(v[0]); })
    .add("--far-edge", 1, "N", "far: volume edge in voxels (default 256)",
      [&](const Args& v) { o.farEdge = std::stoi(v[0]); })
    .add("--far-size", 1, "PX", "far: image edge in pixels (default 128)",
      [&](const Args& v) { o.farSize = std::stoi(v[0]); })
    .add("--far-coverage", 1, "PX", "far: pixels the volume's edge covers (default 56)",
      [&](const Args& v) { o.farCoverage = std::stod(v[0]); })
    .add("--far-super", 1, "S", "far: the reference's S x S sub-pixel rays per pixel (default 8)",
      [&](const Args& v) { o.farSuper = std::max(1, std::stoi(v[0])); })
    .add("--far-levels", 1, "L", "far: pyramid levels 1..L (default 4)",
      [&](const Args& v) { o.farLevels = std::stoi(v[0]); })
    .add("--csv", 1, "FILE", "also write the rows section,dataset,filter,method,level,metric,value",
      [&](const Args& v) { o.csv = v[0]; });
  return p;
}

/// CSV rows: section,dataset,filter,method,level,metric,value.
struct Csv
{
  std::vector<std::string> rows = { "section,dataset,filter,method,level,metric,value" };
  void add(const std::string& section, const std::string& ds, const std::string& filter, const std::string& method,
    int level, const std::string& metric, double value)
  {
    std::ostringstream s;
    s << section << "," << ds << "," << filter << "," << method << "," << level << "," << metric << "," << value;
    this->rows.push_back(s.str());
  }
};

// ------------------------------------------------------------------ images

using Image = std::vector<float>; ///< W x H premultiplied RGBA

/// The image's error against a reference (clipped RGB, peak 1), as
/// mcvol-accuracy scores images.
ImageError score(const Image& a, const Image& ref)
{
  return clippedRgbError(a.data(), ref.data(), a.size() / 4);
}

/// Deterministic ray march of a classified grid through the level-0 camera's
/// rays. step: world units; terminate: early-termination transmittance.
Image march(
  const mcvol::ClassifiedVolumeView& v, const mcvol::Camera& cam0, double step, float terminate, double* ms = nullptr)
{
  const std::unique_ptr<mcvol::Scene> scene = classifiedScene(v);
  const mcvol::Camera cam = forGrid(cam0, v.spacing, v.origin);
  mcvol::MarchSettings s;
  s.step = step;
  s.terminateTransmittance = terminate;
  mcvol::RayMarcher rm;
  mcvol::Accumulator acc;
  const auto t0 = Clock::now();
  rm.render(*scene, cam, s, nullptr, acc);
  if (ms)
  {
    *ms = msSince(t0);
  }
  return Image(acc.rgba(), acc.rgba() + size_t(4) * size_t(cam.width) * size_t(cam.height));
}

struct FrameTimes
{
  double marchMs = 0; ///< ray march at the grid's Nyquist step, early termination 1e-4
  double mcMs = 0;    ///< Monte Carlo, one 1-spp frame (renderer defaults)
};

/// Frame times of a scene (median of `reps`, after one untimed frame each).
FrameTimes timeFrames(const mcvol::Scene& scene, const mcvol::Camera& cam, mcvol::Renderer& r, int reps)
{
  FrameTimes f;
  mcvol::RayMarcher rm;
  mcvol::MarchSettings ms; // step 0: the Nyquist step of this grid (half its smallest spacing)
  mcvol::Accumulator acc;
  rm.render(scene, cam, ms, nullptr, acc);
  std::vector<double> t;
  for (int k = 0; k < reps; ++k)
  {
    const auto t0 = Clock::now();
    rm.render(scene, cam, ms, nullptr, acc);
    t.push_back(msSince(t0));
  }
  f.marchMs = median(t);
  mcvol::RenderSettings rs;
  rs.samplesPerPixel = 1;
  mcvol::Accumulator mc;
  r.render(scene, cam, rs, nullptr, mc);
  t.clear();
  for (int k = 0; k < reps; ++k)
  {
    rs.seed = uint32_t(k + 1);
    const auto t0 = Clock::now();
    r.render(scene, cam, rs, nullptr, mc);
    r.finish();
    t.push_back(msSince(t0));
  }
  f.mcMs = median(t);
  return f;
}

// ------------------------------------------------------------ section levels

const DownsampleFilter kFilters[3] = { DownsampleFilter::Box2, DownsampleFilter::Box4, DownsampleFilter::BSpline };

struct LevelResult
{
  ImageError extFull, extConv, opaFull, opaConv;
};

/// Runs the levels section on one dataset; returns false if the extinction
/// pyramid failed to beat the opacity baseline somewhere.
bool runLevels(const Options& o, const std::string& name, mcvol::Renderer& mc, Csv& csv)
{
  Classified c = makeDataset(name, o.dims);
  const int levels = std::min(o.levels, mcvol::maxPyramidLevels(c.dims));
  const mcvol::Camera cam0 = mcvol::orbitCamera(c.dims, c.spacing, o.width, o.height, 30, 20);
  const double voxel = std::min(c.spacing[0], std::min(c.spacing[1], c.spacing[2]));
  const double fine = voxel / o.stepFraction;
  std::printf("## %s %dx%dx%d (%s), %dx%d, fine step %g voxel\n\n", name.c_str(), c.dims[0], c.dims[1], c.dims[2],
    c.channels ? (std::to_string(c.channels) + " scalar channels classified, density blend").c_str()
               : "made pre-classified",
    o.width, o.height, 1.0 / o.stepFraction);
  std::fflush(stdout);

  // Pyramids, one downsampling step at a time (what build*Pyramid loop over)
  // so that each level's build time is known.
  struct Pyr
  {
    std::vector<mcvol::PyramidLevel> ext, opa;
    std::vector<double> extMs, opaMs;
  };
  std::vector<Pyr> pyr(3);
  for (int fi = 0; fi < 3; ++fi)
  {
    Pyr& p = pyr[size_t(fi)];
    double step = voxel; // the baseline's opacity is for one finer voxel
    for (int l = 1; l <= levels; ++l)
    {
      auto t0 = Clock::now();
      p.ext.push_back(mcvol::downsampleExtinction(l == 1 ? c.view() : p.ext.back().view(), kFilters[fi]));
      p.extMs.push_back(msSince(t0));
      p.ext.back().level = l;
      t0 = Clock::now();
      p.opa.push_back(mcvol::downsampleOpacity(l == 1 ? c.view() : p.opa.back().view(), step, kFilters[fi]));
      p.opaMs.push_back(msSince(t0));
      p.opa.back().level = l;
      step *= 2.0;
    }
  }

  // Full resolution and the criterion's references.
  const Image full = march(c.view(), cam0, fine, 0.f);
  std::vector<std::vector<LevelResult>> res(3, std::vector<LevelResult>(size_t(levels)));
  for (int fi = 0; fi < 3; ++fi)
  {
    for (int l = 1; l <= levels; ++l)
    {
      const std::vector<double> K = equivalentKernel(kFilters[fi], l);
      std::vector<float> blurred = blur(c.voxels, c.dims, K);
      mcvol::ClassifiedVolumeView bv = c.view();
      bv.voxels = blurred.data();
      const Image conv = march(bv, cam0, fine, 0.f);
      blurred = std::vector<float>();
      const Image ext = march(pyr[size_t(fi)].ext[size_t(l - 1)].view(), cam0, fine, 0.f);
      const Image opa = march(pyr[size_t(fi)].opa[size_t(l - 1)].view(), cam0, fine, 0.f);
      LevelResult& r = res[size_t(fi)][size_t(l - 1)];
      r.extFull = score(ext, full);
      r.extConv = score(ext, conv);
      r.opaFull = score(opa, full);
      r.opaConv = score(opa, conv);
      const std::string fn = mcvol::toString(kFilters[fi]);
      csv.add("levels", name, fn, "extinction", l, "rmse_full", r.extFull.rmse);
      csv.add("levels", name, fn, "extinction", l, "psnr_full", r.extFull.psnr);
      csv.add("levels", name, fn, "extinction", l, "rmse_conv", r.extConv.rmse);
      csv.add("levels", name, fn, "extinction", l, "psnr_conv", r.extConv.psnr);
      csv.add("levels", name, fn, "opacity", l, "rmse_full", r.opaFull.rmse);
      csv.add("levels", name, fn, "opacity", l, "psnr_full", r.opaFull.psnr);
      csv.add("levels", name, fn, "opacity", l, "rmse_conv", r.opaConv.rmse);
      csv.add("levels", name, fn, "opacity", l, "psnr_conv", r.opaConv.psnr);
      csv.add("levels", name, fn, "conv_vs_full", l, "rmse", score(conv, full).rmse);
    }
  }

  std::printf("Image error of each level (ray march, extinction compositing) against the full-resolution image "
              "(\"full\") and against the full-resolution image of the volume blurred by the level's equivalent "
              "convolution (\"conv\", the paper's criterion); RMSE of premultiplied RGB, PSNR in dB; ratio = "
              "opacity RMSE / extinction RMSE.\n\n");
  std::printf("| filter | level | ext. full RMSE (PSNR) | ext. conv RMSE (PSNR) | opacity full RMSE (PSNR) | opacity "
              "conv RMSE (PSNR) | ratio full | ratio conv |\n|---|---|---|---|---|---|---|---|\n");
  bool beats = true;
  for (int fi = 0; fi < 3; ++fi)
  {
    for (int l = 1; l <= levels; ++l)
    {
      const LevelResult& r = res[size_t(fi)][size_t(l - 1)];
      const double rf = r.opaFull.rmse / std::max(r.extFull.rmse, 1e-12);
      const double rc = r.opaConv.rmse / std::max(r.extConv.rmse, 1e-12);
      std::printf("| %s | %d | %.4f (%.1f) | %.4f (%.1f) | %.4f (%.1f) | %.4f (%.1f) | %.2f | %.2f |\n",
        mcvol::toString(kFilters[fi]), l, r.extFull.rmse, r.extFull.psnr, r.extConv.rmse, r.extConv.psnr,
        r.opaFull.rmse, r.opaFull.psnr, r.opaConv.rmse, r.opaConv.psnr, rf, rc);
      csv.add("levels", name, mcvol::toString(kFilters[fi]), "ratio", l, "rmse_full", rf);
      csv.add("levels", name, mcvol::toString(kFilters[fi]), "ratio", l, "rmse_conv", rc);
      beats = beats && rf > 1.0 && rc > 1.0;
    }
  }
  std::printf("\nExtinction-based better than opacity averaging at every level and filter, on both criteria: %s\n\n",
    beats ? "yes" : "NO");

  // Frame time, memory and build time per level (box4, the paper's filter for
  // trilinear sampling; the other filters give the same grids' sizes).
  std::printf("Frame time (CPU, %dx%d: ray march at the level's Nyquist step with early termination, Monte Carlo "
              "1-spp frame; median of %d), memory and build time per level (box4 pyramid)%s\n\n",
    o.width, o.height, o.reps, c.channels ? "" : "; no scalar path (made pre-classified)");
  std::printf("| level | grid | MiB | build ms (ext. box2 / box4 / bspline; opacity box4) | ray march ms | MC ms/spp "
              "|\n|---|---|---|---|---|---|\n");
  if (c.channels)
  {
    // The normal path: the scalar channels with their transfer functions.
    mcvol::Scene scalar;
    std::vector<mcvol::ChannelSource> src;
    for (int k = 0; k < c.channels; ++k)
    {
      src.push_back(c.demo.source(k));
    }
    scalar.setVolume(c.dims, c.channels, src.data());
    for (int k = 0; k < c.channels; ++k)
    {
      scalar.setTransferFunction(k, c.tfs[size_t(k)]);
    }
    scalar.setBlendMode(mcvol::BlendMode::Density);
    scalar.update();
    const FrameTimes f = timeFrames(scalar, cam0, mc, o.reps);
    std::printf("| 0 (%d scalar channels) | %dx%dx%d | %.2f | - | %.1f | %.1f |\n", c.channels, c.dims[0], c.dims[1],
      c.dims[2], c.scalarBytes / MiB, f.marchMs, f.mcMs);
    csv.add("levels", name, "-", "scalar", 0, "march_ms", f.marchMs);
    csv.add("levels", name, "-", "scalar", 0, "mc_ms", f.mcMs);
    csv.add("levels", name, "-", "scalar", 0, "mib", c.scalarBytes / MiB);
  }
  {
    const FrameTimes f = timeFrames(*classifiedScene(c.view()), cam0, mc, o.reps);
    const double mib = double(c.voxels.size() * sizeof(float)) / MiB;
    std::printf("| 0 (classified) | %dx%dx%d | %.2f | classify %s | %.1f | %.1f |\n", c.dims[0], c.dims[1], c.dims[2],
      mib, c.channels ? (std::to_string(int(std::lround(c.classifyMs))) + " ms").c_str() : "-", f.marchMs, f.mcMs);
    csv.add("levels", name, "-", "classified", 0, "march_ms", f.marchMs);
    csv.add("levels", name, "-", "classified", 0, "mc_ms", f.mcMs);
    csv.add("levels", name, "-", "classified", 0, "mib", mib);
    csv.add("levels", name, "-", "classified", 0, "classify_ms", c.classifyMs);
  }
  for (int l = 1; l <= levels; ++l)
  {
    const mcvol::PyramidLevel& L = pyr[1].ext[size_t(l - 1)];
    const FrameTimes f = timeFrames(*classifiedScene(L.view()), forGrid(cam0, L.spacing, L.origin), mc, o.reps);
    const double mib = double(L.bytes()) / MiB;
    std::printf("| %d | %dx%dx%d | %.3f | %.1f / %.1f / %.1f; %.1f | %.1f | %.1f |\n", l, L.dims[0], L.dims[1],
      L.dims[2], mib, pyr[0].extMs[size_t(l - 1)], pyr[1].extMs[size_t(l - 1)], pyr[2].extMs[size_t(l - 1)],
      pyr[1].opaMs[size_t(l - 1)], f.marchMs, f.mcMs);
    csv.add("levels", name, "box4", "extinction", l, "march_ms", f.marchMs);
    csv.add("levels", name, "box4", "extinction", l, "mc_ms", f.mcMs);
    csv.add("levels", name, "box4", "extinction", l, "mib", mib);
    for (int fi = 0; fi < 3; ++fi)
    {
      csv.add("levels", name, mcvol::toString(kFilters[fi]), "extinction", l, "build_ms",
        pyr[size_t(fi)].extMs[size_t(l - 1)]);
      csv.add(
        "levels", name, mcvol::toString(kFilters[fi]), "opacity", l, "build_ms", pyr[size_t(fi)].opaMs[size_t(l - 1)]);
    }
  }
  std::printf("\n");
  std::fflush(stdout);
  return beats;
}

// --------------------------------------------------------------- section far

/// A look-at camera at distance `dist` from `center` (azimuth, elevation in
/// degrees; fovy 30 degrees, as orbitCamera), for a grid of `spacing` and
/// `origin`.
mcvol::Camera lookAt(const double center[3], double dist, double radius, double azDeg, double elDeg, int W, int H,
  double fovyDeg, const double spacing[3], const double origin[3])
{
  const double az = azDeg * M_PI / 180.0, el = elDeg * M_PI / 180.0;
  const double eye[3] = { center[0] + dist * std::cos(el) * std::sin(az), center[1] + dist * std::sin(el),
    center[2] + dist * std::cos(el) * std::cos(az) };
  const double up[3] = { 0, 1, 0 };
  const auto vp = mcvol::viewProjection(eye, center, up, fovyDeg, double(W) / double(H),
    std::max(1e-6, dist - 1.5 * radius), dist + 1.5 * radius, false, 1.0);
  mcvol::Camera cam;
  cam.width = W;
  cam.height = H;
  mcvol::invert4x4(vp.data(), cam.invViewProj);
  return forGrid(cam, spacing, origin);
}

/**
 * The automatic level, as the mapper chooses it (vtkMultiChannelVolumeMapper
 * SetLevelOfDetail(-1); this local copy is the benchmark's, kept to the same
 * rule): the pixel footprint is the world size of one pixel at the distance
 * from the camera to the volume's bounding-box centre, footprint =
 * 2 d tan(viewAngle / 2) / heightPixels (perspective), and the level is the
 * one whose voxels are about one pixel: L = floor(log2(footprint / smallest
 * level-0 spacing)), clamped to [0, levels].
 */
int autoLevel(double distance, double viewAngleDeg, int heightPixels, double minSpacing, int levels, double* footprint)
{
  const double fp = 2.0 * distance * std::tan(0.5 * viewAngleDeg * M_PI / 180.0) / double(heightPixels);
  if (footprint)
  {
    *footprint = fp;
  }
  const int L = int(std::floor(std::log2(fp / minSpacing)));
  return std::min(std::max(L, 0), levels);
}

/// Cheap integer hash to [0, 1) (deterministic on every machine).
double hash01(uint64_t x)
{
  x ^= x >> 33;
  x *= 0xff51afd7ed558ccdULL;
  x ^= x >> 33;
  x *= 0xc4ceb9fe1a85ec53ULL;
  x ^= x >> 33;
  return double(x >> 11) * 0x1p-53;
}

/// Block average of a (W s) x (H s) image down to W x H: the pixel footprint's
/// box-filtered value with s^2 regularly placed sub-pixel rays.
Image downsampleImage(const Image& big, int W, int H, int s)
{
  Image out(size_t(4) * size_t(W) * size_t(H), 0.f);
  const double w = 1.0 / double(s * s);
  for (int y = 0; y < H; ++y)
    for (int x = 0; x < W; ++x)
    {
      double acc[4] = { 0, 0, 0, 0 };
      for (int j = 0; j < s; ++j)
        for (int i = 0; i < s; ++i)
        {
          const float* p = big.data() + 4 * (size_t(y * s + j) * size_t(W * s) + size_t(x * s + i));
          for (int c = 0; c < 4; ++c)
            acc[c] += w * p[c];
        }
      for (int c = 0; c < 4; ++c)
        out[4 * (size_t(y) * size_t(W) + size_t(x)) + size_t(c)] = float(acc[c]);
    }
  return out;
}

/**
 * The far-view volumes, N^3 with voxel-scale detail inside a ball of radius
 * 0.45 N (outside empty):
 *   "ball"   dense (sigma 0.35 to 1.05 per voxel) with a random colour per
 *            voxel: the camera sees the ball's first few voxels, i.e.
 *            per-voxel colour noise that one ray per pixel aliases when a
 *            pixel covers several voxels and that the pixel's footprint
 *            averages to a smooth shade;
 *   "sheets" semi-transparent one-voxel sheets (sigma 0.3 per voxel where
 *            (i + j) % 4 == 0, diagonal planes 2.8 voxels apart) with a random
 *            colour per voxel: seen from the study's view, a pattern above
 *            the pixel rate that one ray per pixel turns into moire.
 */
std::vector<float> makeFarVolume(const std::string& kind, int N)
{
  std::vector<float> vox(size_t(4) * size_t(N) * size_t(N) * size_t(N), 0.f);
  const double c = 0.5 * double(N - 1), rad = 0.45 * double(N);
  const bool sheets = kind == "sheets";
  if (!sheets && kind != "ball")
  {
    throw std::invalid_argument("unknown far-view volume " + kind + " (ball, sheets)");
  }
#pragma omp parallel for schedule(static)
  for (int k = 0; k < N; ++k)
    for (int j = 0; j < N; ++j)
      for (int i = 0; i < N; ++i)
      {
        const double dx = i - c, dy = j - c, dz = k - c;
        if (dx * dx + dy * dy + dz * dz > rad * rad || (sheets && (i + j) % 4 != 0))
          continue;
        const uint64_t id = (uint64_t(k) * uint64_t(N) + uint64_t(j)) * uint64_t(N) + uint64_t(i);
        float* p = vox.data() + 4 * id;
        p[0] = sheets ? 0.3f : float(0.35 + 0.7 * hash01(4 * id));
        for (int q = 1; q < 4; ++q)
          p[q] = p[0] * float(0.1 + 0.9 * hash01(4 * id + uint64_t(q)));
      }
  return vox;
}

void runFar(const Options& o, const std::string& kind, mcvol::Renderer& mc, Csv& csv)
{
  const int N = o.farEdge;
  const std::vector<float> vox = makeFarVolume(kind, N);
  const double c = 0.5 * double(N - 1);
  mcvol::ClassifiedVolumeView v0;
  v0.voxels = vox.data();
  v0.dims[0] = v0.dims[1] = v0.dims[2] = N;
  const int levels = std::min(o.farLevels, mcvol::maxPyramidLevels(v0.dims));
  auto t0 = Clock::now();
  const std::vector<mcvol::PyramidLevel> pyr = mcvol::buildExtinctionPyramid(v0, levels, DownsampleFilter::Box4);
  const double buildMs = msSince(t0);
  const std::vector<mcvol::PyramidLevel> opa = mcvol::buildOpacityPyramid(v0, levels, 1.0, DownsampleFilter::Box4);

  const int W = o.farSize, H = o.farSize;
  const double fovy = 30.0;
  const double edge = double(N - 1);
  const double center[3] = { c, c, c };
  const double radius = 0.5 * std::sqrt(3.0) * edge;
  // Distance at which the cube's edge spans farCoverage pixels (at its centre).
  const double dist = edge / (o.farCoverage * 2.0 * std::tan(0.5 * fovy * M_PI / 180.0) / double(H));
  double footprint = 0;
  const int autoL = autoLevel(dist, fovy, H, 1.0, levels, &footprint);
  const double one[3] = { 1, 1, 1 }, zero[3] = { 0, 0, 0 };
  const mcvol::Camera cam0 = lookAt(center, dist, radius, 30, 20, W, H, fovy, one, zero);

  // Reference: s^2 sub-pixel rays per pixel at level 0, box-filtered.
  const int S = o.farSuper;
  const mcvol::Camera big = lookAt(center, dist, radius, 30, 20, W * S, H * S, fovy, one, zero);
  double refMs = 0;
  const Image ref = downsampleImage(march(v0, big, 0.25, 1e-4f, &refMs), W, H, S);

  std::printf("## Far view \"%s\": %d^3 voxel-scale detail at %dx%d (edge over %.0f px; footprint %.2f voxels, "
              "automatic level %d), box4 pyramid built in %.0f ms\n\n",
    kind.c_str(), N, W, H, o.farCoverage, footprint, autoL, buildMs);
  std::printf("Reference: %d x %d sub-pixel rays per pixel at level 0 (ray march, step 1/4 voxel), box-filtered "
              "(%.0f ms). Ray march: one ray per pixel centre at the level's Nyquist step, early termination 1e-4 "
              "(median of %d). Monte Carlo: pixel-jittered samples (renderer defaults), cumulative time.\n\n",
    S, S, refMs, o.reps);
  std::printf(
    "| level | grid | MiB | ray march ms | RM RMSE (PSNR) | opacity-pyramid RM RMSE (PSNR) | MC 1 spp ms | MC "
    "16 spp RMSE (PSNR) | MC 64 spp RMSE (PSNR), ms |\n|---|---|---|---|---|---|---|---|---|\n");
  std::vector<double> rmRmse, rmMs;
  for (int l = 0; l <= levels; ++l)
  {
    const mcvol::ClassifiedVolumeView v = l == 0 ? v0 : pyr[size_t(l - 1)].view();
    const std::unique_ptr<mcvol::Scene> scene = classifiedScene(v);
    const mcvol::Camera cam = forGrid(cam0, v.spacing, v.origin);
    const FrameTimes f = timeFrames(*scene, cam, mc, o.reps);
    const Image rm = march(v, cam0, 0.0, 1e-4f); // step 0: this grid's Nyquist step
    const ImageError s = score(rm, ref);
    rmRmse.push_back(s.rmse);
    rmMs.push_back(f.marchMs);
    ImageError so;
    if (l > 0)
    {
      so = score(march(opa[size_t(l - 1)].view(), cam0, 0.0, 1e-4f), ref);
    }
    // Monte Carlo with pixel jitter converges to the footprint-averaged image
    // of this level.
    mcvol::RenderSettings rs;
    rs.seed = 7;
    mcvol::Accumulator acc;
    double mcMs = 0;
    ImageError s16, s64;
    for (int spp = 1; spp <= 64; spp *= 2)
    {
      rs.samplesPerPixel = spp - int(acc.samples());
      const auto t1 = Clock::now();
      mc.render(*scene, cam, rs, nullptr, acc);
      mc.finish();
      mcMs += msSince(t1);
      const Image im(acc.rgba(), acc.rgba() + size_t(4) * size_t(W) * size_t(H));
      if (spp == 16)
        s16 = score(im, ref);
      if (spp == 64)
        s64 = score(im, ref);
    }
    const double mib =
      double(size_t(4) * sizeof(float) * size_t(v.dims[0]) * size_t(v.dims[1]) * size_t(v.dims[2])) / MiB;
    char opaText[64] = "-";
    if (l > 0)
    {
      std::snprintf(opaText, sizeof(opaText), "%.4f (%.1f)", so.rmse, so.psnr);
    }
    std::printf("| %d%s | %dx%dx%d | %.2f | %.1f | %.4f (%.1f) | %s | %.1f | %.4f (%.1f) | %.4f (%.1f), %.0f |\n", l,
      l == autoL ? " (auto)" : "", v.dims[0], v.dims[1], v.dims[2], mib, f.marchMs, s.rmse, s.psnr, opaText, f.mcMs,
      s16.rmse, s16.psnr, s64.rmse, s64.psnr, mcMs);
    const std::string m = l == autoL ? "auto" : "fixed";
    csv.add("far", kind, "box4", "raymarch", l, "ms", f.marchMs);
    csv.add("far", kind, "box4", "raymarch", l, "rmse", s.rmse);
    csv.add("far", kind, "box4", "raymarch", l, "psnr", s.psnr);
    if (l > 0)
    {
      csv.add("far", kind, "box4", "raymarch_opacity", l, "rmse", so.rmse);
    }
    csv.add("far", kind, "box4", "montecarlo", l, "ms_per_spp", f.mcMs);
    csv.add("far", kind, "box4", "montecarlo", l, "rmse_16spp", s16.rmse);
    csv.add("far", kind, "box4", "montecarlo", l, "rmse_64spp", s64.rmse);
    csv.add("far", kind, "box4", "montecarlo", l, "ms_64spp", mcMs);
    csv.add("far", kind, "box4", m, l, "mib", mib);
    std::fflush(stdout);
  }
  csv.add("far", kind, "box4", "auto", autoL, "footprint_voxels", footprint);
  const int best = int(std::min_element(rmRmse.begin(), rmRmse.end()) - rmRmse.begin());
  std::printf("\nRay march: level 0 RMSE %.4f in %.1f ms; automatic level %d RMSE %.4f in %.1f ms (error x%.2f, time "
              "x%.2f); lowest error at level %d (RMSE %.4f).\n\n",
    rmRmse[0], rmMs[0], autoL, rmRmse[size_t(autoL)], rmMs[size_t(autoL)], rmRmse[size_t(autoL)] / rmRmse[0],
    rmMs[size_t(autoL)] / rmMs[0], best, rmRmse[size_t(best)]);
  csv.add("far", kind, "box4", "best", best, "rmse", rmRmse[size_t(best)]);
}
} // namespace

int main(int argc, char** argv)
{
  Options o;
  try
  {
    makeParser(o).parse(argc, argv);
  }
  catch (const std::exception& e)
  {
    std::fprintf(stderr, "mcvol-pyramid: %s\n", e.what());
    makeParser(o).printHelp();
    return 2;
  }
  try
  {
    int threads = 1;
#ifdef _OPENMP
    threads = omp_get_max_threads();
#endif
    std::unique_ptr<mcvol::Renderer> mc = mcvol::Renderer::create(mcvol::Backend::CPU);
    std::printf("# mcvol-pyramid\n\nCPU, %d threads; levels 1..%d; filters box2 (1 1)/2, box4 (1 1 1 1)/4, bspline "
                "(13 19 19 13)/64; opacity baseline = the same filter on opacities for one finer voxel, "
                "opacity-corrected\n\n",
      threads, o.levels);
    // The equivalent kernels against the library's own 1-D pyramids.
    double worst = 0;
    for (DownsampleFilter f : kFilters)
    {
      for (int l = 1; l <= std::max(o.levels, o.farLevels); ++l)
      {
        worst = std::max(worst, checkKernel(f, l));
      }
    }
    std::printf("Equivalent kernels K_l against the library's 1-D pyramids averaged over phases: largest difference "
                "%.2e\n\n",
      worst);
    if (worst > 1e-5)
    {
      std::fprintf(stderr, "mcvol-pyramid: the equivalent kernel does not match the pyramid (%g)\n", worst);
      return 1;
    }
    std::printf("| filter | level | K_l taps (t >= 0) |\n|---|---|---|\n");
    for (DownsampleFilter f : kFilters)
    {
      for (int l = 1; l <= std::min(o.levels, 2); ++l)
      {
        const std::vector<double> K = equivalentKernel(f, l);
        std::string t;
        for (size_t i = K.size() / 2; i < K.size(); ++i)
        {
          char b[32];
          std::snprintf(b, sizeof(b), "%s%.4f", t.empty() ? "" : " ", K[i]);
          t += b;
        }
        std::printf("| %s | %d | %s |\n", mcvol::toString(f), l, t.c_str());
      }
    }
    std::printf("\n");

    Csv csv;
    bool wallOk = true;
    if (contains(o.sections, "levels"))
    {
      for (const std::string& ds : o.datasets)
      {
        const bool beats = runLevels(o, ds, *mc, csv);
        if (ds == "wall" && !beats)
        {
          wallOk = false;
        }
      }
    }
    if (contains(o.sections, "far"))
    {
      for (const std::string& kind : o.farKinds)
      {
        runFar(o, kind, *mc, csv);
      }
    }
    if (!o.csv.empty())
    {
      writeLines(o.csv, csv.rows);
    }
    if (!wallOk)
    {
      std::fprintf(stderr,
        "mcvol-pyramid: on the one-voxel wall the extinction-based pyramid does not beat opacity "
        "averaging at every level and filter\n");
      return 1;
    }
  }
  catch (const std::exception& e)
  {
    std::fprintf(stderr, "mcvol-pyramid: %s\n", e.what());
    return 1;
  }
  return 0;
}
