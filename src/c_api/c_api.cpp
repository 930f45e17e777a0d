// The C ABI's status reporting, defaults, enumerations and struct conversions, and trees.
#include "c_api_internal.h"
#include "c_struct.h"

#include <array>
#include <cstring>
#include <optional>
#include <string_view>

namespace hmsm::c_api {
namespace {

/// The message of the calling thread's last C call (hmsm_status_message).
thread_local std::string last_message;

/// hmsm::Output for each HMSM_OUTPUT_* value: adding an output is one line here and one in the
/// header's enum.
constexpr std::array<Output, HMSM_OUTPUT_COUNT> kOutputs = {
    Output::node_positions, Output::vertex_positions, Output::vertex_normals,
    Output::chain_rotations, Output::chain_origins, Output::chain_angles, Output::joint_matrices};

/// hmsm::Composition for each HMSM_COMPOSITION_* value; values 1, 2 and 4 are reserved and map
/// to none.
constexpr std::array<std::optional<Composition>, HMSM_COMPOSITION_AUTOMATIC + 1> kCompositions = {
    Composition::pointer_jumping, std::nullopt, std::nullopt, Composition::level_by_level, std::nullopt,
    Composition::path_walk, Composition::automatic};

int32_t to_c(Composition composition) {
    for (size_t i = 0; i < kCompositions.size(); ++i)
        if (kCompositions[i] == composition) return int32_t(i);
    return HMSM_COMPOSITION_AUTOMATIC;
}

}  // namespace

hmsm_status report(const Status& status) {
    try {
        last_message = status.message();
    } catch (...) {
        last_message.clear();  // keep the code; the message could not be stored
    }
    return static_cast<hmsm_status>(status.code());
}

Status to_output(int32_t output, Output& out) {
    if (output < 0 || output >= HMSM_OUTPUT_COUNT)
        return bad("output: unknown value " + std::to_string(output));
    out = kOutputs[static_cast<size_t>(output)];
    return {};
}

Status to_cpp(const hmsm_wind& in, Wind& out) {
    if (in.profile < 0 || in.profile > HMSM_WIND_ATMOSPHERIC)
        return bad("wind.profile: unknown value " + std::to_string(in.profile));
    if (!std::isfinite(in.turbulence) || in.turbulence < 0.0 || in.turbulence > 2.0)
        return bad("wind.turbulence must be finite and in [0, 2]");
    Wind wind;
    wind.profile = static_cast<WindProfile>(in.profile);
    wind.direction = Vec3(in.direction[0], in.direction[1], in.direction[2]);
    wind.strength = in.strength;
    wind.frequency = in.frequency;
    wind.front_speed = in.front_speed;
    wind.turbulence = in.turbulence;
    wind.seed = in.seed;
    HMSM_TRY(validate(wind));  // finite values and ranges; the message names the field
    out = wind;
    return {};
}

void to_c(const Wind& in, hmsm_wind& out) {
    out.profile = static_cast<int32_t>(in.profile);
    for (int i = 0; i < 3; ++i) out.direction[i] = in.direction[i];
    out.strength = in.strength;
    out.frequency = in.frequency;
    out.front_speed = in.front_speed;
    out.turbulence = in.turbulence;
    out.seed = in.seed;
}

Status to_cpp(const hmsm_instance& in, Instance& out, const char* what) {
    if (!finite3(in.origin) || !std::isfinite(in.yaw))
        return bad(std::string(what) + ": origin and yaw must be finite");
    if (!std::isfinite(in.wind_scale) || in.wind_scale < 0.0)
        return bad(std::string(what) + ": wind_scale must be finite and >= 0");
    if (!std::isfinite(in.wind_phase))
        return bad(std::string(what) + ": wind_phase must be finite");
    if (in.active != 0 && in.active != 1) return bad(std::string(what) + ": active must be 0 or 1");
    if (in.level > UINT32_MAX) return bad(std::string(what) + ": level " + std::to_string(in.level) + " is out of range");
    out.model = in.model;
    out.level = uint32_t(in.level);
    out.origin = Vec3(in.origin[0], in.origin[1], in.origin[2]);
    out.yaw = in.yaw;
    out.wind_scale = in.wind_scale;
    out.wind_phase = in.wind_phase;
    out.active = in.active == 1;
    return {};
}

void to_c(const Instance& in, hmsm_instance& out) {
    out.model = in.model;
    for (int i = 0; i < 3; ++i) out.origin[i] = in.origin[i];
    out.yaw = in.yaw;
    out.wind_scale = in.wind_scale;
    out.wind_phase = in.wind_phase;
    out.active = in.active ? 1 : 0;
    out.level = in.level;
}

Status to_cpp(const hmsm_force_field& in, ForceField& out, const char* what) {
    if (in.kind != HMSM_FORCE_FIELD_DIRECTIONAL && in.kind != HMSM_FORCE_FIELD_RADIAL)
        return bad(std::string(what) + ": unknown kind " + std::to_string(in.kind));
    out.kind = static_cast<ForceField::Kind>(in.kind);
    out.center = Vec3(in.center[0], in.center[1], in.center[2]);
    out.radius = in.radius;
    out.directional = Vec3(in.directional[0], in.directional[1], in.directional[2]);
    out.radial = in.radial;
    return {};  // numbers are checked by validate_force_fields
}

Status to_cpp(const hmsm_config& in, SimulationConfig& out) {
    SimulationConfig config;
    if (in.backend < HMSM_BACKEND_CPU || in.backend > HMSM_BACKEND_CPU_PARALLEL)
        return bad("config.backend: unknown value " + std::to_string(in.backend));
    if (in.composition < HMSM_COMPOSITION_POINTER_JUMPING || in.composition > HMSM_COMPOSITION_AUTOMATIC)
        return bad("config.composition: unknown value " + std::to_string(in.composition));
    if (!kCompositions[size_t(in.composition)])
        return bad("config.composition: unknown value " + std::to_string(in.composition) +
                   " (values 1, 2 and 4 are reserved)");
    if (in.vertex_layout != HMSM_VERTEX_LAYOUT_SEPARATE &&
        in.vertex_layout != HMSM_VERTEX_LAYOUT_PACKED)
        return bad("config.vertex_layout: unknown value " + std::to_string(in.vertex_layout));
    if (in.outputs < HMSM_OUTPUTS_JOINTS || in.outputs > HMSM_OUTPUTS_ALL)
        return bad("config.outputs: unknown value " + std::to_string(in.outputs));
    if (in.profile_passes != 0 && in.profile_passes != 1)
        return bad("config.profile_passes must be 0 or 1");
    if (in.model.grouping != HMSM_GROUPING_DIRECTION && in.model.grouping != HMSM_GROUPING_WIDTH)
        return bad("config.model.grouping: unknown value " + std::to_string(in.model.grouping));
    if (in.dynamics != HMSM_DYNAMICS_PAPER && in.dynamics != HMSM_DYNAMICS_COUPLED)
        return bad("config.dynamics: unknown value " + std::to_string(in.dynamics));
    if (in.coupled.leaves_on != 0 && in.coupled.leaves_on != 1)
        return bad("config.coupled.leaves_on must be 0 or 1");
    if (in.instance_layout != HMSM_INSTANCE_LAYOUT_PACKED && in.instance_layout != HMSM_INSTANCE_LAYOUT_PLACED)
        return bad("config.instance_layout: unknown value " + std::to_string(in.instance_layout));
    if (in.exchange != HMSM_EXCHANGE_HELD && in.exchange != HMSM_EXCHANGE_ARTICULATED)
        return bad("config.exchange: unknown value " + std::to_string(in.exchange));
    config.backend = static_cast<BackendKind>(in.backend);
    config.composition = *kCompositions[size_t(in.composition)];
    config.vertex_layout = static_cast<VertexLayout>(in.vertex_layout);
    config.profile_passes = in.profile_passes == 1;
    config.outputs = static_cast<Outputs>(in.outputs);
    config.instance_layout = static_cast<InstanceLayout>(in.instance_layout);
    config.model.grouping = static_cast<Grouping>(in.model.grouping);
    config.model.max_chain_segments = in.model.max_chain_segments;
    config.model.ring_sides = in.model.ring_sides;
    config.model.fix_weight = in.model.fix_weight;
    const hmsm_parameters& p = in.parameters;
    config.parameters = {p.density, p.stiffness, p.damping_ratio, p.wind_gain,
                         p.max_angle, p.dt, p.max_frequency};
    config.model.dynamics = static_cast<Dynamics>(in.dynamics);
    config.model.exchange = static_cast<Exchange>(in.exchange);
    const hmsm_coupled_parameters& k = in.coupled;
    config.parameters.material = {k.modulus, k.wood_density};
    config.parameters.structural_damping = k.structural_damping;
    config.parameters.wood_drag_coefficient = k.wood_drag_coefficient;
    config.parameters.foliage = {k.leaves_on == 1, k.leaf_mass_per_area, k.leaf_drag_coefficient};
    Status wind = to_cpp(in.wind, config.wind);
    if (!wind) return {wind.code(), "config." + wind.message()};
    // Options and parameters are validated (ranges, finite numbers) by Simulation::create.
    out = config;
    return {};
}

void set_defaults(hmsm_wind& out) {
    std::memset(&out, 0, sizeof out);
    out.struct_size = sizeof out;
    to_c(Wind{}, out);
}

void set_defaults(hmsm_config& out) {
    const SimulationConfig defaults;
    std::memset(&out, 0, sizeof out);
    out.struct_size = sizeof out;
    out.backend = static_cast<int32_t>(defaults.backend);
    out.composition = to_c(defaults.composition);
    out.vertex_layout = static_cast<int32_t>(defaults.vertex_layout);
    out.profile_passes = defaults.profile_passes ? 1 : 0;
    out.outputs = static_cast<int32_t>(defaults.outputs);
    out.instance_layout = static_cast<int32_t>(defaults.instance_layout);
    out.model.grouping = static_cast<int32_t>(defaults.model.grouping);
    out.model.max_chain_segments = defaults.model.max_chain_segments;
    out.model.ring_sides = defaults.model.ring_sides;
    out.model.fix_weight = defaults.model.fix_weight;
    const Parameters& p = defaults.parameters;
    out.parameters = {p.density, p.stiffness, p.damping_ratio, p.wind_gain,
                      p.max_angle, p.dt, p.max_frequency};
    out.dynamics = static_cast<int32_t>(defaults.model.dynamics);
    out.exchange = static_cast<int64_t>(defaults.model.exchange);
    out.coupled = {p.material.modulus, p.material.density, p.structural_damping, p.wood_drag_coefficient,
                   p.foliage.mass_per_area, p.foliage.drag_coefficient, p.foliage.on ? 1 : 0};
    set_defaults(out.wind);
    to_c(defaults.wind, out.wind);
}

void set_defaults(hmsm_instance& out) {
    std::memset(&out, 0, sizeof out);
    out.struct_size = sizeof out;
    to_c(Instance{}, out);
}

void set_defaults(hmsm_force_field& out) {
    const ForceField defaults;
    std::memset(&out, 0, sizeof out);
    out.struct_size = sizeof out;
    out.kind = static_cast<int32_t>(defaults.kind);
    for (int i = 0; i < 3; ++i) {
        out.center[i] = defaults.center[i];
        out.directional[i] = defaults.directional[i];
    }
    out.radius = defaults.radius;
    out.radial = defaults.radial;
}

void set_defaults(hmsm_counts& out) {
    std::memset(&out, 0, sizeof out);
    out.struct_size = sizeof out;
}

void set_defaults(hmsm_instance_placement& out) {
    std::memset(&out, 0, sizeof out);
    out.struct_size = sizeof out;
}

void set_defaults(hmsm_level_options& out) {
    std::memset(&out, 0, sizeof out);
    out.struct_size = sizeof out;
    out.max_joints = kDefaultJointBudgets[0];
}

}  // namespace hmsm::c_api

