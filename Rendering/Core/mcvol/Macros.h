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
#define MCVOL_HOT MCVOL_HOST_DEVICE MCVOL_FORCE_INLINE

namespace mcvol
{
/// Upper bound on channels; fixed so per-ray code needs no heap memory.
constexpr int kMaxChannels = 32;
} // namespace mcvol
