// SPDX-License-Identifier: BSD-3-Clause
#include "mcvol/Renderer.h"

#include <algorithm>
#include <stdexcept>

namespace mcvol
{
void Accumulator::resize(int width, int height)
{
  if (width < 0 || height < 0)
  {
    throw std::invalid_argument("mcvol: negative image size");
  }
  if (width != this->Width || height != this->Height)
  {
    this->Width = width;
    this->Height = height;
    this->RGBA.assign(size_t(width) * size_t(height) * 4, 0.f);
    this->Samples = 0;
    this->Pending = false;
  }
}

void Accumulator::reset()
{
  std::fill(this->RGBA.begin(), this->RGBA.end(), 0.f);
  this->Samples = 0;
  this->Pending = false;
}
} // namespace mcvol
