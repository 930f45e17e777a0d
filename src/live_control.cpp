// Live control between steps (docs/model.md 3.9): wind, force fields, per-instance settings,
// adding and removing instances (their reshaping of the device scene: live_reshape.cpp).
#include <hmsm/simulation.h>

#include "model/input_limits.h"
#include "simulation_impl.h"

#include <glm/geometric.hpp>

#include <algorithm>
#include <cmath>
#include <string>

namespace hmsm {

Status validate_force_fields(std::span<const ForceField> fields) {
    if (fields.size() > kMaxForceFields)
        return {ErrorCode::invalid_argument, std::to_string(fields.size()) + " force fields: at most " +
                                                 std::to_string(kMaxForceFields) + " may act at once"};
    for (size_t i = 0; i < fields.size(); ++i) {
        const ForceField& f = fields[i];
        const std::string name = "force field " + std::to_string(i);
        if (f.kind != ForceField::Kind::directional && f.kind != ForceField::Kind::radial)
            return {ErrorCode::invalid_argument, name + ": kind must be directional or radial"};
        HMSM_TRY(detail::check_force_field(name, f.center, f.radius, f.directional, f.radial));
    }
    return {};
}

namespace {

std::string instance_name(uint64_t instance) { return "instance " + std::to_string(instance); }

/// Paused instances in a row that split a group's dispatches in two; fewer stay inside a
/// dispatch, whose threads skip them (gpu_layout.h, instance_wind's paused flag). A dispatch
/// costs a launch per pass, a paused instance inside one only its threads' check, so a split
/// pays only past a long run (16: not tuned). A dispatch per run of active instances costs three
/// times as much with every tenth tree paused (measured: docs/benchmarks/history/
/// 2026-11-26-nvidia-h100-d110289.md, analysis, paused instances; docs/architecture.md).
constexpr uint32_t kPausedRunThatSplits = 16;

/// Unchanged instances between two changed ones that apply_pending rewrites rather than
/// starting another write of instance_wind (16: not tuned).
constexpr uint32_t kWindGapRewritten = 16;

/// The step program's groups: each group's instances from its first active one to its last,
/// split where at least kPausedRunThatSplits paused instances lie in a row. A group with no
/// active instance runs nothing; paused instances left inside a run cost no write.
std::vector<detail::InstanceGroup> active_groups(const detail::SceneData& d,
                                                 const std::vector<Instance>& instances, uint64_t paused) {
    if (paused == 0) return d.groups;  // every group is one run
    std::vector<detail::InstanceGroup> runs;
    for (const detail::InstanceGroup& g : d.groups) {
        const detail::ModelRange& m = d.models[g.model];
        auto active = [&](uint32_t k) { return instances[g.instance_begin + k].active; };
        for (uint32_t k = 0; k < g.instance_count;) {
            if (!active(k)) {
                ++k;
                continue;
            }
            detail::InstanceGroup run = g;
            run.instance_begin = g.instance_begin + k;
            run.chain_begin = g.chain_begin + k * m.chain_count;
            run.node_begin = g.node_begin + k * m.node_count;
            run.vertex_begin = g.vertex_begin + k * m.vertex_count;
            const uint32_t first = k;
            uint32_t end = k + 1;  // one past the run's last active instance
            for (uint32_t paused = 0; k < g.instance_count && paused < kPausedRunThatSplits; ++k) {
                if (!active(k)) {
                    ++paused;
                    continue;
                }
                run.covers_paused |= paused > 0;  // paused instances before this active one
                paused = 0;
                end = k + 1;
            }
            run.instance_count = end - first;
            k = end;
            runs.push_back(run);
        }
    }
    return runs;
}


}  // namespace

Status Simulation::Impl::apply_pending() {
    using detail::BufferId;
    if (header_dirty_ || instance_wind_dirty_ || !dirty_instances_.empty() || program_dirty_)
        ahead_schedule_.live_change();
    if (header_dirty_) {
        wind_scratch_.assign(detail::kWindHeaderScalars, 0.0);
        const double step_span = data_->coupled() ? wind_clock_rate(config_.wind) * config_.parameters.dt : 0.0;
        detail::fill_wind_header(config_.wind, modes_, force_fields_, step_span, wind_scratch_.data());
        HMSM_TRY(backend_->write(BufferId::wind_table, 0, HMSM_WIND_STEPS, wind_scratch_.data(),
                                 detail::Scalar::f64));
        header_dirty_ = false;
    }
    if (instance_wind_dirty_) {
        wind_scratch_.resize(instances_.size() * detail::kInstanceWindScalars);
        for (size_t i = 0; i < instances_.size(); ++i)
            detail::fill_instance_wind(config_.wind, modes_, instances_[i], fade_word(uint32_t(i)),
                                       &wind_scratch_[i * detail::kInstanceWindScalars]);
        HMSM_TRY(backend_->write(BufferId::instance_wind, 0, instances_.size(), wind_scratch_.data(),
                                 detail::Scalar::f64));
        instance_wind_dirty_ = false;
        dirty_instances_.clear();
    }
    if (!dirty_instances_.empty()) {
        // One range per run of changed instances, the unchanged ones of a short gap between two
        // rewritten as they are, all in one write_ranges (a device backend's one transfer); a
        // long gap is not rewritten, so a change costs in proportion to the instances it
        // touched.
        std::sort(dirty_instances_.begin(), dirty_instances_.end());
        std::vector<detail::ElementRange> runs;
        for (size_t k = 0; k < dirty_instances_.size();) {
            const uint32_t begin = dirty_instances_[k];
            uint32_t last = begin;
            while (++k < dirty_instances_.size() && dirty_instances_[k] - last <= kWindGapRewritten)
                last = dirty_instances_[k];
            runs.push_back({begin, uint64_t(last - begin) + 1});
        }
        wind_scratch_.clear();
        for (const detail::ElementRange& run : runs)
            for (uint64_t i = run.first; i < run.first + run.count; ++i) {
                wind_scratch_.resize(wind_scratch_.size() + detail::kInstanceWindScalars);
                detail::fill_instance_wind(config_.wind, modes_, instances_[i], fade_word(uint32_t(i)),
                                           &wind_scratch_[wind_scratch_.size() - detail::kInstanceWindScalars]);
            }
        HMSM_TRY(backend_->write_ranges(BufferId::instance_wind, runs, wind_scratch_.data(), detail::Scalar::f64));
        dirty_instances_.clear();
    }
    return {};
}

const std::vector<detail::Dispatch>& Simulation::Impl::current_program() {
    if (program_dirty_) {
        // Without paused instances the runs are the groups themselves (not copied: a
        // fragmented world has hundreds of thousands).
        std::vector<detail::InstanceGroup> runs;
        if (placed_) {
            // The placed layout's table is kept under changes (placed_list.h): a segment per model.
            placed_list_.groups(*data_, listed_.groups);
            step_program_lists_ = true;
        } else {
            if (paused_count_ > 0) runs = active_groups(*data_, instances_, paused_count_);
            // A fragmented scene runs listed groups, a few per model, where the backend can
            // (listed_groups.h); their instance table is written before the program runs
            // (write_instance_table).
            step_program_lists_ = lists(paused_count_ > 0 ? runs : data_->groups, listed_);
        }
        const std::vector<detail::InstanceGroup>& groups = paused_count_ > 0 ? runs : data_->groups;
        instance_table_dirty_ = step_program_lists_;
        step_program_ = program_for(step_program_lists_ ? listed_.groups : groups, Pass::wind_force);
        ++step_program_id_;
        step_program_walks_ahead_ = std::any_of(step_program_.begin(), step_program_.end(), detail::is_walk_ahead);
        program_dirty_ = false;
    }
    return step_program_;
}

Status Simulation::Impl::write_instance_table() {
    if (placed_) {  // the entries written since the last step, run by run
        instance_table_dirty_ = false;
        if (!placed_list_.pending()) return {};
        std::vector<detail::ElementRange> ranges;
        std::vector<double> values;
        placed_list_.take_writes(ranges, values);
        return backend_->write_ranges(detail::BufferId::instance_table, ranges, values.data(), detail::Scalar::f64);
    }
    if (!instance_table_dirty_) return {};
    HMSM_TRY(backend_->write(detail::BufferId::instance_table, 0, listed_.entries(), listed_.table.data(),
                             detail::Scalar::f64));
    instance_table_dirty_ = false;
    return {};
}

Status Simulation::set_wind(const Wind& wind) {
    Impl& s = *impl_;
    HMSM_TRY(s.check_wind(wind, &s.config_.wind));
    // tau continues: tau_b is tau at the next step under the wind in force so far.
    const uint64_t next = s.steps_done_ + 1;
    s.clock_.base_tau = s.clock_.tau(wind_clock_rate(s.config_.wind), s.config_.parameters.dt, next);
    s.clock_.base_step = next;
    // Only what the change touches is rebuilt: an engine ramping the strength every frame (a
    // gust) rewrites the small wind header, not every instance's wind data or the step program.
    const Wind& old = s.config_.wind;
    const bool turbulence_changed = wind.turbulence != old.turbulence || wind.seed != old.seed;
    // Per-instance data: the phase phi_i (frequency, direction, front), whether the modes'
    // phases are used at all and which profile's they are (turbulent, atmospheric or none); the
    // atmospheric spatial phases also follow the seed's wavenumbers and the strength's sign.
    const bool atmospheric = wind.profile == WindProfile::atmospheric;
    const bool phases_changed =
        wind.frequency != old.frequency || wind.direction != old.direction || wind.front_speed != old.front_speed ||
        (wind.profile == WindProfile::turbulent) != (old.profile == WindProfile::turbulent) ||
        atmospheric != (old.profile == WindProfile::atmospheric) ||
        (atmospheric && (wind.seed != old.seed || (wind.strength < 0.0) != (old.strength < 0.0)));
    const bool profile_changed = wind.profile != old.profile;  // PassConstants.profile of the program
    s.config_.wind = wind;
    s.data_->profile = wind.profile;
    if (turbulence_changed) s.modes_ = detail::wind_modes(wind);
    s.header_dirty_ = true;
    s.instance_wind_dirty_ = s.instance_wind_dirty_ || phases_changed;
    s.program_dirty_ = s.program_dirty_ || profile_changed;
    return {};
}

Status Simulation::set_force_fields(std::span<const ForceField> fields) {
    HMSM_TRY(validate_force_fields(fields));
    HMSM_TRY(impl_->check_forces(fields));
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
    HMSM_TRY(detail::check_wind_scale(instance_name(instance) + ": wind scale", wind_scale));
    Instance changed = impl_->instances_[instance];
    changed.wind_scale = wind_scale;
    HMSM_TRY(detail::check_wind_force(instance_name(instance), impl_->config_.wind.strength, wind_scale,
                                      impl_->largest_wind_area_[changed.model]));
    impl_->instances_[instance].wind_scale = wind_scale;
    impl_->instances_changed();
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
        impl_->paused_count_ += active ? uint64_t(-1) : 1;
        if (impl_->placed_) {  // a paused instance has no entry in the step program's table
            const uint32_t i = uint32_t(instance);
            if (active) impl_->placed_list_.insert(i, impl_->instances_[i].model, impl_->placements_[i]);
            else impl_->placed_list_.erase(i);
        }
        impl_->pause_fade(uint32_t(instance), active);
        impl_->dirty_instances_.push_back(uint32_t(instance));  // its paused flag and fade word
        impl_->program_dirty_ = true;
    }
    return {};
}

