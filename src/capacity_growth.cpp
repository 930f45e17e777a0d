// Growth past the capacity on the device (docs/driving.md, streaming budgets): the buffers the
// capacities size are reallocated 1.5 times larger (or as large as needed, or as reserved) and
// take their live elements with device copies (Backend::grow), so that the change that outgrew
// them goes on in place, at the cost of the instances it touches plus one device copy of the
// live state. Nothing of the state goes through the host.
#include "capacity_growth.h"
#include "simulation_impl.h"

#include <algorithm>

namespace hmsm {

Result<bool> Simulation::Impl::grow_on_device(const detail::ElementCounts& needed, uint64_t instances) {
    detail::SceneData& d = *data_;
    using detail::grown_capacity;
    const uint64_t limit = detail::kMaxStateElements;
    const uint64_t chains = std::max(grown_capacity(d.chain_capacity, needed.chains, limit), reserved_.chains);
    const uint64_t nodes = std::max(grown_capacity(d.node_capacity, needed.nodes, limit), reserved_.nodes);
    const uint64_t vertices = std::max(grown_capacity(d.vertex_capacity, needed.vertices, limit), reserved_.vertices);
    const uint64_t instance_room = std::max<uint64_t>(
        grown_capacity(d.instance_capacity, instances, detail::kMaxGrownInstances), reserved_.instances);
    if (chains == d.chain_capacity && nodes == d.node_capacity && vertices == d.vertex_capacity &&
        instance_room == d.instance_capacity)
        return true;
    const detail::BackendCapabilities can = backend_->capabilities();
    if (!device_growth_ || !can.grows_on_device || !can.reshapes_in_place || instance_room > kMaxInstances)
        return false;
    const uint64_t old_chains = d.chain_capacity, old_nodes = d.node_capacity, old_vertices = d.vertex_capacity;
    const uint32_t old_instances = d.instance_capacity;
    d.chain_capacity = chains;
    d.node_capacity = nodes;
    d.vertex_capacity = vertices;
    d.instance_capacity = uint32_t(instance_room);
    template_zone_.forget();  // the growth carries the slots, not what lies above them
    const Status grown = backend_->grow(d);
    if (!grown) {
        // The backend left every buffer as it was: so are the capacities.
        d.chain_capacity = old_chains;
        d.node_capacity = old_nodes;
        d.vertex_capacity = old_vertices;
        d.instance_capacity = old_instances;
        if (grown.code() == ErrorCode::unsupported) return false;  // the full path grows it
        return grown;
    }
    ++device_growths_;
    growth_ = {};
    // The stride between ping-pong halves is a constant of every dispatch, and the angles
    // integrated ahead lie in a twin that was not carried.
    program_dirty_ = true;
    ahead_schedule_.live_change();
    return true;
}

}  // namespace hmsm
