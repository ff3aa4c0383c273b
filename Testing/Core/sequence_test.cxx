// SPDX-License-Identifier: BSD-3-Clause
// Sample sequences (Sequence.h, Sampler::Sobol; Documentation/design.md,
// "Random numbers and sequences"):
// - the Sobol' coordinates match a textbook construction of the direction
//   numbers; scrambled and shuffled, every power-of-two block of a pixel's
//   samples is stratified (the (0, m, 2)-net property of dimensions 0-1,
//   each dimension alone a (0, m, 1)-net);
// - across pixels every dimension, and pairs of them, are uniform
//   (chi-square);
// - images stay independent of the thread count and the batching;
// - the error against samples per pixel falls faster than with independent
//   samples, on the same scene.
// Significance: each statistical TEST has a family-wise level kAlpha = 0.001,
// split evenly (Bonferroni) over its checks; seeds are fixed.
#include "TestUtil.h"

#include "mcvol/RayMarcher.h"
#include "mcvol/ray/Sequence.h"

#include <cstring>

using namespace mcvol;
using namespace mcvol::test;

namespace
{
constexpr double kAlpha = 1e-3;

/// Direction numbers v_1..v_32 (1-based, as 32-bit fractions) of a Sobol'
/// dimension from the integer recurrence of Bratley and Fox (1988):
/// m_k = 2 a_1 m_(k-1) ^ 4 a_2 m_(k-2) ^ ... ^ 2^s m_(k-s) ^ m_(k-s),
/// v_k = m_k / 2^k; written independently of Sequence.h's bit-window form.
std::vector<uint32_t> directionNumbers(int s, uint32_t a, std::vector<uint64_t> m)
{
  for (int k = s; k < 32; ++k)
  {
    uint64_t x = m[size_t(k - s)] ^ (m[size_t(k - s)] << s);
    for (int i = 1; i < s; ++i)
    {
      if ((a >> (s - 1 - i)) & 1u)
      {
        x ^= m[size_t(k - i)] << i;
      }
    }
    m.push_back(x);
  }
  std::vector<uint32_t> v;
  for (int k = 0; k < 32; ++k)
  {
    v.push_back(uint32_t(m[size_t(k)] << (31 - k)));
  }
  return v;
}

uint32_t referenceSobol(uint32_t i, const std::vector<uint32_t>& v)
{
  uint32_t x = 0;
  for (int k = 0; k < 32; ++k)
  {
    if ((i >> k) & 1u)
    {
      x ^= v[size_t(k)];
    }
  }
  return x;
}

/// The 32-bit coordinate `dim` of sample `k` of padded set `group` of the
/// pixel keyed `key`.
uint32_t point(uint32_t k, int dim, uint32_t key, uint32_t group = 0)
{
  return owenSobolBits(shuffledSobolIndex(k, key, group), dim, key, group);
}
} // namespace

TEST(Sobol, CoordinatesMatchTheTextbookConstruction)
{
  const std::vector<uint32_t> v[5] = {
    directionNumbers(1, 0, { 1 }), // unused for dim 0 (van der Corput below)
    directionNumbers(1, 0, { 1 }),
    directionNumbers(2, 1, { 1, 3 }),
    directionNumbers(3, 1, { 1, 3, 1 }),
    directionNumbers(3, 2, { 1, 1, 1 }),
  };
  TestRand r(17);
  for (int dim = 0; dim < kSequenceDimensions; ++dim)
  {
    for (int t = 0; t < 4000; ++t)
    {
      const uint32_t i = t < 2000 ? uint32_t(t) : uint32_t(r.u64());
      const uint32_t expect = dim == 0 ? reverseBits32(i) : referenceSobol(i, v[dim]);
      ASSERT_EQ(sobolCoordinate(i, dim), expect) << "dim " << dim << " index " << i;
    }
  }
  // The scrambled coordinate's shortcut (dimensions 0-1 skip two reversals)
  // equals the scramble of the coordinate.
  for (int t = 0; t < 4000; ++t)
  {
    const uint32_t i = uint32_t(r.u64()), key = uint32_t(r.u64());
    for (int dim = 0; dim < kSequenceDimensions; ++dim)
    {
      const uint32_t seed = hashCombine(key, uint32_t(dim) * 0x9E3779B9u + 7u * 0x85EBCA6Bu + 1u);
      ASSERT_EQ(owenSobolBits(i, dim, key, 7), nestedUniformScramble(sobolCoordinate(i, dim), seed)) << dim;
    }
  }
  // First points of dimension 1 (Pascal matrix): 0, 1/2, 3/4, 1/4, 5/8.
  EXPECT_EQ(sobolCoordinate(1, 1), 0x80000000u);
  EXPECT_EQ(sobolCoordinate(2, 1), 0xC0000000u);
  EXPECT_EQ(sobolCoordinate(3, 1), 0x40000000u);
  EXPECT_EQ(sobolCoordinate(4, 1), 0xA0000000u);
}

