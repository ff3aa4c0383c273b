// SPDX-License-Identifier: BSD-3-Clause
#include "mcvol/CPURenderer.h"
#include "mcvol/Renderer.h"

#include <stdexcept>

namespace mcvol
{
bool Renderer::cudaAvailable(std::string* why)
{
  // The CUDA backend is a later addition; until it is built in, no device is usable.
  if (why)
  {
    *why = "this build of mcvol has no CUDA backend";
  }
  return false;
}

std::unique_ptr<Renderer> Renderer::create(Backend requested, std::string* why)
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
      if (!cudaAvailable(&cudaWhy))
      {
        throw std::runtime_error("mcvol: the CUDA backend was requested but " + cudaWhy);
      }
      break;
    case Backend::Auto:
    default:
      if (!cudaAvailable(&cudaWhy))
      {
        if (why)
        {
          *why = "CPU backend (auto: " + cudaWhy + ")";
        }
        return std::unique_ptr<Renderer>(new CPURenderer());
      }
      break;
  }
  throw std::runtime_error("mcvol: no backend could be created");
}
} // namespace mcvol
