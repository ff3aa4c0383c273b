// SPDX-License-Identifier: BSD-3-Clause
#include "StandIn.h"

#include "vtkCommunicator.h"
#include "vtkMultiProcessController.h"

#include "mcvol/Pyramid.h"

#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <cstring>
#include <sstream>
#include <stdexcept>

namespace mcvol
{
namespace adapter
{
namespace
{
/// Doubles each process describes its piece with: extent (6), origin (3),
/// spacing (3), channels, level, then per channel its type and format.
constexpr int kDescribe = 14 + 2 * kMaxChannels;

bool Inside(const int* e, int x, int y, int z)
{
  return x >= e[0] && x <= e[1] && y >= e[2] && y <= e[3] && z >= e[4] && z <= e[5];
}

/// The processes below `me` whose pieces overlap `mine`: a voxel of mine
/// that one of them holds is theirs to send.
std::vector<std::array<int, 6>> LowerOverlaps(const std::vector<double>& all, int me, const int* mine)
{
  std::vector<std::array<int, 6>> out;
  for (int q = 0; q < me; ++q)
  {
    std::array<int, 6> e;
    for (int i = 0; i < 6; ++i)
    {
      e[size_t(i)] = int(all[size_t(q * kDescribe + i)]);
    }
    bool overlap = true;
    for (int a = 0; a < 3; ++a)
    {
      overlap = overlap && e[size_t(2 * a)] <= mine[2 * a + 1] && mine[2 * a] <= e[size_t(2 * a + 1)];
    }
    if (overlap)
    {
      out.push_back(e);
    }
  }
  return out;
}

bool Owned(const std::vector<std::array<int, 6>>& lower, int x, int y, int z)
{
  for (const std::array<int, 6>& e : lower)
  {
    if (Inside(e.data(), x, y, z))
    {
      return false;
    }
  }
  return true;
}

size_t ElementBytes(const ChannelSource& src)
{
  return scalarTypeSize(src.type) * (src.format == ChannelFormat::Extinction ? 4u : 1u);
}

/// One voxel of a pre-classified channel as the Scene reads it (sanitised):
/// NaN transparent, sigma in [0, 1e30], each sigma c in [0, sigma].
void ReadClassified(const ChannelSource& src, int64_t v, float out[4])
{
  double q[4];
  for (int i = 0; i < 4; ++i)
  {
    const int64_t at = v * src.stride + i;
    q[i] = src.type == ScalarType::Float64 ? static_cast<const double*>(src.data)[at]
                                           : double(static_cast<const float*>(src.data)[at]);
  }
  if (std::isnan(q[0]) || std::isnan(q[1]) || std::isnan(q[2]) || std::isnan(q[3]) || !(q[0] > 0.0))
  {
    out[0] = out[1] = out[2] = out[3] = 0.f;
    return;
  }
  const double sigma = std::min(q[0], 1e30);
  out[0] = float(sigma);
  for (int i = 1; i < 4; ++i)
  {
    out[i] = float(std::min(std::max(q[i], 0.0), sigma));
  }
}
/// The finest level whose stand-in of a whole volume of `wd` voxels takes
/// at most `limit` bytes: level 0 holds every channel's voxels as stored,
/// level k 16 bytes per channel and coarse voxel. The coarsest level (a
/// single voxel per channel) is taken when none fits.
int AutomaticLevel(const Scene& piece, const int wd[3], double limit)
{
  double exact = 0.0;
  for (int n = 0; n < piece.numChannels(); ++n)
  {
    exact += double(ElementBytes(piece.channel(n)));
  }
  if (exact * double(wd[0]) * double(wd[1]) * double(wd[2]) <= limit)
  {
    return 0;
  }
  for (int k = 1;; ++k)
  {
    double voxels = 1.0;
    bool single = true;
    for (int a = 0; a < 3; ++a)
    {
      const double f = wd[a] > 1 ? std::ldexp(1.0, k) : 1.0;
      const double c = std::ceil(double(wd[a]) / f);
      voxels *= c;
      single = single && c <= 1.0;
    }
    if (16.0 * double(piece.numChannels()) * voxels <= limit || single || k >= 30)
    {
      return k;
    }
  }
}
} // namespace

bool StandIn::Key::operator==(const Key& o) const
{
  if (this->Sources.size() != o.Sources.size() || this->DataMTime != o.DataMTime ||
    this->TablesVersion != o.TablesVersion || this->Level != o.Level || this->MemoryLimit != o.MemoryLimit)
  {
    return false;
  }
  for (int i = 0; i < 6; ++i)
  {
    if (this->Extent[i] != o.Extent[i])
    {
      return false;
    }
  }
  for (size_t n = 0; n < this->Sources.size(); ++n)
  {
    const ChannelSource& a = this->Sources[n];
    const ChannelSource& b = o.Sources[n];
    if (a.data != b.data || a.type != b.type || a.stride != b.stride || a.offset != b.offset || a.format != b.format ||
      a.scale != b.scale)
    {
      return false;
    }
  }
  return true;
}

const std::string& StandIn::Report() const
{
  static const std::string outOfDate = "stand-in out of date: the piece, its tables or the level changed after the "
                                       "last gather; light paths end at the piece until the next one";
  return this->OutOfDate ? outOfDate : this->ReportText;
}

void StandIn::Release()
{
  this->OutOfDate = false;
  this->Resolved = -1;
  this->Have = false;
  this->Split = false;
  this->Whole = Scene();
  std::fill(this->WholeExtentGathered, this->WholeExtentGathered + 6, 0);
  this->WholeExtentGathered[1] = this->WholeExtentGathered[3] = this->WholeExtentGathered[5] = -1;
  this->Exact.clear();
  this->Exact.shrink_to_fit();
  this->Coarse.clear();
  this->Coarse.shrink_to_fit();
  this->TablesApplied = 0;
  this->ReportText = "no stand-in";
}

size_t StandIn::Bytes() const
{
  if (!this->Have || !this->Split)
  {
    return 0;
  }
  size_t bytes = 0;
  for (const auto& c : this->Exact)
  {
    bytes += c.size();
  }
  for (const auto& c : this->Coarse)
  {
    bytes += c.size() * sizeof(float);
  }
  const MemoryStats m = this->Whole.memory();
  return bytes + m.macrocellBytes + m.majorantBytes + m.tableBytes;
}

StandIn::Key StandIn::KeyOf(const Input& in) const
{
  Key key;
  for (int n = 0; n < in.Piece->numChannels(); ++n)
  {
    key.Sources.push_back(in.Piece->channel(n));
  }
  std::copy(in.Extent, in.Extent + 6, key.Extent);
  key.DataMTime = in.DataMTime;
  // A coarse level's voxels are classified: a table edit gathers again.
  key.TablesVersion = (in.Level == kAutomatic ? this->Resolved : in.Level) > 0 ? in.TablesVersion : 0;
  key.Level = in.Level;
  key.MemoryLimit = in.Level == kAutomatic ? in.MemoryLimit : 0.0;
  return key;
}

Scene* StandIn::Update(
  vtkMultiProcessController* controller, const Input& in, bool& changed, double scale[3], double offset[3])
{
  this->Synchronize(controller, in, changed);
  bool tables = false;
  Scene* standIn = this->Use(in, tables, scale, offset);
  changed = changed || tables;
  return standIn;
}

void StandIn::Synchronize(vtkMultiProcessController* controller, const Input& in, bool& changed)
{
  changed = false;
  if (!controller || controller->GetNumberOfProcesses() < 2 || !in.Piece)
  {
    if (this->Have)
    {
      this->Release();
    }
    return;
  }
  const int numChannels = in.Piece->numChannels();
  const Key key = this->KeyOf(in);
  // Whether any process's piece, tables or level changed: then all gather.
  int stale = this->Have && key == this->Current ? 0 : 1;
  int anyStale = 0;
  controller->AllReduce(&stale, &anyStale, 1, vtkCommunicator::MAX_OP);
  if (!anyStale)
  {
    return;
  }
  std::vector<double> mine(size_t(kDescribe), 0.0);
  for (int i = 0; i < 6; ++i)
  {
    mine[size_t(i)] = in.Extent[i];
  }
  for (int a = 0; a < 3; ++a)
  {
    mine[size_t(6 + a)] = in.Origin[a];
    mine[size_t(9 + a)] = in.Spacing[a];
  }
  mine[12] = numChannels;
  mine[13] = in.Level;
  for (int n = 0; n < numChannels; ++n)
  {
    mine[size_t(14 + 2 * n)] = double(int(in.Piece->channel(n).type));
    mine[size_t(15 + 2 * n)] = double(int(in.Piece->channel(n).format));
  }
  std::vector<double> all(size_t(kDescribe) * size_t(controller->GetNumberOfProcesses()));
  controller->AllGather(mine.data(), all.data(), kDescribe);
  this->Have = false;
  this->OutOfDate = false;
  const auto start = std::chrono::steady_clock::now();
  this->Build(controller, in, all);
  this->GatherSeconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  ++this->BuildCount;
  this->Current = this->KeyOf(in); // with the level the automatic choice resolved to
  this->Have = true;
  this->TablesApplied = 0;
  changed = true;
}

Scene* StandIn::Use(const Input& in, bool& changed, double scale[3], double offset[3])
{
  changed = false;
  if (!this->Have || !this->Split || !in.Piece)
  {
    return nullptr;
  }
  if (!(this->KeyOf(in) == this->Current))
  {
    // Only a caller that changes the data between Synchronize() and the
    // render gets here; the render goes on without light from the others.
    this->OutOfDate = true;
    return nullptr;
  }
  this->OutOfDate = false;
  const int numChannels = in.Piece->numChannels();
  // The exact stand-in classifies through the piece's own tables, set here
  // (a transfer-function edit gathers nothing).
  if (this->Resolved == 0 && this->TablesApplied != in.TablesVersion)
  {
    for (int n = 0; n < numChannels; ++n)
    {
      if (in.Piece->channel(n).format == ChannelFormat::Scalar)
      {
        if (size_t(n) >= in.Functions.size() || !in.Functions[size_t(n)])
        {
          throw std::logic_error("mcvol: the stand-in needs the transfer function of every scalar channel");
        }
        this->Whole.setTransferFunction(n, *in.Functions[size_t(n)]);
      }
    }
    this->TablesApplied = in.TablesVersion;
    changed = true;
  }
  this->Whole.setMacrocellSize(in.MacrocellSize);
  this->Whole.setBlendMode(in.Piece->blendMode());
  this->Whole.setInterpolation(in.Interp);
  // A coarse stand-in only ever serves light paths (Scene::setOutside).
  this->Whole.setHostAcceleration(in.HostAcceleration || this->Resolved != 0);
  this->Whole.update();
  std::copy(this->Scale, this->Scale + 3, scale);
  std::copy(this->Offset, this->Offset + 3, offset);
  return &this->Whole;
}

void StandIn::Build(vtkMultiProcessController* controller, const Input& in, const std::vector<double>& all)
{
  const int procs = controller->GetNumberOfProcesses();
  const int me = controller->GetLocalProcessId();
  const int numChannels = in.Piece->numChannels();
  // The pieces must be parts of one image with the same channels; every
  // process checks the same gathered numbers, so all throw together.
  int whole[6] = { 0, -1, 0, -1, 0, -1 };
  bool split = false;
  for (int q = 0; q < procs; ++q)
  {
    const double* d = all.data() + size_t(q) * kDescribe;
    bool same = int(d[12]) == numChannels && int(d[13]) == in.Level;
    for (int n = 0; same && n < numChannels; ++n)
    {
      same = d[14 + 2 * n] == all[size_t(14 + 2 * n)] && d[15 + 2 * n] == all[size_t(15 + 2 * n)];
    }
    for (int a = 0; same && a < 3; ++a)
    {
      const double s0 = all[size_t(9 + a)];
      same = std::fabs(d[9 + a] - s0) <= 1e-6 * std::fabs(s0) && std::fabs(d[6 + a] - all[size_t(6 + a)]) <= 1e-6 * std::fabs(s0);
    }
    if (!same)
    {
      this->Split = false;
      throw std::runtime_error("mcvol: the pieces of the volume do not fit together (process " + std::to_string(q) +
        " has other channels, types, spacing, origin or stand-in level than process 0); no stand-in for lighting "
        "across processes");
    }
    for (int a = 0; a < 3; ++a)
    {
      const int lo = int(d[2 * a]), hi = int(d[2 * a + 1]);
      whole[2 * a] = q == 0 ? lo : std::min(whole[2 * a], lo);
      whole[2 * a + 1] = q == 0 ? hi : std::max(whole[2 * a + 1], hi);
      split = split || lo != int(all[size_t(2 * a)]) || hi != int(all[size_t(2 * a + 1)]);
    }
  }
  this->Exact.clear();
  this->Coarse.clear();
  this->Whole = Scene();
  this->Split = split;
  std::copy(whole, whole + 6, this->WholeExtentGathered);
  if (!split)
  {
    this->ReportText = "no stand-in: every process holds the whole volume";
    return;
  }
  const int* mine = in.Extent;
  const int* pd = in.Piece->dims();
  for (int a = 0; a < 3; ++a)
  {
    if (pd[a] != mine[2 * a + 1] - mine[2 * a] + 1)
    {
      throw std::logic_error("mcvol: the piece's extent does not match its dimensions");
    }
  }
  const int wd[3] = { whole[1] - whole[0] + 1, whole[3] - whole[2] + 1, whole[5] - whole[4] + 1 };
  const std::vector<std::array<int, 6>> lower = LowerOverlaps(all, me, mine);
  std::vector<ChannelSource> sources(static_cast<size_t>(numChannels));
  std::ostringstream report;
  const int level = in.Level == kAutomatic ? AutomaticLevel(*in.Piece, wd, in.MemoryLimit) : in.Level;
  this->Resolved = level;
  if (in.Level == kAutomatic)
  {
    report << "automatic, within " << in.MemoryLimit / double(1 << 20) << " MiB: ";
  }
  if (level == 0)
  {
    // Exact: every voxel comes from one process (the others send zeros), so
    // a bitwise OR puts together the serial volume bit for bit.
    const size_t voxels = size_t(wd[0]) * size_t(wd[1]) * size_t(wd[2]);
    const size_t sliceVoxels = size_t(wd[0]) * size_t(wd[1]);
    this->Exact.resize(size_t(numChannels));
    std::vector<unsigned char> slab;
    for (int n = 0; n < numChannels; ++n)
    {
      const ChannelSource src = in.Piece->channel(n);
      const size_t elem = ElementBytes(src);
      const size_t typeBytes = scalarTypeSize(src.type);
      std::vector<unsigned char>& out = this->Exact[size_t(n)];
      out.assign(voxels * elem, 0);
      const int slabZ = int(std::max<size_t>(1, kSlabBytes / std::max<size_t>(1, sliceVoxels * elem)));
      for (int z0 = 0; z0 < wd[2]; z0 += slabZ)
      {
        const int z1 = std::min(wd[2], z0 + slabZ);
        slab.assign(size_t(z1 - z0) * sliceVoxels * elem, 0);
        for (int z = z0; z < z1; ++z)
        {
          const int gz = z + whole[4];
          if (gz < mine[4] || gz > mine[5])
          {
            continue;
          }
          for (int gy = mine[2]; gy <= mine[3]; ++gy)
          {
            for (int gx = mine[0]; gx <= mine[1]; ++gx)
            {
              if (!Owned(lower, gx, gy, gz))
              {
                continue;
              }
              const int64_t v = (int64_t(gz - mine[4]) * pd[1] + (gy - mine[2])) * pd[0] + (gx - mine[0]);
              const size_t w = (size_t(z - z0) * size_t(wd[1]) + size_t(gy - whole[2])) * size_t(wd[0]) +
                size_t(gx - whole[0]);
              std::memcpy(slab.data() + w * elem,
                static_cast<const unsigned char*>(src.data) + size_t(v * src.stride) * typeBytes, elem);
            }
          }
        }
        controller->AllReduce(slab.data(), out.data() + size_t(z0) * sliceVoxels * elem, vtkIdType(slab.size()),
          vtkCommunicator::BITWISE_OR_OP);
      }
      ChannelSource s = src;
      s.data = out.data();
      s.stride = src.format == ChannelFormat::Extinction ? 4 : 1;
      sources[size_t(n)] = s;
    }
    this->Whole.setVolume(wd, numChannels, sources.data());
    for (int a = 0; a < 3; ++a)
    {
      this->Scale[a] = 1.0;
      this->Offset[a] = double(mine[2 * a] - whole[2 * a]);
    }
    report << "exact stand-in of the whole volume (" << wd[0] << " x " << wd[1] << " x " << wd[2] << " voxels)";
  }
  else
  {
    // Coarse: extinction and extinction-weighted colour averaged over
    // blocks of f = 2^k voxels a side (an axis of one voxel stays), coarse
    // voxel J centred between fine voxels J f and J f + f - 1.
    int f[3], cd[3];
    for (int a = 0; a < 3; ++a)
    {
      f[a] = wd[a] > 1 ? (1 << std::min(level, 30)) : 1;
      cd[a] = (wd[a] + f[a] - 1) / f[a];
    }
    const size_t coarseVoxels = size_t(cd[0]) * size_t(cd[1]) * size_t(cd[2]);
    const size_t sliceVoxels = size_t(pd[0]) * size_t(pd[1]);
    std::vector<float> classified(sliceVoxels * 4);
    std::vector<float> reduced;
    this->Coarse.resize(size_t(numChannels));
    for (int n = 0; n < numChannels; ++n)
    {
      const ChannelSource src = in.Piece->channel(n);
      std::vector<float>& sums = this->Coarse[size_t(n)];
      sums.assign(coarseVoxels * 4, 0.f);
      const size_t typeBytes = scalarTypeSize(src.type);
      for (int z = 0; z < pd[2]; ++z)
      {
        const int64_t first = int64_t(z) * int64_t(sliceVoxels);
        if (src.format == ChannelFormat::Scalar)
        {
          if (size_t(n) >= in.Functions.size() || !in.Functions[size_t(n)])
          {
            throw std::logic_error("mcvol: the stand-in needs the transfer function of every scalar channel");
          }
          ChannelSource slice = src;
          slice.data = static_cast<const unsigned char*>(src.data) + size_t(first * src.stride) * typeBytes;
          const int sliceDims[3] = { pd[0], pd[1], 1 };
          classifyScalars(slice, sliceDims, *in.Functions[size_t(n)], classified.data());
        }
        else
        {
          for (size_t v = 0; v < sliceVoxels; ++v)
          {
            ReadClassified(src, first + int64_t(v), classified.data() + 4 * v);
          }
        }
        const int gz = z + mine[4];
        const size_t cz = size_t((gz - whole[4]) / f[2]);
        for (int y = 0; y < pd[1]; ++y)
        {
          const int gy = y + mine[2];
          const size_t cy = size_t((gy - whole[2]) / f[1]);
          for (int x = 0; x < pd[0]; ++x)
          {
            const int gx = x + mine[0];
            if (!Owned(lower, gx, gy, gz))
            {
              continue;
            }
            const size_t c = (cz * size_t(cd[1]) + cy) * size_t(cd[0]) + size_t((gx - whole[0]) / f[0]);
            const float* q = classified.data() + 4 * (size_t(y) * size_t(pd[0]) + size_t(x));
            for (int i = 0; i < 4; ++i)
            {
              sums[4 * c + size_t(i)] += q[i];
            }
          }
        }
      }
      const size_t slabFloats = std::max<size_t>(4, (kSlabBytes / sizeof(float)) / 4 * 4);
      for (size_t at = 0; at < sums.size(); at += slabFloats)
      {
        const size_t count = std::min(slabFloats, sums.size() - at);
        reduced.resize(count);
        controller->AllReduce(sums.data() + at, reduced.data(), vtkIdType(count), vtkCommunicator::SUM_OP);
        std::copy(reduced.begin(), reduced.end(), sums.begin() + std::ptrdiff_t(at));
      }
      // Sums to means: each block holds min(f, fine voxels left) per axis.
      for (int cz = 0; cz < cd[2]; ++cz)
      {
        const int nz = std::min(f[2], wd[2] - cz * f[2]);
        for (int cy = 0; cy < cd[1]; ++cy)
        {
          const int ny = std::min(f[1], wd[1] - cy * f[1]);
          for (int cx = 0; cx < cd[0]; ++cx)
          {
            const int nx = std::min(f[0], wd[0] - cx * f[0]);
            const float inv = 1.f / float(nx * ny * nz);
            const size_t c = (size_t(cz) * size_t(cd[1]) + size_t(cy)) * size_t(cd[0]) + size_t(cx);
            for (int i = 0; i < 4; ++i)
            {
              sums[4 * c + size_t(i)] *= inv;
            }
          }
        }
      }
      ChannelSource s;
      s.data = sums.data();
      s.type = ScalarType::Float32;
      s.stride = 4;
      s.format = ChannelFormat::Extinction;
      sources[size_t(n)] = s;
    }
    this->Whole.setVolume(cd, numChannels, sources.data());
    double lo[3], hi[3];
    for (int a = 0; a < 3; ++a)
    {
      const double c = 0.5 * double(f[a] - 1);
      this->Scale[a] = 1.0 / double(f[a]);
      this->Offset[a] = (double(mine[2 * a] - whole[2 * a]) - c) / double(f[a]);
      lo[a] = wd[a] > 1 ? -c / double(f[a]) : -0.5;
      hi[a] = wd[a] > 1 ? (double(wd[a] - 1) - c) / double(f[a]) : 0.5;
    }
    this->Whole.setIndexBounds(lo, hi);
    report << "stand-in of the whole volume at level " << level << " (" << cd[0] << " x " << cd[1] << " x "
           << cd[2] << " voxels of " << wd[0] << " x " << wd[1] << " x " << wd[2] << ")";
  }
  this->ReportText = report.str();
}
} // namespace adapter
} // namespace mcvol