// Every aligned block of 2^m samples of a pixel (the first 2^m, and later
// ones: progressive passes) puts exactly one point in each elementary
// interval [a/2^j, (a+1)/2^j) x [b/2^(m-j), (b+1)/2^(m-j)) of dimensions 0-1
// of every padded set, and exactly one point in each interval of width 2^-m
// of every dimension. Deterministic: exact counts.
TEST(Sobol, EveryPowerOfTwoBlockIsStratified)
{
  for (uint32_t key : { 0u, 1u, 0xdeadbeefu, 123456789u })
  {
    for (int m = 0; m <= 10; ++m)
    {
      const uint32_t n = 1u << m;
      for (uint32_t block : { 0u, 1u, 7u })
      {
        for (uint32_t group : { uint32_t(kGroupPixel), kGroupFlight + 3u, kGroupCollision + 5u })
        {
          std::vector<uint32_t> x(n), y(n);
          for (uint32_t k = 0; k < n; ++k)
          {
            x[k] = point(block * n + k, 0, key, group);
            y[k] = point(block * n + k, 1, key, group);
          }
          for (int j = 0; j <= m; ++j)
          {
            std::vector<int> cells(n, 0);
            for (uint32_t k = 0; k < n; ++k)
            {
              const uint32_t a = j == 0 ? 0u : x[k] >> (32 - j);
              const uint32_t b = m - j == 0 ? 0u : y[k] >> (32 - (m - j));
              ++cells[(a << (m - j)) | b];
            }
            for (uint32_t c = 0; c < n; ++c)
            {
              ASSERT_EQ(cells[c], 1) << "key " << key << " m " << m << " block " << block << " group " << group
                                     << " interval 2^-" << j << " x 2^-" << (m - j) << " cell " << c;
            }
          }
        }
        for (int dim = 0; dim < kSequenceDimensions; ++dim)
        {
          std::vector<int> cells(n, 0);
          for (uint32_t k = 0; k < n; ++k)
          {
            ++cells[m == 0 ? 0u : point(block * n + k, dim, key, 9u) >> (32 - m)];
          }
          for (uint32_t c = 0; c < n; ++c)
          {
            ASSERT_EQ(cells[c], 1) << "dim " << dim << " m " << m << " cell " << c;
          }
        }
      }
    }
  }
}

// Over 2^16 pixels, a fixed sample index gives uniform numbers for every
// decision (64 bins each: pixel x and y, two channels' first flights, the
// first two collisions' accept tests and flights, scatter, ambient (2)) and
// uniform pairs (16 x 16 bins: pixel (x, y); the two channels' flights and
// the two collisions' accept tests, which must be independent for the
// estimator to stay unbiased; a collision's (accept, flight)), for sample
// indices 0, 1 and 37: 3 x (11 + 4) chi-square tests, through the Rng.
TEST(Sobol, UniformOverPixels)
{
  const double alpha = kAlpha / (3 * 15);
  const uint32_t P = 1u << 16;
  const int D = 11;
  for (uint32_t k : { 0u, 1u, 37u })
  {
    std::vector<std::vector<double>> one(D, std::vector<double>(64, 0.0));
    std::vector<std::vector<double>> two(4, std::vector<double>(256, 0.0));
    for (uint32_t p = 0; p < P; ++p)
    {
      Rng rng(p, k, 42u);
      rng.startSequence(p, k, 42u);
      float u[D];
      u[0] = rng.sequence(kGroupPixel, 0);
      u[1] = rng.sequence(kGroupPixel, 1);
      u[2] = rng.sequence(kGroupFlight + 0);
      u[3] = rng.sequence(kGroupFlight + 1);
      rng.collision(u[5], u[4]);
      rng.collision(u[7], u[6]);
      u[8] = rng.sequence(kGroupScatter);
      u[9] = rng.sequence(kGroupAmbient, 0);
      u[10] = rng.sequence(kGroupAmbient, 1);
      for (int d = 0; d < D; ++d)
      {
        ASSERT_GE(u[d], 0.f);
        ASSERT_LT(u[d], 1.f);
        one[size_t(d)][size_t(u[d] * 64)] += 1;
      }
      auto cell = [&](int a, int b) { return size_t(u[a] * 16) * 16 + size_t(u[b] * 16); };
      two[0][cell(0, 1)] += 1;
      two[1][cell(2, 3)] += 1;
      two[2][cell(4, 6)] += 1;
      two[3][cell(4, 5)] += 1;
    }
    for (int d = 0; d < D; ++d)
    {
      double stat = 0;
      const double pv = chiSquarePValue(one[size_t(d)], std::vector<double>(64, 1.0 / 64), &stat);
      EXPECT_GT(pv, alpha) << "sample " << k << " decision " << d << ": chi-square " << stat;
    }
    for (int q = 0; q < 4; ++q)
    {
      double stat = 0;
      const double pv = chiSquarePValue(two[size_t(q)], std::vector<double>(256, 1.0 / 256), &stat);
      EXPECT_GT(pv, alpha) << "sample " << k << " pair " << q << ": chi-square " << stat;
    }
  }
}

