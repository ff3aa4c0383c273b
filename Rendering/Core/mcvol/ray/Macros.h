// SPDX-License-Identifier: BSD-3-Clause
#pragma once

/**
 * One macro marks every function that runs per ray, so the same code compiles
 * for the CPU backend (plain C++) and for the CUDA backend (nvcc). There is no
 * second copy of the tracking code for the GPU.
 */
#if defined(__CUDACC__)
#define MCVOL_HOST_DEVICE __host__ __device__
#define MCVOL_FORCE_INLINE __forceinline__
#else
#define MCVOL_HOST_DEVICE
#if defined(__GNUC__)
#define MCVOL_FORCE_INLINE inline __attribute__((always_inline))
#else
#define MCVOL_FORCE_INLINE inline
#endif
#endif

#define MCVOL_FUNC MCVOL_HOST_DEVICE inline
/// Rarely taken per-ray code kept out of line on the CPU, so that its
/// presence does not change how the hot path around it is inlined (the
/// device compiler inlines it as usual).
#if defined(__CUDACC__) || !defined(__GNUC__)
#define MCVOL_OUTLINE MCVOL_HOST_DEVICE inline
#else
#define MCVOL_OUTLINE __attribute__((noinline)) inline
#endif
#define MCVOL_HOT MCVOL_HOST_DEVICE MCVOL_FORCE_INLINE
/// Per-ray code of a path most scenes never take (pre-classified channels):
/// a call on both compilers, so that its registers do not weigh on the hot
/// kernels (inlined, it raises the render kernels' register counts, the lit
/// one's to twice and with spills; ptxas -v).
#if defined(__CUDACC__)
#define MCVOL_COLD __host__ __device__ __noinline__ inline
#elif defined(__GNUC__)
#define MCVOL_COLD __attribute__((noinline)) inline
#else
#define MCVOL_COLD inline
#endif

/// Keeps the loop that follows rolled on the device (nvcc unrolls small
/// constant loops by itself): the out-of-line cubic samplers stay
/// register-light (Sampling.h, sampleChannelCubic).
#if defined(__CUDA_ARCH__)
#define MCVOL_NO_UNROLL _Pragma("unroll 1")
#else
#define MCVOL_NO_UNROLL
#endif

namespace mcvol
{
/// Upper bound on channels; fixed so per-ray code needs no heap memory.
constexpr int kMaxChannels = 32;
} // namespace mcvol
