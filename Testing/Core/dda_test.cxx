// SPDX-License-Identifier: BSD-3-Clause
// The macrocell DDA (and intersectBox) against brute-force walking.
// Random grids (dims including 1, random anisotropic cell sizes, random
// offsets), random rays of several kinds; fixed seeds.
#include "TestUtil.h"

#include "mcvol/ray/DDA.h"

#include <cfloat>

using namespace mcvol;
using mcvol::test::TestRand;

namespace
{
struct Segment
{
  float t0, t1;
  int cell[3];
};

struct Grid
{
  GridView g;
  Vec3f boxLo, boxHi; ///< clip box (the grid's box or a box inside it)
};

Grid randomGrid(TestRand& r)
{
  Grid G;
  for (int a = 0; a < 3; ++a)
  {
    G.g.dims[a] = r.chance(0.25) ? 1 : r.integer(2, 9);
    G.g.cellSize[a] = float(r.uniform(0.2, 4.0));
    G.g.invCellSize[a] = 1.f / G.g.cellSize[a];
    G.g.lo[a] = float(r.uniform(-5.0, 5.0));
    G.boxLo[a] = G.g.lo[a];
    G.boxHi[a] = G.g.lo[a] + float(G.g.dims[a]) * G.g.cellSize[a];
  }
  if (r.chance(0.3))
  {
    // Like Scene: the volume box lies inside the macrocell grid.
    for (int a = 0; a < 3; ++a)
    {
      const float ext = G.boxHi[a] - G.boxLo[a];
      const float lo = G.boxLo[a] + float(r.uniform(0.0, 0.3)) * ext;
      const float hi = G.boxHi[a] - float(r.uniform(0.0, 0.3)) * ext;
      G.boxLo[a] = lo;
      G.boxHi[a] = hi;
    }
  }
  G.g.numChannels = 1;
  return G;
}

std::vector<Segment> walk(const GridView& g, Vec3f o, Vec3f d, float tmin, float tmax)
{
  DDA dda;
  dda.init(g, o, d, tmin, tmax);
  std::vector<Segment> segs;
  const int limit = g.dims[0] + g.dims[1] + g.dims[2] + 8;
  while (!dda.done && int(segs.size()) <= limit)
  {
    segs.push_back({ dda.t0, dda.t1, { dda.cell[0], dda.cell[1], dda.cell[2] } });
    EXPECT_EQ(dda.cellIndex(), int64_t(dda.cell[0] + g.dims[0] * (dda.cell[1] + g.dims[1] * dda.cell[2])));
    dda.next();
  }
  return segs;
}

/// Tolerance, in cells along axis a, for a point at parameter t: a relative
/// 1e-4 of the magnitudes involved in computing its position.
double cellTolerance(const GridView& g, Vec3f o, Vec3f d, double t, int a)
{
  return 1e-4 * (1.0 + (std::fabs(double(o[a]) - g.lo[a]) + std::fabs(t * d[a])) / g.cellSize[a]);
}

/// True if the point at parameter t lies in `cell` (or within tolerance of it).
bool pointInCell(const GridView& g, Vec3f o, Vec3f d, double t, const int cell[3], std::string* why)
{
  for (int a = 0; a < 3; ++a)
  {
    const double p = double(o[a]) + t * double(d[a]);
    const double x = (p - g.lo[a]) / g.cellSize[a];
    int bc = int(std::floor(x));
    bc = std::min(std::max(bc, 0), g.dims[a] - 1);
    if (bc == cell[a])
    {
      continue;
    }
    const double tol = cellTolerance(g, o, d, t, a);
    // Clamped ends of the grid count as inside the end cells.
    const double lo = cell[a] == 0 ? -1e30 : double(cell[a]);
    const double hi = cell[a] == g.dims[a] - 1 ? 1e30 : double(cell[a] + 1);
    if (x >= lo - tol && x <= hi + tol)
    {
      continue;
    }
    if (why)
    {
      *why = "axis " + std::to_string(a) + ": point at cell coordinate " + std::to_string(x) + ", DDA cell " +
        std::to_string(cell[a]);
    }
    return false;
  }
  return true;
}

enum class RayKind
{
  Outside,
  Inside,
  AxisParallel,
  Clipped
};

struct Stats
{
  int rays = 0;
  int hits = 0;
  int segments = 0;
};

/// Generates `count` rays of `kind` through random grids and checks the DDA.
void checkRays(RayKind kind, int count, uint64_t seed, Stats& st)
{
  TestRand r(seed);
  Grid G = randomGrid(r);
  for (int ray = 0; ray < count; ++ray)
  {
    if (ray % 16 == 0)
    {
      G = randomGrid(r);
    }
    const GridView& g = G.g;
    Vec3f center, ext;
    for (int a = 0; a < 3; ++a)
    {
      center[a] = 0.5f * (G.boxLo[a] + G.boxHi[a]);
      ext[a] = G.boxHi[a] - G.boxLo[a];
    }
    const float R = length(ext);
    Vec3f o, target, d;
    for (int a = 0; a < 3; ++a)
    {
      target[a] = G.boxLo[a] + float(r.uniform()) * ext[a];
    }
    if (kind == RayKind::Inside || kind == RayKind::AxisParallel)
    {
      for (int a = 0; a < 3; ++a)
      {
        o[a] = G.boxLo[a] + float(r.uniform()) * ext[a];
      }
      if (kind == RayKind::AxisParallel && r.chance(0.5))
      {
        // Start outside along one axis, so the ray enters through a face.
        const int a = r.integer(0, 2);
        o[a] =
          r.chance(0.5) ? G.boxLo[a] - float(r.uniform(0.1, 3.0)) * R : G.boxHi[a] + float(r.uniform(0.1, 3.0)) * R;
      }
    }
    else
    {
      double u[3], n2 = 0;
      for (double& x : u)
      {
        x = r.uniform(-1, 1);
        n2 += x * x;
      }
      const double s = R * r.uniform(0.6, 4.0) / std::sqrt(n2);
      o = Vec3f(center.x + float(u[0] * s), center.y + float(u[1] * s), center.z + float(u[2] * s));
    }
    d = target - o;
    if (kind == RayKind::AxisParallel)
    {
      // One or two zero components; an axis along which the origin was put
      // outside must keep its component, or the ray misses.
      int zeros = r.integer(1, 2);
      int keep = r.integer(0, 2);
      for (int a = 0; a < 3; ++a)
      {
        if (o[a] < G.boxLo[a] || o[a] > G.boxHi[a])
        {
          keep = a;
        }
      }
      for (int a = 0, z = 0; a < 3 && z < zeros; ++a)
      {
        const int ax = (keep + 1 + a) % 3;
        d[ax] = 0.f;
        ++z;
        // Sometimes exactly on a cell boundary or on a box face.
        const double pick = r.uniform();
        if (pick < 0.2 && g.dims[ax] > 1)
        {
          o[ax] = g.lo[ax] + float(r.integer(1, g.dims[ax] - 1)) * g.cellSize[ax];
          if (o[ax] < G.boxLo[ax] || o[ax] > G.boxHi[ax])
          {
            o[ax] = G.boxLo[ax];
          }
        }
        else if (pick < 0.3)
        {
          o[ax] = r.chance(0.5) ? G.boxLo[ax] : G.boxHi[ax];
        }
      }
      if (d[keep] == 0.f)
      {
        d[keep] = 1.f;
      }
    }
    // Direction of arbitrary length (index-space images of unit directions).
    const float len = length(d);
    if (!(len > 0.f))
    {
      continue;
    }
    d = d * (float(r.uniform(0.1, 10.0)) / len);
    ++st.rays;

    float t0 = 0.f, t1 = FLT_MAX;
    const bool hit = intersectBox(G.boxLo, G.boxHi, o, d, t0, t1);
    if (!hit)
    {
      // Brute force: no point of the ray lies clearly inside the box.
      for (int i = 0; i <= 200; ++i)
      {
        const double t = double(i) / 200.0 * 10.0 * R / length(d);
        bool inside = true;
        for (int a = 0; a < 3; ++a)
        {
          const double p = double(o[a]) + t * d[a];
          const double tol = 1e-4 * (1.0 + std::fabs(p) + ext[a]);
          inside = inside && p > G.boxLo[a] + tol && p < G.boxHi[a] - tol;
        }
        EXPECT_FALSE(inside) << "intersectBox missed a ray that enters the box (ray " << ray << ")";
        if (inside)
        {
          break;
        }
      }
      EXPECT_NE(kind, RayKind::Inside) << "a ray starting inside the box missed it";
      continue;
    }
    ++st.hits;
    EXPECT_GE(t0, 0.f);
    if (kind == RayKind::Inside)
    {
      EXPECT_EQ(t0, 0.f) << "a ray starting inside must start at t = 0";
    }
    if (kind == RayKind::Clipped)
    {
      t1 = t0 + float(r.uniform(0.0, 1.0)) * (t1 - t0);
      if (!(t1 > t0))
      {
        continue;
      }
    }
    // Entry and exit lie on or in the box.
    for (const float t : { t0, t1 })
    {
      for (int a = 0; a < 3; ++a)
      {
        const double p = double(o[a]) + double(t) * d[a];
        const double tol = 1e-4 * (1.0 + std::fabs(double(o[a])) + std::fabs(double(t) * d[a]));
        EXPECT_GE(p, G.boxLo[a] - tol);
        EXPECT_LE(p, G.boxHi[a] + tol);
      }
    }

    const std::vector<Segment> segs = walk(g, o, d, t0, t1);
    st.segments += int(segs.size());
    const std::string where = "ray " + std::to_string(ray) + " (seed " + std::to_string(seed) + ")";
    ASSERT_FALSE(segs.empty()) << where;
    ASSERT_LE(int(segs.size()), g.dims[0] + g.dims[1] + g.dims[2]) << where << ": DDA did not terminate in time";
    EXPECT_EQ(segs.front().t0, t0) << where;
    const double tScale = std::fabs(double(t1)) + 1e-30;
    EXPECT_NEAR(segs.back().t1, t1, 1e-4 * tScale) << where << ": segments do not reach tmax";
    for (size_t i = 0; i < segs.size(); ++i)
    {
      const Segment& s = segs[i];
      EXPECT_LE(s.t0, s.t1) << where << " segment " << i;
      EXPECT_LE(s.t1, t1) << where << " segment " << i << " passes tmax";
      for (int a = 0; a < 3; ++a)
      {
        EXPECT_GE(s.cell[a], 0) << where;
        EXPECT_LT(s.cell[a], g.dims[a]) << where;
      }
      if (i > 0)
      {
        const Segment& p = segs[i - 1];
        EXPECT_EQ(s.t0, p.t1) << where << ": gap or overlap before segment " << i;
        // Neighbouring cells: one step along one axis, in the ray's direction.
        int changed = 0;
        for (int a = 0; a < 3; ++a)
        {
          const int dc = s.cell[a] - p.cell[a];
          if (dc != 0)
          {
            ++changed;
            EXPECT_EQ(dc, d[a] > 0.f ? 1 : -1) << where << ": step against the direction on axis " << a;
          }
        }
        EXPECT_EQ(changed, 1) << where << " segment " << i;
      }
      if (s.t1 > s.t0)
      {
        std::string why;
        const double tm = 0.5 * (double(s.t0) + double(s.t1));
        EXPECT_TRUE(pointInCell(g, o, d, tm, s.cell, &why)) << where << " segment " << i << " midpoint: " << why;
      }
    }
    // Brute force: march in tiny steps, compute each point's cell directly,
    // and compare with the segment covering that parameter.
    const int steps = 1500;
    size_t k = 0;
    for (int i = 0; i <= steps; ++i)
    {
      const double t = double(t0) + (double(t1) - double(t0)) * double(i) / steps;
      while (k + 1 < segs.size() && double(segs[k + 1].t0) <= t)
      {
        ++k;
      }
      std::string why;
      if (!pointInCell(g, o, d, t, segs[k].cell, &why))
      {
        ADD_FAILURE() << where << ": brute-force point t = " << t << " not in segment " << k << "'s cell: " << why;
        break;
      }
    }
  }
}
} // namespace

