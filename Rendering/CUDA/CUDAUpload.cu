// SPDX-License-Identifier: BSD-3-Clause
//
// Device copies of the channels, each held once: a 3D texture (texture
// sampling) or a dense array in its native type (strided channels packed,
// float64 converted to float32).
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
/// The channel's voxels as one dense host array in the device type (float64
/// converted to float32 relative to the offset, exactly as fetchVoxel()
/// converts them; strided channels packed), using `staging` where needed.
const void* denseHostVoxels(const ChannelSource& src, size_t voxels, std::vector<uint8_t>& staging, ScalarType& type)
{
  if (src.type == ScalarType::Float64)
  {
    staging.resize(voxels * sizeof(float));
    float* out = reinterpret_cast<float*>(staging.data());
    const double* in = static_cast<const double*>(src.data);
    for (size_t v = 0; v < voxels; ++v)
    {
      out[v] = float(in[v * size_t(src.stride)] - src.offset);
    }
    type = ScalarType::Float32;
    return staging.data();
  }
  type = src.type;
  if (src.stride == 1)
  {
    return src.data;
  }
  const size_t es = size_t(scalarTypeSize(src.type));
  staging.resize(voxels * es);
  const uint8_t* in = static_cast<const uint8_t*>(src.data);
  for (size_t v = 0; v < voxels; ++v)
  {
    std::memcpy(staging.data() + v * es, in + v * size_t(src.stride) * es, es);
  }
  return staging.data();
}

} // namespace

bool CUDARenderer::Internal::uploadTexture(DeviceChannel& dc, const void* host, const int* dims)
{
  const int* d = dims ? dims : this->Dims;
  cudaTextureReadMode mode = cudaReadModeElementType;
  cudaChannelFormatDesc fmt;
  size_t es = 0;
  if (dc.format == ChannelFormat::Extinction)
  {
    // Pre-classified: float4 texels (sigma, sigma r, sigma g, sigma b).
    fmt = cudaCreateChannelDesc<float4>();
    dc.textureScale = 1.f;
    es = 4 * sizeof(float);
  }
  else
  {
    fmt = formatOf(dc.type, dc.textureScale, mode);
    es = size_t(scalarTypeSize(dc.type));
  }
  const cudaExtent ext = make_cudaExtent(size_t(d[0]), size_t(d[1]), size_t(d[2]));
  const cudaError_t e = cudaMalloc3DArray(&dc.array, &fmt, ext);
  if (e == cudaErrorMemoryAllocation)
  {
    (void)cudaGetLastError();
    dc.array = nullptr;
    return false;
  }
  check(e, "cudaMalloc3DArray");
  dc.arrayBytes = size_t(d[0]) * size_t(d[1]) * size_t(d[2]) * es;
  cudaMemcpy3DParms copy{};
  copy.srcPtr = make_cudaPitchedPtr(const_cast<void*>(host), size_t(d[0]) * es, size_t(d[0]), size_t(d[1]));
  copy.dstArray = dc.array;
  copy.extent = ext;
  copy.kind = cudaMemcpyHostToDevice;
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
  return true;
}

