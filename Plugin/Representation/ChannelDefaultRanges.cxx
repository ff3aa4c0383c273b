// SPDX-License-Identifier: BSD-3-Clause
#include "ChannelDefaultRanges.h"

#include "vtkCommunicator.h"
#include "vtkDataArray.h"
#include "vtkDataSetAttributes.h"
#include "vtkImageData.h"
#include "vtkMultiProcessController.h"
#include "vtkPointData.h"
#include "vtkUnsignedCharArray.h"

#include <algorithm>
#include <climits>
#include <cmath>
#include <cstdint>
#include <iomanip>
#include <limits>
#include <set>
#include <sstream>
#include <unordered_set>
#include <utility>
#include <vector>

namespace
{
constexpr double kLowPercentile = 0.1;
constexpr double kHighPercentile = 99.9;
constexpr size_t kMaxDistinct = 256;
constexpr double kMaxSample = double(1 << 24);

// A 64-bit integer hash (splitmix64's finaliser): a sample's place in its block.
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

/// What the processes exchange; with no controller (or one process) every
/// call returns its own argument, so one code path serves both.
struct Exchange
{
  vtkMultiProcessController* Controller = nullptr;

  bool Parallel() const { return this->Controller && this->Controller->GetNumberOfProcesses() > 1; }
  bool Root() const { return !this->Parallel() || this->Controller->GetLocalProcessId() == 0; }

  void Reduce(std::vector<double>& values, int op) const
  {
    if (this->Parallel() && !values.empty())
    {
      std::vector<double> out(values.size());
      this->Controller->AllReduce(values.data(), out.data(), static_cast<vtkIdType>(values.size()), op);
      values.swap(out);
    }
  }
  double Reduce(double value, int op) const
  {
    std::vector<double> v{ value };
    this->Reduce(v, op);
    return v[0];
  }

  /// Every process's values, concatenated in process order: on every process
  /// (toAll) or on process 0 alone (elsewhere empty).
  /// Every process's count and where its part starts, in process order.
  void Layout(vtkIdType length, std::vector<vtkIdType>& lengths, std::vector<vtkIdType>& offsets) const
  {
    const int n = this->Controller->GetNumberOfProcesses();
    lengths.assign(static_cast<size_t>(n), 0);
    offsets.assign(static_cast<size_t>(n), 0);
    this->Controller->AllGather(&length, lengths.data(), 1);
    for (int r = 1; r < n; ++r)
    {
      offsets[size_t(r)] = offsets[size_t(r - 1)] + lengths[size_t(r - 1)];
    }
  }

  /// Every process's values, concatenated in process order: on every process
  /// (toAll) or on process 0 alone (elsewhere empty).
  std::vector<double> Gather(const std::vector<double>& mine, bool toAll) const
  {
    if (!this->Parallel())
    {
      return mine;
    }
    const vtkIdType length = static_cast<vtkIdType>(mine.size());
    std::vector<vtkIdType> lengths, offsets;
    this->Layout(length, lengths, offsets);
    std::vector<double> all(static_cast<size_t>(offsets.back() + lengths.back()));
    // Gathering an empty buffer is fine; a null pointer is not.
    double dummy = 0.0;
    const double* send = mine.empty() ? &dummy : mine.data();
    double* receive = all.empty() ? &dummy : all.data();
    if (toAll)
    {
      this->Controller->AllGatherV(send, receive, length, lengths.data(), offsets.data());
      return all;
    }
    this->Controller->GatherV(send, receive, length, lengths.data(), offsets.data(), 0);
    return this->Root() ? all : std::vector<double>{};
  }

  std::string GatherText(const std::string& mine) const
  {
    if (!this->Parallel())
    {
      return mine;
    }
    const vtkIdType length = static_cast<vtkIdType>(mine.size());
    std::vector<vtkIdType> lengths, offsets;
    this->Layout(length, lengths, offsets);
    std::string all(static_cast<size_t>(offsets.back() + lengths.back()), '\0');
    char dummy = 0;
    this->Controller->AllGatherV(
      mine.empty() ? &dummy : mine.data(), all.empty() ? &dummy : &all[0], length, lengths.data(), offsets.data());
    return all;
  }

