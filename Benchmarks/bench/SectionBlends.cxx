// SPDX-License-Identifier: BSD-3-Clause
//
// mcvol-bench section "blends": Sahistan et al.'s Table 2 protocol. Every
// channel gets a flat colour map (red, green, blue, white, then again) over
// its dataset opacity, identical for every blend; each blend (density, max,
// mix with equal weights as Eq. 10, post-render compositing) renders a
// converged image (--reference-spp samples, emission-absorption), and the
// non-physical blends are scored against the physically based density blend
// by PSNR and mean absolute difference (the paper also reports FLIP, which
// mcvol does not compute).

#include "BenchCommon.h"
#include "Sections.h"

#include <cmath>
#include <cstdio>
#include <string>
#include <vector>

namespace mcvolbench
{
void runBlends(Bench& bench)
{
  const Options& o = bench.o;
  Setup& s = bench.s;
  mcvol::Renderer& r = bench.r;
  s.load(o, o.channels, o.macrocell, bench.hostAccel);
  const std::string ds = describe(o, s);
  const int N = s.volume.numChannels();
  const float colours[4][3] = { { 1, 0, 0 }, { 0, 1, 0 }, { 0, 0, 1 }, { 1, 1, 1 } };
  for (int n = 0; n < N; ++n)
  {
    mcvol::TransferFunctionDesc tf = demoTransferFunction(s.volume, n, s.ranges[size_t(n)], o.tableSize, o.density);
    for (size_t i = 0; i < tf.opacity.size(); ++i)
    {
      for (int c = 0; c < 3; ++c)
      {
        tf.rgb[3 * i + size_t(c)] = colours[n % 4][c];
      }
    }
    s.scene.setTransferFunction(n, tf);
  }
  s.scene.setMixAverage(false); // Eq. 10 with equal weights, as the paper's mix
  const mcvol::Camera cam = benchCamera(o, s.scene);
  std::printf("## Blend modes (Sahistan et al. Table 2 protocol): %s, %d channels (flat red, green, blue, white), "
              "%dx%d, %d spp each, against density blending\n\n| blend | PSNR to density (dB) | mean abs. difference | "
              "mean alpha |\n|---|---|---|---|\n",
    ds.c_str(), N, o.width, o.height, o.referenceSpp);
  std::vector<float> density;
  for (mcvol::BlendMode mode :
    { mcvol::BlendMode::Density, mcvol::BlendMode::Max, mcvol::BlendMode::Mix, mcvol::BlendMode::Composite })
  {
    s.scene.setBlendMode(mode);
    s.scene.update();
    mcvol::Accumulator acc;
    const std::vector<float> img = renderReference(o, r, s.scene, cam, acc);
    double alpha = 0, mad = 0;
    const size_t P = size_t(o.width) * size_t(o.height);
    for (size_t p = 0; p < P; ++p)
    {
      alpha += img[4 * p + 3];
    }
    alpha /= double(P);
    if (mode == mcvol::BlendMode::Density)
    {
      density = img;
      std::printf("| density (reference) | - | - | %.4f |\n", alpha);
      bench.row("blends", ds, N, o.macrocell, "density", alpha, "alpha", "");
      continue;
    }
    for (size_t p = 0; p < P; ++p)
    {
      for (int c = 0; c < 3; ++c)
      {
        mad += std::fabs(double(img[4 * p + size_t(c)]) - double(density[4 * p + size_t(c)]));
      }
    }
    mad /= double(3 * P);
    const double psnr = psnrOf(acc, density);
    std::printf("| %s | %.2f | %.4f | %.4f |\n", mcvol::toString(mode), psnr, mad, alpha);
    bench.row("blends", ds, N, o.macrocell, mcvol::toString(mode), psnr, "dB", "PSNR to density");
    bench.row("blends", ds, N, o.macrocell, mcvol::toString(mode), mad, "mean abs", "difference to density");
    std::fflush(stdout);
  }
  std::printf("\n");
}
} // namespace mcvolbench
