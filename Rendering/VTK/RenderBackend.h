// SPDX-License-Identifier: BSD-3-Clause
#pragma once

#include "mcvol/Renderer.h"

#include <memory>
#include <string>

namespace mcvol
{
namespace adapter
{
/**
 * Stage 3 of vtkMultiChannelVolumeMapper::Render: the Monte Carlo backend
 * (CPU or CUDA) the mapper's Backend setting asks for, created once per
 * setting, and the words that tell the user which one runs and why.
 * `backend` is a Backend value (vtkMultiChannelVolumeMapper::BACKEND_*).
 */
class RenderBackend
{
public:
  /// Makes sure the renderer for `backend` exists, or none when the mapper
  /// traces without a backend (`uses` false: the ray-marching reference).
  /// False, with `error`, when that backend cannot be had.
  bool Ensure(bool uses, int backend, std::string& error);

  /// The backend that `backend` means here: Auto follows the environment
  /// variable MCVOL_BACKEND (cuda or cpu) when it is set; an explicit choice
  /// is kept.
  static int Effective(int backend);

  /// The CUDA device the next renderer takes (-1: the default, by local MPI
  /// rank); a change gives the current renderer back.
  void SetCudaDevice(int device);

  /// The renderer (nullptr when none is used or it could not be created).
  Renderer* Get() const { return this->Instance.get(); }

  /// "cpu", "cuda" or "none": what runs, or what create() would pick for a
  /// setting not rendered with yet.
  std::string ActiveName(bool uses, int backend) const;
  /// A sentence: which backend and why (auto's reason, or why unavailable).
  std::string Report(bool uses, int backend) const;
  /// For PrintSelf: the active renderer's name, or "(none yet)".
  const char* PrintName(int backend) const;

  /// Gives back a device backend (its copy of the data and grids in GPU
  /// memory). True if one was released: the image on it is gone too.
  bool ReleaseDevice();

private:
  std::unique_ptr<Renderer> Instance;
  int InstanceBackend = -1; // the backend value Instance was created for
  int CudaDevice = -1;      // the CUDA device asked for (-1: by local rank)
  std::string Why;          // from Renderer::create when Instance was made
};
} // namespace adapter
} // namespace mcvol
