// SPDX-License-Identifier: BSD-3-Clause

#include "EquivalentKernel.h"

#include <algorithm>
#include <cmath>
#include <cstdint>

namespace mcvolbench
{
std::vector<double> equivalentKernel(mcvol::DownsampleFilter f, int level)
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

double checkKernel(mcvol::DownsampleFilter f, int level)
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
} // namespace mcvolbench
