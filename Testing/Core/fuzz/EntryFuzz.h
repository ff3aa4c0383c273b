// SPDX-License-Identifier: BSD-3-Clause
#pragma once

#include <cstddef>
#include <cstdint>

namespace mcvol
{
namespace fuzz
{
/**
 * One input of the core's entry-point fuzz harness: `data` decoded into a
 * volume of 1 to 4 channels of any scalar type and stride (voxel values
 * taken from the bytes, NaN and infinities included), a transfer function per
 * channel (any range and table, empty ones too), a macrocell size, then
 * Scene::setVolume, setTransferFunction, setMacrocellSize and update(); a
 * camera (any matrices) whose rays are generated and walked through the
 * scene's macrocell grid by the DDA; and a DDA over a grid and ray given
 * directly. Each call either succeeds or throws std::invalid_argument,
 * which is accepted; anything else (another exception, a sanitizer report,
 * a DDA longer than its grid) ends the process.
 */
void RunOne(const uint8_t* data, size_t size);
} // namespace fuzz
} // namespace mcvol
