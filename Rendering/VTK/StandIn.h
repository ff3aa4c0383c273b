// SPDX-License-Identifier: BSD-3-Clause
#pragma once

#include "vtkType.h" // For vtkMTimeType

#include "mcvol/Scene.h"

#include <string>
#include <vector>

class vtkMultiProcessController;

namespace mcvol
{
namespace adapter
{
/**
 * Stage 6b of vtkMultiChannelVolumeMapper::Render: lighting across the
 * pieces of a volume split over processes (ParaView's pvserver and pvbatch
 * under mpiexec, sort-last). Each process renders its own piece, and camera
 * rays stay in it (the pieces' images are composited in visibility order),
 * but light does not: a shadow ray, or a scattered ray, that leaves the
 * piece goes on through a stand-in for the whole volume, gathered from all
 * processes (Scene::setOutside).
 *
 * - Level 0 (exact): every channel's voxels, as stored (native type, the
 *   classified copy of dependent components included), at full resolution:
 *   the stand-in is the serial volume with the same transfer functions, so
 *   the composited image equals the single-process one within the Monte
 *   Carlo error. A transfer-function edit gathers nothing again.
 * - Level k > 0 (coarse): each channel pre-classified (sigma, sigma rgb)
 *   and averaged over blocks of 2^k voxels a side of the whole volume,
 *   extinction averaged so that optical depth is kept (Kraus and Buerger,
 *   Sec. 4.1; the alignment of the pyramids' Box2 levels, Pyramid.h):
 *   16 bytes per channel and coarse voxel, 1/8^k of the voxels. A
 *   transfer-function edit gathers again.
 *
 * Every process contributes the voxels of its piece that no lower-ranked
 * piece holds (pieces share their boundary points), so the voxels are
 * combined by a bitwise OR (exact, bit for bit) or a sum (coarse), through
 * AllReduce in slabs of at most kSlabBytes.
 *
 * Collective: with more than one process, Update() (or its collective
 * part, Synchronize()) is called by every process for every lit render,
 * and it communicates every time (one small AllReduce that decides whether
 * any process's data or tables changed; the gather when so). With one
 * process it does nothing and holds nothing.
 */
class StandIn
{
public:
  /// What this process renders.
  struct Input
  {
    const Scene* Piece = nullptr; ///< level 0's Scene of the piece (updated)
    int Extent[6] = { 0, -1, 0, -1, 0, -1 };
    double Origin[3] = { 0, 0, 0 };
    double Spacing[3] = { 1, 1, 1 };
    vtkMTimeType DataMTime = 0;                         ///< the channels' values
    unsigned long long TablesVersion = 0;               ///< the transfer-function tables
    std::vector<const TransferFunctionDesc*> Functions; ///< per channel (empty: pre-classified)
    int Level = 0;                                      ///< 0 exact, k > 0 coarse, kAutomatic
    double MemoryLimit = 0.0;                           ///< kAutomatic: bytes the stand-in may take
    int MacrocellSize = 8;
    Interpolation Interp = Interpolation::Linear;
    /// Whether the exact stand-in builds host macrocells and majorants (a
    /// stand-in for light paths must: Scene::setOutside reads them). A
    /// caller that renders it as its own Scene on a backend that builds
    /// them on the device turns it off. A coarse stand-in always builds them.
    bool HostAcceleration = true;
  };

  /**
   * Brings the stand-in up to date (collectively) and returns it, or null
   * when there is none to use: one process, or every process holds the
   * whole volume (nothing is split). `changed` is set when the stand-in
   * was rebuilt (the image restarts). The map from the piece's index space
   * to the stand-in's goes to scale and offset. Throws std::runtime_error
   * (after every process has taken part, so that none waits) when the
   * pieces do not fit together: different channels, types, spacing or
   * origin.
   */
  Scene* Update(vtkMultiProcessController* controller, const Input& in, bool& changed, double scale[3],
    double offset[3]);

  /**
   * Update() in its two parts. Synchronize() is the collective one: every
   * process calls it with its input, and it gathers again when any
   * process's piece, tables or level changed (`changed` set then). Use()
   * communicates nothing: it returns the stand-in gathered for this input,
   * or null when there is none or the input changed since the last
   * Synchronize() (the report says so), with its tables brought up to date.
   */
  void Synchronize(vtkMultiProcessController* controller, const Input& in, bool& changed);
  Scene* Use(const Input& in, bool& changed, double scale[3], double offset[3]);

  /// Frees the stand-in (Update() builds it again when asked).
  void Release();

  size_t Bytes() const;
  /// Whether the stand-in built is level 0 (Scene::setOutside's `exact`).
  bool IsExact() const { return this->Have && this->Split && this->Resolved == 0; }
  /// The whole volume's extent (the union of the pieces' extents) of the
  /// last gather; empty (min > max) before one.
  const int* WholeExtent() const { return this->WholeExtentGathered; }
  double LastGatherSeconds() const { return this->GatherSeconds; }
  int Builds() const { return this->BuildCount; }
  const std::string& Report() const;

  /// Input::Level: the finest level (exact first) whose stand-in takes at
  /// most Input::MemoryLimit bytes, chosen from the whole volume's size.
  static constexpr int kAutomatic = -2;

  /// Largest AllReduce message, in bytes.
  static constexpr size_t kSlabBytes = size_t(16) << 20;

private:
  struct Key
  {
    std::vector<ChannelSource> Sources;
    int Extent[6] = { 0, 0, 0, 0, 0, 0 };
    vtkMTimeType DataMTime = 0;
    unsigned long long TablesVersion = 0; ///< coarse levels only
    int Level = -1;
    double MemoryLimit = 0.0; ///< automatic level only
    bool operator==(const Key& o) const;
  };
  void Build(vtkMultiProcessController* controller, const Input& in, const std::vector<double>& all);
  Key KeyOf(const Input& in) const;

  bool Have = false;
  bool Split = false;
  Key Current;
  Scene Whole;
  std::vector<std::vector<unsigned char>> Exact; ///< per channel, level 0
  std::vector<std::vector<float>> Coarse;        ///< per channel, 4 floats a coarse voxel
  int WholeExtentGathered[6] = { 0, -1, 0, -1, 0, -1 };
  double Scale[3] = { 1, 1, 1 };
  double Offset[3] = { 0, 0, 0 };
  unsigned long long TablesApplied = 0;
  double GatherSeconds = 0.0;
  int BuildCount = 0;
  std::string ReportText = "no stand-in";
  bool OutOfDate = false; ///< the last Use() found the input changed since the gather
  int Resolved = -1;      ///< the level built (the automatic one resolved)
};
} // namespace adapter
} // namespace mcvol
