// SPDX-License-Identifier: BSD-3-Clause
// Scene: the macrocell grid's layout and its per-channel scalar ranges.
#include "mcvol/Scene.h"

#include "mcvol/ray/Acceleration.h"

#include "SceneInternal.h"

#include <algorithm>
#include <chrono>
#include <limits>
#include <stdexcept>

namespace mcvol
{
namespace
{
/// A voxel as the per-ray code reads it (fetchVoxel): float, with a float64
/// channel's offset taken off first.
template <typename T>
float asSample(T v, double)
{
  return float(v);
}
float asSample(double v, double offset)
{
  return float(v - offset);
}

template <typename T>
void rangeOf(const T* data, int64_t stride, double offset, const int dims[3], const int lo[3], const int hi[3],
  float& mn, float& mx)
{
  for (int k = lo[2]; k <= hi[2]; ++k)
  {
    for (int j = lo[1]; j <= hi[1]; ++j)
    {
      const int64_t row = (int64_t(k) * dims[1] + j) * dims[0];
      for (int i = lo[0]; i <= hi[0]; ++i)
      {
        const float v = asSample(data[(row + i) * stride], offset);
        if (v == v) // NaN voxels are transparent: they do not widen the range
        {
          mn = v < mn ? v : mn;
          mx = v > mx ? v : mx;
        }
      }
    }
  }
}
/// Range of a pre-classified channel's sanitised sigma (classifiedVoxel), NaN
/// voxels skipped, as the per-ray code reads it.
void classifiedRangeOf(const ChannelSource& c, const int dims[3], const int lo[3], const int hi[3], float& mn, float& mx)
{
  for (int k = lo[2]; k <= hi[2]; ++k)
  {
    for (int j = lo[1]; j <= hi[1]; ++j)
    {
      const int64_t row = (int64_t(k) * dims[1] + j) * dims[0];
      for (int i = lo[0]; i <= hi[0]; ++i)
      {
        float x[4];
        if (classifiedVoxelAt(c.data, c.type, c.scale, c.stride, row + i, x))
        {
          mn = x[0] < mn ? x[0] : mn;
          mx = x[0] > mx ? x[0] : mx;
        }
      }
    }
  }
}
} // namespace

void Scene::setMacrocellSize(int voxels)
{
  if (voxels < 1)
  {
    throw std::invalid_argument("mcvol: the macrocell size must be at least 1 voxel");
  }
  if (voxels != this->MacrocellSize)
  {
    this->MacrocellSize = voxels;
    this->MacrocellsDirty = true;
  }
}

void Scene::layoutGrid()
{
  GridView& g = this->View.grid;
  VolumeView& v = this->View.volume;
  for (int a = 0; a < 3; ++a)
  {
    v.dims[a] = this->Dims[a];
    if (this->Dims[a] == 1)
    {
      // One voxel along this axis: give it one spacing of thickness so a
      // single slice (or a single voxel) is visible rather than zero-width.
      v.boxLo[a] = -0.5f;
      v.boxHi[a] = 0.5f;
      g.dims[a] = 1;
      g.lo[a] = -0.5f;
      g.cellSize[a] = 1.f;
    }
    else
    {
      v.boxLo[a] = 0.f;
      v.boxHi[a] = float(this->Dims[a] - 1);
      const int cells = (this->Dims[a] - 1 + this->MacrocellSize - 1) / this->MacrocellSize;
      g.dims[a] = std::max(1, cells);
      g.lo[a] = 0.f;
      g.cellSize[a] = float(this->MacrocellSize);
    }
    if (this->HasIndexBounds)
    {
      v.boxLo[a] = float(this->IndexBoundsLo[a]);
      v.boxHi[a] = float(this->IndexBoundsHi[a]);
    }
    g.invCellSize[a] = 1.f / g.cellSize[a];
  }
  v.numChannels = this->NumChannels;
  for (int n = 0; n < this->NumChannels; ++n)
  {
    v.channels[n].data = this->Channels[n].data;
    v.channels[n].stride = this->Channels[n].stride;
    // A float16 pre-classified channel's scale travels in the view's offset
    // (ChannelView::offset), read by fetchClassified() on the host.
    v.channels[n].offset = this->Channels[n].type == ScalarType::Float16 ? this->Channels[n].scale
                                                                          : this->Channels[n].offset;
    v.channels[n].type = this->Channels[n].type;
    v.channels[n].format = this->Channels[n].format;
  }
  g.numChannels = this->NumChannels;
}

void Scene::rebuildMacrocells()
{
  const auto t0 = std::chrono::steady_clock::now();
  this->layoutGrid();
  const GridView& g = this->View.grid;
  const int N = this->NumChannels;
  const int64_t cells = int64_t(g.dims[0]) * g.dims[1] * g.dims[2];
  this->Ranges.assign(size_t(cells) * N * 2, 0.f);
  const int M = this->MacrocellSize;
  const int* D = this->Dims;
  float* ranges = this->Ranges.data();
  const ChannelSource* ch = this->Channels.data();
  const int gd0 = g.dims[0], gd1 = g.dims[1];
  const int apron = footprintApron(this->View.volume.cubic);
#pragma omp parallel for schedule(dynamic, 4)
  for (int64_t c = 0; c < cells; ++c)
  {
    const int cell[3] = { int(c % gd0), int((c / gd0) % gd1), int(c / (int64_t(gd0) * gd1)) };
    int lo[3];
    int hi[3];
    cellVoxelBounds(D, M, cell, apron, lo, hi);
    for (int n = 0; n < N; ++n)
    {
      float mn = std::numeric_limits<float>::infinity();
      float mx = -std::numeric_limits<float>::infinity();
      if (ch[n].format == ChannelFormat::Extinction)
      {
        classifiedRangeOf(ch[n], D, lo, hi, mn, mx);
      }
      else
      {
        visitScalarType(ch[n].type,
        [&](auto tag)
        {
          using T = typename decltype(tag)::type;
          rangeOf(static_cast<const T*>(ch[n].data), ch[n].stride, ch[n].offset, D, lo, hi, mn, mx);
        });
      }
      ranges[(c * N + n) * 2 + 0] = mn;
      ranges[(c * N + n) * 2 + 1] = mx;
    }
  }
  this->Majorants.assign(size_t(cells) * N, 0.f);
  this->LastMacrocellSeconds = detail::secondsSince(t0);
  ++this->DataVersion;
}
} // namespace mcvol