  void Broadcast(double* values, int count) const
  {
    if (this->Parallel())
    {
      this->Controller->Broadcast(values, count, 0);
    }
  }
};

/// The points of a piece that count: all of them, less the upper boundary
/// planes it shares with the next piece (ParaView's image pieces share them),
/// or, where the piece carries ghost points, less those marked duplicate.
struct OwnedPoints
{
  int Dims[3] = { 0, 0, 0 };
  int Owned[3] = { 0, 0, 0 };
  const unsigned char* Ghosts = nullptr;

  OwnedPoints(vtkImageData* image, const int whole[6])
  {
    if (!image || image->GetNumberOfPoints() == 0)
    {
      return;
    }
    int ext[6];
    image->GetExtent(ext);
    vtkUnsignedCharArray* ghosts =
      vtkUnsignedCharArray::SafeDownCast(image->GetPointData()->GetArray(vtkDataSetAttributes::GhostArrayName()));
    this->Ghosts = ghosts ? ghosts->GetPointer(0) : nullptr;
    for (int a = 0; a < 3; ++a)
    {
      this->Dims[a] = ext[2 * a + 1] - ext[2 * a] + 1;
      const bool shared = !this->Ghosts && ext[2 * a + 1] < whole[2 * a + 1];
      this->Owned[a] = this->Dims[a] - (shared ? 1 : 0);
    }
  }

