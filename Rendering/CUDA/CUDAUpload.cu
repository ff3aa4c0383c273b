// SPDX-License-Identifier: BSD-3-Clause
//
// Device copies of the channels: one dense array per channel in its native
// type (strided channels packed, float64 converted to float32) and, for
// texture sampling, a 3D texture made from that array.
#include "CUDAInternal.h"

#include <algorithm>
#include <cstring>
#include <limits>
#include <type_traits>
#include <vector>

namespace mcvol
{
namespace
{
/// Narrow-integer storage of a channel for the texture path.
cudaChannelFormatDesc formatOf(ScalarType t, float& scale, cudaTextureReadMode& mode)
{
  return visitScalarType(t,
    [&](auto tag)
    {
      using T = typename decltype(tag)::type;
      if constexpr (std::is_integral<T>::value)
      {
        // Normalised reads return v / max(T). For int16 they map v to
        // max(v / 32767, -1): -32768 comes back as -32767, inside every
        // macrocell range that holds -32768.
        scale = float(std::numeric_limits<T>::max());
        mode = cudaReadModeNormalizedFloat;
        return cudaCreateChannelDesc<T>();
      }
      else
      {
        scale = 1.f;
        mode = cudaReadModeElementType;
        return cudaCreateChannelDesc<float>();
      }
    });
}
} // namespace

void CUDARenderer::Internal::uploadChannels(const Scene& scene)
{
  const int* d = scene.dims();
  const size_t voxels = size_t(d[0]) * size_t(d[1]) * size_t(d[2]);
  std::vector<uint8_t> staging;
  for (int n = scene.numChannels(); n < this->NumChannels; ++n)
  {
    this->Channels[n].bytes.release();
    this->Channels[n].releaseTexture();
  }
  for (int n = 0; n < scene.numChannels(); ++n)
  {
    const ChannelSource& src = scene.channel(n);
    DeviceChannel& dc = this->Channels[n];
    dc.releaseTexture();
    const void* host = src.data;
    dc.format = src.format;
    if (src.format == ChannelFormat::Extinction)
    {
      // Pre-classified: 4 floats per voxel, packed (stride 4) in linear
      // memory; sampled in software (sampleClassified), no texture.
      staging.resize(voxels * 4 * sizeof(float));
      float* out = reinterpret_cast<float*>(staging.data());
      const float* in = static_cast<const float*>(src.data);
      for (size_t v = 0; v < voxels; ++v)
      {
        std::memcpy(out + 4 * v, in + v * size_t(src.stride), 4 * sizeof(float));
      }
      const size_t bytes = voxels * 4 * sizeof(float);
      dc.type = ScalarType::Float32;
      dc.bytes.resize(bytes);
      MCVOL_CUDA(cudaMemcpy(dc.bytes.ptr, staging.data(), bytes, cudaMemcpyHostToDevice));
      ++this->Updates.dataUploads;
      continue;
    }
    if (src.type == ScalarType::Float64)
    {
      // Doubles become floats relative to the channel's offset, exactly as
      // fetchVoxel() converts them, so both backends see the same values.
      staging.resize(voxels * sizeof(float));
      float* out = reinterpret_cast<float*>(staging.data());
      const double* in = static_cast<const double*>(src.data);
      for (size_t v = 0; v < voxels; ++v)
      {
        out[v] = float(in[v * size_t(src.stride)] - src.offset);
      }
      host = staging.data();
      dc.type = ScalarType::Float32;
    }
    else
    {
      dc.type = src.type;
      if (src.stride != 1)
      {
        const size_t es = size_t(scalarTypeSize(src.type));
        staging.resize(voxels * es);
        const uint8_t* in = static_cast<const uint8_t*>(src.data);
        for (size_t v = 0; v < voxels; ++v)
        {
          std::memcpy(staging.data() + v * es, in + v * size_t(src.stride) * es, es);
        }
        host = staging.data();
      }
    }
    const size_t bytes = voxels * size_t(scalarTypeSize(dc.type));
    dc.bytes.resize(bytes);
    MCVOL_CUDA(cudaMemcpy(dc.bytes.ptr, host, bytes, cudaMemcpyHostToDevice));
    ++this->Updates.dataUploads;
  }
  std::copy(d, d + 3, this->Dims);
  this->NumChannels = scene.numChannels();
  this->TexturesBuilt = false;
}

void CUDARenderer::Internal::buildTextures()
{
  MCVOL_CUDA(cudaDeviceSynchronize()); // no kernel may still read the old textures
  const int* d = this->Dims;
  const bool fits =
    d[0] <= this->Props.maxTexture3D[0] && d[1] <= this->Props.maxTexture3D[1] && d[2] <= this->Props.maxTexture3D[2];
  for (int n = 0; n < this->NumChannels; ++n)
  {
    DeviceChannel& dc = this->Channels[n];
    dc.releaseTexture();
    if (!fits || dc.format == ChannelFormat::Extinction)
    {
      // Too large for a 3D texture, or pre-classified (always software
      // sampling): this channel samples global memory.
      continue;
    }
    cudaTextureReadMode mode;
    cudaChannelFormatDesc fmt = formatOf(dc.type, dc.textureScale, mode);
    const cudaExtent ext = make_cudaExtent(size_t(d[0]), size_t(d[1]), size_t(d[2]));
    const cudaError_t e = cudaMalloc3DArray(&dc.array, &fmt, ext);
    if (e == cudaErrorMemoryAllocation)
    {
      // No room for a second copy: this channel samples global memory.
      (void)cudaGetLastError();
      dc.array = nullptr;
      ++this->Updates.textureFallbacks;
      continue;
    }
    check(e, "cudaMalloc3DArray");
    const size_t es = size_t(scalarTypeSize(dc.type));
    dc.arrayBytes = size_t(d[0]) * size_t(d[1]) * size_t(d[2]) * es;
    cudaMemcpy3DParms copy{};
    copy.srcPtr = make_cudaPitchedPtr(dc.bytes.ptr, size_t(d[0]) * es, size_t(d[0]), size_t(d[1]));
    copy.dstArray = dc.array;
    copy.extent = ext;
    copy.kind = cudaMemcpyDeviceToDevice;
    MCVOL_CUDA(cudaMemcpy3D(&copy));
    cudaResourceDesc res{};
    res.resType = cudaResourceTypeArray;
    res.res.array.array = dc.array;
    cudaTextureDesc td{};
    td.addressMode[0] = td.addressMode[1] = td.addressMode[2] = cudaAddressModeClamp;
    td.readMode = mode;
    td.normalizedCoords = 0;
    td.filterMode = cudaFilterModeLinear;
    MCVOL_CUDA(cudaCreateTextureObject(&dc.linear, &res, &td, nullptr));
    td.filterMode = cudaFilterModePoint;
    MCVOL_CUDA(cudaCreateTextureObject(&dc.point, &res, &td, nullptr));
  }
  this->TexturesBuilt = true;
}
} // namespace mcvol
