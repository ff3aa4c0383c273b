// SPDX-License-Identifier: BSD-3-Clause
#include "View.h"

#include "vtkCamera.h"
#include "vtkImageData.h"
#include "vtkLight.h"
#include "vtkLightCollection.h"
#include "vtkMatrix3x3.h"
#include "vtkMatrix4x4.h"
#include "vtkNew.h"
#include "vtkOpenGLRenderWindow.h"
#include "vtkProp3D.h"
#include "vtkPropCollection.h"
#include "vtkRenderer.h"
#include "vtkVolume.h"
#include "vtkVolumeProperty.h"

#include <algorithm>
#include <cmath>
#include <sstream>

namespace mcvol
{
namespace adapter
{
//------------------------------------------------------------------------------
Viewport GetViewport(vtkRenderer* ren)
{
  Viewport v;
  ren->GetTiledSizeAndOrigin(&v.Width, &v.Height, &v.X0, &v.Y0);
  return v;
}

//------------------------------------------------------------------------------
bool CheckScale(const double spacing[3], const double bounds[6], std::string& error)
{
  double size = 0.0, far = 0.0;
  for (int a = 0; a < 3; ++a)
  {
    size = std::max(size, bounds[2 * a + 1] - bounds[2 * a]);
    far = std::max({ far, std::abs(bounds[2 * a]), std::abs(bounds[2 * a + 1]) });
  }
  const double finest = std::min({ std::abs(spacing[0]), std::abs(spacing[1]), std::abs(spacing[2]) });
  std::ostringstream msg;
  if (!(far <= kMaximumOriginInSpacings * finest))
  {
    msg << "The volume lies too far from the world origin for its voxel size: its bounds reach " << far
        << " with a smallest spacing of " << finest
        << ", and double precision cannot place rays there within 1/64 of a voxel (at most 2^46 spacings from the "
           "origin render). Move the image's origin (or the prop's position) closer to 0.";
    error = msg.str();
    return false;
  }
  if (!(size >= kMinimumVolumeSize))
  {
    msg << "The volume is " << size << " world units across: VTK's camera does not show anything smaller than "
        << kMinimumVolumeSize
        << " (its clipping range is at least 1e-20 thick), so nothing would be drawn. Scale the spacing up "
           "(and the transfer functions' unit distance with it).";
    error = msg.str();
    return false;
  }
  return true;
}

//------------------------------------------------------------------------------
bool ComputeCamera(vtkRenderer* ren, vtkVolume* vol, vtkImageData* image, const int extent[6], const Viewport& viewport,
  Camera& camera, std::string& error)
{
  camera.width = viewport.Width;
  camera.height = viewport.Height;
  vtkCamera* cam = ren->GetActiveCamera();
  // World to normalised device coordinates, as vtkOpenGLCamera computes it.
  vtkMatrix4x4* worldToNDC = cam->GetCompositeProjectionTransformMatrix(ren->GetTiledAspectRatio(), -1, 1);
  vtkNew<vtkMatrix4x4> ndcToWorld;
  if (worldToNDC->Determinant() == 0.0)
  {
    std::ostringstream msg;
    const double* clip = cam->GetClippingRange();
    msg << "The camera's projection is singular (clipping range " << clip[0] << " to " << clip[1] << ", view angle "
        << cam->GetViewAngle() << ", parallel scale " << cam->GetParallelScale()
        << "): set a clipping range with near < far and a non-zero view angle or parallel scale.";
    error = msg.str();
    return false;
  }
  vtkMatrix4x4::Invert(worldToNDC, ndcToWorld);

  // World -> volume model coordinates (the prop's matrix) -> physical image
  // coordinates -> continuous index, with voxel 0 at the extent's start.
  vtkMatrix4x4* propMatrix = vol->GetMatrix();
  if (propMatrix->Determinant() == 0.0)
  {
    error = "The volume's matrix is singular (a zero scale?).";
    return false;
  }
  const double* spacing = image->GetSpacing();
  if (!(spacing[0] != 0.0 && spacing[1] != 0.0 && spacing[2] != 0.0 && std::isfinite(spacing[0]) &&
        std::isfinite(spacing[1]) && std::isfinite(spacing[2])) ||
    image->GetDirectionMatrix()->Determinant() == 0.0)
  {
    std::ostringstream msg;
    msg << "The image's spacing (" << spacing[0] << ", " << spacing[1] << ", " << spacing[2]
        << ") or direction matrix is degenerate: every axis needs a non-zero, "
           "finite spacing and the directions must be independent.";
    error = msg.str();
    return false;
  }
  vtkNew<vtkMatrix4x4> worldToModel;
  vtkMatrix4x4::Invert(propMatrix, worldToModel);
  vtkNew<vtkMatrix4x4> worldToIndex;
  vtkMatrix4x4::Multiply4x4(image->GetPhysicalToIndexMatrix(), worldToModel, worldToIndex);
  for (int r = 0; r < 3; ++r)
  {
    for (int k = 0; k < 4; ++k)
    {
      double v = worldToIndex->GetElement(r, k);
      if (k == 3)
      {
        v -= extent[2 * r];
      }
      camera.worldToIndex[4 * r + k] = v;
    }
  }
  for (int r = 0; r < 4; ++r)
  {
    for (int k = 0; k < 4; ++k)
    {
      camera.invViewProj[4 * r + k] = ndcToWorld->GetElement(r, k);
    }
  }
  return true;
}

//------------------------------------------------------------------------------
bool ReadDepth(vtkOpenGLRenderWindow* window, const Viewport& viewport, std::vector<float>& depth)
{
  depth.resize(static_cast<size_t>(viewport.Width) * static_cast<size_t>(viewport.Height));
  if (window->GetZbufferData(viewport.X0, viewport.Y0, viewport.X0 + viewport.Width - 1,
        viewport.Y0 + viewport.Height - 1, depth.data()) != VTK_OK)
  {
    std::fill(depth.begin(), depth.end(), 1.f);
    return false;
  }
  return true;
}

//------------------------------------------------------------------------------
bool HasOpaqueGeometry(vtkRenderer* ren)
{
  vtkPropCollection* props = ren ? ren->GetViewProps() : nullptr;
  if (!props)
  {
    return true; // cannot tell: read the depth buffer
  }
  vtkCollectionSimpleIterator it;
  props->InitTraversal(it);
  while (vtkProp* prop = props->GetNextProp(it))
  {
    if (!prop->GetVisibility() || !vtkProp3D::SafeDownCast(prop) || vtkVolume::SafeDownCast(prop))
    {
      continue;
    }
    // A prop with no geometry (uninitialized bounds: ParaView keeps visible
    // actors with empty inputs in every render view) cannot occlude anything,
    // and reading the depth buffer back is slow with software OpenGL (a
    // large share of a frame).
    const double* bounds = prop->GetBounds();
    if (bounds && !(bounds[0] <= bounds[1] && bounds[2] <= bounds[3] && bounds[4] <= bounds[5]))
    {
      continue;
    }
    return true;
  }
  return false;
}

//------------------------------------------------------------------------------
LightingDesc CollectLighting(vtkRenderer* ren, vtkVolumeProperty* property, const LightingSettings& settings,
  int numChannels, vtkMTimeType& lightsMTime)
{
  LightingDesc lighting;
  lightsMTime = 0;
  if (!property || !property->GetShade())
  {
    return lighting;
  }
  vtkLightCollection* lights = ren->GetLights();
  lightsMTime = lights->GetMTime();
  vtkCollectionSimpleIterator it;
  lights->InitTraversal(it);
  while (vtkLight* light = lights->GetNextLight(it))
  {
    lightsMTime = std::max(lightsMTime, light->GetMTime());
    if (!light->GetSwitch() || lighting.lights.size() >= size_t(kMaxLights))
    {
      continue;
    }
    LightDesc ld;
    double pos[3], focal[3];
    light->GetTransformedPosition(pos);
    light->GetTransformedFocalPoint(focal);
    ld.point = light->GetPositional() != 0;
    for (int a = 0; a < 3; ++a)
    {
      ld.vector[a] = ld.point ? pos[a] : pos[a] - focal[a];
      ld.color[a] = light->GetDiffuseColor()[a];
    }
    ld.intensity = light->GetIntensity();
    lighting.lights.push_back(ld);
  }
  std::copy(settings.AmbientRadiance, settings.AmbientRadiance + 3, lighting.ambient);
  for (int c = 0; c < numChannels; ++c)
  {
    lighting.albedo.push_back(static_cast<float>(settings.Albedo[c]));
    lighting.anisotropy.push_back(static_cast<float>(settings.Anisotropy[c]));
  }
  lighting.shadows = settings.Shadows;
  lighting.deltaShadows = settings.DeltaShadows;
  lighting.cacheShadows = settings.CacheShadows;
  lighting.cacheSpacing = static_cast<float>(settings.CacheSpacing);
  lighting.maxDepth = settings.MaxScatteringDepth;
  lighting.gradientShading = settings.GradientShading;
  lighting.shininess = static_cast<float>(settings.Shininess);
  return lighting;
}
} // namespace adapter
} // namespace mcvol
