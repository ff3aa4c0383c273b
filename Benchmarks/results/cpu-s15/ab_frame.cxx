// A/B driver: median frame ms of one estimator configuration (not in the repo).
#include "BenchCommon.h"
#include "mcvol/CPURenderer.h"
#include <cstdio>
#include <cstdlib>
#include <string>
using namespace mcvolbench;
int main(int argc, char** argv)
{
  Options o;
  o.dataset = argv[1];
  o.dims = { atoi(argv[2]), atoi(argv[3]), atoi(argv[4]) };
  o.width = o.height = atoi(argv[5]);
  const std::string est = argv[6];
  const float rate = float(atof(argv[7]));
  const int frames = atoi(argv[8]);
  const bool centres = argc > 9 && std::string(argv[9]) == "centres";
  Setup s;
  s.load(o, 0, 8, true);
  mcvol::CPURenderer r;
  mcvol::Camera cam = benchCamera(o, s.scene);
  mcvol::RenderSettings st;
  st.samplesPerPixel = 1;
  st.jitterPixels = !centres;
  st.estimator = est == "ev" ? mcvol::Estimator::ExpectedValue : est == "march" ? mcvol::Estimator::UnbiasedMarch : mcvol::Estimator::Collision;
  st.marchSamplesPerVoxel = rate;
  mcvol::Accumulator acc;
  r.render(s.scene, cam, st, nullptr, acc);
  std::vector<double> ms;
  double sum = 0;
  for (int i = 0; i < frames; ++i)
  {
    acc.reset();
    auto t0 = Clock::now();
    r.render(s.scene, cam, st, nullptr, acc);
    ms.push_back(1e3 * seconds(t0));
  }
  for (size_t p = 0; p < size_t(o.width) * o.height * 4; ++p) sum += acc.rgba()[p];
  std::printf("median %.2f ms  min %.2f  checksum %.9g\n", median(ms), *std::min_element(ms.begin(), ms.end()), sum);
}
