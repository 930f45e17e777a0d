// The C ABI's skins: a model's skin data read into caller buffers, and CPU skinning of one
// instance from its joint matrices (hmsm::build_skin, hmsm::skin_vertices).
#include "c_api_internal.h"
#include "c_struct.h"

#include <span>
#include <type_traits>
#include <vector>

using namespace hmsm;
using namespace hmsm::c_api;

namespace {

bool is_integer_data(int32_t data) {
    return data == HMSM_SKIN_JOINTS || data == HMSM_SKIN_CHAIN_PARENTS || data == HMSM_SKIN_SOURCE_CHAINS;
}

/// Skin data `data` flattened (elements x components) as T.
template <class T>
void flatten(const SkinTemplate& skin, int32_t data, std::vector<T>& out) {
    out.clear();
    auto put = [&](auto value) { out.push_back(static_cast<T>(value)); };
    switch (data) {
        case HMSM_SKIN_BIND_POSITIONS:
            for (const SkinVertex& v : skin.vertices) put(v.position.x), put(v.position.y), put(v.position.z);
            break;
        case HMSM_SKIN_BIND_NORMALS:
            for (const SkinVertex& v : skin.vertices) put(v.normal.x), put(v.normal.y), put(v.normal.z);
            break;
        case HMSM_SKIN_JOINTS:
            for (const SkinVertex& v : skin.vertices) put(v.joints[0]), put(v.joints[1]);
            break;
        case HMSM_SKIN_WEIGHTS:
            for (const SkinVertex& v : skin.vertices) put(v.weights[0]), put(v.weights[1]);
            break;
        case HMSM_SKIN_INVERSE_BIND:
            for (const auto& m : skin.inverse_bind)
                for (double x : m) put(x);
            break;
        case HMSM_SKIN_BIND_MATRICES:
            for (const auto& m : skin.bind)
                for (double x : m) put(x);
            break;
        case HMSM_SKIN_CHAIN_PARENTS:
            for (int32_t parent : skin.parents) put(parent);
            break;
        default:  // HMSM_SKIN_SOURCE_CHAINS
            for (int32_t source : skin.source_chains) put(source);
            break;
    }
}

template <class T>
hmsm_status read_skin(const char* fn, const hmsm_skin* skin, int32_t data, T* values, size_t capacity,
                      size_t* count) {
    return guarded([&]() -> Status {
        if (!skin) return bad(std::string(fn) + ": skin is NULL");
        if (!count) return bad(std::string(fn) + ": count is NULL");
        if (data < 0 || data >= HMSM_SKIN_DATA_COUNT)
            return bad(std::string(fn) + ": data: unknown value " + std::to_string(data));
        constexpr bool reads_integers = std::is_same_v<T, int32_t>;
        if (is_integer_data(data) != reads_integers)
            return bad(std::string(fn) + ": data " + std::to_string(data) + " is " +
                       (reads_integers ? "floating-point: read it with hmsm_skin_read_f32 or _f64"
                                       : "integer: read it with hmsm_skin_read_i32"));
        std::vector<T> flat;
        flatten(skin->skin, data, flat);
        return copy_out(fn, flat, values, capacity, count);
    });
}

}  // namespace

