// The C ABI's stable instance handles (Simulation::index_of and friends, docs/driving.md).
#include "c_api_internal.h"
#include "c_struct.h"

#include <algorithm>
#include <vector>

using namespace hmsm;
using namespace hmsm::c_api;

extern "C" {

hmsm_status hmsm_simulation_add_instances_with_ids(hmsm_simulation* simulation, const hmsm_instance* instances,
                                                   size_t count, hmsm_instance_id* ids) {
    return guarded([&]() -> Status {
        const char* fn = "hmsm_simulation_add_instances_with_ids";
        if (!simulation) return bad(std::string(fn) + ": simulation is NULL");
        if (!ids && count > 0) return bad(std::string(fn) + ": ids is NULL with count > 0");
        std::vector<Instance> converted;
        HMSM_TRY(read_instances(fn, instances, count, converted));
        std::vector<InstanceId> added(count);
        HMSM_TRY(simulation->simulation->add_instances(converted, added));
        std::transform(added.begin(), added.end(), ids, [](InstanceId id) { return uint64_t(id); });
        return {};
    });
}

hmsm_status hmsm_simulation_remove_instances_by_id(hmsm_simulation* simulation, const hmsm_instance_id* ids,
                                                   size_t count) {
    return guarded([&]() -> Status {
        const char* fn = "hmsm_simulation_remove_instances_by_id";
        if (!simulation) return bad(std::string(fn) + ": simulation is NULL");
        if (!ids && count > 0) return bad(std::string(fn) + ": ids is NULL with count > 0");
        std::vector<InstanceId> copied(count);
        std::transform(ids, ids + count, copied.begin(), [](uint64_t id) { return InstanceId(id); });
        return simulation->simulation->remove_instances_by_id(copied);
    });
}

hmsm_status hmsm_simulation_swap_remove_instances(hmsm_simulation* simulation, const hmsm_instance_id* ids,
                                                  size_t count) {
    return guarded([&]() -> Status {
        const char* fn = "hmsm_simulation_swap_remove_instances";
        if (!simulation) return bad(std::string(fn) + ": simulation is NULL");
        if (!ids && count > 0) return bad(std::string(fn) + ": ids is NULL with count > 0");
        std::vector<InstanceId> copied(count);
        std::transform(ids, ids + count, copied.begin(), [](uint64_t id) { return InstanceId(id); });
        return simulation->simulation->swap_remove_instances(copied);
    });
}

hmsm_status hmsm_simulation_index_of(const hmsm_simulation* simulation, hmsm_instance_id id, uint64_t* index) {
    return guarded([&]() -> Status {
        const char* fn = "hmsm_simulation_index_of";
        if (!simulation) return bad(std::string(fn) + ": simulation is NULL");
        if (!index) return bad(std::string(fn) + ": index is NULL");
        Result<uint64_t> found = simulation->simulation->index_of(InstanceId(id));
        if (!found) return {found.status().code(), std::string(fn) + ": " + found.status().message()};
        *index = *found;
        return {};
    });
}

hmsm_status hmsm_simulation_id_of(const hmsm_simulation* simulation, uint64_t index, hmsm_instance_id* id) {
    return guarded([&]() -> Status {
        const char* fn = "hmsm_simulation_id_of";
        if (!simulation) return bad(std::string(fn) + ": simulation is NULL");
        if (!id) return bad(std::string(fn) + ": id is NULL");
        Result<InstanceId> found = simulation->simulation->id_of(index);
        if (!found) return {found.status().code(), std::string(fn) + ": " + found.status().message()};
        *id = uint64_t(*found);
        return {};
    });
}

hmsm_status hmsm_simulation_instance_placement(const hmsm_simulation* simulation, hmsm_instance_id id,
                                               hmsm_instance_placement* placement) {
    return guarded([&]() -> Status {
        const char* fn = "hmsm_simulation_instance_placement";
        if (!simulation) return bad(std::string(fn) + ": simulation is NULL");
        if (!placement) return bad(std::string(fn) + ": placement is NULL");
        size_t bytes = 0;
        HMSM_TRY(field_bytes<hmsm_instance_placement>(std::string(fn) + ": placement", placement->struct_size, bytes));
        const Simulation& sim = *simulation->simulation;
        Result<uint64_t> live = sim.index_of(InstanceId(id));  // its message, under this function's name
        if (!live) return {live.status().code(), std::string(fn) + ": " + live.status().message()};
        Result<InstancePlacement> found = sim.instance_placement(InstanceId(id));
        if (!found) return found.status();
        const hmsm_instance_placement full = {static_cast<uint32_t>(sizeof(hmsm_instance_placement)), found->first_chain,
                                              found->first_node, found->first_vertex};
        write_struct(full, placement, placement->struct_size, bytes);
        return {};
    });
}

}  // extern "C"