// Without a sequence, sequence() and collision() are next() in the order the
// code drew before (flight, then accept): the independent sampler's images
// are unchanged. With one, the first kSequenceCollisions collisions take
// their sets, later ones and everything after endSequence() the PCG stream.
TEST(Sobol, RngSequence)
{
  Rng a(5, 9, 3), b(5, 9, 3);
  for (int i = 0; i < 8; ++i)
  {
    EXPECT_EQ(a.sequence(uint32_t(i)), b.next());
    float f, u;
    a.collision(f, u);
    EXPECT_EQ(f, b.next());
    EXPECT_EQ(u, b.next());
  }
  Rng q(5, 9, 3), plain(5, 9, 3);
  q.startSequence(5, 9, 3);
  const uint32_t key = hashCombine(3u ^ 0x2545F491u, 5);
  const float px = q.sequence(kGroupPixel, 0);
  EXPECT_EQ(px, sequencePoint(9, key, kGroupPixel, 0));
  float p0, p1;
  q.sequence2(kGroupPixel, p0, p1);
  EXPECT_EQ(p0, px);
  EXPECT_EQ(p1, sequencePoint(9, key, kGroupPixel, 1));
  EXPECT_EQ(q.sequence(kGroupPixel, 0), px); // a coordinate, not a stream
  for (uint32_t k = 0; k < kSequenceCollisions; ++k)
  {
    float f, u;
    q.collision(f, u);
    EXPECT_EQ(u, sequencePoint(9, key, kGroupCollision + k, 0));
    EXPECT_EQ(f, sequencePoint(9, key, kGroupCollision + k, 1));
  }
  float f, u;
  q.collision(f, u);
  EXPECT_EQ(f, plain.next());
  EXPECT_EQ(u, plain.next());
  q.endSequence();
  EXPECT_EQ(q.sequence(kGroupFlight), plain.next());
}

namespace
{
Camera cosmoCam(const DemoVolume& v, int W, int H)
{
  return orbitCamera(v.dims, v.spacing, W, H, 30, 20);
}

std::vector<float> image(const Accumulator& a)
{
  return std::vector<float>(a.rgba(), a.rgba() + size_t(a.width()) * a.height() * 4);
}
} // namespace

