// Stable instance handles (docs/driving.md, instance handles): every instance gets the next
// unused id when it enters the simulation. Ordered removal keeps the survivors' order and
// additions append, so the ids stay ascending and an id is found by binary search; after a swap
// removal (docs/model.md 3.9) a hash index of the current ids answers instead.
#include "simulation_impl.h"

#include <algorithm>
#include <string>
#include <unordered_map>

namespace hmsm {

namespace {

std::string id_name(InstanceId id) { return "instance id " + std::to_string(uint64_t(id)); }

/// The current indices of `ids`, or an error naming the first id removed, never given or
/// listed twice.
Result<std::vector<uint64_t>> indices_of(const Simulation& sim, std::span<const InstanceId> ids) {
    std::vector<uint64_t> indices;
    indices.reserve(ids.size());
    for (InstanceId id : ids) {
        Result<uint64_t> index = sim.index_of(id);
        if (!index) return index.status();
        indices.push_back(*index);
    }
    std::vector<uint64_t> sorted = indices;
    std::sort(sorted.begin(), sorted.end());
    if (auto twice = std::adjacent_find(sorted.begin(), sorted.end()); twice != sorted.end())
        return Status{ErrorCode::invalid_argument,
                      id_name(sim.instance_ids()[*twice]) + " is listed twice for removal"};
    return indices;
}

}  // namespace

Status Simulation::add_instances(std::span<const Instance> instances, std::span<InstanceId> ids) {
    if (ids.size() != instances.size())
        return {ErrorCode::invalid_argument, "add_instances: " + std::to_string(instances.size()) +
                                                 " instances but room for " + std::to_string(ids.size()) + " ids"};
    HMSM_TRY(add_instances(instances));
    const std::span<const InstanceId> now = impl_->instance_ids_;
    std::copy(now.end() - std::ptrdiff_t(instances.size()), now.end(), ids.begin());
    return {};
}

Result<uint64_t> Simulation::index_of(InstanceId id) const {
    const std::vector<InstanceId>& ids = impl_->instance_ids_;
    if (impl_->ids_ascending_) {
        auto found = std::lower_bound(ids.begin(), ids.end(), id);
        if (found != ids.end() && *found == id) return uint64_t(found - ids.begin());
    } else {
        const std::unordered_map<uint64_t, uint32_t>& index = impl_->id_index_;
        if (auto found = index.find(uint64_t(id)); found != index.end()) return uint64_t(found->second);
    }
    if (uint64_t(id) < impl_->next_instance_id_)
        return Status{ErrorCode::invalid_argument, id_name(id) + " was removed"};
    return Status{ErrorCode::invalid_argument, id_name(id) + " was never given (the next id is " +
                                                   std::to_string(impl_->next_instance_id_) + ")"};
}

Result<InstancePlacement> Simulation::instance_placement(InstanceId id) const {
    Result<uint64_t> index = index_of(id);
    if (!index) return Status{index.status().code(), "instance_placement: " + index.status().message()};
    const Impl& s = *impl_;
    const uint32_t i = uint32_t(*index);
    if (s.placed_) {
        const detail::ElementCounts& at = s.placements_[i];
        return InstancePlacement{at.chains, at.nodes, at.vertices};
    }
    // Packed: from the group holding the instance, whose instances lie back to back.
    const std::vector<detail::InstanceGroup>& groups = s.data_->groups;
    auto g = std::upper_bound(groups.begin(), groups.end(), i,
                              [](uint32_t at, const detail::InstanceGroup& group) { return at < group.instance_begin; });
    --g;
    const detail::ModelRange& m = s.data_->models[g->model];
    const uint64_t k = i - g->instance_begin;
    return InstancePlacement{g->chain_begin + k * m.chain_count, g->node_begin + k * m.node_count,
                             g->vertex_begin + k * m.vertex_count};
}

Result<InstanceId> Simulation::id_of(uint64_t index) const {
    if (index >= impl_->instance_ids_.size())
        return Status{ErrorCode::invalid_argument, "instance " + std::to_string(index) +
                                                       " does not exist (the simulation has " +
                                                       std::to_string(impl_->instance_ids_.size()) + " instances)"};
    return impl_->instance_ids_[index];
}

std::span<const InstanceId> Simulation::instance_ids() const { return impl_->instance_ids_; }

Status Simulation::remove_instances_by_id(std::span<const InstanceId> ids) {
    Result<std::vector<uint64_t>> indices = indices_of(*this, ids);
    if (!indices) return indices.status();
    return remove_instances(*indices);
}

Status Simulation::swap_remove_instances(std::span<const InstanceId> ids) {
    if (ids.empty()) return {};
    Result<std::vector<uint64_t>> indices = indices_of(*this, ids);
    if (!indices) return indices.status();
    Impl& s = *impl_;
    const uint32_t n = uint32_t(s.instances_.size());
    if (indices->size() == n)
        return {ErrorCode::invalid_argument,
                "cannot remove every instance: a simulation keeps at least one (deactivate it instead)"};
    auto removed_fades = [&] {  // a removed instance fades no more
        for (InstanceId id : ids) s.fades_.erase(uint64_t(id));
    };
    if (s.streaming_paths_ && s.backend_->capabilities().reshapes_in_place) {
        std::vector<uint32_t> sorted(indices->begin(), indices->end());
        std::sort(sorted.begin(), sorted.end());
        Result<bool> in_place = s.swap_remove_in_place(sorted);
        if (!in_place) return in_place.status();
        if (*in_place) {
            removed_fades();
            return {};
        }
        // No room to stage the fillers: the general path, in place where the moves allow,
        // else uploading anew with the room the staging asked for (growth_).
    }
    std::vector<bool> removed(n, false);
    for (uint64_t i : *indices) removed[i] = true;
    // The holes below the new count take, in ascending order, the survivors at or past it in
    // their order; every other survivor keeps its index.
    const uint32_t kept = n - uint32_t(indices->size());
    std::vector<uint32_t> survivors(kept);
    uint32_t from = kept;
    for (uint32_t k = 0; k < kept; ++k) {
        if (!removed[k]) {
            survivors[k] = k;
            continue;
        }
        while (removed[from]) ++from;
        survivors[k] = from++;
    }
    HMSM_TRY(s.reshape(survivors, {}));
    removed_fades();
    return {};
}

}  // namespace hmsm
