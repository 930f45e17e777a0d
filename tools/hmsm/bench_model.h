// hmsm bench: the bandwidth model (bytes the seven passes must move per step) and the copy
// bandwidth each backend's roofline is measured against. docs/benchmarks/README.md documents both.
#pragma once

#include <hmsm/hmsm.h>

#include <array>
#include <cstdint>
#include <string>

namespace hmsm::cli::bench {

/// Compulsory traffic of one step: each pass reads every buffer it reads once and writes every
/// buffer it writes once (a buffer both read and written counts twice), one half of a ping-pong
/// buffer, one round's slice of the jump table. Element sizes are those of gpu_layout.h.
/// Static buffers (model and instance scope, shared by all instances) are counted apart:
/// they stay cache-resident in a forest, but a single tree streams them too. Counts come from
/// SceneData::element_count, so the packed vertex layout (no vertex_normal elements) has the
/// contour pass write 16 bytes per vertex instead of 32.
struct Traffic {
    std::array<double, kPassCount> pass_bytes{};  ///< state + static, per pass
    double state_bytes = 0.0;
    double static_bytes = 0.0;
    double total() const { return state_bytes + static_bytes; }
};
Traffic step_traffic(const Simulation& sim);

/// Bytes of state the backend keeps per instance of `sim`'s scene (for host-memory checks).
double state_bytes_per_instance(const Simulation& sim);

struct CopyBandwidth {
    double bytes_per_second = 0.0;
    std::string method;  ///< device_copy, host_memcpy or host_transfer_estimate
    uint64_t bytes = 0;  ///< size of the copied block
};

/// Single-threaded memcpy between two host blocks of `bytes`: best of `repeats`,
/// counted as (read + written) / seconds, the roofline of the serial CPU backend.
Result<CopyBandwidth> host_memcpy_bandwidth(uint64_t bytes, uint32_t repeats);

/// The backend's own device copy (Backend::measure_copy_bandwidth) when it has one; else
/// host -> device -> host transfers of the vertex-position buffer through Backend::write/read
/// (a lower bound that measures the host link, not device memory).
Result<CopyBandwidth> device_copy_bandwidth(Simulation& sim, uint64_t bytes);

/// Transfers of sim's vertex-position buffer through Backend::write/read, median of `repeats`.
Result<CopyBandwidth> host_transfer_bandwidth(Simulation& sim, uint32_t repeats);

/// MemAvailable of /proc/meminfo in bytes, or 0 when unknown.
double host_available_memory();
/// "model name" of /proc/cpuinfo, or "unknown".
std::string host_cpu_name();

}  // namespace hmsm::cli::bench