  template <typename Fn>
  void ForEach(Fn fn) const
  {
    for (int k = 0; k < this->Owned[2]; ++k)
    {
      for (int j = 0; j < this->Owned[1]; ++j)
      {
        const vtkIdType row = (static_cast<vtkIdType>(k) * this->Dims[1] + j) * this->Dims[0];
        for (int i = 0; i < this->Owned[0]; ++i)
        {
          if (!this->Ghosts || !(this->Ghosts[row + i] & vtkDataSetAttributes::DUPLICATEPOINT))
          {
            fn(row + i);
          }
        }
      }
    }
  }
};

/// Calls fn(value as double) for component `component` of every owned point.
template <typename Fn>
void ForEachValue(vtkDataArray* array, int component, const OwnedPoints& points, Fn fn)
{
  if (!array)
  {
    return;
  }
  const int stride = array->GetNumberOfComponents();
  auto visit = [&](const auto* values)
  { points.ForEach([&](vtkIdType p) { fn(static_cast<double>(values[p * stride + component])); }); };
  void* pointer = array->GetVoidPointer(0);
  switch (array->GetDataType())
  {
    case VTK_UNSIGNED_CHAR:
      return visit(static_cast<const unsigned char*>(pointer));
    case VTK_SIGNED_CHAR:
    case VTK_CHAR:
      return visit(static_cast<const signed char*>(pointer));
    case VTK_SHORT:
      return visit(static_cast<const short*>(pointer));
    case VTK_UNSIGNED_SHORT:
      return visit(static_cast<const unsigned short*>(pointer));
    case VTK_FLOAT:
      return visit(static_cast<const float*>(pointer));
    case VTK_DOUBLE:
      return visit(static_cast<const double*>(pointer));
    case VTK_INT:
      return visit(static_cast<const int*>(pointer));
    case VTK_UNSIGNED_INT:
      return visit(static_cast<const unsigned int*>(pointer));
    case VTK_LONG_LONG:
      return visit(static_cast<const long long*>(pointer));
    case VTK_UNSIGNED_LONG_LONG:
      return visit(static_cast<const unsigned long long*>(pointer));
    default:
      return;
  }
}

/// 1..4: 8- and 16-bit integers, whose order statistics come exactly from a
/// histogram; 5: other supported types; 0: no array or an unsupported type.
int KindOf(vtkDataArray* array)
{
  switch (array ? array->GetDataType() : VTK_VOID)
  {
    case VTK_UNSIGNED_CHAR:
      return 1;
    case VTK_SIGNED_CHAR:
    case VTK_CHAR:
      return 2;
    case VTK_SHORT:
      return 3;
    case VTK_UNSIGNED_SHORT:
      return 4;
    case VTK_FLOAT:
    case VTK_DOUBLE:
    case VTK_INT:
    case VTK_UNSIGNED_INT:
    case VTK_LONG_LONG:
    case VTK_UNSIGNED_LONG_LONG:
      return 5;
    default:
      return 0;
  }
}

bool HistogramRange(
  vtkDataArray* array, int component, int kind, const OwnedPoints& points, const Exchange& x, double range[2])
{
  const bool wide = kind >= 3, isSigned = kind == 2 || kind == 3;
  const size_t bins = wide ? 65536 : 256;
  const double offset = isSigned ? double(bins / 2) : 0.0;
  std::vector<double> histogram(bins, 0.0); // counts, exact in double to 2^53
  ForEachValue(array, component, points, [&](double v) { histogram[static_cast<size_t>(v + offset)] += 1.0; });
  x.Reduce(histogram, vtkCommunicator::SUM_OP);
  double count = 0.0;
  size_t distinct = 0;
  long first = -1, last = -1;
  for (size_t b = 0; b < bins; ++b)
  {
    if (histogram[b] > 0.0)
    {
      count += histogram[b];
      ++distinct;
      first = first < 0 ? static_cast<long>(b) : first;
      last = static_cast<long>(b);
    }
  }
  if (count == 0.0)
  {
    return false;
  }
  const double lo = first - offset, hi = last - offset;
  if (lo == hi || distinct <= kMaxDistinct)
  {
    range[0] = lo;
    range[1] = hi;
    return true;
  }
  // The k-th smallest value: walk the cumulative histogram.
  auto at = [&](size_t k)
  {
    double seen = 0.0;
    for (size_t b = 0; b < bins; ++b)
    {
      seen += histogram[b];
      if (seen > static_cast<double>(k))
      {
        return static_cast<double>(b) - offset;
      }
    }
    return hi;
  };
  const size_t n = static_cast<size_t>(count);
  const double plo = Percentile(n, kLowPercentile, at), phi = Percentile(n, kHighPercentile, at);
  range[0] = plo < phi ? plo : lo;
  range[1] = plo < phi ? phi : hi;
  return true;
}

// Other types: order statistics by nth_element over the finite values, or,
// for more than kMaxSample of them, over a stratified sample of kMaxSample
// (one value at a hashed place in each of kMaxSample equal blocks of the
// finite values, so that no stride of the grid aliases): the 0.1 and 99.9
// percentiles of 2^24 samples are within about 1e-5 of their rank, while
// copying and selecting the billions of values of a large volume would take
// minutes. The minimum, maximum and the distinct-value test read every value.
// Under MPI each process samples its share of the blocks and process 0 picks
// the order statistics.
bool SortedRange(vtkDataArray* array, int component, const OwnedPoints& points, const Exchange& x, double range[2])
{
  double lo = std::numeric_limits<double>::infinity(), hi = -lo, finite = 0.0;
  std::unordered_set<double> distinct;
  ForEachValue(array, component, points,
    [&](double v)
    {
      if (std::isfinite(v))
      {
        finite += 1.0;
        lo = std::min(lo, v);
        hi = std::max(hi, v);
        if (distinct.size() <= kMaxDistinct)
        {
          distinct.insert(v);
        }
      }
    });
  const std::vector<double> counts = x.Gather({ finite }, true);
  double total = 0.0, before = 0.0;
  for (size_t r = 0; r < counts.size(); ++r)
  {
    before += (x.Parallel() && int(r) < x.Controller->GetLocalProcessId()) ? counts[r] : 0.0;
    total += counts[r];
  }
  lo = x.Reduce(lo, vtkCommunicator::MIN_OP);
  hi = x.Reduce(hi, vtkCommunicator::MAX_OP);
  if (total == 0.0)
  {
    return false;
  }
  const std::vector<double> mine(distinct.begin(), distinct.end());
  const std::vector<double> everyones = x.Gather(mine, true);
  const std::set<double> together(everyones.begin(), everyones.end());
  if (lo == hi || together.size() <= kMaxDistinct)
  {
    range[0] = lo;
    range[1] = hi;
    return true;
  }

  std::vector<double> values;
  if (total <= kMaxSample)
  {
    values.reserve(static_cast<size_t>(finite));
    ForEachValue(array, component, points,
      [&](double v)
      {
        if (std::isfinite(v))
        {
          values.push_back(v);
        }
      });
  }
  else
  {
    // Blocks [j N / M, (j + 1) N / M) of the finite values in process order;
    // this process samples those that start among its own.
    const auto blockStart = [&](double j) { return std::floor(j * total / kMaxSample); };
    double j = std::ceil(before * kMaxSample / total);
    while (j < kMaxSample && blockStart(j) < before)
    {
      j += 1.0;
    }
    std::vector<double> targets; // ordinals among this process's finite values
    for (; j < kMaxSample && blockStart(j) < before + finite; j += 1.0)
    {
      const double start = blockStart(j), length = std::max(1.0, blockStart(j + 1.0) - start);
      const double place = start + static_cast<double>(Hash(static_cast<uint64_t>(j)) % static_cast<uint64_t>(length));
      targets.push_back(std::min(place, before + finite - 1.0) - before);
    }
    values.reserve(targets.size());
    double ordinal = 0.0;
    size_t next = 0;
    ForEachValue(array, component, points,
      [&](double v)
      {
        if (std::isfinite(v))
        {
          while (next < targets.size() && targets[next] == ordinal)
          {
            values.push_back(v);
            ++next;
          }
          ordinal += 1.0;
        }
      });
  }
  std::vector<double> all = x.Gather(values, false);
  double percentiles[2] = { lo, hi };
  if (x.Root() && !all.empty())
  {
    auto at = [&](size_t k)
    {
      std::nth_element(all.begin(), all.begin() + static_cast<std::ptrdiff_t>(k), all.end());
      return all[k];
    };
    percentiles[0] = Percentile(all.size(), kLowPercentile, at);
    percentiles[1] = Percentile(all.size(), kHighPercentile, at);
  }
  x.Broadcast(percentiles, 2);
  range[0] = percentiles[0] < percentiles[1] ? percentiles[0] : lo;
  range[1] = percentiles[0] < percentiles[1] ? percentiles[1] : hi;
  return true;
}
}

