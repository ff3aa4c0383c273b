// SPDX-License-Identifier: BSD-3-Clause
#include "RenderBackend.h"

#include "mcvol/Types.h"

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
  try
  {
    this->Instance = Renderer::create(static_cast<Backend>(backend), &this->Why);
  }
  catch (const std::exception& e)
  {
    this->Why = e.what();
    error = std::string("Backend ") + BackendLabel(backend) + " is not available: " + e.what();
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
    if (static_cast<Backend>(backend) == Backend::CPU || !Renderer::cudaAvailable(&why))
    {
      return static_cast<Backend>(backend) == Backend::CUDA ? "none" : "cpu";
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
  const bool cuda = Renderer::cudaAvailable(&why);
  switch (static_cast<Backend>(backend))
  {
    case Backend::CPU:
      return "CPU backend (requested)";
    case Backend::CUDA:
      return cuda ? "CUDA backend (requested; " + why + ")" : "unavailable: the CUDA backend was requested but " + why;
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
  if (this->Instance && this->Instance->buildsAccelerationOnDevice())
  {
    this->Instance.reset();
    this->InstanceBackend = -1;
    return true;
  }
  return false;
}
} // namespace adapter
} // namespace mcvol
