// Streaming an open world (docs/driving.md, streaming budgets): appends and swap removals
// within the capacity edit the instance list, its groups, offsets and handles where the change
// touches it, and move on the device only the state of the instances that change place, so a
// call costs in proportion to the instances it adds or removes (and the groups behind the first
// of them), not to the scene. Results are bit for bit those of reshape() (live_reshape.cpp).
#include "instance_moves.h"
#include "simulation_impl.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <string>

namespace hmsm {

namespace {

using detail::BufferId;
using detail::ElementCounts;
using detail::ElementMove;


/// The moves of one scope (chains, nodes or vertices) of a swap removal, applied in order:
/// the instances that fill the holes go to staging above every live element, the survivors
/// between the holes shift (ordered_shifts), and the staged instances go to their holes.
struct ScopeMoves {
    std::vector<ElementMove> stage, shift, unstage;
};

uint64_t pick(const ElementCounts& c, int scope) {
    return scope == 0 ? c.chains : scope == 1 ? c.nodes : c.vertices;
}

/// Applies `moves` to buffer `id`, each half of a ping-pong buffer `capacity` elements apart.
Status apply_moves(detail::Backend& backend, BufferId id, const std::vector<ElementMove>& moves, uint64_t capacity) {
    if (moves.empty()) return {};
    if (detail::halves_of(id) == 1) return backend.move_elements(id, moves);
    std::vector<ElementMove> both;
    both.reserve(2 * moves.size());
    for (uint64_t h = 0; h < 2; ++h)
        for (ElementMove m : moves) {
            m.src += h * capacity;
            m.dst += h * capacity;
            both.push_back(m);
        }
    return backend.move_elements(id, both);
}

}  // namespace

detail::InstanceOffsets& Simulation::Impl::offsets() {
    if (!offsets_valid_) {
        offsets_.assign(instances_, data_->models);
        offsets_valid_ = true;
    }
    return offsets_;
}

void Simulation::Impl::instance_list_laid_out() {
    offsets_valid_ = false;
    placed_ = data_ && backend_ && wants_placed();
    if (placed_) placements_laid_out();
    lod_tracker_.invalidate();
    paused_count_ = uint64_t(std::count_if(instances_.begin(), instances_.end(), [](const Instance& i) { return !i.active; }));
}

Status Simulation::Impl::check_size(uint64_t count, const detail::ElementCounts& elements) const {
    if (elements.vertices >= std::numeric_limits<uint32_t>::max() ||
        2 * elements.chains >= std::numeric_limits<uint32_t>::max() ||
        elements.nodes >= std::numeric_limits<uint32_t>::max() || count > kMaxInstances)
        return Status{ErrorCode::unsupported,
                      "scene too large: " + std::to_string(count) + " instances with " + std::to_string(elements.vertices) +
                          " mesh vertices and " + std::to_string(elements.chains) +
                          " chains over all instances (at most 2^32 - 1 elements and " + std::to_string(kMaxInstances) +
                          " instances are supported)"};
    return {};
}

Result<bool> Simulation::Impl::append_in_place(std::span<const Instance> added) {
    if (placed_) return append_placed(added);
    detail::SceneData& d = *data_;
    const uint32_t first = uint32_t(instances_.size());
    const ElementCounts live{d.total_chains, d.total_nodes, d.total_vertices};
    ElementCounts grown = live;
    for (const Instance& inst : added) grown += detail::counts_of(d.models[inst.model]);
    HMSM_TRY(check_size(uint64_t(first) + added.size(), grown));
    if (!backend_->capabilities().reshapes_in_place) return false;
    if (grown.chains > d.chain_capacity || grown.nodes > d.node_capacity || grown.vertices > d.vertex_capacity ||
        uint64_t(first) + added.size() > d.instance_capacity) {
        // Past the capacity: the buffers grow on the device where the backend can.
        Result<bool> room = grow_on_device(grown, uint64_t(first) + added.size());
        if (!room || !*room) return room;
    }
    detail::InstanceChangeBracket change(*backend_);
    ahead_schedule_.live_change();
    detail::InstanceOffsets& offsets = this->offsets();

    // Added instances start at rest: S = V = 0 and g = 0 (T, R, O are computed from them).
    const uint64_t added_chains = grown.chains - live.chains;
    if (added_chains > 0) HMSM_TRY(zero_chain_state(std::array{detail::ElementRange{live.chains, added_chains}}));
    std::vector<uint32_t> appended;
    appended.reserve(added.size());
    for (const Instance& inst : added) {
        const uint32_t i = uint32_t(instances_.size());
        appended.push_back(i);
        instances_.push_back(inst);
        const InstanceId id = InstanceId(next_instance_id_++);
        instance_ids_.push_back(id);  // ascending ids stay ascending
        if (!ids_ascending_) id_index_.emplace(uint64_t(id), i);
        d.instance_origin.push_back({inst.origin, 0.0});
        d.instance_yaw.push_back({std::cos(inst.yaw), std::sin(inst.yaw), 0.0, 0.0});
        offsets.push_back(detail::counts_of(d.models[inst.model]));
        lod_tracker_.append();
        if (!inst.active) ++paused_count_;
        dirty_instances_.push_back(i);
    }
    d.instance_wind.resize(size_t(HMSM_INSTANCE_WIND_VEC4S) * 4 * instances_.size(), 0.0);
    detail::relay_groups(d, instances_, appended);
    const detail::ElementRange appended_run{first, instances_.size() - first};
    HMSM_TRY(detail::write_origins_and_yaws(*backend_, d, {&appended_run, 1}));
    instances_changed();
    header_dirty_ = program_dirty_ = true;

    // The added instances' groups: posed at rest from S = V = 0.
    auto at = std::upper_bound(d.groups.begin(), d.groups.end(), first,
                               [](uint32_t i, const detail::InstanceGroup& g) { return i < g.instance_begin; });
    std::vector<detail::InstanceGroup> posed;
    for (auto g = at - 1; g != d.groups.end(); ++g)
        posed.push_back(detail::group_slice(d, *g, std::max(first, g->instance_begin),
                                            g->instance_begin + g->instance_count - std::max(first, g->instance_begin)));
    HMSM_TRY(run_at_rest(posed, Pass::integrate));
    HMSM_TRY(apply_pending());
    return true;
}

Result<bool> Simulation::Impl::swap_remove_in_place(const std::vector<uint32_t>& removed) {
    if (placed_) {
        HMSM_TRY(swap_remove_placed(removed));
        return true;
    }
    detail::SceneData& d = *data_;
    const uint32_t n = uint32_t(instances_.size());
    const detail::SwapFill fill = detail::swap_fill(removed, n);
    const std::vector<uint32_t>&holes = fill.holes, &fillers = fill.fillers;
    detail::InstanceOffsets& offsets = this->offsets();
    auto size = [&](uint32_t i) { return detail::counts_of(d.models[instances_[i].model]); };
    const ElementCounts live{d.total_chains, d.total_nodes, d.total_vertices};
    ElementCounts staged;
    bool same_sizes = true;  // each filler as large as the instance it replaces: nothing shifts
    for (size_t j = 0; j < fillers.size(); ++j) {
        staged += size(fillers[j]);
        same_sizes = same_sizes && size(fillers[j]) == size(holes[j]);
    }
    // Staging lies above every live element, in each scope; without shifts the fillers go
    // straight into the holes, which lie below every filler.
    const ElementCounts room = live + staged;
    if (!same_sizes &&
        (room.chains > d.chain_capacity || room.nodes > d.node_capacity || room.vertices > d.vertex_capacity)) {
        // The staging room grows on the device where the backend can; else the next upload
        // takes it.
        Result<bool> grown = grow_on_device(room, n);
        if (!grown) return grown;
        if (!*grown) {
            growth_ = {room.chains, room.nodes, room.vertices, 0};
            return false;
        }
    }

    // The moves of each scope; delta: what the holes before gained over the removed instances.
    ScopeMoves scopes[3];
    {
        std::vector<ElementMove> ascending[3];
        std::vector<ElementCounts> filler_at(fillers.size());
        ElementCounts at_staging = live;
        for (size_t j = 0; j < fillers.size(); ++j) {
            filler_at[j] = offsets.before(fillers[j]);
            for (int s = 0; s < 3; ++s)
                detail::append_move(scopes[s].stage, pick(filler_at[j], s), pick(at_staging, s), pick(size(fillers[j]), s));
            at_staging += size(fillers[j]);
        }
        ElementCounts delta, staging = live;
        uint32_t begin = 0;  // first survivor of the run that keeps its instance
        for (size_t j = 0; j <= holes.size(); ++j) {
            const uint32_t end = j < holes.size() ? holes[j] : fill.kept;
            if (end > begin) {
                const ElementCounts from = offsets.before(begin), to = offsets.before(end);
                for (int s = 0; s < 3; ++s)
                    if (pick(delta, s) != 0 && pick(to, s) > pick(from, s))
                        ascending[s].push_back({pick(from, s), pick(from + delta, s), pick(to - from, s)});
            }
            if (j == holes.size()) break;
            const ElementCounts hole_at = offsets.before(holes[j]) + delta;
            const ElementCounts source = same_sizes ? filler_at[j] : staging;
            for (int s = 0; s < 3; ++s) detail::append_move(scopes[s].unstage, pick(source, s), pick(hole_at, s), pick(size(fillers[j]), s));
            staging += size(fillers[j]);
            delta += size(fillers[j]);
            delta -= size(holes[j]);
            begin = holes[j] + 1;
        }
        for (int s = 0; s < 3; ++s) {
            scopes[s].shift = detail::ordered_shifts(ascending[s]);
            if (same_sizes) scopes[s].stage.clear();
        }
    }

    detail::InstanceChangeBracket change(*backend_);
    ahead_schedule_.live_change();  // the state moves, the angles integrated ahead with it
    auto move_scope = [&](BufferId id, const ScopeMoves& moves) -> Status {
        std::vector<ElementMove> in_order;  // the three parts in one call, applied in order
        for (const std::vector<ElementMove>* part : {&moves.stage, &moves.shift, &moves.unstage})
            in_order.insert(in_order.end(), part->begin(), part->end());
        return apply_moves(*backend_, id, in_order, d.chain_capacity);
    };
    for (BufferId id : detail::carried_buffers(d.holds_loads())) HMSM_TRY(move_scope(id, scopes[0]));
    // The survivors' outputs (nodes, vertices) move with them, bitwise what they were.
    for (BufferId id : detail::kMovedOutputs) {
        if (d.element_count(id) == 0) continue;
        HMSM_TRY(move_scope(id, detail::buffer_info(id).scope == detail::Scope::node ? scopes[1] : scopes[2]));
    }

    // The host's lists: each hole takes its filler, the end is cut.
    for (size_t j = 0; j < holes.size(); ++j) offsets.add(holes[j], size(fillers[j]) - size(holes[j]));
    for (uint32_t k = fill.kept; k < n; ++k) offsets.pop_back();
    HMSM_TRY(swap_instance_lists(removed, fill));
    return true;
}

Status Simulation::Impl::swap_instance_lists(const std::vector<uint32_t>& removed, const detail::SwapFill& fill) {
    detail::SceneData& d = *data_;
    const uint32_t n = uint32_t(instances_.size()), kept = fill.kept;
    if (ids_ascending_ && !fill.holes.empty()) {
        id_index_.clear();
        id_index_.reserve(instance_ids_.size());
        for (uint32_t i = 0; i < n; ++i) id_index_.emplace(uint64_t(instance_ids_[i]), i);
        ids_ascending_ = false;
    }
    for (uint32_t r : removed) {
        if (!instances_[r].active) --paused_count_;
        if (!ids_ascending_) id_index_.erase(uint64_t(instance_ids_[r]));
    }
    for (size_t j = 0; j < fill.holes.size(); ++j) {
        const uint32_t h = fill.holes[j], f = fill.fillers[j];
        instances_[h] = instances_[f];
        instance_ids_[h] = instance_ids_[f];
        id_index_[uint64_t(instance_ids_[h])] = h;
        d.instance_origin[h] = d.instance_origin[f];
        d.instance_yaw[h] = d.instance_yaw[f];
        lod_tracker_.moved(f, h);
    }
    instances_.resize(kept);
    instance_ids_.resize(kept);
    d.instance_origin.resize(kept);
    d.instance_yaw.resize(kept);
    d.instance_wind.resize(size_t(HMSM_INSTANCE_WIND_VEC4S) * 4 * kept);
    lod_tracker_.resize(kept);
    if (!placed_) detail::relay_groups(d, instances_, fill.holes);  // the placed layout keeps no groups
    instances_changed();
    header_dirty_ = program_dirty_ = true;

    // Origins, yaws and winds of the holes, run by run.
    std::erase_if(dirty_instances_, [&](uint32_t i) { return i >= kept; });
    HMSM_TRY(detail::write_origins_and_yaws(*backend_, d, detail::index_ranges(fill.holes)));
    dirty_instances_.insert(dirty_instances_.end(), fill.holes.begin(), fill.holes.end());
    return apply_pending();
}

}  // namespace hmsm