namespace mcvol
{
std::string RobustRanges(vtkImageData* image, vtkMultiProcessController* controller)
{
  Exchange x;
  x.Controller = controller;
  vtkPointData* pd = image && image->GetNumberOfPoints() > 0 ? image->GetPointData() : nullptr;

  // The whole extent, from the pieces (empty pieces left out).
  std::vector<double> bounds(6);
  int ext[6] = { INT_MAX, INT_MIN, INT_MAX, INT_MIN, INT_MAX, INT_MIN };
  if (pd)
  {
    image->GetExtent(ext);
  }
  for (int a = 0; a < 3; ++a)
  {
    bounds[size_t(2 * a)] = -ext[2 * a]; // a maximum of the negated lower ends
    bounds[size_t(2 * a + 1)] = ext[2 * a + 1];
  }
  x.Reduce(bounds, vtkCommunicator::MAX_OP);
  int whole[6];
  for (int a = 0; a < 3; ++a)
  {
    whole[2 * a] = static_cast<int>(-bounds[size_t(2 * a)]);
    whole[2 * a + 1] = static_cast<int>(bounds[size_t(2 * a + 1)]);
  }
  const OwnedPoints points(pd ? image : nullptr, whole);

  // The arrays and components of every piece, in one order on every process.
  std::ostringstream names;
  for (int a = 0; pd && a < pd->GetNumberOfArrays(); ++a)
  {
    vtkDataArray* array = pd->GetArray(a);
    if (array && array->GetName() && *array->GetName() &&
      std::string(array->GetName()) != vtkDataSetAttributes::GhostArrayName())
    {
      for (int c = 0; c < array->GetNumberOfComponents(); ++c)
      {
        names << array->GetName() << '\t' << c << '\n';
      }
    }
  }
  std::set<std::pair<std::string, int>> keys;
  std::istringstream lines(x.GatherText(names.str()));
  std::string line;
  while (std::getline(lines, line))
  {
    const size_t tab = line.rfind('\t');
    if (tab != std::string::npos)
    {
      keys.emplace(line.substr(0, tab), std::stoi(line.substr(tab + 1)));
    }
  }

  std::ostringstream out;
  out << std::setprecision(17);
  for (const auto& key : keys)
  {
    vtkDataArray* array = pd ? pd->GetArray(key.first.c_str()) : nullptr;
    if (array && key.second >= array->GetNumberOfComponents())
    {
      array = nullptr;
    }
    // The kind every process with the array agrees on: a histogram only
    // where all hold the same 8- or 16-bit type.
    const int kind = KindOf(array);
    const double most = x.Reduce(double(kind), vtkCommunicator::MAX_OP);
    const double least = x.Reduce(kind ? double(kind) : 99.0, vtkCommunicator::MIN_OP);
    if (most == 0.0)
    {
      continue;
    }
    double range[2];
    const bool found = (most == least && most <= 4.0)
      ? HistogramRange(array, key.second, static_cast<int>(most), points, x, range)
      : SortedRange(array, key.second, points, x, range);
    if (found)
    {
      out << key.first << '\t' << key.second << '\t' << range[0] << '\t' << range[1] << '\n';
    }
  }
  return out.str();
}
}