void CUDARenderer::Internal::uploadChannels(const Scene& scene)
{
  // Each channel is held once on the device, so that a channel costs its
  // voxels once: as a 3D texture when texture sampling is on and it fits
  // (hardware filtering, the faster path: Documentation/performance.md),
  // else as a dense array.
  // Ranges are built from whichever holds it; a texture-held channel found
  // to hold NaN or Inf moves to an array afterwards (moveNonFiniteToArrays()).
  const int* d = scene.dims();
  const size_t voxels = size_t(d[0]) * size_t(d[1]) * size_t(d[2]);
  for (int n = 0; n < this->NumChannels; ++n)
  {
    this->Channels[n].bytes.release();
    this->Channels[n].releaseTexture();
  }
  std::copy(d, d + 3, this->Dims);
  this->NumChannels = scene.numChannels();
  const bool fits =
    d[0] <= this->Props.maxTexture3D[0] && d[1] <= this->Props.maxTexture3D[1] && d[2] <= this->Props.maxTexture3D[2];
  std::vector<uint8_t> staging;
  for (int n = 0; n < scene.numChannels(); ++n)
  {
    DeviceChannel& dc = this->Channels[n];
    dc.nonFinite = false;
    const ChannelSource& src = scene.channel(n);
    dc.format = src.format;
    if (src.format == ChannelFormat::Extinction)
    {
      dc.type = ScalarType::Float32;
      if (this->Sampling == CudaSampling::Texture && fits)
      {
        // A float4 texture: the hardware's trilinear filter is the
        // extinction-based interpolation of (sigma, sigma*colour), one fetch
        // per sample instead of 8 software reads. The voxels are sanitised
        // first (classifiedVoxel: what the software path applies per read,
        // and what the ranges bound), so the filter sees only valid ones; a
        // channel with a NaN voxel stays an array (the NaN rule needs
        // unfiltered reads).
        staging.resize(voxels * 4 * sizeof(float));
        float* out = reinterpret_cast<float*>(staging.data());
        bool finite = true;
        for (size_t v = 0; v < voxels && finite; ++v)
        {
          // float16 levels are widened here: the device holds float32, the
          // same values the CPU reads (classifiedVoxelAt).
          finite = classifiedVoxelAt(src.data, src.type, src.scale, src.stride, int64_t(v), out + 4 * v);
        }
        if (finite)
        {
          if (this->uploadTexture(dc, out))
          {
            ++this->Updates.dataUploads;
            continue;
          }
          ++this->Updates.textureFallbacks;
        }
      }
      // Otherwise 4 floats per voxel, packed (stride 4) in linear memory,
      // sampled in software (sampleClassified).
      const void* packed = src.data;
      if (src.type == ScalarType::Float16)
      {
        // Widened to float32 (raw, unsanitised: sampleClassified sanitises
        // each read as on the host; NaN stays NaN).
        staging.resize(voxels * 4 * sizeof(float));
        float* out = reinterpret_cast<float*>(staging.data());
        const uint16_t* in = static_cast<const uint16_t*>(src.data);
        const float s = float(src.scale);
        for (size_t v = 0; v < voxels; ++v)
        {
          for (int e = 0; e < 4; ++e)
          {
            out[4 * v + size_t(e)] = halfToFloat(in[v * size_t(src.stride) + size_t(e)]) * s;
          }
        }
        packed = staging.data();
      }
      else if (src.stride != 4)
      {
        staging.resize(voxels * 4 * sizeof(float));
        float* out = reinterpret_cast<float*>(staging.data());
        const float* in = static_cast<const float*>(src.data);
        for (size_t v = 0; v < voxels; ++v)
        {
          std::memcpy(out + 4 * v, in + v * size_t(src.stride), 4 * sizeof(float));
        }
        packed = staging.data();
      }
      const size_t bytes = voxels * 4 * sizeof(float);
      dc.bytes.resize(bytes);
      MCVOL_CUDA(cudaMemcpy(dc.bytes.ptr, packed, bytes, cudaMemcpyHostToDevice));
      ++this->Updates.dataUploads;
      continue;
    }
    const void* host = denseHostVoxels(src, voxels, staging, dc.type);
    if (this->Sampling == CudaSampling::Texture && fits)
    {
      if (this->uploadTexture(dc, host))
      {
        ++this->Updates.dataUploads;
        continue;
      }
      ++this->Updates.textureFallbacks; // no room for a texture: a dense array instead
    }
    const size_t bytes = voxels * size_t(scalarTypeSize(dc.type));
    dc.bytes.resize(bytes);
    MCVOL_CUDA(cudaMemcpy(dc.bytes.ptr, host, bytes, cudaMemcpyHostToDevice));
    ++this->Updates.dataUploads;
  }
}

void CUDARenderer::Internal::moveNonFiniteToArrays(const Scene& scene)
{
  // Hardware filtering drops a non-finite corner whose weight rounds to 0,
  // where the core's rule makes the sample NaN (transparent): such channels
  // sample a dense array instead of their texture.
  const size_t voxels = size_t(this->Dims[0]) * size_t(this->Dims[1]) * size_t(this->Dims[2]);
  std::vector<uint8_t> staging;
  for (int n = 0; n < this->NumChannels; ++n)
  {
    DeviceChannel& dc = this->Channels[n];
    if (!dc.nonFinite || !dc.array)
    {
      continue;
    }
    MCVOL_CUDA(cudaDeviceSynchronize());
    dc.releaseTexture();
    const void* host = denseHostVoxels(scene.channel(n), voxels, staging, dc.type);
    const size_t bytes = voxels * size_t(scalarTypeSize(dc.type));
    dc.bytes.resize(bytes);
    MCVOL_CUDA(cudaMemcpy(dc.bytes.ptr, host, bytes, cudaMemcpyHostToDevice));
  }
}
} // namespace mcvol
