// SPDX-License-Identifier: BSD-3-Clause
// Extinction-based pyramids of pre-classified volumes, the opacity-averaging
// baseline, and pre-classification of scalar channels (Kraus and Buerger,
// Sections 3.3 and 4).
#include "mcvol/Pyramid.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>

namespace mcvol
{
namespace
{
/// Smallest averaged transparency the opacity baseline turns back into
/// extinction (-ln(1e-30) = 69 optical depths: opaque for any purpose).
constexpr double kMinTransparency = 1e-30;

std::string axisText(int a)
{
  return std::string(1, "xyz"[a]);
}

void checkView(const ClassifiedVolumeView& v)
{
  if (!v.voxels)
  {
    throw std::invalid_argument("mcvol: the pre-classified volume has no voxels");
  }
  if (v.stride < 4)
  {
    throw std::invalid_argument("mcvol: the pre-classified volume's stride must be at least 4 floats (sigma, sigma r, "
                                "sigma g, sigma b per voxel), not " +
      std::to_string(v.stride));
  }
  for (int a = 0; a < 3; ++a)
  {
    if (v.dims[a] < 1)
    {
      throw std::invalid_argument("mcvol: the pre-classified volume has an empty extent (" + axisText(a) + " is " +
        std::to_string(v.dims[a]) + ")");
    }
    if (!(v.spacing[a] > 0.0) || !std::isfinite(v.spacing[a]) || !std::isfinite(v.origin[a]))
    {
      throw std::invalid_argument("mcvol: the pre-classified volume's spacing must be positive and finite and its "
                                  "origin finite (axis " +
        axisText(a) + ")");
    }
  }
}

size_t voxelsOf(const int d[3])
{
  return size_t(d[0]) * size_t(d[1]) * size_t(d[2]);
}

/// Packs the view into 4 floats per voxel, rejecting values a filter must not
/// spread (negative, NaN or infinite sigma; NaN, infinite or negative colour).
std::vector<float> packChecked(const ClassifiedVolumeView& v)
{
  const int64_t n = int64_t(voxelsOf(v.dims));
  std::vector<float> out(size_t(n) * 4);
  int64_t bad = -1;
#pragma omp parallel for schedule(static)
  for (int64_t i = 0; i < n; ++i)
  {
    const float* x = v.voxels + i * v.stride;
    bool ok = x[0] >= 0.f && std::isfinite(x[0]);
    for (int c = 1; c < 4; ++c)
    {
      ok = ok && x[c] >= 0.f && std::isfinite(x[c]);
      out[size_t(i) * 4 + size_t(c)] = x[c];
    }
    out[size_t(i) * 4] = x[0];
    if (!ok)
    {
#pragma omp critical(mcvol_pyramid_bad)
      bad = bad < 0 || i < bad ? i : bad;
    }
  }
  if (bad >= 0)
  {
    const float* x = v.voxels + bad * v.stride;
    throw std::invalid_argument("mcvol: pre-classified voxel " + std::to_string(bad) + " is (" + std::to_string(x[0]) +
      ", " + std::to_string(x[1]) + ", " + std::to_string(x[2]) + ", " + std::to_string(x[3]) +
      "); a pyramid needs finite sigma >= 0 and finite extinction-weighted colours >= 0");
  }
  return out;
}

/// One separable pass along `axis` over packed 4-float voxels: the axis is
/// halved (ceil) and filtered with clamped taps; an axis of 1 is copied.
std::vector<float> filterAxis(const std::vector<float>& in, const int din[3], int axis, const FilterTaps& taps,
  int dout[3])
{
  std::copy(din, din + 3, dout);
  const int n = din[axis];
  if (n == 1)
  {
    return in;
  }
  dout[axis] = (n + 1) / 2;
  std::vector<float> out(voxelsOf(dout) * 4);
  const int64_t stride[3] = { 1, din[0], int64_t(din[0]) * din[1] };
  const int64_t total = int64_t(voxelsOf(dout));
#pragma omp parallel for schedule(static)
  for (int64_t o = 0; o < total; ++o)
  {
    const int idx[3] = { int(o % dout[0]), int((o / dout[0]) % dout[1]), int(o / (int64_t(dout[0]) * dout[1])) };
    int64_t base = 0;
    for (int a = 0; a < 3; ++a)
    {
      if (a != axis)
      {
        base += int64_t(idx[a]) * stride[a];
      }
    }
    double acc[4] = { 0, 0, 0, 0 };
    for (int k = 0; k < taps.count; ++k)
    {
      int j = 2 * idx[axis] + taps.first + k;
      j = j < 0 ? 0 : (j > n - 1 ? n - 1 : j); // clamp to the edge voxel
      const float* x = in.data() + (base + int64_t(j) * stride[axis]) * 4;
      for (int c = 0; c < 4; ++c)
      {
        acc[c] += taps.w[k] * double(x[c]);
      }
    }
    float* y = out.data() + size_t(o) * 4;
    for (int c = 0; c < 4; ++c)
    {
      y[c] = float(acc[c]);
    }
  }
  return out;
}

/// Separable filtering of packed voxels over all three axes.
std::vector<float> filter3(std::vector<float> data, const int dims[3], DownsampleFilter filter, int out[3])
{
  const FilterTaps taps = filterTaps(filter);
  int d[3] = { dims[0], dims[1], dims[2] };
  for (int axis = 0; axis < 3; ++axis)
  {
    int next[3];
    data = filterAxis(data, d, axis, taps, next);
    std::copy(next, next + 3, d);
  }
  std::copy(d, d + 3, out);
  return data;
}

/// The coarser level's geometry: spacing doubled and origin moved by half a
/// finer spacing on every axis that was halved.
void coarseGeometry(const ClassifiedVolumeView& fine, PyramidLevel& out)
{
  for (int a = 0; a < 3; ++a)
  {
    if (fine.dims[a] > 1)
    {
      out.spacing[a] = 2.0 * fine.spacing[a];
      out.origin[a] = fine.origin[a] + 0.5 * fine.spacing[a];
    }
    else
    {
      out.spacing[a] = fine.spacing[a];
      out.origin[a] = fine.origin[a];
    }
  }
}

void checkLevels(const ClassifiedVolumeView& v, int levels)
{
  const int most = maxPyramidLevels(v.dims);
  if (levels < 0 || levels > most)
  {
    throw std::invalid_argument("mcvol: " + std::to_string(levels) + " pyramid levels asked for; a volume of " +
      std::to_string(v.dims[0]) + "x" + std::to_string(v.dims[1]) + "x" + std::to_string(v.dims[2]) + " has 0 to " +
      std::to_string(most) + " above level 0");
  }
}
} // namespace

const char* toString(DownsampleFilter f)
{
  switch (f)
  {
    case DownsampleFilter::Box2:
      return "box2";
    case DownsampleFilter::Box4:
      return "box4";
    case DownsampleFilter::BSpline:
      return "bspline";
  }
  return "unknown";
}

FilterTaps filterTaps(DownsampleFilter f)
{
  FilterTaps t;
  double raw[4] = { 0, 0, 0, 0 };
  switch (f)
  {
    case DownsampleFilter::Box2:
      t.count = 2;
      t.first = 0;
      raw[0] = raw[1] = 1;
      break;
    case DownsampleFilter::Box4:
      t.count = 4;
      t.first = -1;
      raw[0] = raw[1] = raw[2] = raw[3] = 1;
      break;
    case DownsampleFilter::BSpline:
      t.count = 4;
      t.first = -1;
      raw[0] = 13;
      raw[1] = 19;
      raw[2] = 19;
      raw[3] = 13;
      break;
    default:
      throw std::invalid_argument("mcvol: unknown downsampling filter (" + std::to_string(int(f)) + ")");
  }
  double sum = 0;
  for (int k = 0; k < t.count; ++k)
  {
    sum += raw[k];
  }
  for (int k = 0; k < t.count; ++k)
  {
    t.w[k] = raw[k] / sum;
  }
  return t;
}

ClassifiedVolumeView PyramidLevel::view() const
{
  ClassifiedVolumeView v;
  v.voxels = this->voxels.data();
  v.stride = 4;
  for (int a = 0; a < 3; ++a)
  {
    v.dims[a] = this->dims[a];
    v.spacing[a] = this->spacing[a];
    v.origin[a] = this->origin[a];
  }
  return v;
}

ChannelSource PyramidLevel::source() const
{
  ChannelSource s;
  s.data = this->voxels.data();
  s.type = ScalarType::Float32;
  s.stride = 4;
  s.format = ChannelFormat::Extinction;
  return s;
}

int maxPyramidLevels(const int dims[3])
{
  int levels = 0;
  int d = std::max(dims[0], std::max(dims[1], dims[2]));
  while (d > 1)
  {
    d = (d + 1) / 2;
    ++levels;
  }
  return levels;
}

PyramidLevel downsampleExtinction(const ClassifiedVolumeView& fine, DownsampleFilter filter)
{
  checkView(fine);
  (void)filterTaps(filter); // rejects an unknown filter before any work
  PyramidLevel out;
  out.level = 1; // relative to `fine`; the builders number their levels
  out.voxels = filter3(packChecked(fine), fine.dims, filter, out.dims);
  coarseGeometry(fine, out);
  return out;
}

std::vector<PyramidLevel> buildExtinctionPyramid(
  const ClassifiedVolumeView& level0, int levels, DownsampleFilter filter)
{
  checkView(level0);
  checkLevels(level0, levels);
  std::vector<PyramidLevel> out;
  out.reserve(size_t(levels));
  for (int l = 1; l <= levels; ++l)
  {
    PyramidLevel next = downsampleExtinction(l == 1 ? level0 : out.back().view(), filter);
    next.level = l;
    out.push_back(std::move(next));
  }
  return out;
}

PyramidLevel downsampleOpacity(const ClassifiedVolumeView& fine, double step, DownsampleFilter filter)
{
  checkView(fine);
  (void)filterTaps(filter);
  if (!(step > 0.0) || !std::isfinite(step))
  {
    throw std::invalid_argument("mcvol: the opacity baseline's step must be positive and finite");
  }
  std::vector<float> data = packChecked(fine);
  // To opacity for the step and opacity-weighted colour (Eq. 14-15). The
  // first value holds the transparency 1 - alpha instead of alpha: the
  // filter's weights sum to 1, so it averages to 1 - (averaged alpha)
  // exactly, and a float keeps its relative precision where alpha is close
  // to 1 (long steps at coarse levels).
  const int64_t n = int64_t(voxelsOf(fine.dims));
#pragma omp parallel for schedule(static)
  for (int64_t i = 0; i < n; ++i)
  {
    float* x = data.data() + size_t(i) * 4;
    const double s = x[0];
    const double a = -std::expm1(-s * step);
    for (int c = 1; c < 4; ++c)
    {
      x[c] = s > 0.0 ? float(double(x[c]) / s * a) : 0.f;
    }
    x[0] = float(std::exp(-s * step));
  }
  PyramidLevel out;
  out.level = 1; // relative to `fine`; the builders number their levels
  out.voxels = filter3(std::move(data), fine.dims, filter, out.dims);
  coarseGeometry(fine, out);
  // Back to extinction: the averaged opacity is the opacity over `step`.
  const int64_t m = int64_t(out.numVoxels());
#pragma omp parallel for schedule(static)
  for (int64_t i = 0; i < m; ++i)
  {
    float* x = out.voxels.data() + size_t(i) * 4;
    const double T = std::min(std::max(double(x[0]), kMinTransparency), 1.0);
    const double a = 1.0 - T;
    const double sigma = -std::log(T) / step;
    for (int c = 1; c < 4; ++c)
    {
      x[c] = a > 0.0 ? float(std::min(double(x[c]) / a, 1.0) * sigma) : 0.f;
    }
    x[0] = float(sigma);
  }
  return out;
}

std::vector<PyramidLevel> buildOpacityPyramid(
  const ClassifiedVolumeView& level0, int levels, double step0, DownsampleFilter filter)
{
  checkView(level0);
  checkLevels(level0, levels);
  std::vector<PyramidLevel> out;
  out.reserve(size_t(levels));
  double step = step0;
  for (int l = 1; l <= levels; ++l)
  {
    PyramidLevel next = downsampleOpacity(l == 1 ? level0 : out.back().view(), step, filter);
    next.level = l;
    out.push_back(std::move(next));
    step *= 2.0;
  }
  return out;
}

void classifyScalars(const ChannelSource& src, const int dims[3], const TransferFunctionDesc& tf, float* out,
  int64_t outStride, bool accumulate)
{
  if (!src.data || !out)
  {
    throw std::invalid_argument("mcvol: classifyScalars needs input data and an output array");
  }
  if (src.format != ChannelFormat::Scalar)
  {
    throw std::invalid_argument("mcvol: classifyScalars classifies scalar channels; this one is already classified");
  }
  if (src.stride < 1 || outStride < 4)
  {
    throw std::invalid_argument("mcvol: classifyScalars needs an input stride >= 1 and an output stride >= 4");
  }
  if (int(src.type) < int(ScalarType::UInt8) || int(src.type) > int(ScalarType::Float64))
  {
    throw std::invalid_argument("mcvol: classifyScalars: unknown scalar type");
  }
  for (int a = 0; a < 3; ++a)
  {
    if (dims[a] < 1)
    {
      throw std::invalid_argument("mcvol: classifyScalars: the volume has an empty extent");
    }
  }
  const size_t K = tf.opacity.size();
  if (K < 2 || tf.rgb.size() != 3 * K || !(tf.unitDistance > 0.f) || !std::isfinite(tf.unitDistance) ||
    !std::isfinite(tf.scalarMin) || !std::isfinite(tf.scalarMax) || !(tf.scalarMax >= tf.scalarMin))
  {
    throw std::invalid_argument("mcvol: classifyScalars: the transfer function needs >= 2 entries, 3 colour values "
                                "per entry, a positive unit distance and a finite range");
  }
  // The table as Scene builds it: (r, g, b, extinction) per texel.
  std::vector<float> table(K * 4);
  for (size_t i = 0; i < K; ++i)
  {
    if (!std::isfinite(tf.opacity[i]) || !std::isfinite(tf.rgb[3 * i]) || !std::isfinite(tf.rgb[3 * i + 1]) ||
      !std::isfinite(tf.rgb[3 * i + 2]))
    {
      throw std::invalid_argument("mcvol: classifyScalars: the transfer function has a non-finite entry");
    }
    for (int c = 0; c < 3; ++c)
    {
      table[4 * i + size_t(c)] = std::min(std::max(tf.rgb[3 * i + size_t(c)], 0.f), 1.f);
    }
    table[4 * i + 3] = opacityToExtinction(tf.opacity[i], tf.unitDistance);
  }
  double width = tf.scalarMax - tf.scalarMin;
  const double minWidth = std::max(1e-30, 1e-6 * std::fabs(tf.scalarMin - src.offset));
  if (!(width >= minWidth))
  {
    width = minWidth;
  }
  const double scale = double(K - 1) / width;
  const int64_t n = int64_t(voxelsOf(dims));
  visitScalarType(src.type,
    [&](auto tag)
    {
      using T = typename decltype(tag)::type;
      const T* in = static_cast<const T*>(src.data);
#pragma omp parallel for schedule(static)
      for (int64_t v = 0; v < n; ++v)
      {
        const double s = double(in[v * src.stride]);
        float* y = out + v * outStride;
        float r[4] = { 0.f, 0.f, 0.f, 0.f };
        double x = (s - tf.scalarMin) * scale;
        if (x == x)
        {
          x = std::min(std::max(x, 0.0), double(K - 1));
          size_t i = size_t(x);
          i = i > K - 2 ? K - 2 : i;
          const float f = float(x - double(i));
          const float* a = table.data() + i * 4;
          const float* b = a + 4;
          const float sigma = a[3] + f * (b[3] - a[3]);
          r[0] = sigma;
          for (int c = 0; c < 3; ++c)
          {
            r[c + 1] = sigma * (a[c] + f * (b[c] - a[c]));
          }
        }
        for (int c = 0; c < 4; ++c)
        {
          y[c] = accumulate ? y[c] + r[c] : r[c];
        }
      }
    });
}
} // namespace mcvol
