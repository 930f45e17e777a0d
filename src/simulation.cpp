// The Simulation façade: scene flattening, the backend, wind and outputs; the step program it
// runs is built in step_program.cpp.
#include <hmsm/simulation.h>

#include "backend.h"
#include "model/input_limits.h"
#include "scene_data.h"
#include "simulation_impl.h"
#include "step_program.h"

#include <hmsm/levels.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <limits>
#include <string_view>
#include <type_traits>

namespace hmsm {

using detail::Dispatch;
using detail::SceneData;

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
                         can.walks_ahead, jumping_form_);
}

Status Simulation::Impl::run_at_rest(const std::vector<detail::InstanceGroup>& groups, Pass first, uint32_t passes) {
    const detail::RunStep at_rest[1] = {};
    if (lists(groups, one_off_listed_)) return run_one_off(first, passes);
    return backend_->run(program_for(groups, first, passes), at_rest);
}

Status Simulation::Impl::run_one_off(Pass first, uint32_t passes) {
    const detail::RunStep at_rest[1] = {};
    if (one_off_listed_.entries() == 0) return {};  // the placed layout lists even none
    // In the placed layout the step program's table stays where there is room behind it.
    uint32_t base = 0;
    if (placed_ && uint64_t(placed_list_.entries()) + one_off_listed_.entries() <= data_->instance_capacity) {
        base = placed_list_.entries();
        for (detail::InstanceGroup& g : one_off_listed_.groups) g.instance_begin += base;
    } else if (placed_) {
        placed_list_.write_all();
    }
    HMSM_TRY(backend_->write(detail::BufferId::instance_table, base, one_off_listed_.entries(),
                             one_off_listed_.table.data(), detail::Scalar::f64));
    if (base == 0) instance_table_dirty_ = instance_table_dirty_ || step_program_lists_;
    return backend_->run(program_for(one_off_listed_.groups, first, passes), at_rest);
}

bool Simulation::Impl::lists(const std::vector<detail::InstanceGroup>& groups, detail::ListedGroups& into) const {
    if (placed_) {  // every program lists, the slots say where each instance lies
        detail::list_groups(*data_, groups, instances_, into, &placements_);
        return true;
    }
    if (!backend_->capabilities().runs_listed_groups || groups.size() <= 1 || !detail::scene_can_be_listed(*data_))
        return false;
    detail::list_groups(*data_, groups, instances_, into);
    return detail::listing_pays(groups.size(), into.groups.size()) && into.entries() > 0;
}

Status Simulation::Impl::check_size(std::span<const Instance> instances) const {
    uint64_t vertices = 0, chains = 0, nodes = 0;
    const bool with_vertices = config_.outputs == Outputs::all;  // the layout's vertices (create)
    // The layout's nodes: each model's stepped nodes (flattened already after create).
    std::vector<uint64_t> nodes_of(hierarchies_.size());
    for (size_t m = 0; m < nodes_of.size(); ++m)
        nodes_of[m] = data_ ? data_->models[m].node_count : detail::stepped_nodes(hierarchies_[m], config_.outputs).size();
    for (const Instance& inst : instances) {
        if (with_vertices) vertices += meshes_[inst.model].vertices.size();
        chains += 2 * hierarchies_[inst.model].chains.size();
        nodes += nodes_of[inst.model];
    }
    if (vertices >= std::numeric_limits<uint32_t>::max() || chains >= std::numeric_limits<uint32_t>::max() ||
        nodes >= std::numeric_limits<uint32_t>::max() || instances.size() > kMaxInstances)
        return Status{ErrorCode::unsupported,
                      "scene too large: " + std::to_string(instances.size()) + " instances with " +
                          std::to_string(vertices) + " mesh vertices and " + std::to_string(chains / 2) +
                          " chains over all instances (at most 2^32 - 1 elements and " +
                          std::to_string(kMaxInstances) + " instances are supported)"};
    return {};
}

double Simulation::Impl::largest_instance_load() const {
    if (largest_instance_load_ < 0.0) {
        double largest = 0.0;
        for (const Instance& instance : instances_)
            largest = std::max(largest, instance.wind_scale * largest_wind_area_[instance.model]);
        largest_instance_load_ = largest;
    }
    return largest_instance_load_;
}

