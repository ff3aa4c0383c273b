// SPDX-License-Identifier: BSD-3-Clause
#include "FrameCompositor.h"

#include "vtkOpenGLQuadHelper.h"
#include "vtkOpenGLRenderWindow.h"
#include "vtkOpenGLShaderCache.h"
#include "vtkOpenGLState.h"
#include "vtkShaderProgram.h"
#include "vtkTextureObject.h"

#include "vtk_glew.h" // For GL enums

namespace mcvol
{
namespace adapter
{
FrameCompositor::FrameCompositor() = default;
FrameCompositor::~FrameCompositor() = default;

//------------------------------------------------------------------------------
bool FrameCompositor::Draw(vtkOpenGLRenderWindow* window, int width, int height, const float* rgba, std::string& error)
{
  return this->DrawImage(window, width, height, VTK_FLOAT, rgba, error);
}

//------------------------------------------------------------------------------
bool FrameCompositor::Draw(
  vtkOpenGLRenderWindow* window, int width, int height, const unsigned char* rgba8, std::string& error)
{
  return this->DrawImage(window, width, height, VTK_UNSIGNED_CHAR, rgba8, error);
}

//------------------------------------------------------------------------------
bool FrameCompositor::DrawImage(
  vtkOpenGLRenderWindow* window, int width, int height, int type, const void* rgba, std::string& error)
{
  if (this->Texture && this->Texture->GetVTKDataType() != type)
  {
    // A texture object keeps the format and type of its first upload: a
    // device backend's RGBA8 image after a float one (or the reverse) needs
    // a new one, else its bytes are read as the old type.
    this->Texture->ReleaseGraphicsResources(window);
    this->Texture = nullptr;
  }
  if (!this->Texture)
  {
    this->Texture = vtkSmartPointer<vtkTextureObject>::New();
  }
  this->Texture->SetContext(window);
  this->Texture->SetMinificationFilter(vtkTextureObject::Nearest);
  this->Texture->SetMagnificationFilter(vtkTextureObject::Nearest);
  this->Texture->SetWrapS(vtkTextureObject::ClampToEdge);
  this->Texture->SetWrapT(vtkTextureObject::ClampToEdge);
  if (!this->Texture->Create2DFromRaw(
        static_cast<unsigned int>(width), static_cast<unsigned int>(height), 4, type, const_cast<void*>(rgba)))
  {
    error = "Could not upload the image to a texture.";
    return false;
  }

  if (!this->Quad)
  {
    // vtkOpenGLRenderUtilities' full-screen-quad template, filled in (that
    // header pulls in GLEW's).
    const char* fs = "//VTK::System::Dec\n"
                     "//VTK::Output::Dec\n"
                     "in vec2 texCoord;\n"
                     "uniform sampler2D mcvolImage;\n"
                     "void main()\n"
                     "{\n"
                     "  gl_FragData[0] = texture(mcvolImage, texCoord);\n"
                     "}\n";
    this->Quad.reset(new vtkOpenGLQuadHelper(window, nullptr, fs, nullptr));
  }
  else
  {
    window->GetShaderCache()->ReadyShaderProgram(this->Quad->Program);
  }
  if (!this->Quad->Program || !this->Quad->Program->GetCompiled())
  {
    error = "Could not build the shader that draws the image.";
    return false;
  }

  vtkOpenGLState* state = window->GetState();
  vtkOpenGLState::ScopedglEnableDisable blendSaver(state, GL_BLEND);
  vtkOpenGLState::ScopedglEnableDisable depthTestSaver(state, GL_DEPTH_TEST);
  vtkOpenGLState::ScopedglBlendFuncSeparate blendFuncSaver(state);
  vtkOpenGLState::ScopedglDepthMask depthMaskSaver(state);
  state->vtkglEnable(GL_BLEND);
  // The image is premultiplied: "over" is (ONE, ONE_MINUS_SRC_ALPHA).
  state->vtkglBlendFuncSeparate(GL_ONE, GL_ONE_MINUS_SRC_ALPHA, GL_ONE, GL_ONE_MINUS_SRC_ALPHA);
  state->vtkglDisable(GL_DEPTH_TEST);
  state->vtkglDepthMask(GL_FALSE);

  this->Texture->Activate();
  this->Quad->Program->SetUniformi("mcvolImage", this->Texture->GetTextureUnit());
  this->Quad->Render();
  this->Texture->Deactivate();
  return true;
}

//------------------------------------------------------------------------------
void FrameCompositor::ReleaseGraphicsResources(vtkWindow* window)
{
  if (this->Quad)
  {
    this->Quad->ReleaseGraphicsResources(window);
    this->Quad.reset();
  }
  if (this->Texture)
  {
    this->Texture->ReleaseGraphicsResources(window);
    this->Texture = nullptr;
  }
}
} // namespace adapter
} // namespace mcvol
