// Live control between steps (docs/model.md 3.9): wind, force fields, per-instance settings,
// adding and removing instances.
#include <hmsm/simulation.h>

#include "simulation_impl.h"

#include <glm/geometric.hpp>

#include <algorithm>
#include <cmath>
#include <iterator>
#include <limits>
#include <string>

namespace hmsm {

namespace {

bool finite(const Vec3& v) { return std::isfinite(v.x) && std::isfinite(v.y) && std::isfinite(v.z); }

}  // namespace

Status validate_force_fields(std::span<const ForceField> fields) {
    if (fields.size() > kMaxForceFields)
        return {ErrorCode::invalid_argument, std::to_string(fields.size()) + " force fields: at most " +
                                                 std::to_string(kMaxForceFields) + " may act at once"};
    for (size_t i = 0; i < fields.size(); ++i) {
        const ForceField& f = fields[i];
        const std::string name = "force field " + std::to_string(i);
        if (f.kind != ForceField::Kind::directional && f.kind != ForceField::Kind::radial)
            return {ErrorCode::invalid_argument, name + ": kind must be directional or radial"};
        if (!finite(f.center)) return {ErrorCode::invalid_argument, name + ": center is not finite"};
        if (!std::isfinite(f.radius) || !(f.radius > 0.0))
            return {ErrorCode::invalid_argument, name + ": radius must be finite and > 0"};
        if (!finite(f.directional))
            return {ErrorCode::invalid_argument, name + ": directional is not finite"};
        if (!std::isfinite(f.radial)) return {ErrorCode::invalid_argument, name + ": radial is not finite"};
    }
    return {};
}

namespace {

std::string instance_name(uint64_t instance) { return "instance " + std::to_string(instance); }

/// The runs of consecutive active instances of each group: the step program's groups, so an
/// inactive instance costs no thread of any pass.
std::vector<detail::InstanceGroup> active_groups(const detail::SceneData& d,
                                                 const std::vector<Instance>& instances) {
    std::vector<detail::InstanceGroup> runs;
    for (const detail::InstanceGroup& g : d.groups) {
        const detail::ModelRange& m = d.models[g.model];
        for (uint32_t k = 0; k < g.instance_count;) {
            if (!instances[g.instance_begin + k].active) {
                ++k;
                continue;
            }
            detail::InstanceGroup run = g;
            run.instance_begin = g.instance_begin + k;
            run.chain_begin = g.chain_begin + k * m.chain_count;
            run.node_begin = g.node_begin + k * m.node_count;
            run.vertex_begin = g.vertex_begin + k * m.vertex_count;
            run.instance_count = 0;
            while (k < g.instance_count && instances[g.instance_begin + k].active) {
                ++run.instance_count;
                ++k;
            }
            runs.push_back(run);
        }
    }
    return runs;
}

/// The groups covering instances [first, end) of `d`.
std::vector<detail::InstanceGroup> groups_from(const detail::SceneData& d, uint32_t first) {
    std::vector<detail::InstanceGroup> out;
    for (const detail::InstanceGroup& g : d.groups) {
        if (g.instance_begin + g.instance_count <= first) continue;
        detail::InstanceGroup part = g;
        if (g.instance_begin < first) {
            const uint32_t k = first - g.instance_begin;
            const detail::ModelRange& m = d.models[g.model];
            part.instance_begin = first;
            part.instance_count = g.instance_count - k;
            part.chain_begin += k * m.chain_count;
            part.node_begin += k * m.node_count;
            part.vertex_begin += k * m.vertex_count;
        }
        out.push_back(part);
    }
    return out;
}

uint32_t pass_bit(Pass pass) { return 1u << uint32_t(pass); }

}  // namespace

Status Simulation::Impl::apply_pending() {
    using detail::BufferId;
    if (header_dirty_) {
        wind_scratch_.assign(detail::kWindHeaderScalars, 0.0);
        detail::fill_wind_header(config_.wind, modes_, force_fields_, wind_scratch_.data());
        HMSM_TRY(backend_->write(BufferId::wind_table, 0, HMSM_WIND_STEPS, wind_scratch_.data(),
                                 detail::Scalar::f64));
        header_dirty_ = false;
    }
    if (instance_wind_dirty_) {
        wind_scratch_.resize(instances_.size() * detail::kInstanceWindScalars);
        for (size_t i = 0; i < instances_.size(); ++i)
            detail::fill_instance_wind(config_.wind, modes_, instances_[i],
                                       &wind_scratch_[i * detail::kInstanceWindScalars]);
        HMSM_TRY(backend_->write(BufferId::instance_wind, 0, instances_.size(), wind_scratch_.data(),
                                 detail::Scalar::f64));
        instance_wind_dirty_ = false;
        dirty_instances_.clear();
    }
    if (!dirty_instances_.empty()) {
        std::sort(dirty_instances_.begin(), dirty_instances_.end());
        dirty_instances_.erase(std::unique(dirty_instances_.begin(), dirty_instances_.end()),
                               dirty_instances_.end());
        wind_scratch_.resize(detail::kInstanceWindScalars);
        for (uint32_t i : dirty_instances_) {
            detail::fill_instance_wind(config_.wind, modes_, instances_[i], wind_scratch_.data());
            HMSM_TRY(backend_->write(BufferId::instance_wind, i, 1, wind_scratch_.data(), detail::Scalar::f64));
        }
        dirty_instances_.clear();
    }
    if (program_dirty_) {
        step_program_ = program_for(active_groups(*data_, instances_), Pass::wind_force);
        program_dirty_ = false;
    }
    return {};
}

namespace {

/// Capacity after growing to hold `needed`: 1.5 times the current one, so that adding
/// instances one at a time reallocates O(log n) times; never past `limit`.
uint64_t grown(uint64_t current, uint64_t needed, uint64_t limit) {
    if (needed <= current) return current;
    return std::max(needed, std::min(limit, current + current / 2));
}

}  // namespace

Status Simulation::Impl::reshape(const std::vector<uint32_t>& survivors, std::span<const Instance> added) {
    using detail::BufferId;
    std::vector<Instance> next;
    next.reserve(survivors.size() + added.size());
    for (uint32_t i : survivors) next.push_back(instances_[i]);
    next.insert(next.end(), added.begin(), added.end());
    HMSM_TRY(check_size(next));

    Scene layout;  // flatten_scene reads only the instances; models come from the hierarchies
    layout.instances = next;
    auto data = std::make_unique<detail::SceneData>(detail::flatten_scene(
        layout, hierarchies_, meshes_, config_.parameters, config_.model, config_.wind));
    data->vertex_layout = config_.vertex_layout;
    data->outputs = config_.outputs;
    const detail::SceneData& old = *data_;

    // Per old instance: first state chain (chains carry the state; nodes and vertices are
    // recomputed from R and O below).
    std::vector<uint64_t> old_chain(instances_.size() + 1, 0);
    for (size_t i = 0; i < instances_.size(); ++i)
        old_chain[i + 1] = old_chain[i] + old.models[instances_[i].model].chain_count;
    // The chain-scope state: S, V, g, T, the joint matrices and both halves of R and O.
    const BufferId carried[] = {BufferId::chain_state, BufferId::chain_force, BufferId::chain_local,
                                BufferId::joint_matrix, BufferId::chain_rotation, BufferId::chain_origin};
    // First new instance whose state is not where it was (its outputs are recomputed).
    uint32_t first_moved = uint32_t(survivors.size());
    for (uint32_t k = 0; k < survivors.size(); ++k)
        if (survivors[k] != k) {
            first_moved = k;
            break;
        }

    if (backend_->reshapes_in_place() && old.holds(*data)) {
        // In place: the buffers keep their allocation and static data; survivors' state moves
        // down on the device, the instance buffers and the added instances' state are written.
        data->chain_capacity = old.chain_capacity;
        data->node_capacity = old.node_capacity;
        data->vertex_capacity = old.vertex_capacity;
        data->instance_capacity = old.instance_capacity;
        std::vector<detail::ElementMove> moves;  // in chains, ascending: sources never overwritten early
        uint64_t at = 0;
        for (uint32_t k = 0; k < survivors.size(); ++k) {
            const uint64_t from = old_chain[survivors[k]], n = old_chain[survivors[k] + 1] - from;
            if (from != at) {
                if (!moves.empty() && moves.back().src + moves.back().count == from &&
                    moves.back().dst + moves.back().count == at)
                    moves.back().count += n;
                else
                    moves.push_back({from, at, n});
            }
            at += n;
        }
        for (BufferId id : carried) {
            const bool halves = detail::buffer_info(id).scope == detail::Scope::chain_halves;
            std::vector<detail::ElementMove> in_buffer;
            for (uint64_t h = 0; h < (halves ? 2u : 1u); ++h)
                for (detail::ElementMove m : moves) {
                    m.src += h * data->chain_capacity;
                    m.dst += h * data->chain_capacity;
                    in_buffer.push_back(m);
                }
            HMSM_TRY(backend_->move_elements(id, in_buffer));
        }
        // Added instances start at rest: S = V = 0 and g = 0 (the rest is computed below).
        const uint64_t added_chains = data->total_chains - at;
        if (added_chains > 0) {
            const std::vector<double> zeros(added_chains * 4, 0.0);
            HMSM_TRY(backend_->write(BufferId::chain_state, at, added_chains, zeros.data(), detail::Scalar::f64));
            HMSM_TRY(backend_->write(BufferId::chain_force, at, added_chains, zeros.data(), detail::Scalar::f64));
        }
        // Origins and yaws from the first instance that changed place.
        const uint32_t first_changed = first_moved;
        const uint64_t changed = data->instance_count() - first_changed;
        if (changed > 0) {
            std::vector<double> values(changed * 4);
            for (BufferId id : {BufferId::instance_origin, BufferId::instance_yaw}) {
                const auto& source = id == BufferId::instance_origin ? data->instance_origin : data->instance_yaw;
                for (uint64_t i = 0; i < changed; ++i)
                    for (int c = 0; c < 4; ++c) values[4 * i + c] = source[first_changed + i][c];
                HMSM_TRY(backend_->write(id, first_changed, changed, values.data(), detail::Scalar::f64));
            }
        }
        data_ = std::move(data);
    } else {
        // Anew: read the state back in the precision the backend stores it in (so that it
        // carries over bit for bit), allocate with room to grow, upload, write the state back.
        const uint64_t limit = std::numeric_limits<uint32_t>::max() / 2;
        data->chain_capacity = grown(old.chain_capacity, data->total_chains, limit);
        data->node_capacity = grown(old.node_capacity, data->total_nodes, limit);
        data->vertex_capacity = grown(old.vertex_capacity, data->total_vertices, limit);
        data->instance_capacity = uint32_t(grown(old.instance_capacity, data->instance_count(), 1u << 24));
        const detail::Scalar scalar = backend_->kind() == BackendKind::cpu64 ? detail::Scalar::f64 : detail::Scalar::f32;
        struct Saved {
            std::vector<double> f64;
            std::vector<float> f32;
        };
        std::vector<Saved> saved(std::size(carried));
        // Per buffer, the live chains of each half, halves back to back (a scene split into
        // windows maps no element past the live ones).
        const uint64_t live = old.total_chains;
        for (size_t b = 0; b < std::size(carried); ++b) {
            const uint32_t per = detail::shape_scalars(detail::buffer_info(carried[b]).shape);
            const uint32_t halves = detail::buffer_info(carried[b]).scope == detail::Scope::chain_halves ? 2 : 1;
            if (scalar == detail::Scalar::f64) saved[b].f64.resize(halves * live * per);
            else saved[b].f32.resize(halves * live * per);
            for (uint32_t h = 0; h < halves; ++h) {
                void* dst = scalar == detail::Scalar::f64 ? static_cast<void*>(saved[b].f64.data() + h * live * per)
                                                          : static_cast<void*>(saved[b].f32.data() + h * live * per);
                HMSM_TRY(backend_->read(carried[b], h * old.chain_capacity, live, dst, scalar));
            }
        }
        HMSM_TRY(backend_->upload(*data));
        data_ = std::move(data);
        // Per buffer and half, the survivors' chains in their new order (the live chains only:
        // a scene split into windows maps no element past them).
        for (size_t b = 0; b < std::size(carried); ++b) {
            const uint32_t per = detail::shape_scalars(detail::buffer_info(carried[b]).shape);
            const bool halves = detail::buffer_info(carried[b]).scope == detail::Scope::chain_halves;
            auto carry = [&](auto& values) -> Status {
                using V = typename std::decay_t<decltype(values)>::value_type;
                std::vector<V> out(old_chain[instances_.size()] * per);
                for (uint32_t h = 0; h < (halves ? 2u : 1u); ++h) {
                    uint64_t at = 0;
                    for (uint32_t i : survivors) {
                        const uint64_t from = h * live + old_chain[i];
                        const uint64_t n = old_chain[i + 1] - old_chain[i];
                        std::copy_n(values.begin() + from * per, n * per, out.begin() + at * per);
                        at += n;
                    }
                    HMSM_TRY(backend_->write(carried[b], h * data_->chain_capacity, at, out.data(), scalar));
                }
                return {};
            };
            HMSM_TRY(scalar == detail::Scalar::f64 ? carry(saved[b].f64) : carry(saved[b].f32));
        }
        first_moved = 0;  // every output buffer is new
        ++full_uploads_;
    }
    instances_ = std::move(next);
    header_dirty_ = instance_wind_dirty_ = program_dirty_ = true;

    // Survivors whose state moved: node positions and vertices are a pure function of the
    // carried R and O (passes 4, 6, 7 map elements one to one), so recomputing them restores
    // them exactly. Added instances are posed at rest from S = V = 0.
    const double no_wind[1] = {0.0};
    const uint32_t first_added = uint32_t(survivors.size());
    std::vector<detail::InstanceGroup> moved;
    for (detail::InstanceGroup g : groups_from(*data_, first_moved)) {
        if (g.instance_begin >= first_added) continue;
        g.instance_count = std::min(g.instance_count, first_added - g.instance_begin);
        moved.push_back(g);
    }
    const uint32_t outputs = pass_bit(Pass::node_relative) | pass_bit(Pass::node_world) | pass_bit(Pass::contour);
    if (!moved.empty()) HMSM_TRY(backend_->run(program_for(moved, Pass::node_relative, outputs), no_wind));
    if (!added.empty())
        HMSM_TRY(backend_->run(program_for(groups_from(*data_, first_added), Pass::integrate), no_wind));
    return apply_pending();
}

Status Simulation::set_wind(const Wind& wind) {
    Impl& s = *impl_;
    HMSM_TRY(s.check_wind(wind, s.instances_));
    // tau continues: tau_b is tau at the next step under the wind in force so far.
    const uint64_t next = s.steps_done_ + 1;
    s.clock_.base_tau = s.clock_.tau(s.config_.wind.frequency, s.config_.parameters.dt, next);
    s.clock_.base_step = next;
    // Only what the change touches is rebuilt: an engine ramping the strength every frame (a
    // gust) rewrites the small wind header, not every instance's wind data or the step program.
    const Wind& old = s.config_.wind;
    const bool turbulence_changed = wind.turbulence != old.turbulence || wind.seed != old.seed;
    // Per-instance data: the phase phi_i (frequency, direction, front) and whether the modes'
    // phases are used at all (turbulent or not).
    const bool phases_changed = wind.frequency != old.frequency || wind.direction != old.direction ||
                                wind.front_speed != old.front_speed ||
                                (wind.profile == WindProfile::turbulent) != (old.profile == WindProfile::turbulent);
    const bool profile_changed = wind.profile != old.profile;  // PassConstants.profile of the program
    s.config_.wind = wind;
    s.data_->profile = wind.profile;
    s.data_->wind_vector = wind.strength * glm::normalize(wind.direction);
    s.data_->wind_frequency = wind.frequency;
    if (turbulence_changed) s.modes_ = turbulent_modes(wind.turbulence, wind.seed);
    s.header_dirty_ = true;
    s.instance_wind_dirty_ = s.instance_wind_dirty_ || phases_changed;
    s.program_dirty_ = s.program_dirty_ || profile_changed;
    return {};
}

Status Simulation::set_force_fields(std::span<const ForceField> fields) {
    HMSM_TRY(validate_force_fields(fields));
    impl_->force_fields_.assign(fields.begin(), fields.end());
    impl_->header_dirty_ = true;
    return {};
}

namespace {
Status check_instance(uint64_t instance, size_t count) {
    if (instance >= count)
        return {ErrorCode::invalid_argument, instance_name(instance) + " does not exist (the simulation has " +
                                                 std::to_string(count) + " instances)"};
    return {};
}
}  // namespace

Status Simulation::set_instance_wind_scale(uint64_t instance, double wind_scale) {
    HMSM_TRY(check_instance(instance, impl_->instances_.size()));
    if (!std::isfinite(wind_scale) || wind_scale < 0.0)
        return {ErrorCode::invalid_argument, instance_name(instance) + ": wind scale must be finite and >= 0"};
    impl_->instances_[instance].wind_scale = wind_scale;
    impl_->dirty_instances_.push_back(uint32_t(instance));
    return {};
}

Status Simulation::set_instance_wind_phase(uint64_t instance, double wind_phase) {
    HMSM_TRY(check_instance(instance, impl_->instances_.size()));
    Instance changed = impl_->instances_[instance];
    changed.wind_phase = wind_phase;
    if (!std::isfinite(wind_phase) || !std::isfinite(detail::instance_wind_phase(impl_->config_.wind, changed)))
        return {ErrorCode::invalid_argument, instance_name(instance) + ": wind phase is not finite"};
    impl_->instances_[instance] = changed;
    impl_->dirty_instances_.push_back(uint32_t(instance));
    return {};
}

Status Simulation::set_instance_active(uint64_t instance, bool active) {
    HMSM_TRY(check_instance(instance, impl_->instances_.size()));
    if (impl_->instances_[instance].active != active) {
        impl_->instances_[instance].active = active;
        impl_->program_dirty_ = true;
    }
    return {};
}

Status Simulation::add_instances(std::span<const Instance> instances) {
    if (instances.empty()) return {};
    Impl& s = *impl_;
    for (size_t i = 0; i < instances.size(); ++i) {
        const Instance& inst = instances[i];
        const std::string where = "added instance " + std::to_string(i) + ": ";
        if (inst.model >= s.scene_.models.size())
            return {ErrorCode::invalid_argument, where + "model index " + std::to_string(inst.model) +
                                                     " does not exist (the scene has " +
                                                     std::to_string(s.scene_.models.size()) + " models)"};
        if (!std::isfinite(inst.origin.x) || !std::isfinite(inst.origin.y) || !std::isfinite(inst.origin.z))
            return {ErrorCode::invalid_argument, where + "origin is not finite"};
        if (!std::isfinite(inst.yaw)) return {ErrorCode::invalid_argument, where + "yaw is not finite"};
        if (!std::isfinite(inst.wind_scale) || inst.wind_scale < 0.0)
            return {ErrorCode::invalid_argument, where + "wind scale must be finite and >= 0"};
        if (!std::isfinite(inst.wind_phase) ||
            !std::isfinite(detail::instance_wind_phase(s.config_.wind, inst)))
            return {ErrorCode::invalid_argument, where + "wind phase is not finite"};
    }
    std::vector<uint32_t> survivors(s.instances_.size());
    for (uint32_t i = 0; i < survivors.size(); ++i) survivors[i] = i;
    return s.reshape(survivors, instances);
}

Status Simulation::remove_instances(std::span<const uint64_t> indices) {
    if (indices.empty()) return {};
    Impl& s = *impl_;
    std::vector<bool> removed(s.instances_.size(), false);
    for (uint64_t i : indices) {
        HMSM_TRY(check_instance(i, s.instances_.size()));
        if (removed[i])
            return {ErrorCode::invalid_argument, instance_name(i) + " is listed twice for removal"};
        removed[i] = true;
    }
    if (indices.size() == s.instances_.size())
        return {ErrorCode::invalid_argument,
                "cannot remove every instance: a simulation keeps at least one (deactivate it instead)"};
    std::vector<uint32_t> survivors;
    for (uint32_t i = 0; i < s.instances_.size(); ++i)
        if (!removed[i]) survivors.push_back(i);
    return s.reshape(survivors, {});
}

}  // namespace hmsm
