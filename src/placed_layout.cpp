// The placed layout (SimulationConfig::instance_layout, instance_placements.h): appends, swap
// removals and level switches within the capacity give the instances they touch slots of their
// own and move nothing else, so a call costs in proportion to those instances whatever their
// indices. The step program lists every instance with its slot (listed_groups.h). Results are
// bit for bit those of the packed layout (tests/placed_layout_test.cpp).
#include "instance_moves.h"
#include "level_staging.h"
#include "simulation_impl.h"

#include <algorithm>
#include <cmath>

namespace hmsm {

namespace {

using detail::BufferId;
using detail::ElementCounts;
using detail::ElementMove;
using detail::ElementRange;

}  // namespace

detail::ElementCounts Simulation::Impl::first_elements(uint32_t i) {
    return placed_ ? placements_[i] : offsets().before(i);
}

void Simulation::Impl::placed_end_changed() {
    const ElementCounts& end = placements_.end();
    data_->placed_chain_end = end.chains;
    data_->placed_node_end = end.nodes;
    data_->placed_vertex_end = end.vertices;
}

bool Simulation::Impl::wants_placed() const {
    const detail::BackendCapabilities can = backend_->capabilities();
    return config_.instance_layout == InstanceLayout::placed && can.runs_listed_groups && can.reshapes_in_place &&
           detail::scene_can_be_listed(*data_);
}

void Simulation::Impl::placements_laid_out() {
    template_zone_.forget();  // the slots start again from the packed end
    placements_.assign_packed(instances_, data_->models);
    placed_end_changed();
    placed_list_.build(instances_, placements_, uint32_t(data_->models.size()));
    program_dirty_ = true;
}

Status Simulation::Impl::run_at_rest_placed(std::span<const uint32_t> indices, Pass first, uint32_t passes) {
    detail::list_instances(*data_, indices, instances_, placements_, one_off_listed_);
    return run_one_off(first, passes);
}

Status Simulation::Impl::pack_layout() {
    if (!placed_) return {};
    detail::SceneData& d = *data_;
    detail::lay_out_groups(d, instances_);  // the placed changes keep no groups
    auto size = [&](uint32_t i) { return detail::counts_of(d.models[instances_[i].model]); };
    bool packed = true;
    ElementCounts at;
    for (uint32_t i = 0; packed && i < instances_.size(); ++i) {
        packed = placements_[i] == at;
        at += size(i);
    }
    if (packed) {  // only free slots past the instances: dropped
        placements_laid_out();
        return {};
    }
    // Every carried buffer's held chains through the host (halves back to back), each instance
    // from its slot to its packed place; the outputs are then recomputed from R and O (passes 4,
    // 6, 7 map elements one to one), element for element what they were.
    detail::InstanceChangeBracket change(*backend_);
    ahead_schedule_.live_change();
    const detail::Scalar scalar = backend_->kind() == BackendKind::cpu64 ? detail::Scalar::f64 : detail::Scalar::f32;
    const uint64_t held = d.chains_held(), live = d.total_chains;
    for (BufferId id : detail::carried_buffers(d.holds_loads())) {
        const uint32_t per = detail::shape_scalars(detail::buffer_info(id).shape);
        auto pack = [&](auto zero) -> Status {
            using V = decltype(zero);
            std::vector<V> values(held * per), packed_values(live * per);
            for (uint32_t h = 0; h < detail::halves_of(id); ++h) {
                HMSM_TRY(backend_->read(id, h * d.chain_capacity, held, values.data(), scalar));
                uint64_t at = 0;
                for (uint32_t i = 0; i < instances_.size(); ++i) {
                    const uint64_t n = size(i).chains;
                    std::copy_n(values.begin() + placements_[i].chains * per, n * per, packed_values.begin() + at * per);
                    at += n;
                }
                HMSM_TRY(backend_->write(id, h * d.chain_capacity, live, packed_values.data(), scalar));
            }
            return {};
        };
        HMSM_TRY(scalar == detail::Scalar::f64 ? pack(0.0) : pack(0.0f));
    }
    placements_laid_out();
    return recompute_outputs();
}

Result<bool> Simulation::Impl::append_placed(std::span<const Instance> added) {
    detail::SceneData& d = *data_;
    const uint32_t first = uint32_t(instances_.size());
    ElementCounts grown{d.total_chains, d.total_nodes, d.total_vertices};
    std::vector<uint32_t> models;
    for (const Instance& inst : added) {
        grown += detail::counts_of(d.models[inst.model]);
        models.push_back(inst.model);
    }
    HMSM_TRY(check_size(uint64_t(first) + added.size(), grown));
    const ElementCounts end = placements_.end_after(models, d.models);
    if (end.chains > d.chain_capacity || end.nodes > d.node_capacity || end.vertices > d.vertex_capacity ||
        uint64_t(first) + added.size() > d.instance_capacity) {
        Result<bool> room = grow_on_device(end, uint64_t(first) + added.size());
        if (!room || !*room) return room;
    }
    detail::InstanceChangeBracket change(*backend_);
    ahead_schedule_.live_change();

    // Added instances start at rest in their slots: S = V = 0 and g = 0 (T, R, O are computed
    // from them), every slot in one write per buffer.
    std::vector<ElementRange> slots;
    for (const Instance& inst : added) {
        const ElementCounts size = detail::counts_of(d.models[inst.model]);
        const ElementCounts at = placements_.allocate(inst.model, size);
        placements_.push_back(at);
        detail::append_range(slots, at.chains, size.chains);
    }
    placed_end_changed();
    HMSM_TRY(zero_chain_state(slots));

    std::vector<uint32_t> appended;
    appended.reserve(added.size());
    for (const Instance& inst : added) {
        const uint32_t i = uint32_t(instances_.size());
        appended.push_back(i);
        instances_.push_back(inst);
        const InstanceId id = InstanceId(next_instance_id_++);
        instance_ids_.push_back(id);  // ascending ids stay ascending
        if (!ids_ascending_) id_index_.emplace(uint64_t(id), i);
        d.instance_origin.push_back({inst.origin, 0.0});
        d.instance_yaw.push_back({std::cos(inst.yaw), std::sin(inst.yaw), 0.0, 0.0});
        lod_tracker_.append();
        if (inst.active) placed_list_.insert(i, inst.model, placements_[i]);
        else ++paused_count_;
        dirty_instances_.push_back(i);
    }
    placed_list_.resize(uint32_t(instances_.size()));
    offsets_valid_ = false;  // the packed offsets, the groups and their totals are not kept here
    d.groups.clear();
    d.total_chains = grown.chains;
    d.total_nodes = grown.nodes;
    d.total_vertices = grown.vertices;
    d.instance_wind.resize(size_t(HMSM_INSTANCE_WIND_VEC4S) * 4 * instances_.size(), 0.0);
    const ElementRange appended_run{first, instances_.size() - first};
    HMSM_TRY(detail::write_origins_and_yaws(*backend_, d, {&appended_run, 1}));
    instances_changed();
    header_dirty_ = program_dirty_ = true;
    HMSM_TRY(run_at_rest_placed(appended, Pass::integrate));
    HMSM_TRY(apply_pending());
    return true;
}

Status Simulation::Impl::swap_remove_placed(const std::vector<uint32_t>& removed) {
    detail::SceneData& d = *data_;
    // Each hole takes its filler's slot along, so nothing moves on the device.
    const detail::SwapFill fill = detail::swap_fill(removed, uint32_t(instances_.size()));
    detail::InstanceChangeBracket change(*backend_);
    ahead_schedule_.live_change();
    for (uint32_t r : removed) {
        placements_.release(instances_[r].model, placements_[r]);
        placed_list_.erase(r);
        const ElementCounts size = detail::counts_of(d.models[instances_[r].model]);
        d.total_chains -= size.chains;
        d.total_nodes -= size.nodes;
        d.total_vertices -= size.vertices;
    }
    for (size_t j = 0; j < fill.holes.size(); ++j) {
        placements_.set(fill.holes[j], placements_[fill.fillers[j]]);
        placed_list_.renumber(fill.fillers[j], fill.holes[j]);
    }
    placements_.resize(fill.kept);
    placed_list_.resize(fill.kept);
    offsets_valid_ = false;
    d.groups.clear();
    return swap_instance_lists(removed, fill);
}

Status Simulation::Impl::copy_switched_chains(const std::vector<std::pair<uint32_t, uint32_t>>& models,
                                               const std::vector<const detail::LevelCarry*>& carries,
                                               const detail::LevelStaging& staging,
                                               const std::vector<ElementCounts>& slots) {
    // Each switched tree straight from its old slot to its new one: its kept chains by its
    // carry's pattern, its unfolded chains from its model's template. One pair of patterns per
    // distinct carry; the new slots are apart from every old slot and template.
    std::vector<const detail::LevelCarry*> distinct;
    std::vector<detail::PatternCopy> copies;
    for (size_t k = 0; k < models.size(); ++k) {
        const auto found = std::find(distinct.begin(), distinct.end(), carries[k]);
        const uint32_t c = uint32_t(found - distinct.begin());
        if (found == distinct.end()) distinct.push_back(carries[k]);
        copies.push_back({placements_[models[k].first].chains, slots[k].chains, 2 * c});
        if (staging.template_of[k] >= 0)
            copies.push_back({staging.templates[size_t(staging.template_of[k])].at, slots[k].chains, 2 * c + 1});
    }
    std::vector<std::vector<ElementMove>> unfolded(distinct.size());
    std::vector<detail::MovePattern> patterns;
    for (size_t c = 0; c < distinct.size(); ++c) {
        for (const ElementRange& r : distinct[c]->unfolded) unfolded[c].push_back({r.first, r.first, r.count});
        patterns.push_back({distinct[c]->kept});
        patterns.push_back({unfolded[c]});
    }
    return backend_->copy_patterns(detail::carried_buffers(data_->holds_loads()), data_->chain_capacity, patterns,
                                   copies);
}

Status Simulation::Impl::move_switched_chains(const std::vector<std::pair<uint32_t, uint32_t>>& models,
                                              const std::vector<const detail::LevelCarry*>& carries,
                                              const detail::LevelStaging& staging,
                                              const std::vector<ElementCounts>& slots) {
    // In each carried buffer, in order: the switched instances' old chains are copied into the
    // staging, their new chains built there, and each goes to its new slot (all halves).
    const detail::SceneData& d = *data_;
    std::vector<ElementMove> stage, unstage;
    for (size_t k = 0; k < models.size(); ++k)
        detail::append_move(stage, placements_[models[k].first].chains, staging.old_at[k],
                            d.models[instances_[models[k].first].model].chain_count);
    detail::append_build_moves(stage, staging, carries);
    for (size_t k = 0; k < models.size(); ++k)
        detail::append_move(unstage, staging.instance_at[k], slots[k].chains, d.models[models[k].second].chain_count);
    const std::vector<BufferId> carried = detail::carried_buffers(d.holds_loads());
    std::vector<std::vector<ElementMove>> in_buffers(carried.size());
    std::vector<detail::BufferMoves> moves;
    for (size_t b = 0; b < carried.size(); ++b) {
        for (const std::vector<ElementMove>* part : {&stage, &unstage})
            for (uint32_t h = 0; h < detail::halves_of(carried[b]); ++h)
                for (ElementMove m : *part) {
                    m.src += h * d.chain_capacity;
                    m.dst += h * d.chain_capacity;
                    in_buffers[b].push_back(m);
                }
        moves.push_back({carried[b], in_buffers[b]});
    }
    return backend_->move_buffers(moves);
}

Result<bool> Simulation::Impl::staging_from_template_zone(uint64_t slots_end,
                                                          const std::vector<std::pair<uint32_t, uint32_t>>& models,
                                                          const std::vector<const detail::LevelCarry*>& carries,
                                                          detail::LevelStaging& staging) {
    const detail::SceneData& d = *data_;
    const bool unfolds = std::any_of(carries.begin(), carries.end(),
                                     [](const detail::LevelCarry* c) { return !c->unfolded.empty(); });
    if (unfolds && !template_zone_.valid_for(d.chain_capacity, slots_end)) {
        template_zone_.forget();
        // Every run model of a scene model with levels, back to back below the capacity.
        std::vector<int64_t> at(d.models.size(), -1);
        uint64_t zone = 0;
        for (const std::vector<uint32_t>& levels : levels_of_)
            if (levels.size() > 1)
                for (uint32_t m : levels) {
                    at[m] = int64_t(zone);
                    zone += d.models[m].chain_count;
                }
        if (zone == 0 || slots_end + zone > d.chain_capacity) return false;
        const uint64_t base = d.chain_capacity - zone;
        std::vector<std::vector<glm::dmat3>> rest;
        rest.reserve(at.size());
        detail::LevelStaging all;
        for (uint32_t m = 0; m < at.size(); ++m) {
            if (at[m] < 0) continue;
            at[m] += int64_t(base);
            std::vector<glm::dmat3>& q = rest.emplace_back();
            for (const Chain& chain : hierarchies_[m].chains) q.push_back(chain.rest_rotation);
            all.templates.push_back({m, uint64_t(at[m]), &q});
        }
        const detail::Scalar scalar = backend_->kind() == BackendKind::cpu64 ? detail::Scalar::f64 : detail::Scalar::f32;
        HMSM_TRY(detail::write_staging_templates(*backend_, detail::carried_buffers(d.holds_loads()), d.chain_capacity,
                                                 scalar, all));
        template_zone_ = {d.chain_capacity, base, std::move(at)};
    }
    for (size_t k = 0; k < models.size(); ++k) {
        const uint32_t model = models[k].second;
        if (!carries[k]->unfolded.empty() && (model >= template_zone_.at.size() || template_zone_.at[model] < 0))
            return false;
    }
    staging = template_zone_.staging(slots_end, models, carries);
    return true;
}

Result<bool> Simulation::Impl::switch_placed(const std::vector<std::pair<uint32_t, uint32_t>>& models,
                                             const std::vector<const detail::LevelCarry*>& carries) {
    detail::SceneData& d = *data_;
    std::vector<uint32_t> new_models;
    for (auto [i, model] : models) new_models.push_back(model);
    // The staging lies above every slot held once the new slots are taken: where the backend
    // copies patterns, the templates alone.
    const bool direct = backend_->capabilities().copies_patterns;
    const ElementCounts end = placements_.end_after(new_models, d.models);
    const detail::LevelStaging staging =
        direct ? detail::lay_out_templates(end.chains, models, d.models, carries)
               : detail::lay_out_staging(
                     end.chains, models, [&](uint32_t i) { return instances_[i].model; }, d.models, carries);
    if (staging.end > d.chain_capacity || end.nodes > d.node_capacity || end.vertices > d.vertex_capacity) {
        Result<bool> grown = grow_on_device({staging.end, end.nodes, end.vertices}, instances_.size());
        if (!grown) return grown;
        if (!*grown || staging.end > d.chain_capacity) return false;  // not where the growth met its limit
    }
    // New slots first: the old ones are read by the copies below and freed after them.
    std::vector<ElementCounts> slots;
    for (uint32_t model : new_models) slots.push_back(placements_.allocate(model, detail::counts_of(d.models[model])));
    placed_end_changed();
    const std::vector<BufferId> carried = detail::carried_buffers(d.holds_loads());
    const detail::Scalar scalar = backend_->kind() == BackendKind::cpu64 ? detail::Scalar::f64 : detail::Scalar::f32;
    detail::LevelStaging zoned;
    Result<bool> from_zone = direct ? staging_from_template_zone(end.chains, models, carries, zoned) : Result<bool>(false);
    if (!from_zone) return from_zone.status();
    if (!*from_zone) {
        template_zone_.forget();  // the staging above the slots may lie in the zone
        HMSM_TRY(detail::write_staging_templates(*backend_, carried, d.chain_capacity, scalar, staging));
    }
    const detail::LevelStaging& used = *from_zone ? zoned : staging;
    HMSM_TRY(direct ? copy_switched_chains(models, carries, used, slots) : move_switched_chains(models, carries, used, slots));
    for (size_t k = 0; k < models.size(); ++k) {
        const auto [i, model] = models[k];
        const ElementCounts delta = detail::counts_of(d.models[model]) - detail::counts_of(d.models[instances_[i].model]);
        d.total_chains += delta.chains;
        d.total_nodes += delta.nodes;
        d.total_vertices += delta.vertices;
        placements_.release(instances_[i].model, placements_[i]);
        placements_.set(i, slots[k]);
        instances_[i].model = model;
        instances_[i].level = lod_models_[model].level;
        if (instances_[i].active) placed_list_.move_to(i, model, slots[k]);
        lod_tracker_.examine_next(i);
    }
    offsets_valid_ = false;
    d.groups.clear();
    return true;
}

}  // namespace hmsm
