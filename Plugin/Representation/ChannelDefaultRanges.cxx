// SPDX-License-Identifier: BSD-3-Clause
#include "ChannelDefaultRanges.h"

#include "vtkDataArray.h"
#include "vtkImageData.h"
#include "vtkPointData.h"
#include "vtkTypeTraits.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <iomanip>
#include <limits>
#include <sstream>
#include <unordered_set>
#include <vector>

namespace
{
constexpr double kLowPercentile = 0.1;
constexpr double kHighPercentile = 99.9;
constexpr size_t kMaxDistinct = 256;
constexpr size_t kMaxSample = size_t(1) << 24;

// A 64-bit integer hash (splitmix64's finaliser): the sample's place in a block.
uint64_t Hash(uint64_t x)
{
  x += 0x9e3779b97f4a7c15ull;
  x = (x ^ (x >> 30)) * 0xbf58476d1ce4e5b9ull;
  x = (x ^ (x >> 27)) * 0x94d049bb133111ebull;
  return x ^ (x >> 31);
}

// numpy.percentile's default: the order statistics around p / 100 * (n - 1),
// linearly interpolated. `at(k)` gives the k-th smallest value.
template <typename At>
double Percentile(size_t n, double p, At at)
{
  const double position = p / 100.0 * static_cast<double>(n - 1);
  const size_t k = static_cast<size_t>(std::floor(position));
  const double fraction = position - static_cast<double>(k);
  const double a = at(k);
  if (fraction == 0.0 || k + 1 >= n)
  {
    return a;
  }
  return a + fraction * (at(k + 1) - a);
}

// 8- and 16-bit integers: exact order statistics from a histogram.
template <typename T>
bool HistogramRange(const T* values, size_t count, int stride, double range[2])
{
  const long offset = std::is_signed<T>::value ? (1L << (8 * sizeof(T) - 1)) : 0;
  std::vector<uint64_t> histogram(size_t(1) << (8 * sizeof(T)), 0);
  for (size_t i = 0; i < count; ++i)
  {
    ++histogram[static_cast<size_t>(static_cast<long>(values[i * stride]) + offset)];
  }
  size_t distinct = 0;
  long first = -1, last = -1;
  for (size_t b = 0; b < histogram.size(); ++b)
  {
    if (histogram[b])
    {
      ++distinct;
      first = first < 0 ? static_cast<long>(b) : first;
      last = static_cast<long>(b);
    }
  }
  if (count == 0)
  {
    return false;
  }
  const double lo = static_cast<double>(first - offset), hi = static_cast<double>(last - offset);
  if (lo == hi || distinct <= kMaxDistinct)
  {
    range[0] = lo;
    range[1] = hi;
    return true;
  }
  // The k-th smallest value: walk the cumulative histogram.
  auto at = [&](size_t k) {
    uint64_t seen = 0;
    for (size_t b = 0; b < histogram.size(); ++b)
    {
      seen += histogram[b];
      if (seen > k)
      {
        return static_cast<double>(static_cast<long>(b) - offset);
      }
    }
    return hi;
  };
  const double plo = Percentile(count, kLowPercentile, at);
  const double phi = Percentile(count, kHighPercentile, at);
  range[0] = plo < phi ? plo : lo;
  range[1] = plo < phi ? phi : hi;
  return true;
}

// Other types: order statistics by nth_element over the finite values, or,
// for more than kMaxSample values, over a stratified sample of kMaxSample of
// them (one value at a hashed place in each of kMaxSample equal blocks, so
// that no stride of the grid aliases): the 0.1 and 99.9 percentiles of 2^24
// samples are within about 1e-5 of their rank, while copying and selecting
// over the billions of values of a large volume would take minutes. The
// minimum, maximum and the distinct-value test read every value.
template <typename T>
bool SortedRange(const T* values, size_t count, int stride, double range[2])
{
  double lo = std::numeric_limits<double>::infinity(), hi = -lo;
  size_t finiteCount = 0;
  std::unordered_set<double> distinct;
  for (size_t i = 0; i < count; ++i)
  {
    const double v = static_cast<double>(values[i * stride]);
    if (std::isfinite(v))
    {
      ++finiteCount;
      lo = std::min(lo, v);
      hi = std::max(hi, v);
      if (distinct.size() <= kMaxDistinct)
      {
        distinct.insert(v);
      }
    }
  }
  if (finiteCount == 0)
  {
    return false;
  }
  if (lo == hi || distinct.size() <= kMaxDistinct)
  {
    range[0] = lo;
    range[1] = hi;
    return true;
  }
  std::vector<double> finite;
  if (count <= kMaxSample)
  {
    finite.reserve(finiteCount);
    for (size_t i = 0; i < count; ++i)
    {
      const double v = static_cast<double>(values[i * stride]);
      if (std::isfinite(v))
      {
        finite.push_back(v);
      }
    }
  }
  else
  {
    finite.reserve(kMaxSample);
    for (size_t j = 0; j < kMaxSample; ++j)
    {
      const size_t first = j * count / kMaxSample, last = (j + 1) * count / kMaxSample;
      const double v = static_cast<double>(values[(first + Hash(j) % (last - first)) * stride]);
      if (std::isfinite(v))
      {
        finite.push_back(v);
      }
    }
    if (finite.empty())
    {
      range[0] = lo;
      range[1] = hi;
      return true;
    }
  }
  auto at = [&](size_t k) {
    std::nth_element(finite.begin(), finite.begin() + static_cast<std::ptrdiff_t>(k), finite.end());
    return finite[k];
  };
  const size_t n = finite.size();
  const double plo = Percentile(n, kLowPercentile, at);
  const double phi = Percentile(n, kHighPercentile, at);
  range[0] = plo < phi ? plo : lo;
  range[1] = plo < phi ? phi : hi;
  return true;
}
}

