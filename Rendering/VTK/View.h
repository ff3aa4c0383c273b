// SPDX-License-Identifier: BSD-3-Clause
#pragma once

#include "vtkType.h" // For vtkMTimeType

#include "mcvol/Renderer.h"
#include "mcvol/Scene.h"

#include <array>
#include <string>
#include <vector>

class vtkImageData;
class vtkOpenGLRenderWindow;
class vtkRenderer;
class vtkVolume;
class vtkVolumeProperty;

namespace mcvol
{
namespace adapter
{
/**
 * Stage 5 of vtkMultiChannelVolumeMapper::Render: what the renderer's view
 * gives the core: the rays (camera, prop and image matrices), the depth of
 * the opaque geometry already drawn, and the lights.
 */

/// The tile of the render window the renderer draws into.
struct Viewport
{
  int Width = 0;
  int Height = 0;
  int X0 = 0;
  int Y0 = 0;
};

Viewport GetViewport(vtkRenderer* ren);

/**
 * Whether VTK's camera and double precision can place rays on the volume's
 * voxels: the volume must be at least kMinimumVolumeSize across (VTK's camera
 * keeps its clipping range at least 1e-20 thick and culls smaller props, so
 * nothing would be drawn), and no farther from the world origin than
 * kMaximumOriginInSpacings of its smallest spacing (beyond, a double cannot
 * place a point within 1/64 of a voxel). `bounds` are the image's, as
 * vtkMultiChannelVolumeMapper::GetBounds gives them. False with `error`
 * saying why and what to change.
 */
constexpr double kMinimumVolumeSize = 1e-20;
constexpr double kMaximumOriginInSpacings = 70368744177664.0; // 2^46
bool CheckScale(const double spacing[3], const double bounds[6], std::string& error);

/// Rays from the active camera into the image's continuous index space
/// (voxel 0 at the extent's start). False, with `error`, for a singular
/// camera, prop matrix, spacing or direction.
bool ComputeCamera(vtkRenderer* ren, vtkVolume* vol, vtkImageData* image, const int extent[6], const Viewport& viewport,
  Camera& camera, std::string& error);

/// The depth buffer over the viewport (window depth in [0, 1]); false when it
/// could not be read, and `depth` is then all 1 (nothing occludes).
bool ReadDepth(vtkOpenGLRenderWindow* window, const Viewport& viewport, std::vector<float>& depth);

/// True when `ren` draws something besides volumes that can occlude them: a
/// visible 3D prop that is not a vtkVolume and has geometry (initialized
/// bounds, or none reported). Without one the depth buffer
/// holds only the clear value, and reading it back (a full-window
/// glReadPixels) is skipped.
bool HasOpaqueGeometry(vtkRenderer* ren);

/// The mapper's lighting settings (the renderer's lights come on top).
struct LightingSettings
{
  const double* AmbientRadiance = nullptr; ///< 3 values
  const double* Albedo = nullptr;          ///< per channel
  const double* Anisotropy = nullptr;      ///< per channel
  bool Shadows = true;
  bool DeltaShadows = false;
  bool CacheShadows = false;
  double CacheSpacing = 2.0;
  int MaxScatteringDepth = 1;
  bool GradientShading = false;
  double Shininess = 32.0;
};

/// Lighting only with ShadeOn (VTK's volume convention): the renderer's
/// switched-on lights, in world space, and the mapper's settings. Without
/// ShadeOn the result asks for no lighting at all. `lightsMTime` is the
/// lights' time for the accumulation key (0 without ShadeOn).
LightingDesc CollectLighting(vtkRenderer* ren, vtkVolumeProperty* property, const LightingSettings& settings,
  int numChannels, vtkMTimeType& lightsMTime);
} // namespace adapter
} // namespace mcvol
