// Room reserved up front (docs/driving.md, streaming budgets): the capacities grow once, now,
// so that adding instances and switching their levels within the room later costs only what
// those changes touch. reserve_instances(count) sizes the room for `count` instances of the
// largest model; reserve_instances(per_level) for a world of levels of detail, where most
// instances run coarse levels and room for all at the full level would be tens of times too
// large (500,000 paper-1 trees: 1.2 billion chains against about 19 million).
#include "capacity_growth.h"
#include "simulation_impl.h"

#include <algorithm>
#include <string>

namespace hmsm {

Status Simulation::Impl::reserve_room(const Reserved& room) {
    const detail::SceneData& d = *data_;
    const bool fits = room.chains <= d.chain_capacity && room.nodes <= d.node_capacity &&
                      room.vertices <= d.vertex_capacity && room.instances <= d.instance_capacity;
    const Reserved before = reserved_;
    reserved_ = room;
    if (fits || !backend_->capabilities().reshapes_in_place) return {};
    const detail::ElementCounts live{d.total_chains, d.total_nodes, d.total_vertices};
    Result<bool> on_device = grow_on_device(live, d.instance_count());
    if (!on_device) reserved_ = before;
    if (!on_device || *on_device) return on_device.status();
    std::vector<uint32_t> everyone(instances_.size());
    for (uint32_t i = 0; i < everyone.size(); ++i) everyone[i] = i;
    Status grown_now = reshape(everyone, {}, /*reupload=*/true);
    if (!grown_now) reserved_ = before;
    return grown_now;
}

namespace {

Status too_large(const std::string& what) {
    return {ErrorCode::unsupported, "reserve_instances: room for " + what + " would take more than " +
                                        std::to_string(detail::kMaxStateElements) + " elements of one buffer"};
}

}  // namespace

Status Simulation::reserve_instances(uint64_t count) {
    Impl& s = *impl_;
    if (count > kMaxInstances)
        return {ErrorCode::unsupported, "reserve_instances: " + std::to_string(count) + " instances, at most " +
                                            std::to_string(kMaxInstances) + " are supported"};
    Impl::Reserved room;
    for (const detail::ModelRange& m : s.data_->models) {
        room.chains = std::max(room.chains, count * m.chain_count);
        room.nodes = std::max(room.nodes, count * m.node_count);
        room.vertices = std::max(room.vertices, count * m.vertex_count);
    }
    room.instances = count;
    if (room.chains > detail::kMaxStateElements || room.nodes > detail::kMaxStateElements ||
        room.vertices > detail::kMaxStateElements)
        return too_large(std::to_string(count) + " instances of the largest model");
    return s.reserve_room(room);
}

Status Simulation::reserve_instances(std::span<const uint64_t> per_level) {
    Impl& s = *impl_;
    size_t levels = 0;
    for (const std::vector<uint32_t>& of_model : s.levels_of_) levels = std::max(levels, of_model.size());
    if (per_level.empty())
        return {ErrorCode::invalid_argument, "reserve_instances: no level counts given (one per level, finest first)"};
    if (per_level.size() > levels)
        return {ErrorCode::invalid_argument, "reserve_instances: " + std::to_string(per_level.size()) +
                                                 " level counts, but the scene's models have at most " +
                                                 std::to_string(levels) + " levels (Scene::lod_budgets)"};
    Impl::Reserved room;
    for (size_t k = 0; k < per_level.size(); ++k) {
        const uint64_t count = per_level[k];
        if (count > kMaxInstances || room.instances + count > kMaxInstances)
            return {ErrorCode::unsupported, "reserve_instances: level " + std::to_string(k) + " brings the instances to " +
                                                std::to_string(room.instances + count) + ", at most " +
                                                std::to_string(kMaxInstances) + " are supported"};
        // The largest run model at level k among the scene models that have it.
        detail::ElementCounts largest{};
        for (const std::vector<uint32_t>& of_model : s.levels_of_) {
            if (k >= of_model.size()) continue;
            const detail::ModelRange& m = s.data_->models[of_model[k]];
            largest.chains = std::max<uint64_t>(largest.chains, m.chain_count);
            largest.nodes = std::max<uint64_t>(largest.nodes, m.node_count);
            largest.vertices = std::max<uint64_t>(largest.vertices, m.vertex_count);
        }
        room.chains += count * largest.chains;  // the counts sum to at most 2^24: no overflow
        room.nodes += count * largest.nodes;
        room.vertices += count * largest.vertices;
        room.instances += count;
    }
    // A level switch on a device that copies patterns (CUDA, Vulkan) unfolds chains from one
    // template of each level at rest, kept above the instances (docs/architecture.md): room
    // for all of them.
    for (const detail::ModelRange& m : s.data_->models) room.chains += m.chain_count;
    if (room.chains > detail::kMaxStateElements || room.nodes > detail::kMaxStateElements ||
        room.vertices > detail::kMaxStateElements)
        return too_large(std::to_string(room.instances) + " instances at the levels given");
    return s.reserve_room(room);
}

}  // namespace hmsm
