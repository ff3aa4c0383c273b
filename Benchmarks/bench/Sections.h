// SPDX-License-Identifier: BSD-3-Clause
//
// The mcvol-bench sections, one per Section*.cxx; mcvol_bench.cxx runs the
// ones named by --sections.

#pragma once

#include "BenchCommon.h"

namespace mcvolbench
{
void runTrackers(Bench& bench);
void runChannels(Bench& bench);
void runMacrocell(Bench& bench);
void runRebuild(Bench& bench);
void runMemory(Bench& bench);
void runPaper(Bench& bench);
void runSampling(Bench& bench);
void runEffects(Bench& bench);
void runConverge(Bench& bench);
void runVisibility(Bench& bench);
void runEstimate(Bench& bench);
void runSequences(Bench& bench);
void runPyramid(Bench& bench);
void runPilots(Bench& bench);
void runBlends(Bench& bench);
void runRaymarch(Bench& bench);
void runSplit(Bench& bench);
} // namespace mcvolbench
