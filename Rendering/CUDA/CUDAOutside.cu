// SPDX-License-Identifier: BSD-3-Clause
//
// CUDA backend: the stand-in of the other pieces of a split volume for lit
// rendering (Scene::setOutside, SceneView::outside) on the device. Its
// scalar channels of finite voxels are textures under texture sampling, as
// the piece's are; the others are packed arrays read in software. Its
// macrocells and majorants are the host's, so the kernels trace the light
// paths in it as the CPU backend does.
#include "CUDAInternal.h"

#include "mcvol/RenderSetup.h"
#include "mcvol/Scene.h"

#include <cmath>
#include <cstring>
#include <vector>

namespace mcvol
{
namespace
{
/// One stand-in channel as a packed host array in the type the device reads
/// (float64 to float32 as the main upload converts it: scalars relative to
/// the offset, pre-classified values as they are), in `staging` where the
/// source cannot be copied as it is. Returns the pointer and sets `bytes`
/// and `type`.
const void* packedChannel(const ChannelSource& src, size_t voxels, std::vector<uint8_t>& staging, size_t& bytes,
  ScalarType& type)
{
  const bool classified = src.format == ChannelFormat::Extinction;
  const size_t per = classified ? 4 : 1;
  if (src.type == ScalarType::Float16)
  {
    throw std::invalid_argument("mcvol (CUDA): the stand-in of the other pieces holds float16 voxels; the CUDA "
                                "backend reads float32 stand-ins only");
  }
  if (src.type == ScalarType::Float64)
  {
    staging.resize(voxels * per * sizeof(float));
    float* out = reinterpret_cast<float*>(staging.data());
    const double* in = static_cast<const double*>(src.data);
    for (size_t v = 0; v < voxels; ++v)
    {
      for (size_t i = 0; i < per; ++i)
      {
        out[v * per + i] = float(in[v * size_t(src.stride) + i] - (classified ? 0.0 : src.offset));
      }
    }
    type = ScalarType::Float32;
    bytes = staging.size();
    return staging.data();
  }
  type = src.type;
  const size_t es = size_t(scalarTypeSize(src.type)) * per;
  bytes = voxels * es;
  if (size_t(src.stride) == per)
  {
    return src.data;
  }
  staging.resize(bytes);
  const uint8_t* in = static_cast<const uint8_t*>(src.data);
  const size_t stride = size_t(src.stride) * size_t(scalarTypeSize(src.type));
  for (size_t v = 0; v < voxels; ++v)
  {
    std::memcpy(staging.data() + v * es, in + v * stride, es);
  }
  return staging.data();
}

/// Whether the voxels (dense, of `type`: packedChannel()'s, float32 or
/// integers) are all finite: hardware filtering would drop a non-finite
/// corner whose weight rounds to 0, where the core's rule makes the sample
/// NaN, so such a channel stays an array.
bool allFinite(const void* voxels, ScalarType type, size_t count)
{
  if (type != ScalarType::Float32)
  {
    return true;
  }
  const float* v = static_cast<const float*>(voxels);
  bool finite = true;
  for (size_t i = 0; i < count; ++i)
  {
    finite = finite && std::isfinite(v[i]);
  }
  return finite;
}
} // namespace

void CUDARenderer::Internal::linkOutside(const Scene& scene, const Camera& camera, SceneView& s)
{
  s.outside = nullptr;
  SceneView o;
  if (!prepareOutside(scene, camera, s, o))
  {
    return;
  }
  const Scene& standIn = *scene.outside();
  OutsideCopy& copy = this->Outside;
  const bool same = copy.SceneId == standIn.id();
  const int* dims = standIn.dims();
  const size_t voxels = size_t(dims[0]) * size_t(dims[1]) * size_t(dims[2]);
  if (!same || copy.ContentVersion != standIn.contentVersion())
  {
    const bool fits = dims[0] <= this->Props.maxTexture3D[0] && dims[1] <= this->Props.maxTexture3D[1] &&
      dims[2] <= this->Props.maxTexture3D[2];
    std::vector<uint8_t> staging;
    for (int n = 0; n < kMaxChannels; ++n)
    {
      copy.Channels[n].release();
      copy.Textures[n].releaseTexture();
    }
    for (int n = 0; n < standIn.numChannels(); ++n)
    {
      const ChannelSource& src = standIn.channel(n);
      size_t bytes = 0;
      ScalarType type = ScalarType::Float32;
      const void* host = packedChannel(src, voxels, staging, bytes, type);
      DeviceChannel& tex = copy.Textures[n];
      tex.type = type;
      tex.format = src.format;
      if (this->Sampling == CudaSampling::Texture && fits && src.format == ChannelFormat::Scalar &&
        allFinite(host, type, voxels) && this->uploadTexture(tex, host, dims))
      {
        continue;
      }
      copy.Channels[n].resize(bytes);
      MCVOL_CUDA(cudaMemcpy(copy.Channels[n].ptr, host, bytes, cudaMemcpyHostToDevice));
    }
    copy.ContentVersion = standIn.contentVersion();
    copy.DataVersion = ~0ull;
  }
  if (!same || copy.DataVersion != standIn.dataVersion())
  {
    const std::vector<float>& tables = standIn.tables();
    const std::vector<float>& majorants = standIn.majorants();
    copy.Tables.resize(tables.size());
    copy.Majorants.resize(majorants.size());
    MCVOL_CUDA(cudaMemcpy(copy.Tables.ptr, tables.data(), tables.size() * sizeof(float), cudaMemcpyHostToDevice));
    MCVOL_CUDA(
      cudaMemcpy(copy.Majorants.ptr, majorants.data(), majorants.size() * sizeof(float), cudaMemcpyHostToDevice));
    copy.DataVersion = standIn.dataVersion();
  }
  copy.SceneId = standIn.id();
  // The per-render view with device pointers: textures where they are held
  // (as the piece's, renderView()), else arrays read in software.
  for (int n = 0; n < standIn.numChannels(); ++n)
  {
    const ChannelSource& src = standIn.channel(n);
    const DeviceChannel& tex = copy.Textures[n];
    ChannelView& c = o.volume.channels[n];
    c.data = copy.Channels[n].ptr; // null for a texture-held channel
    c.type = src.type == ScalarType::Float64 ? ScalarType::Float32 : src.type;
    c.stride = src.format == ChannelFormat::Extinction ? 4 : 1;
    c.offset = 0.0;
    c.texture = tex.array ? (o.volume.nearest ? tex.point : tex.linear) : 0;
    c.voxelTexture = tex.array ? tex.point : 0;
    c.voxelTextureDims[0] = dims[0];
    c.voxelTextureDims[1] = dims[1];
    c.textureScale = tex.array ? tex.textureScale : 1.f;
    c.format = src.format;
  }
  o.tables.texels = copy.Tables.ptr;
  o.grid.majorants = copy.Majorants.ptr;
  o.importance = ImportanceView();
  copy.View.resize(1);
  MCVOL_CUDA(cudaMemcpy(copy.View.ptr, &o, sizeof(SceneView), cudaMemcpyHostToDevice));
  copy.HostView = o;
  s.outside = copy.View.ptr;
}
} // namespace mcvol
