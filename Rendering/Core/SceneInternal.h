// SPDX-License-Identifier: BSD-3-Clause
#pragma once

// Helpers shared by the Scene*.cxx files, which define Scene's members by
// topic; private to the core (backends read Scene through mcvol/Scene.h).

#include <chrono>
#include <cstdint>
#include <string>

namespace mcvol
{
namespace detail
{
inline double secondsSince(std::chrono::steady_clock::time_point t0)
{
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
}

/// "channel n", the way every error message names a channel.
inline std::string channelText(int n)
{
  return "channel " + std::to_string(n);
}

/// Writes to `active` the channels whose majorant is non-zero in some cell of
/// `majorants` ([cell][channel]) and returns how many there are.
int findActiveChannels(const float* majorants, int64_t cells, int numChannels, int* active);
} // namespace detail
} // namespace mcvol
