// SPDX-License-Identifier: BSD-3-Clause
// Extinction-based pyramids of pre-classified volumes, the opacity-averaging
// baseline, and pre-classification of scalar channels (Kraus and Buerger,
// Sections 3.3 and 4).
#include "mcvol/Pyramid.h"

#ifdef _OPENMP
#include <omp.h>
#endif

#include <algorithm>
#include <cstdint>
#if defined(__linux__)
#include <sys/mman.h>
#endif
#include <array>
#include <cmath>
#include <deque>
#include <limits>
#include <memory>
#include <stdexcept>
#include <string>
#include <utility>

namespace mcvol
{
namespace
{
/**
 * Resize v to n values (zeros), asking the kernel to back its storage with
 * transparent huge pages where it allows them (Linux, THP mode "madvise").
 * A level is sampled at random positions by every ray: with 4 KiB pages
 * nearly every corner read of a large level also misses the TLB.
 */
template <typename T>
void resizeHuge(std::vector<T>& v, size_t n)
{
  v.clear();
  v.shrink_to_fit();
  v.reserve(n);
#if defined(__linux__) && defined(MADV_HUGEPAGE)
  constexpr uintptr_t kHuge = uintptr_t(2) << 20;
  const uintptr_t lo = (reinterpret_cast<uintptr_t>(v.data()) + kHuge - 1) & ~(kHuge - 1);
  const uintptr_t hi = (reinterpret_cast<uintptr_t>(v.data() + n)) & ~(kHuge - 1);
  if (hi > lo)
  {
    // Advice only: where it is refused the pages stay 4 KiB.
    (void)madvise(reinterpret_cast<void*>(lo), size_t(hi - lo), MADV_HUGEPAGE);
  }
#endif
  v.resize(n);
}
} // namespace

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
std::vector<float> filterAxis(
  const std::vector<float>& in, const int din[3], int axis, const FilterTaps& taps, int dout[3])
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
/// finer spacing on every axis that was halved; `fine`'s box as the bounds
/// (the builders of several levels put level 0's there).
void coarseGeometry(const ClassifiedVolumeView& fine, PyramidLevel& out)
{
  volumeBounds(fine.dims, fine.spacing, fine.origin, out.boundsLo, out.boundsHi);
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
/// Rejects values a filter must not spread in `n` packed voxels (as
/// packChecked does for a whole volume); `first` numbers them for the error.
void checkPacked(const float* x, int64_t n, int64_t first)
{
  int64_t bad = -1;
#pragma omp parallel for schedule(static)
  for (int64_t i = 0; i < n; ++i)
  {
    const float* v = x + i * 4;
    bool ok = true;
    for (int c = 0; c < 4; ++c)
    {
      ok = ok && v[c] >= 0.f && std::isfinite(v[c]);
    }
    if (!ok)
    {
#pragma omp critical(mcvol_pyramid_bad_slice)
      bad = bad < 0 || i < bad ? i : bad;
    }
  }
  if (bad >= 0)
  {
    const float* v = x + bad * 4;
    throw std::invalid_argument("mcvol: pre-classified voxel " + std::to_string(first + bad) + " is (" +
      std::to_string(v[0]) + ", " + std::to_string(v[1]) + ", " + std::to_string(v[2]) + ", " + std::to_string(v[3]) +
      "); a pyramid needs finite sigma >= 0 and finite extinction-weighted colours >= 0");
  }
}

/// Bytes held by the streaming stages now, and the most they held.
struct WorkMeter
{
  size_t now = 0;
  size_t peak = 0;
  void add(size_t bytes)
  {
    this->now += bytes;
    this->peak = std::max(this->peak, this->now);
  }
  void sub(size_t bytes) { this->now -= std::min(bytes, this->now); }
};

/**
 * One halving of a stream of z-slices: each slice pushed is filtered along x
 * and y (filterAxis, as filter3 does), kept while the z taps of a coarse
 * slice still need it, and each coarse slice of [first, end) is handed to
 * `emit` as soon as its last tap is in. Slices are numbered globally (the
 * whole volume's z), so that a stage can run over one z-range of the volume
 * (its clamped taps still see the whole volume's ends). The arithmetic is
 * filter3's: per axis the taps in order, accumulated in double and stored
 * as float.
 */
class SliceStage
{
public:
  using Emit = std::function<void(int c, const float* slice)>;

  SliceStage(const int inDims[3], const FilterTaps& taps, int first, int end, WorkMeter& meter, Emit emit)
    : Taps(taps)
    , Next(first)
    , End(end)
    , Meter(meter)
    , Out(std::move(emit))
  {
    std::copy(inDims, inDims + 3, this->In);
    for (int a = 0; a < 3; ++a)
    {
      this->Coarse[a] = this->In[a] > 1 ? (this->In[a] + 1) / 2 : 1;
    }
  }

  /// The finer slices [lo, hi) that coarse slices [first, end) read.
  static void inputRange(int n, const FilterTaps& taps, int first, int end, int& lo, int& hi)
  {
    if (n == 1)
    {
      lo = 0; // not halved: the one slice is the coarse one
      hi = 1;
      return;
    }
    lo = std::max(0, 2 * first + taps.first);
    hi = std::min(n, 2 * (end - 1) + taps.first + taps.count);
  }

  /// The finer slice z (global), in increasing order.
  void push(int z, const float* slice)
  {
    std::vector<float> fxy = this->filterXY(slice);
    this->Meter.add(fxy.size() * sizeof(float));
    if (this->In[2] == 1)
    {
      // An axis of 1 is not filtered: the xy-filtered slice is the level.
      this->Out(0, fxy.data());
      this->Meter.sub(fxy.size() * sizeof(float));
      return;
    }
    this->Ring.emplace_back(z, std::move(fxy));
    const int n = this->In[2];
    while (this->Next < this->End)
    {
      const int last = std::min(2 * this->Next + this->Taps.first + this->Taps.count - 1, n - 1);
      if (last > z)
      {
        break;
      }
      this->emitCoarse(this->Next);
      ++this->Next;
      // Slices below the next coarse slice's first tap are done with.
      const int keepFrom = std::min(2 * this->Next + this->Taps.first, n - 1);
      while (!this->Ring.empty() && this->Ring.front().first < keepFrom)
      {
        this->Meter.sub(this->Ring.front().second.size() * sizeof(float));
        this->Ring.pop_front();
      }
    }
  }

private:
  /// The slice filtered along x, stored as float, then along y: filterAxis
  /// on both axes (the same taps in the same order, accumulated in double),
  /// row by row and without its index arithmetic or copies.
  std::vector<float> filterXY(const float* in)
  {
    const int nx = this->In[0], ny = this->In[1];
    const int mx = this->Coarse[0], my = this->Coarse[1];
    const FilterTaps& t = this->Taps;
    std::vector<float> fx;
    const float* rows = in;
    if (nx > 1)
    {
      fx.resize(size_t(mx) * size_t(ny) * 4);
      this->Meter.add(fx.size() * sizeof(float));
      for (int j = 0; j < ny; ++j)
      {
        const float* row = in + size_t(j) * size_t(nx) * 4;
        float* dst = fx.data() + size_t(j) * size_t(mx) * 4;
        for (int i = 0; i < mx; ++i)
        {
          double acc[4] = { 0, 0, 0, 0 };
          for (int k = 0; k < t.count; ++k)
          {
            int q = 2 * i + t.first + k;
            q = q < 0 ? 0 : (q > nx - 1 ? nx - 1 : q); // clamp to the edge voxel
            const float* x = row + size_t(q) * 4;
            for (int c = 0; c < 4; ++c)
            {
              acc[c] += t.w[k] * double(x[c]);
            }
          }
          for (int c = 0; c < 4; ++c)
          {
            dst[size_t(i) * 4 + size_t(c)] = float(acc[c]);
          }
        }
      }
      rows = fx.data();
    }
    std::vector<float> out(size_t(mx) * size_t(my) * 4);
    if (ny == 1)
    {
      std::copy(rows, rows + out.size(), out.begin());
    }
    else
    {
      const size_t rowFloats = size_t(mx) * 4;
      for (int jj = 0; jj < my; ++jj)
      {
        const float* src[4] = { nullptr, nullptr, nullptr, nullptr };
        for (int k = 0; k < t.count; ++k)
        {
          int q = 2 * jj + t.first + k;
          q = q < 0 ? 0 : (q > ny - 1 ? ny - 1 : q);
          src[k] = rows + size_t(q) * rowFloats;
        }
        float* dst = out.data() + size_t(jj) * rowFloats;
        for (size_t v = 0; v < rowFloats; ++v)
        {
          double acc = 0.0;
          for (int k = 0; k < t.count; ++k)
          {
            acc += t.w[k] * double(src[k][v]);
          }
          dst[v] = float(acc);
        }
      }
    }
    this->Meter.sub(fx.size() * sizeof(float));
    return out;
  }

  const std::vector<float>& held(int j) const
  {
    for (const auto& entry : this->Ring)
    {
      if (entry.first == j)
      {
        return entry.second;
      }
    }
    throw std::logic_error("mcvol: streamed pyramid lost slice " + std::to_string(j));
  }

  void emitCoarse(int c)
  {
    const int n = this->In[2];
    const int64_t voxels = int64_t(this->Coarse[0]) * int64_t(this->Coarse[1]);
    const float* src[4] = { nullptr, nullptr, nullptr, nullptr };
    for (int k = 0; k < this->Taps.count; ++k)
    {
      int j = 2 * c + this->Taps.first + k;
      j = j < 0 ? 0 : (j > n - 1 ? n - 1 : j); // clamp to the edge slice
      src[k] = this->held(j).data();
    }
    std::vector<float> out(size_t(voxels) * 4);
    this->Meter.add(out.size() * sizeof(float));
    for (int64_t v = 0; v < voxels; ++v)
    {
      double acc[4] = { 0, 0, 0, 0 };
      for (int k = 0; k < this->Taps.count; ++k)
      {
        const float* x = src[k] + v * 4;
        for (int ch = 0; ch < 4; ++ch)
        {
          acc[ch] += this->Taps.w[k] * double(x[ch]);
        }
      }
      for (int ch = 0; ch < 4; ++ch)
      {
        out[size_t(v) * 4 + size_t(ch)] = float(acc[ch]);
      }
    }
    this->Out(c, out.data());
    this->Meter.sub(out.size() * sizeof(float));
  }

  FilterTaps Taps;
  int In[3] = { 1, 1, 1 };
  int Coarse[3] = { 1, 1, 1 };
  int Next = 0; // the next coarse slice to emit
  int End = 0;  // one past the last coarse slice to emit
  WorkMeter& Meter;
  Emit Out;
  std::deque<std::pair<int, std::vector<float>>> Ring;
};

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

void volumeBounds(const int dims[3], const double spacing[3], const double origin[3], double lo[3], double hi[3])
{
  for (int a = 0; a < 3; ++a)
  {
    if (dims[a] == 1)
    {
      lo[a] = origin[a] - 0.5 * spacing[a];
      hi[a] = origin[a] + 0.5 * spacing[a];
    }
    else
    {
      lo[a] = origin[a];
      hi[a] = origin[a] + double(dims[a] - 1) * spacing[a];
    }
  }
}

void PyramidLevel::indexBounds(double lo[3], double hi[3]) const
{
  for (int a = 0; a < 3; ++a)
  {
    if (std::isfinite(this->boundsLo[a]) && std::isfinite(this->boundsHi[a]))
    {
      lo[a] = (this->boundsLo[a] - this->origin[a]) / this->spacing[a];
      hi[a] = (this->boundsHi[a] - this->origin[a]) / this->spacing[a];
    }
    else
    {
      lo[a] = this->dims[a] == 1 ? -0.5 : 0.0;
      hi[a] = this->dims[a] == 1 ? 0.5 : double(this->dims[a] - 1);
    }
  }
}

ClassifiedVolumeView PyramidLevel::view() const
{
  if (this->halfPrecision())
  {
    throw std::logic_error("mcvol: a half-precision pyramid level has no float32 view");
  }
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
  if (this->halfPrecision())
  {
    s.data = this->halfVoxels.data();
    s.type = ScalarType::Float16;
    s.scale = this->halfScale;
  }
  else
  {
    s.data = this->voxels.data();
    s.type = ScalarType::Float32;
  }
  s.stride = 4;
  s.format = ChannelFormat::Extinction;
  return s;
}

void PyramidLevel::toHalfPrecision()
{
  if (this->halfPrecision() || this->voxels.empty())
  {
    return;
  }
  float largest = 0.f;
  for (const float v : this->voxels)
  {
    if (std::isinf(v) || v < 0.f)
    {
      throw std::invalid_argument("mcvol: toHalfPrecision: a pyramid level holds an infinite or negative value");
    }
    largest = v > largest ? v : largest; // NaN compares false
  }
  // halfScale = 2^(e - 14) with largest = m 2^e, m in [0.5, 1): the largest
  // stored value is m 2^14, in [2^13, 2^14). Powers of two keep v / scale
  // and its product back exact.
  int e = 0;
  (void)std::frexp(largest > 0.f ? largest : 1.f, &e);
  const double scale = std::ldexp(1.0, e - 14);
  // In double: for a level of float subnormals 1 / scale exceeds float's
  // range (the scaled values never do: they are below 2^14).
  const double inverse = 1.0 / scale;
  std::vector<uint16_t> half;
  resizeHuge(half, this->voxels.size());
  const int64_t n = int64_t(half.size());
#pragma omp parallel for schedule(static)
  for (int64_t i = 0; i < n; ++i)
  {
    half[size_t(i)] = floatToHalf(float(double(this->voxels[size_t(i)]) * inverse));
  }
  this->halfScale = scale;
  this->halfVoxels = std::move(half);
  std::vector<float>().swap(this->voxels);
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
    volumeBounds(level0.dims, level0.spacing, level0.origin, next.boundsLo, next.boundsHi);
    out.push_back(std::move(next));
  }
  return out;
}

void levelDims(const int dims[3], int level, int out[3])
{
  for (int a = 0; a < 3; ++a)
  {
    int d = dims[a];
    for (int l = 0; l < level; ++l)
    {
      d = d > 1 ? (d + 1) / 2 : 1;
    }
    out[a] = d;
  }
}

size_t levelBytes(const int dims[3], int level, int channels, bool halfPrecision)
{
  int d[3];
  levelDims(dims, level, d);
  return voxelsOf(d) * 4 * (halfPrecision ? sizeof(uint16_t) : sizeof(float)) * size_t(std::max(channels, 0));
}

namespace
{
/// streamExtinctionLevel; `checkSlices` false skips the check of each slice
/// for the classifier's own slices, which are finite and >= 0 by
/// construction (classifyScalars checks its table).
PyramidLevel streamLevel(const int dims[3], const double spacing[3], const double origin[3], int level,
  DownsampleFilter filter, const std::function<void(int z, float* out)>& slice, size_t* peakWorkBytes, bool checkSlices)
{
  // The geometry and the level are checked, and the level's geometry made,
  // as pyramidLevelGeometry() does for a device build.
  PyramidLevel out = pyramidLevelGeometry(dims, spacing, origin, level);
  if (!slice)
  {
    throw std::invalid_argument("mcvol: a streamed pyramid needs a slice source");
  }
  const FilterTaps taps = filterTaps(filter);
  // Stage l (0-based) halves the grid of dims stageDims[l].
  std::vector<std::array<int, 3>> stageDims(static_cast<size_t>(level));
  int stage[3] = { dims[0], dims[1], dims[2] };
  for (int l = 0; l < level; ++l)
  {
    stageDims[size_t(l)] = { stage[0], stage[1], stage[2] };
    levelDims(stage, 1, stage);
  }
  resizeHuge(out.voxels, out.numVoxels() * 4);
  const size_t outSlice = size_t(out.dims[0]) * size_t(out.dims[1]) * 4;
  const size_t inSlice = size_t(dims[0]) * size_t(dims[1]) * 4;

  // The level's z-slices are split into chunks, each streamed by one thread
  // from the level-0 slices it needs (its taps' halo included, a few slices
  // per stage): one parallel region for the whole build rather than several
  // per slice, whose barriers cost far more than the work on a loaded
  // machine. Within a chunk everything is serial and in order.
  int threads = 1;
#ifdef _OPENMP
  threads = omp_get_max_threads();
#endif
  const int chunks = std::max(1, std::min(out.dims[2], 2 * threads));
  std::vector<size_t> chunkPeak(static_cast<size_t>(chunks), 0);
  std::vector<std::string> chunkError(static_cast<size_t>(chunks));
#pragma omp parallel for schedule(dynamic, 1) if (chunks > 1)
  for (int t = 0; t < chunks; ++t)
  {
    try
    {
      // Output slices [c0, c1) and, stage by stage back to level 0, the
      // slices they read.
      const int c0 = int(int64_t(out.dims[2]) * t / chunks);
      const int c1 = int(int64_t(out.dims[2]) * (t + 1) / chunks);
      if (c0 >= c1)
      {
        continue;
      }
      std::vector<std::array<int, 2>> range(size_t(level) + 1);
      range[size_t(level)] = { c0, c1 };
      for (int l = level - 1; l >= 0; --l)
      {
        int lo = 0, hi = 0;
        SliceStage::inputRange(stageDims[size_t(l)][2], taps, range[size_t(l) + 1][0], range[size_t(l) + 1][1], lo, hi);
        range[size_t(l)] = { lo, hi };
      }
      WorkMeter meter;
      std::vector<std::unique_ptr<SliceStage>> stages(static_cast<size_t>(level));
      for (int l = level - 1; l >= 0; --l)
      {
        SliceStage::Emit emit;
        if (l == level - 1)
        {
          emit = [&out, outSlice](int c, const float* s)
          { std::copy(s, s + outSlice, out.voxels.data() + size_t(c) * outSlice); };
        }
        else
        {
          emit = [&stages, l](int c, const float* s) { stages[size_t(l) + 1]->push(c, s); };
        }
        stages[size_t(l)].reset(new SliceStage(
          stageDims[size_t(l)].data(), taps, range[size_t(l) + 1][0], range[size_t(l) + 1][1], meter, std::move(emit)));
      }
      std::vector<float> buffer(inSlice);
      meter.add(buffer.size() * sizeof(float));
      for (int z = range[0][0]; z < range[0][1]; ++z)
      {
        std::fill(buffer.begin(), buffer.end(), 0.f); // what the slice leaves unwritten is empty
        slice(z, buffer.data());
        if (checkSlices)
        {
          checkPacked(buffer.data(), int64_t(dims[0]) * dims[1], int64_t(z) * dims[0] * dims[1]);
        }
        stages[0]->push(z, buffer.data());
      }
      chunkPeak[size_t(t)] = meter.peak;
    }
    catch (const std::exception& e)
    {
      chunkError[size_t(t)] = e.what();
    }
  }
  for (const std::string& e : chunkError)
  {
    if (!e.empty())
    {
      throw std::invalid_argument(e);
    }
  }
  if (peakWorkBytes)
  {
    // At most `threads` chunks run at once: the largest chunk's peak times
    // that (an upper bound of what the build held at any time).
    const size_t largest = *std::max_element(chunkPeak.begin(), chunkPeak.end());
    *peakWorkBytes = largest * size_t(std::min(threads, chunks));
  }
  return out;
}

} // namespace

std::vector<ClassificationTable> classificationTables(const ClassifyInput* inputs, int numInputs)
{
  if (!inputs || numInputs < 1)
  {
    throw std::invalid_argument("mcvol: classifyExtinctionLevel needs at least one channel");
  }
  for (int n = 0; n < numInputs; ++n)
  {
    if (!inputs[n].tf || !inputs[n].source.data)
    {
      throw std::invalid_argument(
        "mcvol: classifyExtinctionLevel: channel " + std::to_string(n) + " has no data or no transfer function");
    }
  }
  std::vector<ClassificationTable> tables;
  for (int n = 0; n < numInputs; ++n)
  {
    tables.push_back(classificationTable(inputs[n].source, *inputs[n].tf));
  }
  return tables;
}

PyramidLevel pyramidLevelGeometry(const int dims[3], const double spacing[3], const double origin[3], int level)
{
  // streamLevel's checks and geometry.
  static const float kNoVoxels[4] = { 0, 0, 0, 0 };
  ClassifiedVolumeView g;
  g.voxels = kNoVoxels;
  for (int a = 0; a < 3; ++a)
  {
    g.dims[a] = dims[a];
    g.spacing[a] = spacing[a];
    g.origin[a] = origin[a];
  }
  checkView(g);
  if (level < 1 || level > maxPyramidLevels(dims))
  {
    throw std::invalid_argument("mcvol: level " + std::to_string(level) + " asked of a streamed pyramid; a volume of " +
      std::to_string(dims[0]) + "x" + std::to_string(dims[1]) + "x" + std::to_string(dims[2]) + " has levels 1 to " +
      std::to_string(maxPyramidLevels(dims)));
  }
  PyramidLevel out;
  out.level = level;
  for (int l = 0; l < level; ++l)
  {
    PyramidLevel next;
    coarseGeometry(g, next);
    levelDims(g.dims, 1, next.dims);
    std::copy(next.dims, next.dims + 3, g.dims);
    std::copy(next.spacing, next.spacing + 3, g.spacing);
    std::copy(next.origin, next.origin + 3, g.origin);
  }
  std::copy(g.dims, g.dims + 3, out.dims);
  std::copy(g.spacing, g.spacing + 3, out.spacing);
  std::copy(g.origin, g.origin + 3, out.origin);
  volumeBounds(dims, spacing, origin, out.boundsLo, out.boundsHi);
  return out;
}

PyramidLevel streamExtinctionLevel(const int dims[3], const double spacing[3], const double origin[3], int level,
  DownsampleFilter filter, const std::function<void(int z, float* out)>& slice, size_t* peakWorkBytes)
{
  return streamLevel(dims, spacing, origin, level, filter, slice, peakWorkBytes, true);
}

/// Checks `src` and `tf` and tabulates `tf` (the table as Scene builds it).
ClassificationTable classificationTable(const ChannelSource& src, const TransferFunctionDesc& tf)
{
  if (src.format != ChannelFormat::Scalar)
  {
    throw std::invalid_argument("mcvol: classifyScalars classifies scalar channels; this one is already classified");
  }
  if (src.stride < 1)
  {
    throw std::invalid_argument("mcvol: classifyScalars needs an input stride >= 1 and an output stride >= 4");
  }
  if (int(src.type) < int(ScalarType::UInt8) || int(src.type) > int(ScalarType::Float64))
  {
    throw std::invalid_argument("mcvol: classifyScalars: unknown scalar type");
  }
  const size_t K = tf.opacity.size();
  if (K < 2 || tf.rgb.size() != 3 * K || !(tf.unitDistance > 0.f) || !std::isfinite(tf.unitDistance) ||
    !std::isfinite(tf.scalarMin) || !std::isfinite(tf.scalarMax) || !(tf.scalarMax >= tf.scalarMin))
  {
    throw std::invalid_argument("mcvol: classifyScalars: the transfer function needs >= 2 entries, 3 colour values "
                                "per entry, a positive unit distance and a finite range");
  }
  ClassificationTable t;
  t.K = K;
  t.texels.resize(K * 4);
  for (size_t i = 0; i < K; ++i)
  {
    if (!std::isfinite(tf.opacity[i]) || !std::isfinite(tf.rgb[3 * i]) || !std::isfinite(tf.rgb[3 * i + 1]) ||
      !std::isfinite(tf.rgb[3 * i + 2]))
    {
      throw std::invalid_argument("mcvol: classifyScalars: the transfer function has a non-finite entry");
    }
    for (int c = 0; c < 3; ++c)
    {
      t.texels[4 * i + size_t(c)] = std::min(std::max(tf.rgb[3 * i + size_t(c)], 0.f), 1.f);
    }
    t.texels[4 * i + 3] = opacityToExtinction(tf.opacity[i], tf.unitDistance);
  }
  double width = tf.scalarMax - tf.scalarMin;
  const double minWidth = std::max(1e-30, 1e-6 * std::fabs(tf.scalarMin - src.offset));
  if (!(width >= minWidth))
  {
    width = minWidth;
  }
  t.scalarMin = tf.scalarMin;
  t.scale = double(K - 1) / width;
  return t;
}

namespace
{
/// Voxels [first, first + count) of `src` through `t` into out[v * outStride]
/// (v counted from `first`), serially: classifyScalars' loop body.
template <class T>
void classifyRangeOf(
  const ClassificationTable& t, const T* in, int64_t stride, int64_t count, float* out, int64_t outStride, bool accumulate)
{
  const size_t K = t.K;
  for (int64_t v = 0; v < count; ++v)
  {
    const double s = double(in[v * stride]);
    float* y = out + v * outStride;
    float r[4] = { 0.f, 0.f, 0.f, 0.f };
    double x = (s - t.scalarMin) * t.scale;
    if (x == x)
    {
      x = std::min(std::max(x, 0.0), double(K - 1));
      size_t i = size_t(x);
      i = i > K - 2 ? K - 2 : i;
      const float f = float(x - double(i));
      const float* a = t.texels.data() + i * 4;
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
}

void classifyRange(const ClassificationTable& t, const ChannelSource& src, int64_t first, int64_t count, float* out,
  int64_t outStride, bool accumulate)
{
  visitScalarType(src.type,
    [&](auto tag)
    {
      using T = typename decltype(tag)::type;
      const T* in = static_cast<const T*>(src.data) + first * src.stride;
      classifyRangeOf(t, in, src.stride, count, out, outStride, accumulate);
    });
}
} // namespace

PyramidLevel classifyExtinctionLevel(const ClassifyInput* inputs, int numInputs, const int dims[3],
  const double spacing[3], const double origin[3], int level, DownsampleFilter filter, size_t* peakWorkBytes)
{
  // The tables once, then every slice block by block: all channels of a
  // block are added while it is in cache (a pass per channel over a whole
  // slice would stream it through memory once per channel).
  const std::vector<ClassificationTable> tables = classificationTables(inputs, numInputs);
  const int64_t sliceVoxels = int64_t(dims[0]) * int64_t(dims[1]);
  auto classifySlice = [&](int z, float* out)
  {
    constexpr int64_t kBlock = 4096; // 64 KiB of output
    for (int64_t first = 0; first < sliceVoxels; first += kBlock)
    {
      const int64_t count = std::min(kBlock, sliceVoxels - first);
      for (int n = 0; n < numInputs; ++n)
      {
        classifyRange(
          tables[size_t(n)], inputs[n].source, int64_t(z) * sliceVoxels + first, count, out + first * 4, 4, n > 0);
      }
    }
  };
  return streamLevel(dims, spacing, origin, level, filter, classifySlice, peakWorkBytes, false);
}

int chooseLevelOfDetail(double pixelFootprintWorld, const double spacing[3], int levels)
{
  if (levels < 0)
  {
    throw std::invalid_argument("mcvol: chooseLevelOfDetail: levels must be >= 0, not " + std::to_string(levels));
  }
  if (!(pixelFootprintWorld >= 0.0))
  {
    throw std::invalid_argument(
      "mcvol: chooseLevelOfDetail: the pixel footprint must be >= 0 (got " + std::to_string(pixelFootprintWorld) + ")");
  }
  double finest = std::numeric_limits<double>::infinity();
  for (int a = 0; a < 3; ++a)
  {
    if (!(spacing[a] > 0.0) || !std::isfinite(spacing[a]))
    {
      throw std::invalid_argument("mcvol: chooseLevelOfDetail: spacing must be positive and finite (axis " +
        axisText(a) + " is " + std::to_string(spacing[a]) + ")");
    }
    finest = std::min(finest, spacing[a]);
  }
  if (std::isinf(pixelFootprintWorld))
  {
    return levels;
  }
  const double ratio = pixelFootprintWorld / finest;
  if (!(ratio >= 2.0))
  {
    return 0; // floor(log2(ratio)) <= 0
  }
  // floor(log2) by comparison, exact at powers of two (log2 of 2^k is k in
  // IEEE arithmetic, but a ratio one ulp below must not round up).
  int level = int(std::floor(std::log2(ratio)));
  while (level > 0 && std::ldexp(1.0, level) > ratio)
  {
    --level;
  }
  while (std::ldexp(1.0, level + 1) <= ratio)
  {
    ++level;
  }
  return std::min(level, levels);
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
    volumeBounds(level0.dims, level0.spacing, level0.origin, next.boundsLo, next.boundsHi);
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
  if (src.stride < 1 || outStride < 4)
  {
    throw std::invalid_argument("mcvol: classifyScalars needs an input stride >= 1 and an output stride >= 4");
  }
  for (int a = 0; a < 3; ++a)
  {
    if (dims[a] < 1)
    {
      throw std::invalid_argument("mcvol: classifyScalars: the volume has an empty extent");
    }
  }
  const ClassificationTable table = classificationTable(src, tf);
  const int64_t n = int64_t(voxelsOf(dims));
  // Blocks of voxels, one thread each (the per-voxel work is the same).
  constexpr int64_t kBlock = 4096;
  const int64_t blocks = (n + kBlock - 1) / kBlock;
#pragma omp parallel for schedule(static)
  for (int64_t blk = 0; blk < blocks; ++blk)
  {
    const int64_t first = blk * kBlock;
    const int64_t count = std::min(kBlock, n - first);
    classifyRange(table, src, first, count, out + first * outStride, outStride, accumulate);
  }
}

} // namespace mcvol
