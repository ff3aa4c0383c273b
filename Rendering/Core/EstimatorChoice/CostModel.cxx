// SPDX-License-Identifier: BSD-3-Clause
//
// The cost of one pilot sample: a linear model of the work counters a render
// reports, not the pilot's wall time, so that the choice (and with it the
// image) is the same for a fixed seed whatever the machine's load or thread
// count.
#include "mcvol/EstimatorChoice.h"

namespace mcvol
{
double CostModel::cost(const RenderCounters& c) const
{
  return this->perRay * double(c.rays) + this->perDdaStep * double(c.ddaSteps) +
    this->perTentative * double(c.tentativeCollisions) + this->perChannelSample * double(c.channelSamples);
}

CostModel defaultCostModel(const std::string& backendName)
{
  // Fitted by Benchmarks/studies/fit_cost_model.py to the frame times of
  // `mcvol-bench --sections converge`: on the GPU for the four paper-sized
  // datasets at 1024^2, on the CPU for the four demo datasets at 256^2
  // (Documentation/performance.md). The fit keeps the weights non-negative;
  // the per-ray weight comes out 0 on both backends because the DDA steps
  // already carry the per-ray cost.
  CostModel m;
  if (backendName == "cuda")
  {
    m.perRay = 0.0;
    m.perDdaStep = 0.02527;
    m.perTentative = 0.05904;
    m.perChannelSample = 0.01309;
    return m;
  }
  m.perRay = 0.0;
  m.perDdaStep = 34.42;
  m.perTentative = 11.61;
  m.perChannelSample = 10.57;
  return m;
}
} // namespace mcvol