Status Simulation::Impl::check_instance_forces(const Wind& wind) const {
    // The wind force A s lambda of every chain must stay in the range the float backends
    // compute in (docs/model.md 3.11): the largest wind area of each model bounds its chains.
    // An engine changes the wind every frame over forests of many thousand instances, so the
    // largest load over all instances decides unless it is within rounding of the limit; the
    // instances are then checked one by one, as the message names the first offender.
    if (detail::check_wind_force({}, wind.strength * (1.0 + 1e-9), 1.0, largest_instance_load())) return {};
    for (size_t i = 0; i < instances_.size(); ++i) {
        const uint32_t m = instances_[i].model;
        if (detail::check_wind_force({}, wind.strength, instances_[i].wind_scale, largest_wind_area_[m])) continue;
        return detail::check_wind_force("instance " + std::to_string(i) + " (model '" +
                                            detail::quote_input(scene_.model_names[lod_models_[m].scene_model]) + "')",
                                        wind.strength, instances_[i].wind_scale, largest_wind_area_[m]);
    }
    return {};
}

Status Simulation::Impl::check_forces(std::span<const ForceField> fields) const {
    double area = 0.0;
    for (double a : largest_wind_area_) area = std::max(area, a);
    for (size_t f = 0; f < fields.size(); ++f) {
        const ForceField& field = fields[f];
        const double strength = field.kind == ForceField::Kind::radial
                                    ? field.radial
                                    : std::max({std::abs(field.directional.x), std::abs(field.directional.y),
                                                std::abs(field.directional.z)});
        HMSM_TRY(detail::check_wind_force("force field " + std::to_string(f), strength, 1.0, area));
    }
    return {};
}

Status Simulation::Impl::check_wind(const Wind& wind, const Wind* in_force) const {
    HMSM_TRY(validate(wind));
    // The clock f t (atmospheric: U t) at the next step (docs/model.md 3.11).
    const double next_time = double(steps_done_ + 1) * config_.parameters.dt;
    const double rate = wind_clock_rate(wind);
    HMSM_TRY(detail::check_wind_clock(rate, next_time, clock_.base_tau + rate * next_time));
    HMSM_TRY(check_instance_forces(wind));
    HMSM_TRY(check_forces(force_fields_));
    // A front so slow that -f (o.d)/v overflows would make the phase, and every force, NaN.
    // The phase depends on the frequency, direction, front speed and whether the profile is
    // atmospheric (detail::wind_phase); each instance's phase was checked under `in_force`.
    const auto atmospheric = [](const Wind& w) { return w.profile == WindProfile::atmospheric; };
    if (in_force && wind.frequency == in_force->frequency && wind.direction == in_force->direction &&
        wind.front_speed == in_force->front_speed && atmospheric(wind) == atmospheric(*in_force))
        return {};
    for (size_t i = 0; i < instances_.size(); ++i)
        if (!std::isfinite(detail::instance_wind_phase(wind, instances_[i])))
            return Status{ErrorCode::invalid_argument,
                          "instance " + std::to_string(i) + ": wind phase p - f (o.d)/v is not finite (front speed " +
                              number(wind.front_speed) + " too small for its origin)"};
    return {};
}

