#include "cuda_error.h"

#include <string>

namespace hmsm::detail::cuda {

Status cuda_status(cudaError_t error, const char* expression, const char* file, int line) {
    (void)cudaGetLastError();  // clears a non-sticky error; a sticky one stays with the context
    std::string where = std::string(file);
    if (auto slash = where.find_last_of('/'); slash != std::string::npos) where.erase(0, slash + 1);
    std::string message = std::string("cuda: ") + cudaGetErrorName(error) + " (" +
                          cudaGetErrorString(error) + ") from " + expression + " at " + where +
                          ":" + std::to_string(line);
    ErrorCode code = error == cudaErrorMemoryAllocation ? ErrorCode::out_of_memory
                                                         : ErrorCode::device_error;
    return {code, std::move(message)};
}

}  // namespace hmsm::detail::cuda
