// HMSM_HOST_DEVICE: marks the small functions shared by the C++ model, the CPU passes and the
// CUDA kernels (src/common/wind_profile.h, src/common/octahedral.h) so that nvcc compiles them for both sides.
#pragma once

#ifdef __CUDACC__
#define HMSM_HOST_DEVICE __host__ __device__ __forceinline__
#else
#define HMSM_HOST_DEVICE inline
#endif
