// hmsm bench: bytes per step from the buffer table and the copy bandwidth to compare them with.
#include "simulation_access.h"
#include "bench_model.h"

#include "backend.h"
#include "buffers.h"
#include "scene_data.h"

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <memory>
#include <new>
#include <vector>

namespace hmsm::cli::bench {
namespace {

using detail::BufferId;
using detail::Scope;

double median_of(std::vector<double> v) {
    std::sort(v.begin(), v.end());
    const size_t n = v.size();
    return n == 0 ? 0.0 : n % 2 ? v[n / 2] : 0.5 * (v[n / 2 - 1] + v[n / 2]);
}

/// Bytes of one element as gpu_layout.h stores it (every scalar is 4 bytes).
double element_bytes(const detail::BufferInfo& info) {
    return 4.0 * detail::shape_scalars(info.shape);
}

/// Bytes one sweep of pass `p` moves through buffer `info`: one half of a ping-pong buffer, one
/// round of the jump table, the attach node of each chain where root_positions gathers relative
/// positions, all of anything else.
double sweep_bytes(const detail::SceneData& d, Pass p, const detail::BufferInfo& info) {
    double elements = double(d.element_count(info.id));
    // A pass sweeps the live state, not the capacity kept for instances to come.
    auto live = [&](uint64_t count, uint64_t capacity) { return capacity > 0 ? double(count) / double(capacity) : 1.0; };
    if (info.scope == Scope::chain || info.scope == Scope::chain_halves) elements *= live(d.total_chains, d.chain_capacity);
    if (info.scope == Scope::node) elements *= live(d.total_nodes, d.node_capacity);
    if (info.scope == Scope::vertex) elements *= live(d.total_vertices, d.vertex_capacity);
    if (info.scope == Scope::instance) elements *= live(d.instance_count(), d.instance_capacity);
    if (p == Pass::root_positions && info.id == BufferId::node_relative) elements = double(d.total_chains);
    if (info.scope == Scope::chain_halves) elements /= 2.0;
    if (info.scope == Scope::model_chain_jump) elements /= double(std::max(1u, d.jump_rounds));
    return elements * element_bytes(info);
}

bool is_state_scope(Scope s) {
    return s == Scope::chain || s == Scope::chain_halves || s == Scope::node || s == Scope::vertex;
}

}  // namespace

Traffic step_traffic(const Simulation& sim) {
    const detail::SceneData& d = hmsm::detail::scene_data_of(sim);
    // The buffers each pass touches in the simulation's step program: its own reads and writes,
    // or, for a path-walk dispatch, the dispatch's (counted under its leader), which leave out what the
    // walk keeps in registers.
    // A program of the walk that integrates ahead (CUDA forests) is counted as its steps run
    // when nothing changes: without the wind pair, whose work the walk ahead does with the pose
    // in its registers, and without the top poses (the chains of depth 0 and 1, a few per
    // instance), whose pose halves the walk ahead reads only for those chains.
    const std::vector<detail::Dispatch>& program = detail::step_program_of(sim);
    const bool ahead =
        std::any_of(program.begin(), program.end(), [](const auto& x) { return detail::is_walk_ahead(x); });
    const uint32_t top_poses = detail::kWalkTopPosesWrites;
    std::array<uint32_t, kPassCount> reads{}, writes{};
    for (const detail::Dispatch& dispatch : program) {
        if (ahead && (dispatch.pass == Pass::wind_force || detail::is_top_poses_walk(dispatch))) continue;
        for (Pass p : kAllPasses) {
            if (!(detail::dispatch_passes(dispatch) >> uint32_t(p) & 1u)) continue;
            const bool walk = detail::runs_path_walk(dispatch);
            if (walk && p != dispatch.pass) continue;
            const uint32_t walk_reads = detail::dispatch_reads(dispatch) & ~(ahead ? top_poses : 0u);
            reads[uint32_t(p)] |= walk ? walk_reads : detail::pass_reads(p);
            writes[uint32_t(p)] |= walk ? detail::dispatch_writes(dispatch) : detail::pass_writes(p);
        }
    }
    Traffic t;
    for (Pass p : kAllPasses) {
        const uint32_t reads_p = reads[uint32_t(p)], writes_p = writes[uint32_t(p)];
        for (const detail::BufferInfo& info : detail::kBufferTable) {
            const uint32_t bit = 1u << uint32_t(info.id);
            const int touches = ((reads_p & bit) ? 1 : 0) + ((writes_p & bit) ? 1 : 0);
            if (touches == 0) continue;
            const double bytes = touches * sweep_bytes(d, p, info);
            t.pass_bytes[uint32_t(p)] += bytes;
            (detail::is_static(info.id) ? t.static_bytes : t.state_bytes) += bytes;
        }
    }
    return t;
}

double state_bytes_per_instance(const Simulation& sim) {
    const detail::SceneData& d = hmsm::detail::scene_data_of(sim);
    double bytes = 0.0;
    for (const detail::BufferInfo& info : detail::kBufferTable)
        if (is_state_scope(info.scope)) bytes += double(d.element_count(info.id)) * element_bytes(info);
    return bytes / double(std::max<uint64_t>(1, sim.instance_count()));
}

Result<CopyBandwidth> host_memcpy_bandwidth(uint64_t bytes, uint32_t repeats) {
    std::unique_ptr<char[]> src, dst;
    try {
        src.reset(new char[bytes]);
        dst.reset(new char[bytes]);
    } catch (const std::bad_alloc&) {
        return Status{ErrorCode::out_of_memory,
                      "host memcpy: cannot allocate 2 x " + std::to_string(bytes) + " bytes"};
    }
    std::memset(src.get(), 1, bytes);  // fault the pages in before timing
    std::memset(dst.get(), 2, bytes);
    std::vector<double> seconds;
    for (uint32_t r = 0; r < std::max(1u, repeats); ++r) {
        auto start = std::chrono::steady_clock::now();
        std::memcpy(dst.get(), src.get(), bytes);
        seconds.push_back(std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count());
        src[r % bytes] ^= dst[(r * 7919) % bytes];  // keep the copies observable
    }
    // Best of the repeats: a capability, which a noisy neighbour can only lower.
    const double s = *std::min_element(seconds.begin(), seconds.end());
    if (!(s > 0.0)) return Status{ErrorCode::internal, "host memcpy: timer resolution too coarse"};
    return CopyBandwidth{2.0 * double(bytes) / s, "host_memcpy", bytes};
}

Result<CopyBandwidth> host_transfer_bandwidth(Simulation& sim, uint32_t repeats) {
    const uint64_t count = sim.vertex_count();
    const double bytes = double(count) * 16.0;
    std::vector<float> host(count * 4, 0.0f);
    std::vector<double> write_s, read_s;
    detail::Backend& backend = hmsm::detail::backend_of(sim);
    for (uint32_t r = 0; r < std::max(1u, repeats); ++r) {
        auto t0 = std::chrono::steady_clock::now();
        HMSM_TRY(backend.write(BufferId::vertex_position, 0, count, host.data(), detail::Scalar::f32));
        auto t1 = std::chrono::steady_clock::now();
        HMSM_TRY(backend.read(BufferId::vertex_position, 0, count, host.data(), detail::Scalar::f32));
        auto t2 = std::chrono::steady_clock::now();
        write_s.push_back(std::chrono::duration<double>(t1 - t0).count());
        read_s.push_back(std::chrono::duration<double>(t2 - t1).count());
    }
    const double s = median_of(write_s) + median_of(read_s);
    if (!(s > 0.0)) return Status{ErrorCode::internal, "host transfer: timer resolution too coarse"};
    // The next step's contour pass rewrites every vertex position, so the scribble is harmless.
    return CopyBandwidth{2.0 * bytes / s, "host_transfer_estimate", uint64_t(bytes)};
}

Result<CopyBandwidth> device_copy_bandwidth(Simulation& sim, uint64_t bytes) {
    Result<double> measured = hmsm::detail::backend_of(sim).measure_copy_bandwidth(bytes);
    if (measured) return CopyBandwidth{*measured, "device_copy", bytes};
    const ErrorCode code = measured.status().code();
    if (code != ErrorCode::unsupported && code != ErrorCode::out_of_memory) return measured.status();
    return host_transfer_bandwidth(sim, 3);
}

double host_available_memory() {
    std::ifstream in("/proc/meminfo");
    std::string line;
    while (std::getline(in, line)) {
        double kib = 0.0;
        if (std::sscanf(line.c_str(), "MemAvailable: %lf kB", &kib) == 1) return kib * 1024.0;
    }
    return 0.0;
}

std::string host_cpu_name() {
    std::ifstream in("/proc/cpuinfo");
    std::string line;
    while (std::getline(in, line)) {
        if (line.rfind("model name", 0) == 0) {
            size_t colon = line.find(':');
            if (colon != std::string::npos) {
                size_t start = line.find_first_not_of(' ', colon + 1);
                return start == std::string::npos ? "unknown" : line.substr(start);
            }
        }
    }
    return "unknown";
}

}  // namespace hmsm::cli::bench