// Same image whatever the thread count (bit for bit) and batching (16 renders
// of 1 sample against one of 16: the same samples, accumulated in another
// order), for both trackers, lit and unlit.
TEST(Sobol, ReproducibleWhateverThreadsAndBatches)
{
  const DemoVolume v = makeDemo("cosmology", { 32, 32, 32 });
  Scene scene;
  configureDemo(scene, v, 8);
  const Camera cam = cosmoCam(v, 41, 33);
  for (bool lit : { false, true })
  {
    LightingDesc L;
    if (lit)
    {
      LightDesc light;
      light.intensity = 2.0;
      L.lights.push_back(light);
      L.ambient[0] = L.ambient[1] = L.ambient[2] = 0.3;
      L.maxDepth = 3;
    }
    scene.setLighting(L);
    ASSERT_EQ(scene.lit(), lit);
    scene.update();
    for (Tracker t : { Tracker::OneDDA, Tracker::NDDA })
    {
      RenderSettings rs;
      rs.sampler = Sampler::Sobol;
      rs.seed = 9;
      rs.tracker = t;
      rs.samplesPerPixel = 16;
      std::vector<float> ref;
      for (int threads : { 1, 2 })
      {
        CPURenderer r;
        r.setThreads(threads);
        Accumulator acc;
        r.render(scene, cam, rs, nullptr, acc);
        if (threads == 1)
        {
          ref = image(acc);
          continue;
        }
        const std::vector<float> img = image(acc);
        EXPECT_EQ(0, std::memcmp(ref.data(), img.data(), ref.size() * sizeof(float)))
          << toString(t) << (lit ? " lit" : "") << ": 2 threads differ from 1";
      }
      CPURenderer r;
      Accumulator acc;
      RenderSettings one = rs;
      one.samplesPerPixel = 1;
      for (int k = 0; k < 16; ++k)
      {
        r.render(scene, cam, one, nullptr, acc);
      }
      const std::vector<float> img = image(acc);
      double maxDiff = 0, sum = 0;
      for (size_t i = 0; i < ref.size(); ++i)
      {
        maxDiff = std::max(maxDiff, double(std::fabs(img[i] - ref[i])));
        sum += ref[i];
      }
      EXPECT_LE(maxDiff, 1e-5) << toString(t) << (lit ? " lit" : "") << ": 16 x 1 spp against 1 x 16 spp";
      EXPECT_GT(sum, 10.0) << "empty image";
      // The setting takes effect: the independent sampler gives another image.
      RenderSettings ind = rs;
      ind.sampler = Sampler::Independent;
      Accumulator other;
      r.render(scene, cam, ind, nullptr, other);
      EXPECT_NE(0, std::memcmp(ref.data(), other.rgba(), ref.size() * sizeof(float)));
    }
  }
}

// A transparent channel is never active: adding one, in the middle of the
// list, leaves the image bit for bit as it was, with either sampler and
// tracker (the Sobol' sets of the first flights are keyed by the place in
// the active list, not by the channel's index).
TEST(Sobol, TransparentChannelChangesNothing)
{
  TestVolume two(12, 12, 12, 2, 0.5f), three(12, 12, 12, 3, 0.5f);
  for (int k = 0; k < 12; ++k)
  {
    for (int j = 0; j < 12; ++j)
    {
      for (int i = 0; i < 12; ++i)
      {
        const float a = float((i * 7 + j * 3 + k) % 11) / 10.f, b = float((i + j * 5 + k * 2) % 7) / 6.f;
        two.channels[0][two.index(i, j, k)] = three.channels[0][three.index(i, j, k)] = a;
        two.channels[1][two.index(i, j, k)] = three.channels[2][three.index(i, j, k)] = b;
      }
    }
  }
  TransferFunctionDesc ta = flatTF(0.f, 1, 0.2f, 0.1f, 4.f, 16), tb = flatTF(0.f, 0.1f, 0.4f, 1, 4.f, 16);
  for (int t = 0; t < 16; ++t)
  {
    ta.opacity[size_t(t)] = 0.5f * float(t) / 15.f;
    tb.opacity[size_t(t)] = 0.4f * float(15 - t) / 15.f;
  }
  Scene s2, s3;
  configure(s2, two, { ta, tb }, 4);
  configure(s3, three, { ta, flatTF(0.f, 0, 1, 0, 4.f, 16), tb }, 4);
  const Camera cam = orthoAlongZ(24, 24, 0.5, 10.5, 0.5, 10.5, 20.0, 40.0);
  for (Sampler sampler : { Sampler::Independent, Sampler::Sobol })
  {
    for (Tracker t : { Tracker::OneDDA, Tracker::NDDA })
    {
      RenderSettings rs;
      rs.sampler = sampler;
      rs.tracker = t;
      rs.seed = 3;
      rs.samplesPerPixel = 8;
      CPURenderer r;
      Accumulator a2, a3;
      r.render(s2, cam, rs, nullptr, a2);
      r.render(s3, cam, rs, nullptr, a3);
      const std::vector<float> i2 = image(a2), i3 = image(a3);
      double alpha = 0;
      for (size_t p = 3; p < i2.size(); p += 4)
      {
        alpha += i2[p];
      }
      EXPECT_GT(alpha, 24 * 24 * 0.1) << "nearly empty image: the test would be weak";
      EXPECT_EQ(0, std::memcmp(i2.data(), i3.data(), i2.size() * sizeof(float)))
        << toString(sampler) << " " << toString(t) << ": a transparent channel changed the image";
    }
  }
}
