// The Simulation façade: scene flattening, the backend, wind and outputs; the step program it
// runs is built in step_program.cpp.
#include <hmsm/simulation.h>

#include "backend.h"
#include "common/octahedral.h"
#include "scene_data.h"
#include "simulation_impl.h"
#include "step_program.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <type_traits>

namespace hmsm {

using detail::Dispatch;
using detail::SceneData;

const char* to_string(BackendKind kind) {
    switch (kind) {
        case BackendKind::cpu: return "cpu";
        case BackendKind::cpu64: return "cpu64";
        case BackendKind::cpu_parallel: return "cpu-parallel";
        case BackendKind::vulkan: return "vulkan";
        case BackendKind::cuda: return "cuda";
        case BackendKind::automatic: return "auto";
    }
    return "?";
}

std::optional<BackendKind> parse_backend_kind(std::string_view name) {
    for (BackendKind k : {BackendKind::cpu, BackendKind::cpu64, BackendKind::cpu_parallel,
                          BackendKind::vulkan, BackendKind::cuda, BackendKind::automatic})
        if (name == to_string(k)) return k;
    return std::nullopt;
}

const char* to_string(Composition composition) {
    switch (composition) {
        case Composition::pointer_jumping: return "pointer_jumping";
        case Composition::pointer_jumping_per_round: return "pointer_jumping_per_round";
        case Composition::pointer_jumping_in_dispatch: return "pointer_jumping_in_dispatch";
        case Composition::level_by_level: return "level_by_level";
        case Composition::path_walk: return "path_walk";
        case Composition::automatic: return "automatic";
    }
    return "?";
}

std::optional<Composition> parse_composition(std::string_view name) {
    for (Composition c : {Composition::pointer_jumping, Composition::pointer_jumping_per_round,
                          Composition::pointer_jumping_in_dispatch, Composition::level_by_level,
                          Composition::path_walk, Composition::automatic})
        if (name == to_string(c)) return c;
    return std::nullopt;
}

std::optional<Pass> parse_pass(std::string_view name) {
    for (Pass p : kAllPasses)
        if (pass_name(p) == name) return p;
    return std::nullopt;
}

const char* to_string(Outputs outputs) {
    switch (outputs) {
        case Outputs::joints: return "joints";
        case Outputs::joints_and_nodes: return "nodes";
        case Outputs::all: return "all";
    }
    return "?";
}

std::optional<Outputs> parse_outputs(std::string_view name) {
    for (Outputs o : {Outputs::joints, Outputs::joints_and_nodes, Outputs::all})
        if (name == to_string(o)) return o;
    return std::nullopt;
}

const char* to_string(VertexLayout layout) {
    return layout == VertexLayout::packed ? "packed" : "separate";
}

std::optional<VertexLayout> parse_vertex_layout(std::string_view name) {
    if (name == "separate") return VertexLayout::separate;
    if (name == "packed") return VertexLayout::packed;
    return std::nullopt;
}

uint32_t output_components(Output output) {
    switch (output) {
        case Output::joint_matrices: return 12;
        case Output::chain_rotations: return 9;
        case Output::chain_angles: return 4;
        default: return 3;
    }
}

namespace {

std::string number(double v) {
    char buf[32];
    std::snprintf(buf, sizeof buf, "%.6g", v);
    return buf;
}

}  // namespace

Result<std::unique_ptr<Simulation>> Simulation::create(const Scene& scene,
                                                       const SimulationConfig& config) {
    return Impl::create(scene, config, nullptr);
}

Simulation::Simulation(std::unique_ptr<Impl> impl) : impl_(std::move(impl)) {}

std::vector<Dispatch> Simulation::Impl::program_for(const std::vector<detail::InstanceGroup>& groups,
                                                    Pass first, uint32_t passes) const {
    const detail::BackendCapabilities can = backend_->capabilities();
    return build_program(*data_, groups, config_.composition, can.dispatches_are_expensive, first, passes,
                         can.walks_ahead);
}

Status Simulation::Impl::check_size(std::span<const Instance> instances) const {
    uint64_t vertices = 0, chains = 0, nodes = 0;
    for (const Instance& inst : instances) {
        vertices += meshes_[inst.model].vertices.size();
        chains += 2 * hierarchies_[inst.model].chains.size();
        nodes += hierarchies_[inst.model].node_owner.size();
    }
    if (vertices >= std::numeric_limits<uint32_t>::max() || chains >= std::numeric_limits<uint32_t>::max() ||
        nodes >= std::numeric_limits<uint32_t>::max() || instances.size() >= (uint64_t(1) << 24))
        return Status{ErrorCode::unsupported,
                      "scene too large: " + std::to_string(instances.size()) + " instances with " +
                          std::to_string(vertices) + " mesh vertices and " + std::to_string(chains / 2) +
                          " chains over all instances (at most 2^32 - 1 elements and 2^24 instances are supported)"};
    return {};
}

Status Simulation::Impl::check_wind(const Wind& wind, std::span<const Instance> instances) const {
    HMSM_TRY(validate(wind));
    // The wind force A s must stay in the range the float backends compute in (see the
    // constants check in build_hierarchy); a front so slow that -f (o.d)/v overflows would make
    // the phase, and every force, NaN.
    const double strength = std::abs(wind.strength);
    for (size_t m = 0; m < hierarchies_.size(); ++m)
        for (const Chain& chain : hierarchies_[m].chains)
            if (strength > 1e30 || chain.wind_area * strength > 1e30)
                return Status{ErrorCode::invalid_argument,
                              "wind strength " + number(wind.strength) + " is too strong for model '" +
                                  scene_.model_names[m] + "': wind force A*s above 1e30, beyond the computable range"};
    for (size_t i = 0; i < instances.size(); ++i)
        if (!std::isfinite(detail::instance_wind_phase(wind, instances[i])))
            return Status{ErrorCode::invalid_argument,
                          "instance " + std::to_string(i) + ": wind phase p - f (o.d)/v is not finite (front speed " +
                              number(wind.front_speed) + " too small for its origin)"};
    return {};
}

Result<std::unique_ptr<Simulation>> Simulation::Impl::create(const Scene& scene,
                                                             const SimulationConfig& config,
                                                             std::unique_ptr<detail::Backend> backend) {
    HMSM_TRY(validate(config.model));
    HMSM_TRY(validate(config.parameters));
    HMSM_TRY(validate(config.wind));
    HMSM_TRY(validate_scene(scene));

    std::unique_ptr<Simulation> created(new Simulation(std::make_unique<Impl>()));
    Impl* sim = created->impl_.get();
    sim->config_ = config;
    sim->scene_ = scene;
    for (size_t m = 0; m < scene.models.size(); ++m) {
        auto hierarchy = build_hierarchy(scene.models[m], config.model, config.parameters);
        if (!hierarchy) {
            return Status{hierarchy.status().code(),
                          "model '" + scene.model_names[m] + "': " + hierarchy.status().message()};
        }
        sim->meshes_.push_back(build_mesh(scene.models[m], *hierarchy, config.model));
        sim->hierarchies_.push_back(std::move(hierarchy).value());
    }

    sim->instances_ = scene.instances;
    HMSM_TRY(sim->check_wind(config.wind, scene.instances));
    HMSM_TRY(sim->check_size(scene.instances));
    sim->modes_ = turbulent_modes(config.wind.turbulence, config.wind.seed);

    sim->data_ = std::make_unique<SceneData>(
        detail::flatten_scene(scene, sim->hierarchies_, sim->meshes_, config.parameters,
                              config.model, config.wind));
    sim->data_->vertex_layout = config.vertex_layout;
    sim->data_->outputs = config.outputs;

    if (backend) {
        sim->backend_ = std::move(backend);
        sim->config_.backend = sim->backend_->kind();
    } else {
        auto created = detail::create_backend(config.backend, config.cpu_threads);
        if (!created) return created.status();
        sim->backend_ = std::move(created).value();
    }
    if (config.composition == Composition::automatic)
        sim->config_.composition =
            sim->backend_->capabilities().prefers_path_walk ? Composition::path_walk : Composition::pointer_jumping;
    sim->backend_->set_profiling(config.profile_passes);
    HMSM_TRY(sim->backend_->upload(*sim->data_));

    // Pose at rest (every instance, active or not): with g = 0, integrate keeps S = V = 0 and
    // writes the rest transforms; the remaining passes then fill R, O, node positions and the mesh.
    const detail::RunStep at_rest[1] = {};
    HMSM_TRY(sim->backend_->run(sim->program_for(sim->data_->groups, Pass::integrate), at_rest));
    HMSM_TRY(sim->apply_pending());
    return created;
}

Simulation::~Simulation() = default;

Status Simulation::Impl::step(uint32_t count) {
    HMSM_TRY(apply_pending());
    const Wind& wind = config_.wind;
    const double dt = config_.parameters.dt;
    uint32_t done = 0;
    times_ = {};
    while (done < count) {
        // One wind-table slot per step of the run: tau mod 2 and the turbulent mode phases,
        // reduced on the host in double; and one for the step after the run, which a walk
        // that integrates ahead reads (gpu_layout.h HMSM_DISPATCH_WALK_AHEAD).
        const uint32_t steps = std::min<uint32_t>(count - done, HMSM_WIND_STEP_SLOTS - 1);
        wind_scratch_.resize(size_t(steps + 1) * detail::kWindStepScalars);
        run_steps_.resize(steps);
        for (uint32_t k = 0; k <= steps; ++k) {
            const uint64_t n = steps_done_ + k + 1;  // steps_done_ counts the earlier chunks
            const double tau = clock_.tau(wind.frequency, dt, n);
            if (!std::isfinite(tau) && k == steps) {  // the step after: its own step() will say
                std::fill_n(&wind_scratch_[size_t(k) * detail::kWindStepScalars], detail::kWindStepScalars, 0.0);
                continue;
            }
            if (!std::isfinite(tau))  // f * t overflowed: no phase, and the profile would be NaN
                return Status{ErrorCode::invalid_argument,
                              "wind frequency " + number(wind.frequency) + " times time " +
                                  number(double(n - 1) * dt) + " s overflows: the wind phase is not finite"};
            detail::fill_wind_step(wind, modes_, tau, &wind_scratch_[size_t(k) * detail::kWindStepScalars]);
            if (k < steps) run_steps_[k] = {k, detail::AheadStep::whole};
        }
        HMSM_TRY(backend_->write(detail::BufferId::wind_table, HMSM_WIND_STEPS,
                                 uint64_t(steps + 1) * HMSM_WIND_STEP_VEC4S, wind_scratch_.data(),
                                 detail::Scalar::f64));
        // The walk that integrates ahead: the step layer says how each step runs.
        const bool ahead = std::any_of(step_program_.begin(), step_program_.end(), detail::is_walk_ahead);
        if (ahead) ahead_schedule_.plan(run_steps_);
        if (Status run = backend_->run(step_program_, run_steps_); !run.ok() || !ahead) {
            ahead_schedule_.forget();
            HMSM_TRY(run);
        }
        const PassTimes chunk = backend_->pass_times();
        for (size_t p = 0; p < chunk.seconds.size(); ++p) times_.seconds[p] += chunk.seconds[p];
        times_.steps += chunk.steps;
        done += steps;
        steps_done_ += steps;
    }
    return {};
}

Status Simulation::step(uint32_t count) { return impl_->step(count); }
uint64_t Simulation::steps_done() const { return impl_->steps_done_; }
double Simulation::time() const { return double(impl_->steps_done_) * impl_->config_.parameters.dt; }
PassTimes Simulation::pass_times() const { return impl_->times_; }
BackendKind Simulation::backend_kind() const { return impl_->backend_->kind(); }
std::string Simulation::device_name() const { return impl_->backend_->device_name(); }
const SimulationConfig& Simulation::config() const { return impl_->config_; }
const Scene& Simulation::scene() const { return impl_->scene_; }
const Hierarchy& Simulation::hierarchy(uint32_t model) const { return impl_->hierarchies_[model]; }
const MeshTemplate& Simulation::mesh(uint32_t model) const { return impl_->meshes_[model]; }
uint64_t Simulation::instance_count() const { return impl_->instances_.size(); }
uint64_t Simulation::chain_count() const { return impl_->data_->total_chains; }
uint64_t Simulation::node_count() const { return impl_->data_->total_nodes; }
uint64_t Simulation::vertex_count() const { return impl_->data_->total_vertices; }
uint32_t Simulation::jump_rounds() const { return impl_->data_->jump_rounds; }
uint32_t Simulation::capped_chain_count() const {
    uint32_t n = 0;
    for (const auto& h : impl_->hierarchies_) n += uint32_t(h.capped_chain_count);
    return n;
}
const Wind& Simulation::wind() const { return impl_->config_.wind; }
std::span<const ForceField> Simulation::force_fields() const { return impl_->force_fields_; }
std::span<const Instance> Simulation::instances() const { return impl_->instances_; }

Status Simulation::Impl::read_elements(Output output, std::vector<double>* as_double,
                                 std::vector<float>* as_float) const {
    std::lock_guard lock(read_mutex_);
    using detail::BufferId;
    const bool vertex_output = output == Output::vertex_positions || output == Output::vertex_normals;
    if ((vertex_output && !data_->produces_vertices()) ||
        (output == Output::node_positions && !data_->produces_nodes()))
        return Status{ErrorCode::invalid_argument,
                      std::string("read: output ") +
                          (vertex_output ? (output == Output::vertex_positions ? "vertex_positions" : "vertex_normals")
                                         : "node_positions") +
                          " is not produced by this simulation (SimulationConfig::outputs = " +
                          to_string(config_.outputs) + ")"};
    if (output == Output::vertex_normals && data_->packed_vertices())
        return read_packed_normals(as_double, as_float);
    BufferId id = BufferId::node_world;
    uint64_t first = 0, count = data_->total_nodes;
    switch (output) {
        case Output::node_positions: break;
        case Output::vertex_positions: id = BufferId::vertex_position; count = data_->total_vertices; break;
        case Output::vertex_normals: id = BufferId::vertex_normal; count = data_->total_vertices; break;
        // The pose of a step is its joint matrix [R | O] by rows (the path walk writes no R or
        // O half; every composition writes the joint matrix).
        case Output::chain_rotations:
        case Output::chain_origins: id = BufferId::joint_matrix; count = data_->total_chains; break;
        case Output::chain_angles: id = BufferId::chain_state; count = data_->total_chains; break;
        case Output::joint_matrices: id = BufferId::joint_matrix; count = data_->total_chains; break;
        default:  // a value cast from an integer (the C ABI checks its own)
            return {ErrorCode::invalid_argument,
                    "read: unknown output " + std::to_string(static_cast<int>(output))};
    }
    const uint32_t stored = detail::shape_scalars(detail::buffer_info(id).shape);
    const uint32_t wanted = output_components(output);
    // Output component k -> its scalar in the stored element: from a joint matrix's rows
    // (r00 r01 r02 ox, r10 ...) R column by column or O; else xyz of a vec4 or all.
    auto source = [output](uint32_t k) {
        if (output == Output::chain_rotations) return (k % 3) * 4 + k / 3;
        if (output == Output::chain_origins) return k * 4 + 3;
        return k;
    };
    auto repack = [&](const auto& raw, auto& out) {
        out.resize(count * wanted);
        if (stored == 4 && wanted == 3) {  // positions and normals: the per-frame hot path
            for (uint64_t i = 0; i < count; ++i) {
                out[3 * i] = raw[4 * i];
                out[3 * i + 1] = raw[4 * i + 1];
                out[3 * i + 2] = raw[4 * i + 2];
            }
            return;
        }
        for (uint64_t i = 0; i < count; ++i)
            for (uint32_t k = 0; k < wanted; ++k)
                out[i * wanted + k] = raw[i * stored + source(k)];
    };
    if (as_double) {
        stored_f64_.resize(count * stored);
        HMSM_TRY(backend_->read(id, first, count, stored_f64_.data(), detail::Scalar::f64));
        repack(stored_f64_, *as_double);
    } else {
        stored_f32_.resize(count * stored);
        HMSM_TRY(backend_->read(id, first, count, stored_f32_.data(), detail::Scalar::f32));
        repack(stored_f32_, *as_float);
    }
    return {};
}

Status Simulation::Impl::read_packed_normals(std::vector<double>* as_double,
                                       std::vector<float>* as_float) const {
    // VertexLayout::packed: each normal is the octahedral word in its position's w. The double
    // CPU oracle holds the word as an integer value, every other backend as float bits
    // (detail::packed_word_to_w), so the positions are read in the precision they are stored in.
    const uint64_t count = data_->total_vertices;
    auto decode = [count](const auto& positions, auto& normals) {
        using Stored = typename std::decay_t<decltype(positions)>::value_type;
        using Decoded = typename std::decay_t<decltype(normals)>::value_type;
        normals.resize(count * 3);
        for (uint64_t i = 0; i < count; ++i) {
            const auto n = detail::decode_normal_word<Decoded>(
                detail::packed_word_from_w<Stored>(positions[4 * i + 3]));
            normals[3 * i] = n.x;
            normals[3 * i + 1] = n.y;
            normals[3 * i + 2] = n.z;
        }
    };
    auto decode_into_request = [&](const auto& positions) {
        if (as_double) decode(positions, *as_double);
        else decode(positions, *as_float);
    };
    if (backend_->kind() == BackendKind::cpu64) {
        stored_f64_.resize(count * 4);
        HMSM_TRY(backend_->read(detail::BufferId::vertex_position, 0, count, stored_f64_.data(),
                                detail::Scalar::f64));
        decode_into_request(stored_f64_);
    } else {
        stored_f32_.resize(count * 4);
        HMSM_TRY(backend_->read(detail::BufferId::vertex_position, 0, count, stored_f32_.data(),
                                detail::Scalar::f32));
        decode_into_request(stored_f32_);
    }
    return {};
}

Status Simulation::read(Output output, std::vector<float>& values) const {
    return impl_->read_elements(output, nullptr, &values);
}
Status Simulation::read(Output output, std::vector<double>& values) const {
    return impl_->read_elements(output, &values, nullptr);
}

}  // namespace hmsm
