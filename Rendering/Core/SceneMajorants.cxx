// SPDX-License-Identifier: BSD-3-Clause
// Scene: per-channel majorant grids from the macrocell ranges and the
// transfer-function tables, and which channels they leave active.
#include "mcvol/Scene.h"

#include "mcvol/ray/Acceleration.h"

#include "SceneInternal.h"

#include <vector>

namespace mcvol
{
void Scene::rebuildMajorants(int channel)
{
  const GridView& g = this->View.grid;
  const TableView& tv = this->View.tables;
  const int N = this->NumChannels;
  const int K = tv.size;
  const int64_t cells = int64_t(g.dims[0]) * g.dims[1] * g.dims[2];
  const float* table = this->Tables.data() + size_t(channel) * K * 4;
  const float* ranges = this->Ranges.data();
  float* maj = this->Majorants.data();
  if (this->Channels[size_t(channel)].format == ChannelFormat::Extinction)
  {
    // Pre-classified: the ranges hold sigma itself (identity rule).
#pragma omp parallel for schedule(static) if (cells > 100000)
    for (int64_t c = 0; c < cells; ++c)
    {
      maj[c * N + channel] =
        classifiedCellMajorant(ranges[(c * N + channel) * 2 + 0], ranges[(c * N + channel) * 2 + 1]);
    }
    return;
  }
  // Range-maximum queries over the table's extinctions in O(1) per cell (a
  // sparse table): a cell's scalar range can cover most of the table, so a
  // per-cell loop over texels would make a rebuild cost cells x K.
  std::vector<float> sparse(size_t(sparseLevels(K)) * size_t(K), 0.f);
  buildSparseTable(table, K, sparse.data());
  const float* sp = sparse.data();
  // Threads only pay off on large grids; a small rebuild is sub-millisecond
  // on one core and would otherwise wait for busy threads to wake.
#pragma omp parallel for schedule(static) if (cells > 100000)
  for (int64_t c = 0; c < cells; ++c)
  {
    maj[c * N + channel] =
      cellMajorant(tv, channel, ranges[(c * N + channel) * 2 + 0], ranges[(c * N + channel) * 2 + 1], sp);
  }
}

namespace detail
{
int findActiveChannels(const float* majorants, int64_t cells, int numChannels, int* active)
{
  int numActive = 0;
  for (int n = 0; n < numChannels; ++n)
  {
    bool any = false;
    for (int64_t c = 0; c < cells && !any; ++c)
    {
      any = majorants[size_t(c) * numChannels + n] > 0.f;
    }
    if (any)
    {
      active[numActive++] = n;
    }
  }
  return numActive;
}
} // namespace detail
} // namespace mcvol
