// SPDX-License-Identifier: BSD-3-Clause
// The backend factory (Renderer::create, Renderer::cudaAvailable): the only
// code that names every backend, so the backends do not depend on each other.
#include "mcvol/CPURenderer.h"
#include "mcvol/Renderer.h"

#ifdef MCVOL_WITH_CUDA
#include "mcvol/CUDARenderer.h"
#endif

#include <stdexcept>

namespace mcvol
{
bool Renderer::cudaAvailable(std::string* why, int cudaDevice)
{
#ifdef MCVOL_WITH_CUDA
  std::string how;
  const int device = cudaDevice >= 0 ? cudaDevice : CUDARenderer::defaultDevice(&how);
  const bool usable = CUDARenderer::deviceUsable(why, device);
  if (usable && why)
  {
    *why += cudaDevice >= 0 ? ", device " + std::to_string(device) + " (requested)" : ", " + how;
  }
  return usable;
#else
  (void)cudaDevice;
  if (why)
  {
    *why = "this build of mcvol has no CUDA backend (" MCVOL_NO_CUDA_REASON ")";
  }
  return false;
#endif
}

std::unique_ptr<Renderer> Renderer::create(Backend requested, std::string* why, int cudaDevice)
{
  std::string cudaWhy;
  switch (requested)
  {
    case Backend::CPU:
      if (why)
      {
        *why = "CPU backend (requested)";
      }
      return std::unique_ptr<Renderer>(new CPURenderer());
    case Backend::CUDA:
      if (!cudaAvailable(&cudaWhy, cudaDevice))
      {
        throw std::runtime_error("mcvol: the CUDA backend was requested but " + cudaWhy);
      }
#ifdef MCVOL_WITH_CUDA
      if (why)
      {
        *why = "CUDA backend (requested; " + cudaWhy + ")";
      }
      return std::unique_ptr<Renderer>(new CUDARenderer(cudaDevice));
#else
      break;
#endif
    case Backend::Auto:
    default:
      if (!cudaAvailable(&cudaWhy, cudaDevice))
      {
        if (why)
        {
          *why = "CPU backend (auto: " + cudaWhy + ")";
        }
        return std::unique_ptr<Renderer>(new CPURenderer());
      }
#ifdef MCVOL_WITH_CUDA
      if (why)
      {
        *why = "CUDA backend (auto: " + cudaWhy + ")";
      }
      return std::unique_ptr<Renderer>(new CUDARenderer(cudaDevice));
#else
      break;
#endif
  }
  throw std::runtime_error("mcvol: no backend could be created");
}
} // namespace mcvol
