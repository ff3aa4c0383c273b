// SPDX-License-Identifier: BSD-3-Clause
#include "RenderBackend.h"

#include "mcvol/ray/Types.h"

#include <cstdlib>
#include <cstring>
#include <exception>

namespace mcvol
{
namespace adapter
{
namespace
{
const char* BackendLabel(int backend)
{
  switch (static_cast<Backend>(backend))
  {
    case Backend::CPU:
      return "CPU";
    case Backend::CUDA:
      return "CUDA";
    default:
      return "Auto";
  }
}
} // namespace

//------------------------------------------------------------------------------
int RenderBackend::Effective(int backend)
{
  // The environment decides only what Auto means, never an explicit choice:
  // MCVOL_BACKEND=cuda makes Auto demand CUDA (an error without a device,
  // instead of a quiet fall-back to the CPU), so a test run on a GPU machine
  // proves that it ran on the GPU; MCVOL_BACKEND=cpu keeps Auto off the GPU.
  if (static_cast<Backend>(backend) != Backend::Auto)
  {
    return backend;
  }
  const char* env = std::getenv("MCVOL_BACKEND");
  if (env && (std::strcmp(env, "cuda") == 0 || std::strcmp(env, "CUDA") == 0))
  {
    return static_cast<int>(Backend::CUDA);
  }
  if (env && (std::strcmp(env, "cpu") == 0 || std::strcmp(env, "CPU") == 0))
  {
    return static_cast<int>(Backend::CPU);
  }
  return backend;
}

//------------------------------------------------------------------------------
void RenderBackend::SetCudaDevice(int device)
{
  if (device != this->CudaDevice)
  {
    this->CudaDevice = device;
    this->Instance.reset();
    this->InstanceBackend = -1;
  }
}

//------------------------------------------------------------------------------
bool RenderBackend::Ensure(bool uses, int backend, std::string& error)
{
  if (!uses)
  {
    this->Instance.reset();
    this->InstanceBackend = -1;
    return true;
  }
  if (this->Instance && this->InstanceBackend == backend)
  {
    return true;
  }
  this->Instance.reset();
  this->InstanceBackend = backend;
  const int effective = Effective(backend);
  try
  {
    this->Instance = Renderer::create(static_cast<Backend>(effective), &this->Why, this->CudaDevice);
    const std::string requested = "(requested";
    const size_t at = this->Why.find(requested);
    if (effective != backend && at != std::string::npos)
    {
      // Word it as Report() does before the first render.
      this->Why.replace(at, requested.size(),
        std::string("(auto, MCVOL_BACKEND=") + (static_cast<Backend>(effective) == Backend::CUDA ? "cuda" : "cpu"));
    }
  }
  catch (const std::exception& e)
  {
    this->Why = e.what();
    error = std::string("Backend ") + BackendLabel(effective) + (effective != backend ? " (from MCVOL_BACKEND)" : "") +
      " is not available: " + e.what();
    return false;
  }
  if (!this->Instance)
  {
    error = "No rendering backend could be created.";
    return false;
  }
  return true;
}

//------------------------------------------------------------------------------
std::string RenderBackend::ActiveName(bool uses, int backend) const
{
  if (!uses)
  {
    return "cpu";
  }
  if (this->InstanceBackend != backend)
  {
    // Not rendered with this setting yet: say what create() would pick.
    std::string why;
    const Backend effective = static_cast<Backend>(Effective(backend));
    if (effective == Backend::CPU || !Renderer::cudaAvailable(&why, this->CudaDevice))
    {
      return effective == Backend::CUDA ? "none" : "cpu";
    }
    return "cuda";
  }
  return this->Instance ? this->Instance->name() : "none";
}

//------------------------------------------------------------------------------
std::string RenderBackend::Report(bool uses, int backend) const
{
  if (!uses)
  {
    return "CPU ray marcher (the reference; no Monte Carlo backend is used)";
  }
  if (this->InstanceBackend == backend)
  {
    return this->Instance ? this->Why : "unavailable: " + this->Why;
  }
  // Not rendered with this setting yet: what create() would say (without
  // creating a renderer).
  std::string why;
  const bool cuda = Renderer::cudaAvailable(&why, this->CudaDevice);
  const bool fromEnv = Effective(backend) != backend;
  switch (static_cast<Backend>(Effective(backend)))
  {
    case Backend::CPU:
      return fromEnv ? "CPU backend (auto, MCVOL_BACKEND=cpu)" : "CPU backend (requested)";
    case Backend::CUDA:
      return cuda ? std::string("CUDA backend (") + (fromEnv ? "auto, MCVOL_BACKEND=cuda" : "requested") + "; " + why + ")"
                  : std::string("unavailable: the CUDA backend was requested") +
          (fromEnv ? " (auto, MCVOL_BACKEND=cuda)" : "") + " but " + why;
    default:
      return cuda ? "CUDA backend (auto: " + why + ")" : "CPU backend (auto: " + why + ")";
  }
}

//------------------------------------------------------------------------------
const char* RenderBackend::PrintName(int backend) const
{
  return this->Instance && this->InstanceBackend == backend ? this->Instance->name() : "(none yet)";
}

//------------------------------------------------------------------------------
bool RenderBackend::ReleaseDevice()
{
  if (this->Instance && this->Instance->device()) // a device backend: it holds device memory
  {
    this->Instance.reset();
    this->InstanceBackend = -1;
    return true;
  }
  return false;
}
} // namespace adapter
} // namespace mcvol