using namespace hmsm;
using namespace hmsm::c_api;

namespace {
Status hand_out(Result<TreeModel> tree, hmsm_tree** out) {
    if (!tree) return tree.status();
    *out = new hmsm_tree{std::move(*tree)};
    return {};
}

/// The body of every hmsm_*_init: hmsm's defaults in the caller's layout of T.
template <class T>
hmsm_status init_struct(const char* fn, T* out, size_t struct_size) {
    return guarded([&]() -> Status {
        const std::string what = std::string(fn) + ": " + CStruct<T>::name;
        if (!out) return bad(what + " is NULL");
        size_t bytes = 0;
        HMSM_TRY(field_bytes<T>(what, struct_size, bytes));
        T full;
        set_defaults(full);
        write_struct(full, out, static_cast<uint32_t>(struct_size), bytes);
        return {};
    });
}
}  // namespace

extern "C" {

uint32_t hmsm_abi_version(void) { return HMSM_C_ABI_VERSION; }

const char* hmsm_status_message(void) { return last_message.c_str(); }

const char* hmsm_status_name(hmsm_status status) {
    switch (status) {
        case HMSM_OK: return "ok";
        case HMSM_INVALID_ARGUMENT: return "invalid_argument";
        case HMSM_INVALID_TREE: return "invalid_tree";
        case HMSM_IO: return "io";
        case HMSM_NO_DEVICE: return "no_device";
        case HMSM_DEVICE_ERROR: return "device_error";
        case HMSM_OUT_OF_MEMORY: return "out_of_memory";
        case HMSM_UNSUPPORTED: return "unsupported";
        case HMSM_INTERNAL: return "internal";
        default: return "unknown";
    }
}

hmsm_status hmsm_wind_init(hmsm_wind* wind, size_t struct_size) {
    return init_struct("hmsm_wind_init", wind, struct_size);
}

hmsm_status hmsm_config_init(hmsm_config* config, size_t struct_size) {
    return init_struct("hmsm_config_init", config, struct_size);
}

hmsm_status hmsm_instance_init(hmsm_instance* instance, size_t struct_size) {
    return init_struct("hmsm_instance_init", instance, struct_size);
}

hmsm_status hmsm_force_field_init(hmsm_force_field* field, size_t struct_size) {
    return init_struct("hmsm_force_field_init", field, struct_size);
}

hmsm_status hmsm_counts_init(hmsm_counts* counts, size_t struct_size) {
    return init_struct("hmsm_counts_init", counts, struct_size);
}

hmsm_status hmsm_instance_placement_init(hmsm_instance_placement* placement, size_t struct_size) {
    return init_struct("hmsm_instance_placement_init", placement, struct_size);
}

hmsm_status hmsm_level_options_init(hmsm_level_options* options, size_t struct_size) {
    return init_struct("hmsm_level_options_init", options, struct_size);
}

hmsm_status hmsm_output_components(int32_t output, uint32_t* components) {
    return guarded([&]() -> Status {
        if (!components) return bad("hmsm_output_components: components is NULL");
        Output out;
        HMSM_TRY(to_output(output, out));
        *components = hmsm::output_components(out);
        return {};
    });
}

// --- trees ---------------------------------------------------------------------------------

hmsm_status hmsm_tree_load(const char* path, hmsm_tree** tree) {
    return guarded([&]() -> Status {
        if (!path) return bad("hmsm_tree_load: path is NULL");
        if (!tree) return bad("hmsm_tree_load: tree is NULL");
        return hand_out(load_tree(path), tree);
    });
}

hmsm_status hmsm_tree_parse(const char* json, size_t length, hmsm_tree** tree) {
    return guarded([&]() -> Status {
        if (!json) return bad("hmsm_tree_parse: json is NULL");
        if (!tree) return bad("hmsm_tree_parse: tree is NULL");
        return hand_out(parse_tree(std::string_view(json, length)), tree);
    });
}

hmsm_status hmsm_tree_preset(const char* name, uint64_t seed, hmsm_tree** tree) {
    return guarded([&]() -> Status {
        if (!name) return bad("hmsm_tree_preset: name is NULL");
        if (!tree) return bad("hmsm_tree_preset: tree is NULL");
        return hand_out(generate_preset(name, seed), tree);
    });
}

hmsm_status hmsm_tree_from_nodes(const int32_t* parents, const double* positions,
                                 const double* radii, size_t count, hmsm_tree** tree) {
    return guarded([&]() -> Status {
        if (!parents || !positions || !radii)
            return bad("hmsm_tree_from_nodes: parents, positions and radii must not be NULL");
        if (!tree) return bad("hmsm_tree_from_nodes: tree is NULL");
        TreeModel model;
        model.nodes.resize(count);
        for (size_t i = 0; i < count; ++i)
            model.nodes[i] = {parents[i],
                              Vec3(positions[3 * i], positions[3 * i + 1], positions[3 * i + 2]),
                              radii[i]};
        HMSM_TRY(validate_tree(model));  // names the offending node (NaN included)
        *tree = new hmsm_tree{std::move(model)};
        return {};
    });
}

hmsm_status hmsm_tree_node_count(const hmsm_tree* tree, uint64_t* count) {
    return guarded([&]() -> Status {
        if (!tree) return bad("hmsm_tree_node_count: tree is NULL");
        if (!count) return bad("hmsm_tree_node_count: count is NULL");
        *count = tree->model.nodes.size();
        return {};
    });
}

void hmsm_tree_destroy(hmsm_tree* tree) { delete tree; }

}  // extern "C"
