// Reading outputs back: Simulation::read, and the asynchronous request_read / take_read pair.
// Every path ends in one host pass from the elements as the backend stores them (float words,
// double on cpu64) into the caller's vector: components picked out of vec4s and joint
// matrices, or octahedral normal words decoded (VertexLayout::packed). A large output is
// converted in chunks on several threads; an output that is the stored elements in the
// caller's precision is copied, or read by the backend straight into the caller's vector.
#include <hmsm/simulation.h>

#include "backend.h"
#include "common/octahedral.h"
#include "instance_moves.h"
#include "scene_data.h"
#include "simulation_impl.h"

#include <algorithm>
#include <cstring>
#include <iterator>
#include <string>
#include <thread>
#include <type_traits>

namespace hmsm {

using detail::BufferId;

namespace {

std::string output_name(Output output) {
    static constexpr const char* kNames[] = {"node_positions", "vertex_positions", "vertex_normals", "chain_rotations",
                                             "chain_origins", "chain_angles", "joint_matrices"};
    const auto k = static_cast<uint32_t>(output);
    return k < std::size(kNames) ? kNames[k] : std::to_string(k);
}

}  // namespace

Result<Simulation::Impl::ReadSource> Simulation::Impl::read_source(Output output, const char* fn) const {
    const bool vertex_output = output == Output::vertex_positions || output == Output::vertex_normals;
    if ((vertex_output && !data_->produces_vertices()) ||
        (output == Output::node_positions && !data_->produces_nodes()))
        return Status{ErrorCode::invalid_argument,
                      std::string(fn) + ": output " +
                          (vertex_output ? (output == Output::vertex_positions ? "vertex_positions" : "vertex_normals")
                                         : "node_positions") +
                          " is not produced by this simulation (SimulationConfig::outputs = " +
                          to_string(config_.outputs) + ")"};
    ReadSource source;
    source.output = output;
    source.count = data_->total_nodes;
    switch (output) {
        case Output::node_positions: break;
        case Output::vertex_positions: source.id = BufferId::vertex_position; source.count = data_->total_vertices; break;
        case Output::vertex_normals:
            // VertexLayout::packed: each normal is the octahedral word in its position's w.
            source.packed_normals = data_->packed_vertices();
            source.id = source.packed_normals ? BufferId::vertex_position : BufferId::vertex_normal;
            source.count = data_->total_vertices;
            break;
        // The pose of a step is its joint matrix [R | O] by rows (the path walk writes no R or
        // O half; every composition writes the joint matrix).
        case Output::chain_rotations:
        case Output::chain_origins:
        case Output::joint_matrices: source.id = BufferId::joint_matrix; source.count = data_->total_chains; break;
        case Output::chain_angles: source.id = BufferId::chain_state; source.count = data_->total_chains; break;
        default:  // a value cast from an integer (the C ABI checks its own)
            return Status{ErrorCode::invalid_argument,
                          std::string(fn) + ": unknown output " + std::to_string(static_cast<int>(output))};
    }
    source.stored = detail::shape_scalars(detail::buffer_info(source.id).shape);
    source.held = source.count;
    if (placed_) {
        // Every slot is read; each instance's elements go to their place in index order.
        const detail::Scope scope = detail::buffer_info(source.id).scope;
        const bool nodes = scope == detail::Scope::node, vertices = scope == detail::Scope::vertex;
        source.held = nodes ? data_->nodes_held() : vertices ? data_->vertices_held() : data_->chains_held();
        uint64_t at = 0;
        for (uint32_t i = 0; i < instances_.size(); ++i) {
            const detail::ModelRange& m = data_->models[instances_[i].model];
            const uint64_t from = nodes ? placements_[i].nodes : vertices ? placements_[i].vertices : placements_[i].chains;
            const uint64_t n = nodes ? m.node_count : vertices ? m.vertex_count : m.chain_count;
            detail::append_move(source.gather, from, at, n);
            at += n;
        }
        if (source.gather.size() == 1 && source.gather[0].src == 0) source.gather.clear();  // the output's order
        if (source.gather.empty()) source.held = source.count;
    }
    return source;
}

template <class Stored>
const Stored* Simulation::Impl::gathered(const ReadSource& source, const Stored* raw, std::vector<Stored>& into) const {
    if (source.gather.empty()) return raw;
    const uint64_t stored = source.stored;
    into.resize(source.count * stored);
    for (const detail::ElementMove& m : source.gather)
        std::memcpy(into.data() + m.dst * stored, raw + m.src * stored, m.count * stored * sizeof(Stored));
    return into.data();
}

template <class Stored, class Out>
void Simulation::Impl::unpack(const ReadSource& source, const Stored* raw, std::vector<Out>& out) const {
    if constexpr (std::is_same_v<Stored, double>) raw = gathered(source, raw, gathered_f64_);
    else raw = gathered(source, raw, gathered_f32_);
    const uint64_t count = source.count;
    if (source.packed_normals) {
        // The double CPU oracle holds the word as an integer value, every other backend as
        // float bits (detail::packed_word_to_w).
        out.resize(count * 3);
        Out* dst = out.data();
        for_element_ranges(count, 3 * sizeof(Out), [&](uint64_t begin, uint64_t end) {
            for (uint64_t i = begin; i < end; ++i) {
                const auto n = detail::decode_normal_word<Out>(detail::packed_word_from_w<Stored>(raw[4 * i + 3]));
                dst[3 * i] = n.x;
                dst[3 * i + 1] = n.y;
                dst[3 * i + 2] = n.z;
            }
        });
        return;
    }
    const uint32_t stored = source.stored;
    const uint32_t wanted = output_components(source.output);
    out.resize(count * wanted);
    Out* dst = out.data();
    if (stored == 4 && wanted == 3) {  // positions and normals: the per-frame hot path
        for_element_ranges(count, 3 * sizeof(Out), [&](uint64_t begin, uint64_t end) {
            for (uint64_t i = begin; i < end; ++i) {
                dst[3 * i] = Out(raw[4 * i]);
                dst[3 * i + 1] = Out(raw[4 * i + 1]);
                dst[3 * i + 2] = Out(raw[4 * i + 2]);
            }
        });
        return;
    }
    if (stored == wanted) {  // joint matrices and angles: every scalar in order
        for_element_ranges(count, wanted * sizeof(Out), [&](uint64_t begin, uint64_t end) {
            if constexpr (std::is_same_v<Stored, Out>) {
                std::memcpy(dst + begin * wanted, raw + begin * wanted, (end - begin) * wanted * sizeof(Out));
            } else {
                for (uint64_t i = begin * wanted; i < end * wanted; ++i) dst[i] = Out(raw[i]);
            }
        });
        return;
    }
    // Output component k -> its scalar in the stored element: from a joint matrix's rows
    // (r00 r01 r02 ox, r10 ...) R column by column or O.
    const bool rotations = source.output == Output::chain_rotations;
    for_element_ranges(count, wanted * sizeof(Out), [&](uint64_t begin, uint64_t end) {
        for (uint64_t i = begin; i < end; ++i)
            for (uint32_t k = 0; k < wanted; ++k)
                dst[i * wanted + k] = Out(raw[i * stored + (rotations ? (k % 3) * 4 + k / 3 : k * 4 + 3)]);
    });
}

template <class Out>
Status Simulation::Impl::read_into(Output output, std::vector<Out>& out) const {
    std::lock_guard lock(read_mutex_);
    auto source = read_source(output, "read");
    if (!source) return source.status();
    if (backend_->capabilities().reads_async) {  // one copy into the backend's pinned slot
        HMSM_TRY(backend_->request_read(detail::kSyncReadSlot, source->id, 0, source->held));
        auto raw = backend_->take_read(detail::kSyncReadSlot);
        if (!raw) return raw.status();
        unpack(*source, *raw, out);
        return {};
    }
    // Where the output is the stored elements themselves in the caller's precision (joint
    // matrices and angles as float, or as double on cpu64), the backend reads straight into
    // the caller's vector.
    constexpr detail::Scalar out_scalar = std::is_same_v<Out, double> ? detail::Scalar::f64 : detail::Scalar::f32;
    const bool stores_out = backend_->kind() == BackendKind::cpu64 ? out_scalar == detail::Scalar::f64
                                                                   : out_scalar == detail::Scalar::f32;
    if (stores_out && !source->packed_normals && source->gather.empty() && source->stored == output_components(output)) {
        out.resize(source->count * source->stored);
        Status status = backend_->read(source->id, 0, source->count, out.data(), out_scalar);
        if (!status) out.clear();  // no partial output
        return status;
    }
    // Elements as the backend stores them (cpu64: double), converted in unpack: the same
    // values as the backend's own conversion.
    const uint64_t scalars = source->held * source->stored;
    if (backend_->kind() == BackendKind::cpu64) {
        stored_f64_.resize(scalars);
        HMSM_TRY(backend_->read(source->id, 0, source->held, stored_f64_.data(), detail::Scalar::f64));
        unpack(*source, stored_f64_.data(), out);
    } else {
        stored_f32_.resize(scalars);
        HMSM_TRY(backend_->read(source->id, 0, source->held, stored_f32_.data(), detail::Scalar::f32));
        unpack(*source, stored_f32_.data(), out);
    }
    return {};
}

Status Simulation::Impl::request_read(Output output) {
    auto source = read_source(output, "request_read");
    if (!source) return source.status();
    const uint32_t slot = uint32_t(output);
    if (backend_->capabilities().reads_async) {
        HMSM_TRY(backend_->request_read(slot, source->id, 0, source->held));
    } else {
        // Read now: the values are those of the request whatever runs before take_read.
        PendingRead& snapshot = pending_reads_[slot];
        snapshot.requested = false;
        const uint64_t scalars = source->held * source->stored;
        if (backend_->kind() == BackendKind::cpu64) {
            snapshot.f64.resize(scalars);
            HMSM_TRY(backend_->read(source->id, 0, source->held, snapshot.f64.data(), detail::Scalar::f64));
        } else {
            snapshot.f32.resize(scalars);
            HMSM_TRY(backend_->read(source->id, 0, source->held, snapshot.f32.data(), detail::Scalar::f32));
        }
    }
    pending_reads_[slot].source = std::move(*source);  // the slots as they were at the request
    pending_reads_[slot].requested = true;
    return {};
}

template <class Out>
Status Simulation::Impl::take_read(Output output, std::vector<Out>& out) {
    const uint32_t slot = uint32_t(output);
    if (slot >= detail::kSyncReadSlot)
        return {ErrorCode::invalid_argument, "take_read: unknown output " + std::to_string(static_cast<int>(output))};
    const PendingRead& pending = pending_reads_[slot];
    if (!pending.requested)
        return {ErrorCode::invalid_argument, "take_read: output " + output_name(output) +
                                                 " was not requested (call request_read first)"};
    if (backend_->capabilities().reads_async) {
        auto raw = backend_->take_read(slot);
        if (!raw) return raw.status();
        unpack(pending.source, *raw, out);
    } else if (backend_->kind() == BackendKind::cpu64) {
        unpack(pending.source, pending.f64.data(), out);
    } else {
        unpack(pending.source, pending.f32.data(), out);
    }
    return {};
}

Status Simulation::read(Output output, std::vector<float>& values) const { return impl_->read_into(output, values); }
Status Simulation::read(Output output, std::vector<double>& values) const { return impl_->read_into(output, values); }
Status Simulation::request_read(Output output) { return impl_->request_read(output); }
Status Simulation::take_read(Output output, std::vector<float>& values) { return impl_->take_read(output, values); }
Status Simulation::take_read(Output output, std::vector<double>& values) { return impl_->take_read(output, values); }

}  // namespace hmsm
