// The C ABI's simulations: create, step, read into caller buffers, live control, destroy.
#include "c_api_internal.h"
#include "c_struct.h"
#include "model/input_limits.h"

#include <cstring>
#include <vector>

using namespace hmsm;
using namespace hmsm::c_api;

namespace {

/// `fn` over `simulation`: fetch(simulation, output, values as std::vector<T>), then copied
/// out to the caller's buffer (read and take_read share everything but the fetch).
template <class T, class Sim, class Fetch>
hmsm_status output_to_caller(const char* fn, Sim* simulation, int32_t output, T* values, size_t capacity,
                             size_t* count, Fetch fetch) {
    return guarded([&]() -> Status {
        if (!simulation) return bad(std::string(fn) + ": simulation is NULL");
        if (!count) return bad(std::string(fn) + ": count is NULL");
        Output which;
        HMSM_TRY(to_output(output, which));
        std::vector<T> data;
        HMSM_TRY(fetch(*simulation->simulation, which, data));
        return copy_out(fn, data, values, capacity, count);
    });
}

template <class T>
hmsm_status read_output(const char* fn, const hmsm_simulation* simulation, int32_t output,
                        T* values, size_t capacity, size_t* count) {
    return output_to_caller(fn, simulation, output, values, capacity, count,
                            [](const Simulation& sim, Output o, std::vector<T>& data) { return sim.read(o, data); });
}

template <class T>
hmsm_status take_output(const char* fn, hmsm_simulation* simulation, int32_t output, T* values, size_t capacity,
                        size_t* count) {
    return output_to_caller(fn, simulation, output, values, capacity, count,
                            [](Simulation& sim, Output o, std::vector<T>& data) { return sim.take_read(o, data); });
}

Status check_instance(const char* fn, const hmsm_simulation* simulation, uint64_t instance) {
    if (!simulation) return bad(std::string(fn) + ": simulation is NULL");
    const uint64_t n = simulation->simulation->instance_count();
    if (instance >= n)
        return bad(std::string(fn) + ": instance " + std::to_string(instance) +
                   " does not exist (" + std::to_string(n) + " instances)");
    return {};
}

}  // namespace

