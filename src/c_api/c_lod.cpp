// The C ABI's levels of detail at run time (Simulation::set_instance_lod and friends,
// docs/driving.md): budgets per scene model, switches by handle, distance bands.
#include "c_api_internal.h"

#include <algorithm>
#include <vector>

using namespace hmsm;
using namespace hmsm::c_api;

extern "C" {

hmsm_status hmsm_scene_set_lod_budgets(hmsm_scene* scene, uint32_t model, const int32_t* budgets, size_t count) {
    return guarded([&]() -> Status {
        const std::string fn = "hmsm_scene_set_lod_budgets";
        if (!scene) return bad(fn + ": scene is NULL");
        if (!budgets && count > 0) return bad(fn + ": budgets is NULL with count > 0");
        const size_t models = scene->scene.models.size();
        if (model >= models)
            return bad(fn + ": model " + std::to_string(model) + " does not exist (" + std::to_string(models) +
                       " models)");
        for (size_t k = 0; k < count; ++k)
            if (budgets[k] < 1)
                return bad(fn + ": budgets[" + std::to_string(k) + "] = " + std::to_string(budgets[k]) +
                           ": below the trunk-only level, the coarsest there is (1 joint)");
        scene->scene.lod_budgets.resize(models);
        scene->scene.lod_budgets[model].assign(budgets, budgets + count);
        return {};
    });
}

hmsm_status hmsm_simulation_set_instance_lods(hmsm_simulation* simulation, const hmsm_instance_id* ids,
                                              const uint32_t* levels, size_t count) {
    return guarded([&]() -> Status {
        const std::string fn = "hmsm_simulation_set_instance_lods";
        if (!simulation) return bad(fn + ": simulation is NULL");
        if ((!ids || !levels) && count > 0) return bad(fn + ": ids or levels is NULL with count > 0");
        std::vector<InstanceId> copied(count);
        std::transform(ids, ids + count, copied.begin(), [](uint64_t id) { return InstanceId(id); });
        Status done = simulation->simulation->set_instance_lods(copied, {levels, count});
        if (!done) return {done.code(), fn + ": " + done.message()};
        return {};
    });
}

hmsm_status hmsm_simulation_instance_lod(const hmsm_simulation* simulation, hmsm_instance_id id, uint32_t* level) {
    return guarded([&]() -> Status {
        const std::string fn = "hmsm_simulation_instance_lod";
        if (!simulation) return bad(fn + ": simulation is NULL");
        if (!level) return bad(fn + ": level is NULL");
        Result<uint32_t> found = simulation->simulation->instance_lod(InstanceId(id));
        if (!found) return {found.status().code(), fn + ": " + found.status().message()};
        *level = *found;
        return {};
    });
}

hmsm_status hmsm_simulation_set_lod_bands(hmsm_simulation* simulation, const double* edges, size_t count,
                                          double hysteresis) {
    return guarded([&]() -> Status {
        const std::string fn = "hmsm_simulation_set_lod_bands";
        if (!simulation) return bad(fn + ": simulation is NULL");
        if (!edges && count > 0) return bad(fn + ": edges is NULL with count > 0");
        LodBands bands = simulation->simulation->lod_bands();
        bands.edges.assign(edges, edges + count);
        bands.hysteresis = hysteresis;
        Status done = simulation->simulation->set_lod_bands(bands);
        if (!done) return {done.code(), fn + ": " + done.message()};
        return {};
    });
}

hmsm_status hmsm_simulation_set_lod_fade(hmsm_simulation* simulation, uint32_t steps, double bound_m) {
    return guarded([&]() -> Status {
        const std::string fn = "hmsm_simulation_set_lod_fade";
        if (!simulation) return bad(fn + ": simulation is NULL");
        LodBands bands = simulation->simulation->lod_bands();
        bands.fade_steps = steps;
        bands.fade_bound_m = bound_m;
        Status done = simulation->simulation->set_lod_bands(bands);
        if (!done) return {done.code(), fn + ": " + done.message()};
        return {};
    });
}

hmsm_status hmsm_simulation_update_lod(hmsm_simulation* simulation, const double viewer[3], uint64_t* switched) {
    return guarded([&]() -> Status {
        const std::string fn = "hmsm_simulation_update_lod";
        if (!simulation) return bad(fn + ": simulation is NULL");
        if (!viewer) return bad(fn + ": viewer is NULL");
        Result<uint64_t> done = simulation->simulation->update_lod(Vec3(viewer[0], viewer[1], viewer[2]));
        if (!done) return {done.status().code(), fn + ": " + done.status().message()};
        if (switched) *switched = *done;
        return {};
    });
}

}  // extern "C"
