// SPDX-License-Identifier: BSD-3-Clause
#pragma once

#include "vtkSmartPointer.h" // For vtkSmartPointer

#include <memory>
#include <string>

class vtkOpenGLQuadHelper;
class vtkOpenGLRenderWindow;
class vtkTextureObject;
class vtkWindow;

namespace mcvol
{
namespace adapter
{
/**
 * Stage 8 of vtkMultiChannelVolumeMapper::Render: draws the accumulated
 * image (premultiplied float RGBA, the mean over the samples so far) over
 * what the render window holds, with "over" blending and no depth test (the
 * rays already stopped at the opaque geometry's depth).
 */
class FrameCompositor
{
public:
  FrameCompositor();
  ~FrameCompositor();

  /// False, with `error`, when the texture or the shader cannot be made.
  bool Draw(vtkOpenGLRenderWindow* window, int width, int height, const float* rgba, std::string& error);
  /// The same from premultiplied RGBA8 (a device backend's display image:
  /// a quarter of the bytes to copy and upload).
  bool Draw(vtkOpenGLRenderWindow* window, int width, int height, const unsigned char* rgba8, std::string& error);

  void ReleaseGraphicsResources(vtkWindow* window);

private:
  bool DrawImage(vtkOpenGLRenderWindow* window, int width, int height, int type, const void* rgba, std::string& error);

  vtkSmartPointer<vtkTextureObject> Texture;
  std::unique_ptr<vtkOpenGLQuadHelper> Quad;
};
} // namespace adapter
} // namespace mcvol