Status Simulation::add_instances(std::span<const Instance> instances) {
    if (instances.empty()) return {};
    Impl& s = *impl_;
    if (instances.size() > kMaxInstances - s.instances_.size())
        return {ErrorCode::unsupported, "scene too large: " + std::to_string(s.instances_.size()) + " + " +
                                            std::to_string(instances.size()) + " instances, at most " +
                                            std::to_string(kMaxInstances) + " are supported"};
    // Each added instance names the model it runs: its scene model's run model for its level.
    std::vector<Instance> run(instances.begin(), instances.end());
    for (size_t i = 0; i < instances.size(); ++i) {
        const Instance& inst = instances[i];
        const std::string where = "added instance " + std::to_string(i) + ": ";
        if (inst.model >= s.scene_.models.size())
            return {ErrorCode::invalid_argument, where + "model index " + std::to_string(inst.model) +
                                                     " does not exist (the scene has " +
                                                     std::to_string(s.scene_.models.size()) + " models)"};
        const std::vector<uint32_t>& levels = s.levels_of_[inst.model];
        if (inst.level >= levels.size())
            return {ErrorCode::invalid_argument,
                    where + "level " + std::to_string(inst.level) + " does not exist (model '" +
                        detail::quote_input(s.scene_.model_names[inst.model]) + "' has levels 0 to " +
                        std::to_string(levels.size() - 1) + ", Scene::lod_budgets)"};
        run[i].model = levels[inst.level];
        HMSM_TRY(detail::check_coordinate(where + "origin", inst.origin));
        if (!std::isfinite(inst.yaw)) return {ErrorCode::invalid_argument, where + "yaw is not finite"};
        HMSM_TRY(detail::check_wind_scale(where + "wind scale", inst.wind_scale));
        HMSM_TRY(detail::check_wind_force(where + "model '" + detail::quote_input(s.scene_.model_names[inst.model]) + "'",
                                          s.config_.wind.strength, inst.wind_scale,
                                          s.largest_wind_area_[run[i].model]));
        if (!std::isfinite(inst.wind_phase) ||
            !std::isfinite(detail::instance_wind_phase(s.config_.wind, inst)))
            return {ErrorCode::invalid_argument, where + "wind phase is not finite"};
    }
    if (s.streaming_paths_) {
        Result<bool> appended = s.append_in_place(run);
        if (!appended) return appended.status();
        if (*appended) return {};
    }
    std::vector<uint32_t> survivors(s.instances_.size());
    for (uint32_t i = 0; i < survivors.size(); ++i) survivors[i] = i;
    return s.reshape(survivors, run);
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
    std::vector<uint64_t> leaving;
    for (uint32_t i = 0; i < s.instances_.size(); ++i)
        if (!removed[i]) survivors.push_back(i);
        else leaving.push_back(uint64_t(s.instance_ids_[i]));
    HMSM_TRY(s.reshape(survivors, {}));
    for (uint64_t id : leaving) s.fades_.erase(id);  // a removed instance fades no more
    return {};
}

Status Simulation::reset_instances(std::span<const uint32_t> indices) {
    if (indices.empty()) return {};
    Impl& s = *impl_;
    std::vector<bool> listed(s.instances_.size(), false);
    for (uint32_t i : indices) {
        HMSM_TRY(check_instance(i, s.instances_.size()));
        if (listed[i]) return {ErrorCode::invalid_argument, instance_name(i) + " is listed twice for reset"};
        listed[i] = true;
    }
    std::vector<uint32_t> sorted(indices.begin(), indices.end());
    std::sort(sorted.begin(), sorted.end());
    return s.reset(sorted);
}

}  // namespace hmsm
