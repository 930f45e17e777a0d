// Stable instance handles (docs/driving.md, instance handles): every instance gets the next
// unused id when it enters the simulation. Removal keeps the survivors' order and additions
// append, so the current ids are always ascending and an id is found by binary search.
#include "simulation_impl.h"

#include <algorithm>
#include <string>

namespace hmsm {

namespace {

std::string id_name(InstanceId id) { return "instance id " + std::to_string(uint64_t(id)); }

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
    auto found = std::lower_bound(ids.begin(), ids.end(), id);
    if (found != ids.end() && *found == id) return uint64_t(found - ids.begin());
    if (uint64_t(id) < impl_->next_instance_id_)
        return Status{ErrorCode::invalid_argument, id_name(id) + " was removed"};
    return Status{ErrorCode::invalid_argument, id_name(id) + " was never given (the next id is " +
                                                   std::to_string(impl_->next_instance_id_) + ")"};
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
    std::vector<uint64_t> indices;
    indices.reserve(ids.size());
    for (InstanceId id : ids) {
        Result<uint64_t> index = index_of(id);
        if (!index) return index.status();
        indices.push_back(*index);
    }
    std::vector<uint64_t> sorted = indices;
    std::sort(sorted.begin(), sorted.end());
    if (auto twice = std::adjacent_find(sorted.begin(), sorted.end()); twice != sorted.end())
        return {ErrorCode::invalid_argument, id_name(impl_->instance_ids_[*twice]) + " is listed twice for removal"};
    return remove_instances(indices);
}

}  // namespace hmsm
