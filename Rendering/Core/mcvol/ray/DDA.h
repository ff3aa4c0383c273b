// SPDX-License-Identifier: BSD-3-Clause
#pragma once

#include "mcvol/ray/SceneView.h"

#include <cfloat>
#include <cmath>
#include <cstdint>

namespace mcvol
{
/**
 * Clips a ray to an axis-aligned box; returns false if it misses. Handles
 * direction components that are exactly zero (axis-parallel rays) without
 * dividing by zero: such a ray is inside the slab or misses it entirely.
 */
MCVOL_HOT bool intersectBox(Vec3f lo, Vec3f hi, Vec3f o, Vec3f d, float& t0, float& t1)
{
  for (int a = 0; a < 3; ++a)
  {
    if (!(o[a] == o[a]) || !(d[a] == d[a]))
    {
      return false; // NaN: no ray (it would pass every comparison below)
    }
    if (d[a] == 0.f)
    {
      if (o[a] < lo[a] || o[a] > hi[a])
      {
        return false;
      }
      continue;
    }
    const float inv = 1.f / d[a];
    float ta = (lo[a] - o[a]) * inv;
    float tb = (hi[a] - o[a]) * inv;
    if (ta > tb)
    {
      const float tmp = ta;
      ta = tb;
      tb = tmp;
    }
    t0 = ta > t0 ? ta : t0;
    t1 = tb < t1 ? tb : t1;
  }
  return t0 < t1;
}

/**
 * 3D DDA (Amanatides and Woo) over the macrocell grid. It yields the cells a
 * ray crosses as segments [t0, t1] of the ray parameter, in order, covering
 * [tmin, tmax] without gaps. Crossing distances are recomputed from the cell
 * boundary at each step (not accumulated), so long traversals do not drift,
 * and a zero direction component never produces a step along that axis.
 * The outermost cells reach past the grid (a face of the grid is never
 * crossed), so the segments cover [tmin, tmax] also where the ray's box
 * reaches past the grid: a level of detail clipped to level 0's box
 * (Scene::setIndexBounds). (MDWTracker sets t_near.x twice instead of t_far.x; axis-parallel rays are
 * tested against brute-force walking in DDA_test.)
 */
struct DDA
{
  int cell[3];
  int step[3];
  float tNext[3];
  float t0 = 0.f; ///< entry of the current cell
  float t1 = 0.f; ///< exit of the current cell (or tEnd)
  float tEnd = 0.f;
  bool done = true;

  MCVOL_HOT void init(const GridView& g, Vec3f o, Vec3f d, float tmin, float tmax)
  {
    this->O = o;
    this->tEnd = tmax;
    this->t0 = tmin;
    this->done = !(tmin < tmax);
    const Vec3f p = o + d * tmin;
    this->Dims[0] = g.dims[0];
    this->Dims[1] = g.dims[1];
    this->Dims[2] = g.dims[2];
    this->initAxis<0>(g, p, d, tmin);
    this->initAxis<1>(g, p, d, tmin);
    this->initAxis<2>(g, p, d, tmin);
    this->t1 = minf(minf(minf(this->tNext[0], this->tNext[1]), this->tNext[2]), this->tEnd);
  }

  /// 64-bit: a fine grid over a large volume can hold more than 2^31 cells.
  MCVOL_HOT int64_t cellIndex() const
  {
    return this->cell[0] + int64_t(this->Dims[0]) * (this->cell[1] + int64_t(this->Dims[1]) * this->cell[2]);
  }

  /// Moves to the next cell; returns false when the ray has left the grid or
  /// passed tEnd.
  MCVOL_HOT bool next()
  {
    if (this->t1 >= this->tEnd)
    {
      this->done = true;
      return false;
    }
    // The axis of the nearest crossing, the first of equal ones.
    const bool y = this->tNext[1] < this->tNext[0];
    if (this->tNext[2] < (y ? this->tNext[1] : this->tNext[0]))
    {
      return this->advance<2>();
    }
    return y ? this->advance<1>() : this->advance<0>();
  }

  /// Stops the traversal (a collision was accepted).
  MCVOL_HOT void stop() { this->done = true; }

private:
  // Every member is indexed by a constant (the axis is a template argument):
  // an index known only at run time keeps the whole traversal state in
  // local memory on the GPU, a load per access in the tracking loop.
  template <int A>
  MCVOL_HOT void initAxis(const GridView& g, Vec3f p, Vec3f d, float tmin)
  {
    const float x = (p[A] - g.lo[A]) * g.invCellSize[A];
    // Compared before the conversion: a float beyond int's range (a ray
    // starting far outside a fine grid) must not be converted.
    int c = x >= 0.f ? (x < float(g.dims[A]) ? int(x) : g.dims[A] - 1) : -1;
    c = clampi(c, 0, g.dims[A] - 1);
    this->cell[A] = c;
    this->Lo[A] = g.lo[A];
    this->Cs[A] = g.cellSize[A];
    if (d[A] > 0.f)
    {
      this->step[A] = 1;
      this->InvD[A] = 1.f / d[A];
    }
    else if (d[A] < 0.f)
    {
      this->step[A] = -1;
      this->InvD[A] = 1.f / d[A];
    }
    else
    {
      this->step[A] = 0;
      this->InvD[A] = 0.f;
    }
    this->tNext[A] = this->crossing<A>(tmin);
  }

  /// One step along axis A (next()).
  template <int A>
  MCVOL_HOT bool advance()
  {
    this->cell[A] += this->step[A];
    if (this->cell[A] < 0 || this->cell[A] >= this->Dims[A])
    {
      this->done = true;
      return false;
    }
    this->t0 = this->t1;
    this->tNext[A] = this->crossing<A>(this->t0);
    this->t1 = minf(minf(minf(this->tNext[0], this->tNext[1]), this->tNext[2]), this->tEnd);
    return true;
  }

  template <int A>
  MCVOL_HOT float crossing(float tmin) const
  {
    const int beyond = this->cell[A] + this->step[A];
    if (this->step[A] == 0 || beyond < 0 || beyond >= this->Dims[A])
    {
      return FLT_MAX; // no step along a, or a face of the grid: the cell reaches tEnd
    }
    const int b = this->cell[A] + (this->step[A] > 0 ? 1 : 0);
    const float t = (this->Lo[A] + float(b) * this->Cs[A] - this->O[A]) * this->InvD[A];
    return t > tmin ? t : tmin;
  }

  Vec3f O;
  Vec3f Lo;
  Vec3f Cs;
  Vec3f InvD;
  int Dims[3];
};
} // namespace mcvol