extern "C" {

hmsm_status hmsm_simulation_create(const hmsm_scene* scene, const hmsm_config* config,
                                   hmsm_simulation** simulation) {
    return guarded([&]() -> Status {
        if (!scene) return bad("hmsm_simulation_create: scene is NULL");
        if (!config) return bad("hmsm_simulation_create: config is NULL");
        if (!simulation) return bad("hmsm_simulation_create: simulation is NULL");
        hmsm_config full;
        HMSM_TRY(read_struct("hmsm_simulation_create: config", config, full));
        SimulationConfig converted;
        HMSM_TRY(to_cpp(full, converted));
        auto created = Simulation::create(scene->scene, converted);
        if (!created) return created.status();
        *simulation = new hmsm_simulation{std::move(*created)};
        return {};
    });
}

void hmsm_simulation_destroy(hmsm_simulation* simulation) { delete simulation; }

hmsm_status hmsm_simulation_step(hmsm_simulation* simulation, uint32_t count) {
    return guarded([&]() -> Status {
        if (!simulation) return bad("hmsm_simulation_step: simulation is NULL");
        return simulation->simulation->step(count);
    });
}

hmsm_status hmsm_simulation_read_f32(const hmsm_simulation* simulation, int32_t output,
                                     float* values, size_t capacity, size_t* count) {
    return read_output("hmsm_simulation_read_f32", simulation, output, values, capacity, count);
}

hmsm_status hmsm_simulation_read_f64(const hmsm_simulation* simulation, int32_t output,
                                     double* values, size_t capacity, size_t* count) {
    return read_output("hmsm_simulation_read_f64", simulation, output, values, capacity, count);
}

hmsm_status hmsm_simulation_request_read(hmsm_simulation* simulation, int32_t output) {
    return guarded([&]() -> Status {
        if (!simulation) return bad("hmsm_simulation_request_read: simulation is NULL");
        Output which;
        HMSM_TRY(to_output(output, which));
        return simulation->simulation->request_read(which);
    });
}

hmsm_status hmsm_simulation_take_read_f32(hmsm_simulation* simulation, int32_t output, float* values,
                                          size_t capacity, size_t* count) {
    return take_output("hmsm_simulation_take_read_f32", simulation, output, values, capacity, count);
}

hmsm_status hmsm_simulation_take_read_f64(hmsm_simulation* simulation, int32_t output, double* values,
                                          size_t capacity, size_t* count) {
    return take_output("hmsm_simulation_take_read_f64", simulation, output, values, capacity, count);
}

hmsm_status hmsm_simulation_counts(const hmsm_simulation* simulation, hmsm_counts* counts) {
    return guarded([&]() -> Status {
        if (!simulation) return bad("hmsm_simulation_counts: simulation is NULL");
        if (!counts) return bad("hmsm_simulation_counts: counts is NULL");
        size_t bytes = 0;
        HMSM_TRY(field_bytes<hmsm_counts>("hmsm_simulation_counts: counts", counts->struct_size, bytes));
        const Simulation& sim = *simulation->simulation;
        const hmsm_counts full = {static_cast<uint32_t>(sizeof(hmsm_counts)), sim.instance_count(), sim.chain_count(),
                                  sim.node_count(), sim.vertex_count(), sim.steps_done(), sim.time()};
        write_struct(full, counts, counts->struct_size, bytes);
        return {};
    });
}

hmsm_status hmsm_simulation_backend(const hmsm_simulation* simulation, int32_t* backend) {
    return guarded([&]() -> Status {
        if (!simulation) return bad("hmsm_simulation_backend: simulation is NULL");
        if (!backend) return bad("hmsm_simulation_backend: backend is NULL");
        *backend = static_cast<int32_t>(simulation->simulation->backend_kind());
        return {};
    });
}

hmsm_status hmsm_simulation_device_name(const hmsm_simulation* simulation, char* name,
                                        size_t capacity, size_t* length) {
    return guarded([&]() -> Status {
        const char* fn = "hmsm_simulation_device_name";
        if (!simulation) return bad(std::string(fn) + ": simulation is NULL");
        const std::string device = simulation->simulation->device_name();
        std::vector<char> text(device.begin(), device.end());
        text.push_back('\0');
        return copy_out(fn, text, name, capacity, length);
    });
}

hmsm_status hmsm_simulation_mesh_indices(const hmsm_simulation* simulation, uint32_t model,
                                         uint32_t* indices, size_t capacity, size_t* count) {
    return guarded([&]() -> Status {
        const char* fn = "hmsm_simulation_mesh_indices";
        if (!simulation) return bad(std::string(fn) + ": simulation is NULL");
        const Simulation& sim = *simulation->simulation;
        if (model >= sim.scene().models.size())
            return bad(std::string(fn) + ": model " + std::to_string(model) + " does not exist (" +
                       std::to_string(sim.scene().models.size()) + " models)");
        return copy_out(fn, sim.mesh(model).indices, indices, capacity, count);
    });
}

// --- live control: argument checks here, the rules themselves in hmsm::Simulation -------------

hmsm_status hmsm_simulation_set_wind(hmsm_simulation* simulation, const hmsm_wind* wind) {
    return guarded([&]() -> Status {
        if (!simulation) return bad("hmsm_simulation_set_wind: simulation is NULL");
        if (!wind) return bad("hmsm_simulation_set_wind: wind is NULL");
        hmsm_wind full;
        HMSM_TRY(read_struct("hmsm_simulation_set_wind: wind", wind, full));
        Wind converted;
        HMSM_TRY(to_cpp(full, converted));
        return simulation->simulation->set_wind(converted);
    });
}

hmsm_status hmsm_simulation_get_wind(const hmsm_simulation* simulation, hmsm_wind* wind) {
    return guarded([&]() -> Status {
        if (!simulation) return bad("hmsm_simulation_get_wind: simulation is NULL");
        if (!wind) return bad("hmsm_simulation_get_wind: wind is NULL");
        size_t bytes = 0;
        HMSM_TRY(field_bytes<hmsm_wind>("hmsm_simulation_get_wind: wind", wind->struct_size, bytes));
        hmsm_wind full;
        set_defaults(full);
        to_c(simulation->simulation->wind(), full);
        write_struct(full, wind, wind->struct_size, bytes);
        return {};
    });
}

hmsm_status hmsm_simulation_set_force_fields(hmsm_simulation* simulation,
                                             const hmsm_force_field* fields, size_t count) {
    return guarded([&]() -> Status {
        const char* fn = "hmsm_simulation_set_force_fields";
        if (!simulation) return bad(std::string(fn) + ": simulation is NULL");
        if (!fields && count > 0) return bad(std::string(fn) + ": fields is NULL with count > 0");
        if (count > kMaxForceFields)
            return bad(std::string(fn) + ": " + std::to_string(count) + " fields, at most " +
                       std::to_string(kMaxForceFields));
        std::vector<hmsm_force_field> full;
        HMSM_TRY(read_array(std::string(fn) + ": fields", fields, count, full));
        std::vector<ForceField> converted(count);
        for (size_t i = 0; i < count; ++i) {
            const std::string what = std::string(fn) + ": field " + std::to_string(i);
            HMSM_TRY(to_cpp(full[i], converted[i], what.c_str()));
        }
        HMSM_TRY(validate_force_fields(converted));
        return simulation->simulation->set_force_fields(converted);
    });
}


hmsm_status hmsm_simulation_set_instance_wind_scale(hmsm_simulation* simulation,
                                                    uint64_t instance, double wind_scale) {
    return guarded([&]() -> Status {
        const char* fn = "hmsm_simulation_set_instance_wind_scale";
        HMSM_TRY(check_instance(fn, simulation, instance));
        HMSM_TRY(detail::check_wind_scale(std::string(fn) + ": wind_scale", wind_scale));
        return simulation->simulation->set_instance_wind_scale(instance, wind_scale);
    });
}

hmsm_status hmsm_simulation_set_instance_wind_phase(hmsm_simulation* simulation,
                                                    uint64_t instance, double wind_phase) {
    return guarded([&]() -> Status {
        const char* fn = "hmsm_simulation_set_instance_wind_phase";
        HMSM_TRY(check_instance(fn, simulation, instance));
        if (!std::isfinite(wind_phase)) return bad(std::string(fn) + ": wind_phase must be finite");
        return simulation->simulation->set_instance_wind_phase(instance, wind_phase);
    });
}

hmsm_status hmsm_simulation_set_instance_active(hmsm_simulation* simulation, uint64_t instance,
                                                int32_t active) {
    return guarded([&]() -> Status {
        const char* fn = "hmsm_simulation_set_instance_active";
        HMSM_TRY(check_instance(fn, simulation, instance));
        if (active != 0 && active != 1) return bad(std::string(fn) + ": active must be 0 or 1");
        return simulation->simulation->set_instance_active(instance, active == 1);
    });
}

}  // extern "C"

