// CUDA errors as hmsm Status values (errors are values; nothing here aborts).
#pragma once

#include <hmsm/status.h>

#include <cuda_runtime_api.h>

namespace hmsm::detail::cuda {

/// Maps a failed CUDA call to a Status: out_of_memory for allocation failures, device_error
/// otherwise, with the CUDA error name, the expression and where it was called. A non-sticky
/// error is also cleared from the runtime's last-error slot so it does not resurface later.
Status cuda_status(cudaError_t error, const char* expression, const char* file, int line);

}  // namespace hmsm::detail::cuda

/// Evaluates a CUDA runtime call and returns its failure as a Status from the enclosing function.
#define CUDA_TRY(expr)                                                                       \
    do {                                                                                     \
        const cudaError_t cuda_try_error_ = (expr);                                          \
        if (cuda_try_error_ != cudaSuccess)                                                  \
            return ::hmsm::detail::cuda::cuda_status(cuda_try_error_, #expr, __FILE__, __LINE__); \
    } while (0)
