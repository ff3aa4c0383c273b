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
    if (this->EstimateError)
    {
      this->Even.assign(this->RGBA.size(), 0.f);
    }
    this->EvenValid = this->EstimateError;
    this->Samples = 0;
    this->SumsValid = true;
    this->Pending = false;
    this->EvenPending = false;
    this->ClearRGBA = false;
    this->ClearEven = false;
    this->Importance = ImportancePool();
  }
}

void Accumulator::reset()
{
  // The zeros are written on the first host access (settle()): with a device
  // backend the image starts on the device, and clearing two float images on
  // the host at every camera move would take about half of a GPU frame at
  // 1024^2.
  this->ClearRGBA = true;
  if (this->EstimateError)
  {
    if (this->Even.size() != this->RGBA.size())
    {
      this->Even.assign(this->RGBA.size(), 0.f);
    }
    this->ClearEven = true;
  }
  this->EvenValid = this->EstimateError;
  this->Samples = 0;
  this->SumsValid = true; // at 0 samples the sums are not read
  this->Pending = false;
  this->EvenPending = false;
  // The segment lists belong to the image: a new image refines anew.
  std::fill(this->Importance.counts.begin(), this->Importance.counts.end(), uint8_t(0));
  this->Importance.passes = 0;
  this->Importance.overflows = 0;
}

void Accumulator::clearHost() const
{
  if (this->ClearRGBA)
  {
    std::fill(this->RGBA.begin(), this->RGBA.end(), 0.f);
    this->ClearRGBA = false;
  }
  if (this->ClearEven)
  {
    std::fill(this->Even.begin(), this->Even.end(), 0.f);
    this->ClearEven = false;
  }
}

float* Accumulator::rgbaForOverwrite()
{
  this->ClearRGBA = false;
  this->SumsValid = false;
  return this->RGBA.data();
}

float* Accumulator::evenRGBAForOverwrite()
{
  if (!this->EvenValid)
  {
    return nullptr;
  }
  this->ClearEven = false;
  this->SumsValid = false;
  return this->Even.data();
}

namespace
{
/// Sums of `n` samples whose mean is `mean`.
void sumsFromMean(std::vector<double>& sums, const float* mean, size_t count, uint32_t n)
{
  sums.resize(count);
  for (size_t i = 0; i < count; ++i)
  {
    sums[i] = double(mean[i]) * double(n);
  }
}
} // namespace

double* Accumulator::sums()
{
  this->settle();
  if (this->Sum.size() != this->RGBA.size())
  {
    this->Sum.assign(this->RGBA.size(), 0.0);
    this->EvenSum.clear();
    this->SumsValid = this->Samples == 0;
  }
  if (this->EvenValid && this->EvenSum.size() != this->Even.size())
  {
    this->EvenSum.assign(this->Even.size(), 0.0);
    this->SumsValid = this->SumsValid && this->Samples == 0;
  }
  if (!this->SumsValid)
  {
    sumsFromMean(this->Sum, this->RGBA.data(), this->RGBA.size(), this->Samples);
    if (this->EvenValid)
    {
      sumsFromMean(this->EvenSum, this->Even.data(), this->Even.size(), evenSamples(this->Samples));
    }
    this->SumsValid = true;
  }
  return this->Sum.data();
}

double* Accumulator::evenSums()
{
  this->sums();
  return this->EvenValid ? this->EvenSum.data() : nullptr;
}

void Accumulator::setErrorEstimation(bool on)
{
  if (on == this->EstimateError)
  {
    return;
  }
  this->EstimateError = on;
  if (on)
  {
    this->Even.assign(this->RGBA.size(), 0.f);
    this->ClearEven = false;
    // Samples already taken were not split into halves.
    this->EvenValid = this->Samples == 0;
  }
  else
  {
    std::vector<double>().swap(this->EvenSum);
    std::vector<float>().swap(this->Even);
    this->ClearEven = false;
    this->EvenValid = false;
  }
}

double Accumulator::estimatedMSE() const
{
  const uint32_t n = this->Samples;
  if (n < 2 || !this->EvenValid || this->Pending || this->EvenPending || this->Even.size() != this->RGBA.size())
  {
    return -1.0;
  }
  const size_t pixels = size_t(this->Width) * size_t(this->Height);
  if (pixels == 0)
  {
    return -1.0;
  }
  this->settle();
  const double nA = double(evenSamples(n));
  const double nB = double(n) - nA;
  const float* m = this->RGBA.data();
  const float* a = this->Even.data();
  double sum = 0.0;
  for (size_t p = 0; p < pixels; ++p)
  {
    for (int c = 0; c < 3; ++c)
    {
      const double d = double(a[4 * p + c]) - double(m[4 * p + c]);
      sum += d * d;
    }
  }
  return (nA / nB) * sum / double(3 * pixels);
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
