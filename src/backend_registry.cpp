// Which backends this build has, and `automatic` selection: CUDA, then a Vulkan GPU (not a CPU
// driver such as lavapipe), then cpu-parallel when more than one thread is available, else the
// serial CPU in float.
#include "backend.h"

namespace hmsm {

std::vector<BackendKind> compiled_backends() {
    std::vector<BackendKind> kinds = {BackendKind::cpu, BackendKind::cpu64, BackendKind::cpu_parallel};
#ifdef HMSM_HAVE_VULKAN
    kinds.push_back(BackendKind::vulkan);
#endif
#ifdef HMSM_HAVE_CUDA
    kinds.push_back(BackendKind::cuda);
#endif
    return kinds;
}

namespace detail {

#ifdef HMSM_HAVE_VULKAN
bool vulkan_backend_is_cpu_device(const Backend& backend);  // src/vulkan
#endif

Result<std::unique_ptr<Backend>> create_backend(BackendKind kind, uint32_t cpu_threads) {
    switch (kind) {
        case BackendKind::cpu: return create_cpu_backend(false);
        case BackendKind::cpu64: return create_cpu_backend(true);
        case BackendKind::cpu_parallel: return create_cpu_parallel_backend(cpu_threads);
        case BackendKind::vulkan:
#ifdef HMSM_HAVE_VULKAN
            return create_vulkan_backend();
#else
            return Status{ErrorCode::no_device, "vulkan: this build of hmsm has no Vulkan backend"};
#endif
        case BackendKind::cuda:
#ifdef HMSM_HAVE_CUDA
            return create_cuda_backend();
#else
            return Status{ErrorCode::no_device, "cuda: this build of hmsm has no CUDA backend"};
#endif
        case BackendKind::automatic: {
#ifdef HMSM_HAVE_CUDA
            if (auto cuda = create_cuda_backend(); cuda.ok()) return cuda;
#endif
#ifdef HMSM_HAVE_VULKAN
            if (auto vulkan = create_vulkan_backend();
                vulkan.ok() && !vulkan_backend_is_cpu_device(*vulkan.value()))
                return vulkan;
#endif
            // Without a GPU: all cores where there is more than one (bitwise the serial
            // results; a scene too small to split runs on the caller alone).
            auto threads = cpu_thread_count(cpu_threads);
            if (!threads) return threads.status();
            if (*threads > 1) return create_cpu_parallel_backend(*threads);
            return create_cpu_backend(false);
        }
    }
    return Status{ErrorCode::internal, "unknown backend kind"};
}

}  // namespace detail
}  // namespace hmsm