namespace hmsm::c_api {

Status read_instances(const char* fn, const hmsm_instance* instances, size_t count, std::vector<Instance>& out) {
    if (!instances && count > 0) return bad(std::string(fn) + ": instances is NULL with count > 0");
    std::vector<hmsm_instance> full;
    HMSM_TRY(read_array(std::string(fn) + ": instances", instances, count, full));
    out.assign(count, Instance{});
    for (size_t i = 0; i < count; ++i) {
        const std::string what = std::string(fn) + ": instance " + std::to_string(i);
        HMSM_TRY(to_cpp(full[i], out[i], what.c_str()));
    }
    return {};
}

}  // namespace hmsm::c_api

extern "C" {

hmsm_status hmsm_simulation_add_instances(hmsm_simulation* simulation,
                                          const hmsm_instance* instances, size_t count) {
    return guarded([&]() -> Status {
        const char* fn = "hmsm_simulation_add_instances";
        if (!simulation) return bad(std::string(fn) + ": simulation is NULL");
        std::vector<Instance> converted;
        HMSM_TRY(read_instances(fn, instances, count, converted));
        return simulation->simulation->add_instances(converted);
    });
}

hmsm_status hmsm_simulation_reserve_instances(hmsm_simulation* simulation, uint64_t count) {
    return guarded([&]() -> Status {
        if (!simulation) return bad("hmsm_simulation_reserve_instances: simulation is NULL");
        return simulation->simulation->reserve_instances(count);
    });
}

hmsm_status hmsm_simulation_reserve_level_instances(hmsm_simulation* simulation, const uint64_t* per_level,
                                                    size_t count) {
    return guarded([&]() -> Status {
        if (!simulation) return bad("hmsm_simulation_reserve_level_instances: simulation is NULL");
        if (!per_level && count > 0) return bad("hmsm_simulation_reserve_level_instances: per_level is NULL");
        return simulation->simulation->reserve_instances(std::span<const uint64_t>(per_level, count));
    });
}

hmsm_status hmsm_simulation_remove_instances(hmsm_simulation* simulation, const uint64_t* indices,
                                             size_t count) {
    return guarded([&]() -> Status {
        const char* fn = "hmsm_simulation_remove_instances";
        if (!simulation) return bad(std::string(fn) + ": simulation is NULL");
        if (!indices && count > 0) return bad(std::string(fn) + ": indices is NULL with count > 0");
        std::vector<uint64_t> copied(indices, indices + count);
        return simulation->simulation->remove_instances(copied);
    });
}

hmsm_status hmsm_simulation_reset_instances(hmsm_simulation* simulation, const uint32_t* indices,
                                            size_t count) {
    return guarded([&]() -> Status {
        const char* fn = "hmsm_simulation_reset_instances";
        if (!simulation) return bad(std::string(fn) + ": simulation is NULL");
        if (!indices && count > 0) return bad(std::string(fn) + ": indices is NULL with count > 0");
        std::vector<uint32_t> copied(indices, indices + count);
        return simulation->simulation->reset_instances(copied);
    });
}

hmsm_status hmsm_simulation_instances(const hmsm_simulation* simulation, hmsm_instance* instances,
                                      size_t capacity, size_t* count) {
    return guarded([&]() -> Status {
        const char* fn = "hmsm_simulation_instances";
        if (!simulation) return bad(std::string(fn) + ": simulation is NULL");
        if (!count) return bad(std::string(fn) + ": count is NULL");
        const auto list = simulation->simulation->instances();
        *count = list.size();
        if (!instances && capacity == 0) return {};
        if (!instances)
            return bad(std::string(fn) + ": instances is NULL with capacity " + std::to_string(capacity));
        if (capacity < list.size())
            return bad(std::string(fn) + ": capacity " + std::to_string(capacity) + " is too small, " +
                       std::to_string(list.size()) + " needed");
        const uint32_t stride = instances[0].struct_size;
        size_t bytes = 0;
        HMSM_TRY(field_bytes<hmsm_instance>(std::string(fn) + ": instances[0]", stride, bytes));
        auto* base = reinterpret_cast<unsigned char*>(instances);
        for (size_t i = 0; i < list.size(); ++i) {
            hmsm_instance full;
            set_defaults(full);
            to_c(list[i], full);
            write_struct(full, base + i * stride, stride, bytes);
        }
        return {};
    });
}

}  // extern "C"
