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
    this->Importance = ImportancePool();
  }
}

void Accumulator::reset()
{
  std::fill(this->RGBA.begin(), this->RGBA.end(), 0.f);
  this->Samples = 0;
  this->Pending = false;
  // The segment lists belong to the image: a new image refines anew.
  std::fill(this->Importance.counts.begin(), this->Importance.counts.end(), uint8_t(0));
  this->Importance.passes = 0;
  this->Importance.overflows = 0;
}

Accumulator::ImportancePool& Accumulator::importancePool(bool hostLists)
{
  const size_t pixels = size_t(this->Width) * size_t(this->Height);
  ImportancePool& p = this->Importance;
  if (hostLists && p.counts.size() != pixels)
  {
    p.segments.assign(pixels * size_t(kImportanceCapacity), ImportanceSegment());
    p.counts.assign(pixels, uint8_t(0));
    p.totals.assign(pixels, 0.f);
    p.passes = 0;
    p.overflows = 0;
  }
  return p;
}
} // namespace mcvol