Result<std::unique_ptr<Simulation>> Simulation::Impl::create(const Scene& scene,
                                                             const SimulationConfig& config,
                                                             std::unique_ptr<detail::Backend> backend,
                                                             detail::JumpingForm jumping_form) {
    HMSM_TRY(validate(config.model));
    HMSM_TRY(validate(config.parameters));
    HMSM_TRY(validate(config.wind));
    if (config.instance_layout != InstanceLayout::packed && config.instance_layout != InstanceLayout::placed)
        return Status{ErrorCode::invalid_argument, "create: unknown instance_layout " +
                                                       std::to_string(static_cast<int>(config.instance_layout))};
    HMSM_TRY(validate_scene(scene));

    // Sized from the models' counts before anything is built (docs/model.md 3.11).
    uint64_t build_bytes = 0;
    for (const TreeModel& model : scene.models)
        build_bytes += detail::model_build_bytes(model.nodes.size(), model.leaves.size(), config.model.ring_sides);
    if (build_bytes > detail::size_limits().build_bytes)
        return Status{ErrorCode::unsupported,
                      "scene too large: building its " + std::to_string(scene.models.size()) + " model(s) takes about " +
                          std::to_string(build_bytes >> 20) + " MiB of host memory, more than the limit of " +
                          std::to_string(detail::size_limits().build_bytes >> 20) + " MiB (docs/model.md 3.11)"};

    std::unique_ptr<Simulation> created(new Simulation(std::make_unique<Impl>()));
    Impl* sim = created->impl_.get();
    sim->config_ = config;
    sim->jumping_form_ = jumping_form;
    sim->scene_ = scene;
    for (size_t m = 0; m < scene.models.size(); ++m) {
        auto hierarchy = build_hierarchy(scene.models[m], config.model, config.parameters);
        if (!hierarchy) {
            return Status{hierarchy.status().code(),
                          "model '" + scene.model_names[m] + "': " + hierarchy.status().message()};
        }
        MeshTemplate mesh = build_mesh(scene.models[m], *hierarchy, config.model);
        Impl::LodModel lod{uint32_t(m), 0, {}};
        for (size_t c = 0; c < hierarchy->chains.size(); ++c) lod.source_chain.push_back(int32_t(c));
        if (m < scene.lod_budgets.size() && !scene.lod_budgets[m].empty())
            HMSM_TRY(sim->add_lod_levels(uint32_t(m), *hierarchy, mesh));
        const int32_t budget = m < scene.joint_budgets.size() ? scene.joint_budgets[m] : 0;
        if (budget > 0) {  // the model's level of detail in its place (docs/model.md 3.13)
            auto level = build_level(scene.models[m], *hierarchy, config.parameters, budget);
            if (!level)
                return Status{level.status().code(), "model '" + scene.model_names[m] + "': " + level.status().message()};
            mesh = build_level_mesh(scene.models[m], *hierarchy, mesh, *level);
            *hierarchy = std::move(level->hierarchy);
            lod.source_chain = std::move(level->source_chain);
        }
        sim->lod_models_.push_back(std::move(lod));
        sim->meshes_.push_back(std::move(mesh));
        double largest = 0.0;
        for (const Chain& chain : hierarchy->chains) largest = std::max(largest, chain.wind_area);
        sim->largest_wind_area_.push_back(largest);
        sim->hierarchies_.push_back(std::move(hierarchy).value());
    }

    HMSM_TRY(sim->append_lod_levels());
    sim->instances_ = scene.instances;
    for (Instance& inst : sim->instances_) inst.model = sim->levels_of_[inst.model][inst.level];
    for (uint64_t i = 0; i < scene.instances.size(); ++i) sim->instance_ids_.push_back(InstanceId(i));
    sim->next_instance_id_ = scene.instances.size();
    sim->instance_list_laid_out();
    HMSM_TRY(sim->check_wind(config.wind));
    HMSM_TRY(sim->check_size(sim->instances_));
    sim->modes_ = detail::wind_modes(config.wind);

    // Without vertex outputs no mesh is flattened: the layout then holds no vertex at all, so
    // forests of joints-only trees are not bounded by vertices they never produce.
    const std::vector<MeshTemplate> no_meshes(config.outputs == Outputs::all ? 0 : sim->meshes_.size());
    sim->data_ = std::make_unique<SceneData>(
        detail::flatten_scene(sim->instances_, sim->hierarchies_, config.outputs == Outputs::all ? sim->meshes_ : no_meshes,
                              config.parameters, config.model, config.wind, config.outputs));
    sim->data_->vertex_layout = config.vertex_layout;
    auto keep = sim->chain_keep_ranks();
    if (!keep) return keep.status();
    if (keep->size() != sim->data_->chain_parent.size())
        return Status{ErrorCode::internal, "create: the keep ranks do not cover the model chains"};
    sim->data_->chain_keep_level = std::move(keep).value();

    if (backend) {
        sim->backend_ = std::move(backend);
        sim->config_.backend = sim->backend_->kind();
    } else {
        auto created = detail::create_backend(config.backend, config.cpu_threads);
        if (!created) return created.status();
        sim->backend_ = std::move(created).value();
    }
    if (config.composition == Composition::automatic) {
        int32_t deepest = 0;
        for (const Hierarchy& h : sim->hierarchies_) deepest = std::max(deepest, h.max_depth);
        sim->config_.composition =
            detail::automatic_composition(sim->backend_->capabilities().prefers_path_walk, deepest);
    }
    sim->backend_->set_profiling(config.profile_passes);
    const char* device_growth = std::getenv("HMSM_DEVICE_GROWTH");
    sim->device_growth_ = !(device_growth && std::string_view(device_growth) == "0");
    HMSM_TRY(sim->backend_->upload(*sim->data_));
    sim->instance_list_laid_out();  // the placed layout starts packed

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
    const std::vector<detail::Dispatch>& program = current_program();
    HMSM_TRY(write_instance_table());
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
            const double tau = clock_.sample(wind_clock_rate(wind), dt, n, data_->coupled());
            if (!(std::abs(tau) <= detail::kMaxWindPhase) && k == steps) {  // the step after: its own step() will say
                std::fill_n(&wind_scratch_[size_t(k) * detail::kWindStepScalars], detail::kWindStepScalars, 0.0);
                continue;
            }
            if (!(std::abs(tau) <= detail::kMaxWindPhase))  // f t past the clock's range
                HMSM_TRY(detail::check_wind_clock(wind_clock_rate(wind), double(n - 1) * dt, tau));
            detail::fill_wind_step(wind, modes_, tau, &wind_scratch_[size_t(k) * detail::kWindStepScalars]);
            wind_scratch_[size_t(k) * detail::kWindStepScalars + 1] = double(n % 2);  // the load half step n writes
            wind_scratch_[size_t(k) * detail::kWindStepScalars + 2] = double(n & HMSM_FADE_END_MASK);  // fades' clock
            if (k < steps) run_steps_[k] = {k, detail::AheadStep::whole};
        }
        HMSM_TRY(backend_->write(detail::BufferId::wind_table, HMSM_WIND_STEPS,
                                 uint64_t(steps + 1) * HMSM_WIND_STEP_VEC4S, wind_scratch_.data(),
                                 detail::Scalar::f64));
        // The walk that integrates ahead: the step layer says how each step runs.
        const bool ahead = step_program_walks_ahead_;
        if (ahead) ahead_schedule_.plan(run_steps_);
        if (Status run = backend_->run(program, run_steps_, step_program_id_); !run.ok() || !ahead) {
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

Status Simulation::step(uint32_t count) {
    return impl_->fades_.empty() ? impl_->step(count) : impl_->step_fading(count);
}
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
uint64_t Simulation::node_count() const {
    if (impl_->data_->produces_nodes()) return impl_->data_->total_nodes;
    uint64_t nodes = 0;  // the skeletons', although the layout holds only the attach nodes
    for (const Instance& instance : impl_->instances_) nodes += impl_->hierarchies_[instance.model].node_owner.size();
    return nodes;
}
uint64_t Simulation::vertex_count() const {
    if (impl_->data_->produces_vertices()) return impl_->data_->total_vertices;
    uint64_t vertices = 0;  // the meshes' (skins draw them), although the layout holds none
    for (const Instance& instance : impl_->instances_) vertices += impl_->meshes_[instance.model].vertices.size();
    return vertices;
}
uint32_t Simulation::jump_rounds() const { return impl_->data_->jump_rounds; }
uint32_t Simulation::capped_chain_count() const {
    uint32_t n = 0;
    for (size_t m = 0; m < impl_->scene_.models.size(); ++m) n += uint32_t(impl_->hierarchies_[m].capped_chain_count);
    return n;
}
const Wind& Simulation::wind() const { return impl_->config_.wind; }
std::span<const ForceField> Simulation::force_fields() const { return impl_->force_fields_; }
std::span<const Instance> Simulation::instances() const { return impl_->instances_; }

}  // namespace hmsm
