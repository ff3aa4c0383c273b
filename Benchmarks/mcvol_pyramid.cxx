// SPDX-License-Identifier: BSD-3-Clause
//
// mcvol-pyramid: the levels-of-detail part of the accuracy-versus-time study
// (issue 13; Kraus and Buerger, "Interpolating and Downsampling RGBA Volume
// Data", Sections 3-4). VTK-free, CPU only (the GPU frame times of the levels
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
//     (equivalentKernel() below), rendered at full resolution the same way;
//   - frame time per level (ray march at the level's own Nyquist step with
//     early termination; Monte Carlo 1-spp frames, the renderer's defaults),
//     memory per level and build time (classify, each downsampling step).
//   Datasets: the study's phantoms (figure3, microscopy, cosmology, weather at
//   their stored sizes), "wall" (a one-voxel wall of tau = 4 per voxel, the
//   paper's Sec. 3.6 / 4.1 case, facing the view), "wall-x" (the same wall
//   seen at a grazing angle) and "figure2" (the paper's Figure 2/3
//   example: every 2x2x2 block of a two-voxel slab holds 4 voxels of tau = 4
//   and 4 of tau = 0, checkered, so every axis ray through it meets one of
//   each: extinction averaging keeps alpha = 0.98 there, opacity averaging
//   gives 0.74).
//   The program exits 1 if on the wall the extinction-based pyramid is not
//   better than the opacity baseline at every level and filter, on both
//   criteria (the requirement; the other datasets are reported).
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