TEST(DDA, RaysFromOutside)
{
  Stats s;
  checkRays(RayKind::Outside, 3000, 1, s);
  EXPECT_GT(s.hits, 2000);
}

TEST(DDA, RaysStartingInside)
{
  Stats s;
  checkRays(RayKind::Inside, 3000, 2, s);
  EXPECT_EQ(s.hits, s.rays);
}

TEST(DDA, AxisParallelRays)
{
  Stats s;
  checkRays(RayKind::AxisParallel, 4000, 3, s);
  EXPECT_GT(s.hits, 3000);
}

TEST(DDA, RaysClippedByTmax)
{
  Stats s;
  checkRays(RayKind::Clipped, 3000, 4, s);
  EXPECT_GT(s.hits, 2000);
}

// A ray exactly along a grid line (two zero components, on cell boundaries)
// and a ray through a grid corner diagonal: finite, ordered, complete.
TEST(DDA, DegenerateRays)
{
  GridView g;
  for (int a = 0; a < 3; ++a)
  {
    g.dims[a] = 4;
    g.lo[a] = 0.f;
    g.cellSize[a] = 2.f;
    g.invCellSize[a] = 0.5f;
  }
  g.numChannels = 1;
  // Along z on the line x = 2, y = 4 (cell boundaries).
  std::vector<Segment> s = walk(g, Vec3f(2.f, 4.f, -1.f), Vec3f(0.f, 0.f, 1.f), 1.f, 9.f);
  ASSERT_EQ(s.size(), 4u);
  for (int i = 0; i < 4; ++i)
  {
    EXPECT_EQ(s[size_t(i)].cell[0], 1);
    EXPECT_EQ(s[size_t(i)].cell[1], 2);
    EXPECT_EQ(s[size_t(i)].cell[2], i);
    EXPECT_FLOAT_EQ(s[size_t(i)].t1, 1.f + 2.f * float(i + 1));
  }
  // Exact diagonal through cell corners: every cell of the diagonal is
  // visited, with zero-length segments between them allowed.
  s = walk(g, Vec3f(0.f, 0.f, 0.f), Vec3f(1.f, 1.f, 1.f), 0.f, 8.f);
  int diagonal = 0;
  for (const Segment& x : s)
  {
    EXPECT_TRUE(std::isfinite(x.t0) && std::isfinite(x.t1));
    if (x.t1 > x.t0)
    {
      EXPECT_EQ(x.cell[0], x.cell[1]);
      EXPECT_EQ(x.cell[1], x.cell[2]);
      ++diagonal;
    }
  }
  EXPECT_EQ(diagonal, 4);
  EXPECT_EQ(s.back().t1, 8.f);
  // At a corner the crossings tie: x steps first, then y, then z (the first
  // axis of equal crossings), one fixed order on every backend.
  ASSERT_GE(s.size(), 4u);
  const int corner[3][3] = { { 1, 0, 0 }, { 1, 1, 0 }, { 1, 1, 1 } };
  for (int i = 0; i < 3; ++i)
  {
    for (int a = 0; a < 3; ++a)
    {
      EXPECT_EQ(s[size_t(i + 1)].cell[a], corner[i][a]) << "step " << i + 1 << ", axis " << a;
    }
  }
  EXPECT_EQ(s[1].t0, 2.f);
  EXPECT_EQ(s[1].t1, 2.f);
  // Negative direction along x only.
  s = walk(g, Vec3f(7.5f, 1.f, 1.f), Vec3f(-2.f, 0.f, 0.f), 0.f, 3.75f);
  ASSERT_EQ(s.size(), 4u);
  EXPECT_EQ(s.front().cell[0], 3);
  EXPECT_EQ(s.back().cell[0], 0);
  EXPECT_FLOAT_EQ(s[0].t1, 0.75f);
  // Empty interval: no segment.
  DDA dda;
  dda.init(g, Vec3f(1.f, 1.f, 1.f), Vec3f(1.f, 0.f, 0.f), 2.f, 2.f);
  EXPECT_TRUE(dda.done);
}