namespace mcvol
{
bool RobustRange(vtkDataArray* array, int component, double range[2])
{
  if (!array || component < 0 || component >= array->GetNumberOfComponents())
  {
    return false;
  }
  const size_t count = static_cast<size_t>(array->GetNumberOfTuples());
  const int stride = array->GetNumberOfComponents();
  void* pointer = array->GetVoidPointer(0);
  switch (array->GetDataType())
  {
    case VTK_UNSIGNED_CHAR:
      return HistogramRange(static_cast<const unsigned char*>(pointer) + component, count, stride, range);
    case VTK_SIGNED_CHAR:
      return HistogramRange(static_cast<const signed char*>(pointer) + component, count, stride, range);
    case VTK_CHAR:
      return HistogramRange(static_cast<const signed char*>(pointer) + component, count, stride, range);
    case VTK_SHORT:
      return HistogramRange(static_cast<const short*>(pointer) + component, count, stride, range);
    case VTK_UNSIGNED_SHORT:
      return HistogramRange(static_cast<const unsigned short*>(pointer) + component, count, stride, range);
    case VTK_FLOAT:
      return SortedRange(static_cast<const float*>(pointer) + component, count, stride, range);
    case VTK_DOUBLE:
      return SortedRange(static_cast<const double*>(pointer) + component, count, stride, range);
    case VTK_INT:
      return SortedRange(static_cast<const int*>(pointer) + component, count, stride, range);
    case VTK_UNSIGNED_INT:
      return SortedRange(static_cast<const unsigned int*>(pointer) + component, count, stride, range);
    case VTK_LONG_LONG:
      return SortedRange(static_cast<const long long*>(pointer) + component, count, stride, range);
    case VTK_UNSIGNED_LONG_LONG:
      return SortedRange(static_cast<const unsigned long long*>(pointer) + component, count, stride, range);
    default:
      return false;
  }
}

std::string RobustRanges(vtkImageData* image)
{
  std::ostringstream out;
  out << std::setprecision(17);
  vtkPointData* pd = image ? image->GetPointData() : nullptr;
  for (int a = 0; pd && a < pd->GetNumberOfArrays(); ++a)
  {
    vtkDataArray* array = pd->GetArray(a);
    if (!array || !array->GetName() || !*array->GetName())
    {
      continue;
    }
    for (int c = 0; c < array->GetNumberOfComponents(); ++c)
    {
      double range[2];
      if (RobustRange(array, c, range))
      {
        out << array->GetName() << '\t' << c << '\t' << range[0] << '\t' << range[1] << '\n';
      }
    }
  }
  return out.str();
}
}