namespace
{
using Clock = std::chrono::steady_clock;
using mcvol::DownsampleFilter;

double msSince(Clock::time_point t0)
{
  return 1e3 * std::chrono::duration<double>(Clock::now() - t0).count();
}

double median(std::vector<double> v)
{
  std::sort(v.begin(), v.end());
  const size_t n = v.size();
  return n % 2 ? v[n / 2] : 0.5 * (v[n / 2 - 1] + v[n / 2]);
}

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

std::vector<std::string> split(const std::string& s)
{
  std::vector<std::string> out;
  std::stringstream ss(s);
  std::string item;
  while (std::getline(ss, item, ','))
  {
    if (!item.empty())
    {
      out.push_back(item);
    }
  }
  return out;
}

void usage()
{
  std::puts("usage: mcvol-pyramid [--datasets figure3,microscopy,cosmology,weather,wall,wall-x,figure2]\n"
            "                     [--sections levels,far] [--dims X Y Z] [--size W H] [--levels L]\n"
            "                     [--step-fraction F] [--reps N] [--far-volumes ball,sheets]\n"
            "                     [--far-edge N] [--far-size PX] [--far-coverage PX]\n"
            "                     [--far-super S] [--far-levels L] [--csv FILE]");
}

Options parse(int argc, char** argv)
{
  Options o;
  for (int i = 1; i < argc; ++i)
  {
    const std::string a = argv[i];
    auto need = [&](int n)
    {
      if (i + n >= argc)
      {
        throw std::invalid_argument(a + " needs " + std::to_string(n) + " value(s)");
      }
    };
    if (a == "--datasets")
    {
      need(1);
      o.datasets = split(argv[++i]);
    }
    else if (a == "--sections")
    {
      need(1);
      o.sections = split(argv[++i]);
    }
    else if (a == "--dims")
    {
      need(3);
      for (int k = 0; k < 3; ++k)
        o.dims[size_t(k)] = std::stoi(argv[++i]);
    }
    else if (a == "--size")
    {
      need(2);
      o.width = std::stoi(argv[++i]);
      o.height = std::stoi(argv[++i]);
    }
    else if (a == "--levels")
    {
      need(1);
      o.levels = std::stoi(argv[++i]);
    }
    else if (a == "--step-fraction")
    {
      need(1);
      o.stepFraction = std::stod(argv[++i]);
    }
    else if (a == "--reps")
    {
      need(1);
      o.reps = std::max(1, std::stoi(argv[++i]));
    }
    else if (a == "--far-volumes")
    {
      need(1);
      o.farKinds = split(argv[++i]);
    }
    else if (a == "--far-edge")
    {
      need(1);
      o.farEdge = std::stoi(argv[++i]);
    }
    else if (a == "--far-size")
    {
      need(1);
      o.farSize = std::stoi(argv[++i]);
    }
    else if (a == "--far-coverage")
    {
      need(1);
      o.farCoverage = std::stod(argv[++i]);
    }
    else if (a == "--far-super")
    {
      need(1);
      o.farSuper = std::max(1, std::stoi(argv[++i]));
    }
    else if (a == "--far-levels")
    {
      need(1);
      o.farLevels = std::stoi(argv[++i]);
    }
    else if (a == "--csv")
    {
      need(1);
      o.csv = argv[++i];
    }
    else if (a == "--help" || a == "-h")
    {
      usage();
      std::exit(0);
    }
    else
    {
      throw std::invalid_argument("unknown option " + a);
    }
  }
  return o;
}

bool wants(const Options& o, const std::string& s)
{
  return std::find(o.sections.begin(), o.sections.end(), s) != o.sections.end();
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

struct Score
{
  double rmse = 0;
  double psnr = 0;
};

/// RMSE and PSNR (peak 1) of the premultiplied RGB clipped to [0, 1], as
/// mcvol-accuracy and accuracy_study.py score images.
Score score(const Image& a, const Image& ref)
{
  double se = 0;
  const size_t P = a.size() / 4;
  for (size_t p = 0; p < P; ++p)
  {
    for (int c = 0; c < 3; ++c)
    {
      const double x = std::min(1.0, std::max(0.0, double(a[4 * p + size_t(c)])));
      const double y = std::min(1.0, std::max(0.0, double(ref[4 * p + size_t(c)])));
      se += (x - y) * (x - y);
    }
  }
  const double mse = se / double(3 * P);
  return { std::sqrt(mse), mse > 0 ? -10.0 * std::log10(mse) : 300.0 };
}

/// A camera for a volume of `spacing` and `origin`: the level-0 camera's
/// rays, this grid's world-to-index map (so every level lines up with
/// level 0, whose origin is 0).
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

/// One pre-classified grid as a scene (one Extinction channel, density blend).
struct GridScene
{
  mcvol::Scene scene;
  explicit GridScene(const mcvol::ClassifiedVolumeView& v, int macrocell = 8)
  {
    mcvol::ChannelSource src;
    src.data = v.voxels;
    src.type = mcvol::ScalarType::Float32;
    src.stride = v.stride;
    src.format = mcvol::ChannelFormat::Extinction;
    this->scene.setVolume(v.dims, 1, &src);
    this->scene.setMacrocellSize(macrocell);
    this->scene.setBlendMode(mcvol::BlendMode::Density);
    this->scene.update();
  }
};

/// Deterministic ray march of a classified grid through the level-0 camera's
/// rays. step: world units; terminate: early-termination transmittance.
Image march(
  const mcvol::ClassifiedVolumeView& v, const mcvol::Camera& cam0, double step, float terminate, double* ms = nullptr)
{
  GridScene g(v);
  const mcvol::Camera cam = forGrid(cam0, v.spacing, v.origin);
  mcvol::MarchSettings s;
  s.step = step;
  s.terminateTransmittance = terminate;
  mcvol::RayMarcher rm;
  mcvol::Accumulator acc;
  const auto t0 = Clock::now();
  rm.render(g.scene, cam, s, nullptr, acc);
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

// ------------------------------------------------------- equivalent kernel

/**
 * The equivalent convolution of downsampling to level l and reconstructing
 * there (the paper's criterion, Sec. 4.2, after Kraus' quasi-convolution
 * pyramid blurring): the shift-invariant filter that the pyramid
 * approximates, per axis (the 3-D filter is its tensor product).
 *
 * Derivation, in fine voxels along one axis, s = 2^l. Coarse voxel c of
 * level l is centred at p_c = s c + (s - 1) / 2 (cell-centred levels,
 * Pyramid.h). Level m reads level m-1 voxels 2c + first + k with weights
 * w_k, i.e. at offsets (first + k - 1/2) 2^(m-1) fine voxels from its centre;
 * so level l's voxel is sum_o W(o) f(p_c + o), W the taps of level 1, the
 * taps of level 2 dilated by 2, ..., of level l dilated by 2^(l-1), all
 * convolved (offsets are half-integers for l >= 1). Trilinear
 * reconstruction at level l is the tent T_s(t) = max(0, 1 - |t| / s) over
 * the coarse centres. A fine voxel at y therefore reaches x with weight
 * sum_c T_s(x - p_c) W(y - p_c). This depends on the phase of y against the
 * coarse grid; averaged over the s phases (y = 0..s-1 with x - y = t fixed),
 * y - p_c runs over every offset of the lattice once, so
 *
 *     K_l(t) = (1/s) sum_o W(o) T_s(t + o),      t integer,
 *
 * which sums to 1 (the tent's partition of unity). Rendering the level
 * approximates rendering the full-resolution volume convolved with K_l (in
 * extinction and extinction-weighted colour); how far the image is from
 * that is the criterion's error. The full-resolution render of the blurred
 * volume adds level 0's own trilinear reconstruction (a tent of width 1,
 * variance 1/6 voxel^2 against K_1's 1.9 for box4), as every full-resolution
 * render does. checkKernel() compares K_l with the library's own 1-D
 * pyramid averaged over the phases.
 *
 * Returns K_l(t) for t = -R..R (index t + R).
 */
std::vector<double> equivalentKernel(DownsampleFilter f, int level)
{
  const mcvol::FilterTaps taps = mcvol::filterTaps(f);
  // W on offsets in half fine voxels (integers): index h + H for offset h/2.
  std::vector<double> W = { 1.0 };
  int H = 0; // W[i] is at half-offset i - H
  for (int m = 1; m <= level; ++m)
  {
    const int dil = 1 << (m - 1);
    int lo = 0, hi = 0; // half-offsets of this level's taps: (2 (first + k) - 1) dil
    for (int k = 0; k < taps.count; ++k)
    {
      const int h = (2 * (taps.first + k) - 1) * dil;
      lo = k == 0 ? h : std::min(lo, h);
      hi = k == 0 ? h : std::max(hi, h);
    }
    std::vector<double> next(W.size() + size_t(hi - lo), 0.0);
    for (size_t i = 0; i < W.size(); ++i)
    {
      for (int k = 0; k < taps.count; ++k)
      {
        const int h = (2 * (taps.first + k) - 1) * dil;
        next[i + size_t(h - lo)] += W[i] * taps.w[k];
      }
    }
    W.swap(next);
    H = H - lo;
  }
  const int s = 1 << level;
  const int maxHalf = std::max(H, int(W.size()) - 1 - H);
  const int R = s + (maxHalf + 1) / 2;
  std::vector<double> K(size_t(2 * R + 1), 0.0);
  for (int t = -R; t <= R; ++t)
  {
    double sum = 0;
    for (size_t i = 0; i < W.size(); ++i)
    {
      const double o = 0.5 * double(int(i) - H);
      sum += W[i] * std::max(0.0, 1.0 - std::fabs(double(t) + o) / double(s));
    }
    K[size_t(t + R)] = sum / double(s);
  }
  return K;
}

/**
 * K_l measured on the library itself: a 1-D volume (N x 1 x 1) with one
 * voxel of sigma 1 at y, its extinction pyramid, level l reconstructed by
 * linear interpolation at every fine voxel x (its spacing and origin), the
 * response at x = y + t averaged over the s phases of y. Returns the largest
 * difference from equivalentKernel().
 */
double checkKernel(DownsampleFilter f, int level)
{
  const std::vector<double> K = equivalentKernel(f, level);
  const int R = int(K.size() / 2);
  const int s = 1 << level;
  const int N = 8 * (R + s) + 16 * s;
  std::vector<double> avg(K.size(), 0.0);
  for (int phase = 0; phase < s; ++phase)
  {
    const int y = N / 2 + phase;
    std::vector<float> v(size_t(4 * N), 0.f);
    v[size_t(4 * y)] = 1.f;
    mcvol::ClassifiedVolumeView view;
    view.voxels = v.data();
    view.dims[0] = N;
    view.dims[1] = view.dims[2] = 1;
    const std::vector<mcvol::PyramidLevel> pyr = mcvol::buildExtinctionPyramid(view, level, f);
    const mcvol::PyramidLevel& L = pyr.back();
    for (int t = -R; t <= R; ++t)
    {
      const double u = (double(y + t) - L.origin[0]) / L.spacing[0];
      const int i0 = std::min(std::max(int(std::floor(u)), 0), L.dims[0] - 2);
      const double fr = u - double(i0);
      const double val = (1.0 - fr) * L.voxels[size_t(4 * i0)] + fr * L.voxels[size_t(4 * (i0 + 1))];
      avg[size_t(t + R)] += val / double(s);
    }
  }
  double worst = 0;
  for (size_t i = 0; i < K.size(); ++i)
  {
    worst = std::max(worst, std::fabs(avg[i] - K[i]));
  }
  return worst;
}

/// Separable convolution of a packed float4 volume with a symmetric kernel
/// (index t + R), clamped at the edges as the pyramid's filters are.
std::vector<float> blur(const std::vector<float>& in, const int d[3], const std::vector<double>& K)
{
  const int R = int(K.size() / 2);
  std::vector<float> a = in, b(in.size());
  const int64_t stride[3] = { 1, d[0], int64_t(d[0]) * d[1] };
  const int64_t n = int64_t(d[0]) * d[1] * d[2];
  for (int axis = 0; axis < 3; ++axis)
  {
    if (d[axis] == 1)
    {
      continue; // not downsampled either
    }
#pragma omp parallel for schedule(static)
    for (int64_t v = 0; v < n; ++v)
    {
      const int64_t idx = (v / stride[axis]) % d[axis];
      const int64_t base = v - idx * stride[axis];
      double acc[4] = { 0, 0, 0, 0 };
      for (int t = -R; t <= R; ++t)
      {
        const int64_t j = std::min<int64_t>(std::max<int64_t>(idx + t, 0), d[axis] - 1);
        const float* x = a.data() + (base + j * stride[axis]) * 4;
        const double w = K[size_t(t + R)];
        for (int c = 0; c < 4; ++c)
        {
          acc[c] += w * double(x[c]);
        }
      }
      for (int c = 0; c < 4; ++c)
      {
        b[size_t(v) * 4 + size_t(c)] = float(acc[c]);
      }
    }
    a.swap(b);
  }
  return a;
}

// ---------------------------------------------------------------- datasets

/// A dataset pre-classified to level 0 (packed float4), with what it came from.
struct Classified
{
  std::string name;
  int dims[3] = { 0, 0, 0 };
  double spacing[3] = { 1, 1, 1 };
  std::vector<float> voxels;
  int channels = 0;       ///< scalar channels classified (0: made classified)
  double scalarBytes = 0; ///< the scalar channels' bytes
  double classifyMs = 0;
  mcvol::DemoVolume demo; ///< the scalar data (demo datasets), for the normal path's frame time
  std::vector<mcvol::TransferFunctionDesc> tfs;

  mcvol::ClassifiedVolumeView view() const
  {
    mcvol::ClassifiedVolumeView v;
    v.voxels = this->voxels.data();
    for (int a = 0; a < 3; ++a)
    {
      v.dims[a] = this->dims[a];
      v.spacing[a] = this->spacing[a];
    }
    return v;
  }
};

/// A demo dataset classified with accumulate = true: the density blend of
/// its channels (their extinctions and extinction-weighted colours add), the
/// same tables as mcvol-accuracy's scenes.
Classified classifyDemo(const std::string& name, std::array<int, 3> dims)
{
  Classified c;
  c.name = name;
  c.demo = mcvol::makeDemo(name, dims);
  const mcvol::DemoVolume& v = c.demo;
  std::copy(v.dims, v.dims + 3, c.dims);
  std::copy(v.spacing, v.spacing + 3, c.spacing);
  c.channels = v.numChannels();
  const size_t n = size_t(c.dims[0]) * size_t(c.dims[1]) * size_t(c.dims[2]);
  for (int k = 0; k < v.numChannels(); ++k)
  {
    const std::array<float, 2> r = v.range(k);
    c.tfs.push_back(mcvol::sampleTransferFunction(v.transferFunctions[size_t(k)], r[0], r[1], 1024, v.spacing[0]));
    c.scalarBytes += double(v.channels[size_t(k)].size());
  }
  const auto t0 = Clock::now();
  c.voxels.assign(4 * n, 0.f);
  for (int k = 0; k < v.numChannels(); ++k)
  {
    mcvol::classifyScalars(v.source(k), c.dims, c.tfs[size_t(k)], c.voxels.data(), 4, true);
  }
  c.classifyMs = msSince(t0);
  return c;
}

/// The paper's thin wall (Sec. 3.6, Figs. 5-6; Sec. 4.1): a one-voxel wall of
/// tau = 4 per voxel (alpha 0.98 across it) through the middle of an
/// otherwise empty cube; warm white. "wall": normal along z, the axis closest
/// to the study's view direction (36 degrees off it), so rays cross the wall
/// as in Sec. 4.1; "wall-x": normal along x, seen at a grazing 62 degrees, so
/// every ray crossing it is nearly opaque at any level and what is left to
/// compare is mostly the wall's projected width.
Classified makeWall(const std::string& name, std::array<int, 3> dims)
{
  Classified c;
  c.name = name;
  const int N = dims[0] > 0 ? dims[0] : 64;
  c.dims[0] = c.dims[1] = c.dims[2] = N;
  if (dims[0] > 0)
  {
    std::copy(dims.begin(), dims.end(), c.dims);
  }
  c.voxels.assign(size_t(4) * size_t(c.dims[0]) * size_t(c.dims[1]) * size_t(c.dims[2]), 0.f);
  const float rgb[3] = { 1.0f, 0.85f, 0.6f };
  const int axis = name == "wall-x" ? 0 : 2;
  const int at = c.dims[axis] / 2;
  for (int k = 0; k < c.dims[2]; ++k)
    for (int j = 0; j < c.dims[1]; ++j)
      for (int i = 0; i < c.dims[0]; ++i)
      {
        const int idx[3] = { i, j, k };
        if (idx[axis] != at)
        {
          continue;
        }
        float* p = c.voxels.data() + 4 * ((size_t(k) * size_t(c.dims[1]) + size_t(j)) * size_t(c.dims[0]) + size_t(i));
        p[0] = 4.f;
        for (int q = 0; q < 3; ++q)
          p[q + 1] = 4.f * rgb[q];
      }
  return c;
}

/// The paper's Figure 2/3 example, made visible: a slab two voxels thick
/// (z = 2m, 2m + 1 with m = N/4, aligned with the level-1 blocks) in which
/// every 2x2x2 block has 4 voxels of tau = 4 and 4 of 0, checkered
/// ((i + j + k) even), so a ray along any axis meets one of each. Level 1
/// averages each block to tau' = 2 (alpha 0.98 over 2 voxels); opacity
/// averaging gives 0.49, corrected to 0.74. Light blue.
Classified makeFigure2(std::array<int, 3> dims)
{
  Classified c;
  c.name = "figure2";
  const int N = dims[0] > 0 ? dims[0] : 64;
  c.dims[0] = c.dims[1] = c.dims[2] = N;
  if (dims[0] > 0)
  {
    std::copy(dims.begin(), dims.end(), c.dims);
  }
  c.voxels.assign(size_t(4) * size_t(c.dims[0]) * size_t(c.dims[1]) * size_t(c.dims[2]), 0.f);
  const float rgb[3] = { 0.55f, 0.8f, 1.0f };
  const int z0 = 2 * (c.dims[2] / 4);
  for (int k = z0; k < std::min(z0 + 2, c.dims[2]); ++k)
    for (int j = 0; j < c.dims[1]; ++j)
      for (int i = 0; i < c.dims[0]; ++i)
      {
        if ((i + j + k) % 2)
        {
          continue;
        }
        float* p = c.voxels.data() + 4 * ((size_t(k) * size_t(c.dims[1]) + size_t(j)) * size_t(c.dims[0]) + size_t(i));
        p[0] = 4.f;
        for (int q = 0; q < 3; ++q)
          p[q + 1] = 4.f * rgb[q];
      }
  return c;
}

Classified makeDataset(const std::string& name, std::array<int, 3> dims)
{
  if (name == "wall" || name == "wall-x")
  {
    return makeWall(name, dims);
  }
  if (name == "figure2")
  {
    return makeFigure2(dims);
  }
  return classifyDemo(name, dims);
}

// ------------------------------------------------------------ section levels

const DownsampleFilter kFilters[3] = { DownsampleFilter::Box2, DownsampleFilter::Box4, DownsampleFilter::BSpline };

struct LevelResult
{
  Score extFull, extConv, opaFull, opaConv;
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
    GridScene g(c.view());
    const FrameTimes f = timeFrames(g.scene, cam0, mc, o.reps);
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
    GridScene g(L.view());
    const FrameTimes f = timeFrames(g.scene, forGrid(cam0, L.spacing, L.origin), mc, o.reps);
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
    GridScene g(v);
    const mcvol::Camera cam = forGrid(cam0, v.spacing, v.origin);
    const FrameTimes f = timeFrames(g.scene, cam, mc, o.reps);
    const Image rm = march(v, cam0, 0.0, 1e-4f); // step 0: this grid's Nyquist step
    const Score s = score(rm, ref);
    rmRmse.push_back(s.rmse);
    rmMs.push_back(f.marchMs);
    Score so{ 0, 0 };
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
    Score s16{ 0, 0 }, s64{ 0, 0 };
    for (int spp = 1; spp <= 64; spp *= 2)
    {
      rs.samplesPerPixel = spp - int(acc.samples());
      const auto t1 = Clock::now();
      mc.render(g.scene, cam, rs, nullptr, acc);
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
    o = parse(argc, argv);
  }
  catch (const std::exception& e)
  {
    std::fprintf(stderr, "mcvol-pyramid: %s\n", e.what());
    usage();
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
    if (wants(o, "levels"))
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
    if (wants(o, "far"))
    {
      for (const std::string& kind : o.farKinds)
      {
        runFar(o, kind, *mc, csv);
      }
    }
    if (!o.csv.empty())
    {
      std::ofstream f(o.csv);
      for (const auto& l : csv.rows)
      {
        f << l << "\n";
      }
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
