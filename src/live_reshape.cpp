// Adding and removing instances (docs/model.md 3.9, docs/driving.md): the instance list is
// replaced by the survivors (in order, or with holes filled from the end for a swap removal)
// followed by the added instances, every survivor keeps its state bit for bit, and the device
// scene is kept where the capacity allows or grows on the device (in place), or is uploaded
// anew with room to grow.
#include "capacity_growth.h"
#include "instance_moves.h"
#include "simulation_impl.h"

#include <algorithm>
#include <array>
#include <limits>

namespace hmsm {

namespace {

using detail::BufferId;
using detail::carried_buffers;
using detail::halves_of;
using detail::grown_capacity;
using detail::kMaxStateElements;
using detail::kMovedOutputs;

/// Moves that bring each survivor's elements [old[i], old[i + 1]) behind the survivor before
/// it in the new list, neighbours coalesced; `end` receives the elements the survivors hold.
/// For survivors in ascending order the moves go down and ascend, so that no source is
/// overwritten before it is read; for another order, sequential_safe() tells.
std::vector<detail::ElementMove> survivor_moves(const std::vector<uint32_t>& survivors,
                                                const std::vector<uint64_t>& old, uint64_t& end) {
    std::vector<detail::ElementMove> moves;
    uint64_t at = 0;
    for (uint32_t i : survivors) {
        const uint64_t from = old[i], n = old[i + 1] - from;
        if (from != at) {
            if (!moves.empty() && moves.back().src + moves.back().count == from &&
                moves.back().dst + moves.back().count == at)
                moves.back().count += n;
            else
                moves.push_back({from, at, n});
        }
        at += n;
    }
    end = at;
    return moves;
}

/// Whether applying `moves` one after the other reads every source before a move writes over
/// it: each move goes down (or nowhere) and ends at or below every later move's source.
bool sequential_safe(const std::vector<detail::ElementMove>& moves) {
    uint64_t later_sources = std::numeric_limits<uint64_t>::max();
    for (size_t k = moves.size(); k-- > 0;) {
        const detail::ElementMove& m = moves[k];
        if (m.dst > m.src || m.dst + m.count > later_sources) return false;
        later_sources = std::min(later_sources, m.src);
    }
    return true;
}

/// Elements per instance of `instances` as running sums: old[i] is the first element of
/// instance i, old[n] the total (`per` picks chains, nodes or vertices of a model).
template <class Per>
std::vector<uint64_t> running_offsets(const std::vector<Instance>& instances, Per per) {
    std::vector<uint64_t> old(instances.size() + 1, 0);
    for (size_t i = 0; i < instances.size(); ++i) old[i + 1] = old[i] + per(instances[i].model);
    return old;
}

/// The groups covering instances [first, end) of `d`.
std::vector<detail::InstanceGroup> groups_from(const detail::SceneData& d, uint32_t first) {
    std::vector<detail::InstanceGroup> out;
    for (const detail::InstanceGroup& g : d.groups) {
        if (g.instance_begin + g.instance_count <= first) continue;
        detail::InstanceGroup part = g;
        if (g.instance_begin < first) {
            const uint32_t k = first - g.instance_begin;
            const detail::ModelRange& m = d.models[g.model];
            part.instance_begin = first;
            part.instance_count = g.instance_count - k;
            part.chain_begin += k * m.chain_count;
            part.node_begin += k * m.node_count;
            part.vertex_begin += k * m.vertex_count;
        }
        out.push_back(part);
    }
    return out;
}


}  // namespace

Status Simulation::Impl::reshape(const std::vector<uint32_t>& survivors, std::span<const Instance> added,
                                 bool reupload) {
    struct InstanceChange {
        detail::Backend& backend;
        explicit InstanceChange(detail::Backend& b) : backend(b) { backend.begin_instance_change(); }
        ~InstanceChange() { backend.end_instance_change(); }
    } change(*backend_);
    HMSM_TRY(pack_layout());  // the moves below take the layout as packed
    std::vector<Instance> next;
    next.reserve(survivors.size() + added.size());
    for (uint32_t i : survivors) next.push_back(instances_[i]);
    next.insert(next.end(), added.begin(), added.end());
    HMSM_TRY(check_size(next));

    // The new instance layout over the models as they are: the model arrays are not rebuilt.
    auto data = std::make_unique<detail::SceneData>();
    data->models = data_->models;
    detail::lay_out_instances(*data, next);

    // Per old instance: its first state chain.
    const std::vector<uint64_t> old_chain =
        running_offsets(instances_, [&](uint32_t model) { return data_->models[model].chain_count; });
    // The first and last new instances whose state is not where it was (added ones included).
    uint32_t first_moved = uint32_t(survivors.size()), last_moved = 0;
    bool ascending = true;
    for (uint32_t k = 0; k < survivors.size(); ++k) {
        if (survivors[k] != k) {
            first_moved = std::min(first_moved, k);
            last_moved = k;
        }
        if (k > 0 && survivors[k] < survivors[k - 1]) ascending = false;
    }
    if (!added.empty()) last_moved = uint32_t(next.size() - 1);

    ahead_schedule_.live_change();  // the state moves, the angles integrated ahead with it
    bool in_place = !reupload && backend_->capabilities().reshapes_in_place;
    if (in_place && !ascending) {
        // A swap removal moves instances from the end into the holes: in place when each one
        // fills a hole of its own size (one model) or the instances between shift down; where
        // they would shift up over sources not yet read, the scene is uploaded anew.
        const auto per_node = [&](uint32_t model) { return data_->models[model].node_count; };
        const auto per_vertex = [&](uint32_t model) { return data_->models[model].vertex_count; };
        uint64_t end = 0;
        in_place = sequential_safe(survivor_moves(survivors, old_chain, end)) &&
                   sequential_safe(survivor_moves(survivors, running_offsets(instances_, per_node), end)) &&
                   sequential_safe(survivor_moves(survivors, running_offsets(instances_, per_vertex), end));
    }
    if (in_place && !data_->holds(*data)) {
        // Past the capacity: the buffers grow on the device where the backend can, and the
        // change goes on in place.
        Result<bool> grown = grow_on_device({data->total_chains, data->total_nodes, data->total_vertices},
                                            data->instance_count());
        if (!grown) return grown.status();
        in_place = *grown;
    }
    if (in_place) {
        HMSM_TRY(reshape_in_place(std::move(data), survivors, old_chain, first_moved));
    } else {
        HMSM_TRY(reshape_anew(std::move(data), survivors, old_chain));
        first_moved = 0;  // every instance buffer is new
    }
    instances_ = std::move(next);
    instances_changed();
    instance_list_laid_out();
    std::vector<InstanceId> ids;
    ids.reserve(instances_.size());
    for (uint32_t i : survivors) ids.push_back(instance_ids_[i]);
    for (size_t k = 0; k < added.size(); ++k) ids.push_back(InstanceId(next_instance_id_++));
    instance_ids_ = std::move(ids);
    ids_ascending_ = std::is_sorted(instance_ids_.begin(), instance_ids_.end());
    id_index_.clear();
    if (!ids_ascending_) {  // built here: index_of is a const call and may run concurrently
        id_index_.reserve(instance_ids_.size());
        for (uint32_t i = 0; i < instance_ids_.size(); ++i) id_index_.emplace(uint64_t(instance_ids_[i]), i);
    }
    header_dirty_ = program_dirty_ = true;
    if (!in_place) {
        instance_wind_dirty_ = true;
    } else if (first_moved < instances_.size()) {
        // Winds of the instances that changed place or came: written as one range, together
        // with those changed before whose place stayed (apply_pending).
        std::erase_if(dirty_instances_, [&](uint32_t i) { return i >= instances_.size(); });
        for (uint32_t i = first_moved; i <= last_moved; ++i) dirty_instances_.push_back(i);
    } else {
        std::erase_if(dirty_instances_, [&](uint32_t i) { return i >= instances_.size(); });
    }

    // Added instances are posed at rest from S = V = 0. In place, the survivors' outputs moved
    // with their state; after an upload every output buffer is new: node positions and vertices
    // are a pure function of the carried R and O (passes 4, 6, 7 map elements one to one), so
    // recomputing them restores them exactly.
    const uint32_t first_added = uint32_t(survivors.size());
    if (!in_place && first_added > 0) {
        std::vector<detail::InstanceGroup> survived;
        for (detail::InstanceGroup g : data_->groups) {
            if (g.instance_begin >= first_added) continue;
            g.instance_count = std::min(g.instance_count, first_added - g.instance_begin);
            survived.push_back(g);
        }
        const uint32_t outputs = (1u << uint32_t(Pass::node_relative)) | (1u << uint32_t(Pass::node_world)) |
                                 (1u << uint32_t(Pass::contour));
        HMSM_TRY(run_at_rest(survived, Pass::node_relative, outputs));
    }
    if (!added.empty())
        HMSM_TRY(run_at_rest(groups_from(*data_, first_added), Pass::integrate));
    return apply_pending();
}

Status Simulation::Impl::reset(std::span<const uint32_t> indices) {
    // Pending live changes first, so that the rest pose below is the last word for these
    // instances whatever was changed before.
    HMSM_TRY(apply_pending());
    // Runs of neighbours in one group become one group slice. Slices cover no paused instance
    // (their flag is not read), so a paused instance is reset too and stays paused.
    if (placed_) {
        // S = V = 0 and g = 0 in each instance's slot, then the run from pass 2 (as below).
        std::vector<detail::ElementRange> ranges;
        for (uint32_t i : indices)
            detail::append_range(ranges, placements_[i].chains, data_->models[instances_[i].model].chain_count);
        HMSM_TRY(zero_chain_state(ranges));
        ahead_schedule_.live_change();
        return run_at_rest_placed(indices, Pass::integrate);
    }
    const std::vector<detail::InstanceGroup> slices = detail::slices_covering(*data_, indices);
    uint64_t covered = 0;
    for (const detail::InstanceGroup& g : slices) covered += g.instance_count;
    if (covered != indices.size())
        return {ErrorCode::internal, "reset: " + std::to_string(indices.size() - covered) + " instances are in no group"};
    // S = V = 0 and g = 0, as for an added instance; the run from pass 2 computes T, R, O, the
    // joint matrices, nodes and vertices from them.
    std::vector<detail::ElementRange> ranges;  // every slice at once
    for (const detail::InstanceGroup& g : slices)
        ranges.push_back({g.chain_begin, uint64_t(g.instance_count) * data_->models[g.model].chain_count});
    HMSM_TRY(zero_chain_state(ranges));
    ahead_schedule_.live_change();  // the reset angles replace any integrated ahead
    return run_at_rest(slices, Pass::integrate);
}

Status Simulation::Impl::zero_chain_state(std::span<const detail::ElementRange> ranges) {
    uint64_t chains = 0;
    for (const detail::ElementRange& r : ranges) chains += r.count;
    const std::vector<double> zeros(chains * 12, 0.0);  // a mat3x4 per chain at most
    HMSM_TRY(backend_->write_ranges(BufferId::chain_state, ranges, zeros.data(), detail::Scalar::f64));
    HMSM_TRY(backend_->write_ranges(BufferId::chain_force, ranges, zeros.data(), detail::Scalar::f64));
    if (data_->holds_loads()) {  // both halves of the loads
        std::vector<detail::ElementRange> both_halves;
        for (uint64_t half : {uint64_t(0), data_->chain_capacity})
            for (const detail::ElementRange& r : ranges) both_halves.push_back({half + r.first, r.count});
        HMSM_TRY(backend_->write_ranges(BufferId::chain_load, both_halves, zeros.data(), detail::Scalar::f64));
    }
    // The articulated exchange's impulses, which a run at rest from integrate sweeps in place of
    // pass 1's (they lie where T goes: gpu_layout.h).
    if (data_->articulated())
        HMSM_TRY(backend_->write_ranges(BufferId::chain_local, ranges, zeros.data(), detail::Scalar::f64));
    return {};
}

Status Simulation::Impl::reshape_in_place(std::unique_ptr<detail::SceneData> next,
                                          const std::vector<uint32_t>& survivors,
                                          const std::vector<uint64_t>& old_chain, uint32_t first_moved) {
    // The buffers keep their allocation and static data: survivors' state moves down on the
    // device, the instance buffers and the added instances' state are written.
    next->chain_capacity = data_->chain_capacity;
    next->node_capacity = data_->node_capacity;
    next->vertex_capacity = data_->vertex_capacity;
    next->instance_capacity = data_->instance_capacity;
    uint64_t at = 0;  // chains the survivors hold
    const std::vector<detail::ElementMove> moves = survivor_moves(survivors, old_chain, at);
    for (BufferId id : carried_buffers(data_->holds_loads())) {
        std::vector<detail::ElementMove> in_buffer;
        for (uint64_t h = 0; h < halves_of(id); ++h)
            for (detail::ElementMove m : moves) {
                m.src += h * next->chain_capacity;
                m.dst += h * next->chain_capacity;
                in_buffer.push_back(m);
            }
        HMSM_TRY(backend_->move_elements(id, in_buffer));
    }
    // The survivors' outputs (nodes, vertices) move with them: bitwise what they were, and a
    // copy instead of passes 4, 6 and 7 over every instance behind the first gap.
    const std::vector<uint64_t> old_node =
        running_offsets(instances_, [&](uint32_t model) { return data_->models[model].node_count; });
    const std::vector<uint64_t> old_vertex =
        running_offsets(instances_, [&](uint32_t model) { return data_->models[model].vertex_count; });
    uint64_t nodes = 0, vertices = 0;
    const std::vector<detail::ElementMove> node_moves = survivor_moves(survivors, old_node, nodes);
    const std::vector<detail::ElementMove> vertex_moves = survivor_moves(survivors, old_vertex, vertices);
    for (BufferId id : kMovedOutputs) {
        if (data_->element_count(id) == 0) continue;
        const bool node_scope = detail::buffer_info(id).scope == detail::Scope::node;
        HMSM_TRY(backend_->move_elements(id, node_scope ? node_moves : vertex_moves));
    }
    // Added instances start at rest: S = V = 0 and g = 0 (T, R, O are computed from them).
    // (The capacity and the dynamics are data_'s, which zero_chain_state reads.)
    const uint64_t added_chains = next->total_chains - at;
    if (added_chains > 0) HMSM_TRY(zero_chain_state(std::array{detail::ElementRange{at, added_chains}}));
    // Origins and yaws of the instances that changed place or came, every run in one write.
    const uint32_t count = next->instance_count();
    std::vector<detail::ElementRange> runs;
    for (uint32_t first = first_moved; first < count;) {
        uint32_t end = first + 1;
        while (end < count && (end >= survivors.size() || survivors[end] != end)) ++end;
        runs.push_back({first, end - first});
        first = end;
        while (first < count && first < survivors.size() && survivors[first] == first) ++first;
    }
    std::vector<double> values;
    for (BufferId id : {BufferId::instance_origin, BufferId::instance_yaw}) {
        const auto& source = id == BufferId::instance_origin ? next->instance_origin : next->instance_yaw;
        values.clear();
        for (const detail::ElementRange& r : runs)
            for (uint64_t i = r.first; i < r.first + r.count; ++i)
                for (int c = 0; c < 4; ++c) values.push_back(source[i][c]);
        HMSM_TRY(backend_->write_ranges(id, runs, values.data(), detail::Scalar::f64));
    }
    data_->take_instance_layout(std::move(*next));
    return {};
}

Status Simulation::Impl::reshape_anew(std::unique_ptr<detail::SceneData> next,
                                      const std::vector<uint32_t>& survivors,
                                      const std::vector<uint64_t>& old_chain) {
    // Read the state back in the precision the backend stores it in (so that it carries over
    // bit for bit), allocate with room to grow, upload, write the state back. Only live chains
    // are read and written: a scene split into windows maps no element past them.
    {
        detail::SceneData whole = *data_;  // the model arrays and uniforms, then the new layout
        whole.take_instance_layout(std::move(*next));
        *next = std::move(whole);
    }
    const uint64_t limit = kMaxStateElements;
    // growth_: the room a swap removal's staging asked for, grown as the live counts are.
    auto room = [&](uint64_t current, uint64_t live, uint64_t reserved, uint64_t staging) {
        return std::max({grown_capacity(current, live, limit), reserved,
                         grown_capacity(current, std::min(staging, limit), limit)});
    };
    next->chain_capacity = room(data_->chain_capacity, next->total_chains, reserved_.chains, growth_.chains);
    next->node_capacity = room(data_->node_capacity, next->total_nodes, reserved_.nodes, growth_.nodes);
    next->vertex_capacity = room(data_->vertex_capacity, next->total_vertices, reserved_.vertices, growth_.vertices);
    next->instance_capacity = uint32_t(std::max<uint64_t>(
        grown_capacity(data_->instance_capacity, next->instance_count(), detail::kMaxGrownInstances),
        reserved_.instances));
    growth_ = {};
    const detail::Scalar scalar = backend_->kind() == BackendKind::cpu64 ? detail::Scalar::f64 : detail::Scalar::f32;
    struct Saved {
        std::vector<double> f64;
        std::vector<float> f32;
    };
    const std::vector<BufferId> carried = carried_buffers(data_->holds_loads());
    std::vector<Saved> saved(std::size(carried));  // per buffer, the halves back to back
    const uint64_t live = data_->total_chains;
    for (size_t b = 0; b < std::size(carried); ++b) {
        const uint32_t per = detail::shape_scalars(detail::buffer_info(carried[b]).shape);
        const uint64_t scalars = halves_of(carried[b]) * live * per;
        if (scalar == detail::Scalar::f64) saved[b].f64.resize(scalars);
        else saved[b].f32.resize(scalars);
        for (uint32_t h = 0; h < halves_of(carried[b]); ++h) {
            void* dst = scalar == detail::Scalar::f64 ? static_cast<void*>(saved[b].f64.data() + h * live * per)
                                                      : static_cast<void*>(saved[b].f32.data() + h * live * per);
            HMSM_TRY(backend_->read(carried[b], h * data_->chain_capacity, live, dst, scalar));
        }
    }
    template_zone_.forget();
    HMSM_TRY(backend_->upload(*next));
    data_ = std::move(next);
    ++full_uploads_;
    for (size_t b = 0; b < std::size(carried); ++b) {
        const uint32_t per = detail::shape_scalars(detail::buffer_info(carried[b]).shape);
        auto carry = [&](auto& values) -> Status {
            using V = typename std::decay_t<decltype(values)>::value_type;
            std::vector<V> out(live * per);
            for (uint32_t h = 0; h < halves_of(carried[b]); ++h) {
                uint64_t at = 0;
                for (uint32_t i : survivors) {
                    const uint64_t from = h * live + old_chain[i];
                    const uint64_t n = old_chain[i + 1] - old_chain[i];
                    std::copy_n(values.begin() + from * per, n * per, out.begin() + at * per);
                    at += n;
                }
                HMSM_TRY(backend_->write(carried[b], h * data_->chain_capacity, at, out.data(), scalar));
            }
            return {};
        };
        HMSM_TRY(scalar == detail::Scalar::f64 ? carry(saved[b].f64) : carry(saved[b].f32));
    }
    return {};
}

}  // namespace hmsm