extern "C" {

hmsm_status hmsm_skin_create(const hmsm_simulation* simulation, uint32_t model, hmsm_skin** skin) {
    return guarded([&]() -> Status {
        const char* fn = "hmsm_skin_create";
        if (!simulation) return bad(std::string(fn) + ": simulation is NULL");
        if (!skin) return bad(std::string(fn) + ": skin is NULL");
        const Simulation& sim = *simulation->simulation;
        const size_t models = sim.scene().models.size();
        if (model >= models)
            return bad(std::string(fn) + ": model " + std::to_string(model) + " does not exist (" +
                       std::to_string(models) + " models)");
        *skin = new hmsm_skin{build_skin(sim.scene().models[model], sim.hierarchy(model), sim.mesh(model),
                                         sim.config().model)};
        return {};
    });
}

hmsm_status hmsm_skin_create_level(const hmsm_simulation* simulation, uint32_t model,
                                   const hmsm_level_options* options, hmsm_skin** skin) {
    return guarded([&]() -> Status {
        const char* fn = "hmsm_skin_create_level";
        if (!simulation) return bad(std::string(fn) + ": simulation is NULL");
        if (!options) return bad(std::string(fn) + ": options is NULL");
        if (!skin) return bad(std::string(fn) + ": skin is NULL");
        hmsm_level_options read{};
        HMSM_TRY(read_struct(std::string(fn) + ": options", options, read));
        const Simulation& sim = *simulation->simulation;
        const size_t models = sim.scene().models.size();
        if (model >= models)
            return bad(std::string(fn) + ": model " + std::to_string(model) + " does not exist (" +
                       std::to_string(models) + " models)");
        const TreeModel& tree = sim.scene().models[model];
        auto level = build_level(tree, sim.hierarchy(model), sim.config().parameters, read.max_joints);
        if (!level) return Status{level.status().code(), std::string(fn) + ": options->max_joints: " + level.status().message()};
        *skin = new hmsm_skin{build_skin(tree, sim.hierarchy(model), sim.mesh(model), sim.config().model, *level)};
        return {};
    });
}

void hmsm_skin_destroy(hmsm_skin* skin) { delete skin; }

hmsm_status hmsm_skin_sizes(const hmsm_skin* skin, uint64_t* vertices, uint64_t* chains) {
    return guarded([&]() -> Status {
        if (!skin) return bad("hmsm_skin_sizes: skin is NULL");
        if (!vertices || !chains) return bad("hmsm_skin_sizes: vertices and chains must not be NULL");
        *vertices = skin->skin.vertices.size();
        *chains = skin->skin.inverse_bind.size();
        return {};
    });
}

hmsm_status hmsm_skin_read_f32(const hmsm_skin* skin, int32_t data, float* values, size_t capacity,
                               size_t* count) {
    return read_skin("hmsm_skin_read_f32", skin, data, values, capacity, count);
}

hmsm_status hmsm_skin_read_f64(const hmsm_skin* skin, int32_t data, double* values, size_t capacity,
                               size_t* count) {
    return read_skin("hmsm_skin_read_f64", skin, data, values, capacity, count);
}

hmsm_status hmsm_skin_read_i32(const hmsm_skin* skin, int32_t data, int32_t* values, size_t capacity,
                               size_t* count) {
    return read_skin("hmsm_skin_read_i32", skin, data, values, capacity, count);
}

hmsm_status hmsm_skin_vertices(const hmsm_skin* skin, const float* joint_matrices, size_t joint_values,
                               float* positions, float* normals, size_t capacity, size_t* count,
                               uint32_t threads) {
    return guarded([&]() -> Status {
        const std::string fn = "hmsm_skin_vertices";
        if (!skin) return bad(fn + ": skin is NULL");
        if (!count) return bad(fn + ": count is NULL");
        const size_t needed = 3 * skin->skin.vertices.size();
        *count = needed;
        if (!positions && capacity == 0) return {};
        if (!positions) return bad(fn + ": positions is NULL with capacity " + std::to_string(capacity));
        if (capacity < needed)
            return bad(fn + ": capacity " + std::to_string(capacity) + " is too small, " +
                       std::to_string(needed) + " needed");
        if (!joint_matrices) return bad(fn + ": joint_matrices is NULL");
        const size_t chains = skin->skin.inverse_bind.size();
        if (joint_values < 12 * chains)
            return bad(fn + ": joint_values " + std::to_string(joint_values) + " is too small, 12 x " +
                       std::to_string(chains) + " chains needed");
        return skin_vertices(skin->skin, std::span<const float>(joint_matrices, 12 * chains),
                             std::span<float>(positions, needed),
                             normals ? std::span<float>(normals, needed) : std::span<float>(), threads);
    });
}

}  // extern "C"
