// SPDX-License-Identifier: BSD-3-Clause
#include "vtkMultiChannelRayMarchMapper.h"

#include "vtkObjectFactory.h"

#include "VTK/Settings.h"
#include "mcvol/MarchSetup.h"
#include "mcvol/ray/RayMarch.h"
#include "mcvol/Renderer.h"
#include "mcvol/Scene.h"

#include <chrono>
#include <exception>

vtkStandardNewMacro(vtkMultiChannelRayMarchMapper);

//------------------------------------------------------------------------------
vtkMultiChannelRayMarchMapper::vtkMultiChannelRayMarchMapper() = default;

//------------------------------------------------------------------------------
vtkMultiChannelRayMarchMapper::~vtkMultiChannelRayMarchMapper() = default;

//------------------------------------------------------------------------------
const char* vtkMultiChannelRayMarchMapper::GetCompositingModelAsString()
{
  return this->CompositingModel == OPACITY_COMPOSITING ? "opacity" : "extinction";
}

//------------------------------------------------------------------------------
bool vtkMultiChannelRayMarchMapper::AddsSamples()
{
  return false; // one deterministic image per change
}

//------------------------------------------------------------------------------
bool vtkMultiChannelRayMarchMapper::TraceImage(const mcvol::Scene& scene, const mcvol::Camera& camera,
  const float* depth, mcvol::Renderer* renderer, mcvol::Accumulator& accum, std::string& error)
{
  if (!renderer)
  {
    error = "no rendering backend";
    return false;
  }
  if (accum.samples() > 0)
  {
    // Nothing changed since the image was traced: draw it again.
    this->LastTraceSeconds = 0.0;
    return true;
  }
  mcvol::MarchSettings ms;
  ms.step = this->StepSize;
  ms.jitter = this->Jitter;
  ms.seed = this->EffectiveSeed();
  ms.terminateTransmittance = static_cast<float>(this->TerminationTransmittance);
  ms.skipEmpty = this->EmptySpaceSkipping;
  ms.compositing =
    this->CompositingModel == OPACITY_COMPOSITING ? mcvol::Compositing::Opacity : mcvol::Compositing::Extinction;
  try
  {
    const auto t0 = std::chrono::steady_clock::now();
    mcvol::MarchCounters counters;
    this->LastStepSize = mcvol::marchEffectiveStep(camera, ms);
    // The chosen backend's march (CPU: the OpenMP RayMarcher with the
    // Scene's host grids; CUDA: the same per-ray code over the device copies
    // the backend keeps).
    renderer->march(scene, camera, ms, depth, accum, &counters);
    this->LastSampleCount = static_cast<double>(counters.samples);
    this->LastSkippedCells = static_cast<double>(counters.skippedCells);
    this->LastTraceSeconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  }
  catch (const std::exception& e)
  {
    error = e.what();
    return false;
  }
  return true;
}

//------------------------------------------------------------------------------
void vtkMultiChannelRayMarchMapper::PrintSelf(ostream& os, vtkIndent indent)
{
  this->Superclass::PrintSelf(os, indent);
  os << indent << "StepSize: " << this->StepSize << (this->StepSize == 0.0 ? " (Nyquist)" : "") << "\n";
  os << indent << "LastStepSize: " << this->LastStepSize << "\n";
  os << indent << "Jitter: " << this->Jitter << "\n";
  os << indent << "TerminationTransmittance: " << this->TerminationTransmittance << "\n";
  os << indent << "EmptySpaceSkipping: " << this->EmptySpaceSkipping << "\n";
  os << indent << "CompositingModel: " << this->GetCompositingModelAsString() << "\n";
}

//------------------------------------------------------------------------------
void vtkMultiChannelRayMarchMapper::SetStepSize(double value)
{
  mcvol::adapter::SetClamped(this, "SetStepSize", value, 0.0, VTK_DOUBLE_MAX, this->StepSize);
}

//------------------------------------------------------------------------------
void vtkMultiChannelRayMarchMapper::SetTerminationTransmittance(double value)
{
  mcvol::adapter::SetClamped(this, "SetTerminationTransmittance", value, 0.0, 0.999, this->TerminationTransmittance);
}
