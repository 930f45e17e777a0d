// Levels of detail at run time (docs/driving.md, levels of detail): every level of a model is a
// model of the device scene from create() on, and a switch runs an instance on another of them.
// The instance keeps its index: the chains both levels keep carry their state element for
// element (a level keeps the full model's chains with their constants, docs/model.md 3.12), and
// chains the finer level unfolds start rigid with their parent (level_carry.h). Within the
// capacity nothing is read back: the switched instances are built in staging on the device and
// the instances between and behind them shift there (instance_moves.h).
#include "instance_moves.h"
#include "level_carry.h"
#include "level_staging.h"
#include "simulation_impl.h"

#include <hmsm/levels.h>

#include <glm/geometric.hpp>

#include <algorithm>
#include <cmath>
#include <string>
#include <utility>

namespace hmsm {

namespace {

using detail::BufferId;
using detail::carried_buffers;
using detail::ElementMove;
using detail::halves_of;
using detail::InstanceGroup;
using detail::LevelCarry;
using detail::SceneData;

std::string id_name(InstanceId id) { return "instance id " + std::to_string(uint64_t(id)); }

uint64_t grown(uint64_t current, uint64_t needed) {
    return needed <= current ? current : std::max(needed, current + current / 2);
}

}  // namespace

Status Simulation::Impl::add_lod_levels(uint32_t m, const Hierarchy& full, const MeshTemplate& full_mesh) {
    const std::vector<int32_t>& budgets = scene_.lod_budgets[m];
    for (size_t k = 0; k < budgets.size(); ++k) {
        auto level = build_level(scene_.models[m], full, config_.parameters, budgets[k]);
        if (!level)
            return Status{level.status().code(), "model '" + scene_.model_names[m] + "': level " +
                                                     std::to_string(k + 1) + ": " + level.status().message()};
        PendingLevel pending;
        pending.mesh = build_level_mesh(scene_.models[m], full, full_mesh, *level);
        pending.lod = {m, uint32_t(k + 1), std::move(level->source_chain)};
        pending.hierarchy = std::move(level->hierarchy);
        pending_levels_.push_back(std::move(pending));
    }
    return {};
}

Status Simulation::Impl::append_lod_levels() {
    levels_of_.resize(scene_.models.size());
    for (uint32_t m = 0; m < levels_of_.size(); ++m) levels_of_[m] = {m};
    for (PendingLevel& level : pending_levels_) {
        double largest = 0.0;
        for (const Chain& chain : level.hierarchy.chains) largest = std::max(largest, chain.wind_area);
        levels_of_[level.lod.scene_model].push_back(uint32_t(hierarchies_.size()));
        largest_wind_area_.push_back(largest);
        hierarchies_.push_back(std::move(level.hierarchy));
        meshes_.push_back(std::move(level.mesh));
        lod_models_.push_back(std::move(level.lod));
    }
    pending_levels_.clear();
    return {};
}

namespace {

/// Carries the chain-scope state of `old` (live chains, halves back to back) into the layout of
/// the new instance list: instance i moves whole from old_chain[i] to new_chain[i] unless it has
/// a carry (carries[i] non-null), then carry_switched.
template <class V>
std::vector<V> carry_layout(const std::vector<V>& old, uint32_t per, uint32_t halves, BufferId id,
                            const std::vector<uint64_t>& old_chain, const std::vector<uint64_t>& new_chain,
                            const std::vector<const LevelCarry*>& carries) {
    const uint64_t old_live = old_chain.back(), new_live = new_chain.back();
    std::vector<V> out(size_t(halves * new_live * per), V(0));
    for (uint32_t h = 0; h < halves; ++h) {
        const V* src = old.data() + h * old_live * per;
        V* dst = out.data() + h * new_live * per;
        for (size_t i = 0; i + 1 < old_chain.size(); ++i) {
            if (carries[i])
                carry_switched(dst + new_chain[i] * per, *carries[i], per, id,
                               [&](int32_t c) { return src + (old_chain[i] + uint64_t(c)) * per; });
            else std::copy_n(src + old_chain[i] * per, (old_chain[i + 1] - old_chain[i]) * per, dst + new_chain[i] * per);
        }
    }
    return out;
}

/// Elements per instance of `instances` as running sums (`per` picks chains, nodes or
/// vertices of a model): offsets[i] is the first element of instance i, offsets[n] the total.
template <class Per>
std::vector<uint64_t> running_offsets(const std::vector<Instance>& instances, Per per) {
    std::vector<uint64_t> offsets(instances.size() + 1, 0);
    for (size_t i = 0; i < instances.size(); ++i) offsets[i + 1] = offsets[i] + per(instances[i].model);
    return offsets;
}


}  // namespace

const LevelCarry& Simulation::Impl::level_carry(uint32_t from, uint32_t into) {
    const uint64_t key = (uint64_t(from) << 32) | into;
    auto found = level_carries_.find(key);
    if (found != level_carries_.end()) return found->second;
    std::vector<glm::dmat3> rest;
    rest.reserve(hierarchies_[into].chains.size());
    for (const Chain& chain : hierarchies_[into].chains) rest.push_back(chain.rest_rotation);
    return level_carries_
        .emplace(key, detail::make_level_carry(lod_models_[from].source_chain, lod_models_[into].source_chain,
                                               std::move(rest)))
        .first->second;
}

Status Simulation::Impl::switch_models(const std::vector<std::pair<uint32_t, uint32_t>>& models) {
    if (models.empty()) return {};
    detail::InstanceChangeBracket change(*backend_);
    std::vector<uint32_t> switched;  // ascending, as `models`
    detail::ElementCounts totals{data_->total_chains, data_->total_nodes, data_->total_vertices};
    for (auto [i, model] : models) {
        switched.push_back(i);
        totals += detail::counts_of(data_->models[model]) - detail::counts_of(data_->models[instances_[i].model]);
    }
    HMSM_TRY(check_size(instances_.size(), totals));
    std::vector<const LevelCarry*> carries(models.size());
    for (size_t k = 0; k < models.size(); ++k) carries[k] = &level_carry(instances_[models[k].first].model, models[k].second);
    // Every instance keeps its place, origin and yaw: only the groups and totals change.

    // The state as the backend stores it, so that everything carried is bit for bit.
    const detail::Scalar scalar = backend_->kind() == BackendKind::cpu64 ? detail::Scalar::f64 : detail::Scalar::f32;
    const std::vector<BufferId> carried = carried_buffers(data_->holds_loads());
    ahead_schedule_.live_change();  // the state moves, the angles integrated ahead with it
    const uint64_t staging_base = std::max(data_->chains_held(), totals.chains);
    const detail::LevelStaging staging = detail::lay_out_staging(
        staging_base, models, [&](uint32_t i) { return instances_[i].model; }, data_->models, carries);
    bool in_place = streaming_paths_ && backend_->capabilities().reshapes_in_place;
    if (in_place && placed_) {
        // New slots, nothing shifts (placed_layout.cpp).
        Result<bool> placed = switch_placed(models, carries);
        if (!placed) return placed.status();
        in_place = *placed;
    } else if (in_place && (staging.end > data_->chain_capacity || totals.nodes > data_->node_capacity ||
                            totals.vertices > data_->vertex_capacity)) {
        // Past the capacity: the buffers grow on the device where the backend can, and the
        // switch goes on in place.
        Result<bool> grown = grow_on_device({staging.end, totals.nodes, totals.vertices}, instances_.size());
        if (!grown) return grown.status();
        in_place = *grown && staging.end <= data_->chain_capacity;  // not where the growth met its limit
    }
    if (in_place && !placed_) {
        // The first elements, old and new, of the switched instances and those after them.
        detail::InstanceOffsets& offsets = this->offsets();
        const uint32_t count = uint32_t(instances_.size());
        detail::ByInstance<uint64_t> old_chain, new_chain, old_node, new_node, old_vertex, new_vertex;
        detail::ElementCounts delta;
        auto add_offsets = [&](uint32_t at) {
            const detail::ElementCounts old = offsets.before(at), now = old + delta;
            old_chain.add(at, old.chains);
            new_chain.add(at, now.chains);
            old_node.add(at, old.nodes);
            new_node.add(at, now.nodes);
            old_vertex.add(at, old.vertices);
            new_vertex.add(at, now.vertices);
        };
        add_offsets(0);
        for (auto [i, model] : models) {
            add_offsets(i);
            delta += detail::counts_of(data_->models[model]) - detail::counts_of(data_->models[instances_[i].model]);
            add_offsets(i + 1);
        }
        add_offsets(count);
        // Nothing goes through the host but the templates. In each carried buffer, in order: the
        // switched instances' old chains are copied into the staging, their new chains built
        // there (kept chains from that copy, unfolded ones from the template), the instances
        // between and behind them shift (of R and O only the pose half), and the staged
        // instances go to their new places.
        std::vector<ElementMove> stage, unstage;
        const std::vector<detail::IndexRun> runs = detail::index_runs(switched);
        for (size_t k = 0; const detail::IndexRun& run : runs) {
            stage.push_back({old_chain[run.first], staging.old_at[k], old_chain[run.end] - old_chain[run.first]});
            k += run.end - run.first;
        }
        detail::append_build_moves(stage, staging, carries);
        for (size_t k = 0; const detail::IndexRun& run : runs) {
            unstage.push_back({staging.instance_at[k], new_chain[run.first], new_chain[run.end] - new_chain[run.first]});
            k += run.end - run.first;
        }
        const std::vector<ElementMove> shift = detail::shift_moves(old_chain, new_chain, count, switched);
        const uint32_t pose_half = HMSM_FINAL_HALF(data_->jump_rounds);
        const uint64_t capacity = data_->chain_capacity;
        std::vector<std::vector<ElementMove>> in_buffers;
        in_buffers.reserve(carried.size());
        std::vector<detail::BufferMoves> moves;
        for (BufferId id : carried) {
            std::vector<ElementMove>& in_buffer = in_buffers.emplace_back();
            for (const std::vector<ElementMove>* part : {&std::as_const(stage), &shift, &std::as_const(unstage)})
                for (uint32_t h = 0; h < halves_of(id); ++h)
                    if (part != &shift || detail::half_moves(id, h, pose_half))
                        for (ElementMove m : *part) {
                            m.src += h * capacity;
                            m.dst += h * capacity;
                            in_buffer.push_back(m);
                        }
            moves.push_back({id, in_buffer});
        }
        const std::vector<ElementMove> node_moves = detail::shift_moves(old_node, new_node, count, switched);
        const std::vector<ElementMove> vertex_moves = detail::shift_moves(old_vertex, new_vertex, count, switched);
        for (BufferId id : detail::kMovedOutputs) {
            const bool node_scope = detail::buffer_info(id).scope == detail::Scope::node;
            const std::vector<ElementMove>& in_buffer = node_scope ? node_moves : vertex_moves;
            if (data_->element_count(id) > 0 && !in_buffer.empty()) moves.push_back({id, in_buffer});
        }
        HMSM_TRY(detail::write_staging_templates(*backend_, carried, capacity, scalar, staging));
        HMSM_TRY(backend_->move_buffers(moves));
        for (auto [i, model] : models) {
            offsets.add(i, detail::counts_of(data_->models[model]) - detail::counts_of(data_->models[instances_[i].model]));
            instances_[i].model = model;
            instances_[i].level = lod_models_[model].level;
            lod_tracker_.examine_next(i);
        }
        detail::relay_groups(*data_, instances_, switched);
    } else if (!in_place) {
        // Past the capacity where the backend cannot grow its buffers on the device (or where
        // it cannot move state): every instance's state is read, laid out anew and uploaded
        // with room to grow.
        HMSM_TRY(pack_layout());
        std::vector<Instance> next = instances_;
        std::vector<const LevelCarry*> all_carries(instances_.size(), nullptr);
        std::vector<std::vector<double>> values64(carried.size());
        std::vector<std::vector<float>> values32(carried.size());
        for (size_t k = 0; k < models.size(); ++k) {
            next[models[k].first].model = models[k].second;
            next[models[k].first].level = lod_models_[models[k].second].level;
            all_carries[models[k].first] = carries[k];
        }
        const auto chains_of = [&](uint32_t model) { return data_->models[model].chain_count; };
        const std::vector<uint64_t> old_chain = running_offsets(instances_, chains_of);
        const std::vector<uint64_t> new_chain = running_offsets(next, chains_of);
        auto laid = std::make_unique<SceneData>();
        laid->models = data_->models;
        detail::lay_out_instances(*laid, next);
        const uint64_t old_live = data_->total_chains;
        for (size_t b = 0; b < carried.size(); ++b) {
            const uint32_t per = detail::shape_scalars(detail::buffer_info(carried[b]).shape);
            const uint32_t halves = halves_of(carried[b]);
            auto read_all = [&](auto& values) -> Status {
                values.resize(size_t(halves * old_live * per));
                for (uint32_t h = 0; h < halves; ++h)
                    HMSM_TRY(backend_->read(carried[b], h * data_->chain_capacity, old_live,
                                            values.data() + h * old_live * per, scalar));
                values = carry_layout(values, per, halves, carried[b], old_chain, new_chain, all_carries);
                return {};
            };
            HMSM_TRY(scalar == detail::Scalar::f64 ? read_all(values64[b]) : read_all(values32[b]));
        }
        detail::SceneData whole = *data_;
        whole.take_instance_layout(std::move(*laid));
        // With room for the next switch's staging (a switch in place builds the switched
        // instances above the live chains).
        whole.chain_capacity = std::max(grown(data_->chain_capacity, std::max(whole.total_chains, staging.end)),
                                        reserved_.chains);
        whole.node_capacity = std::max(grown(data_->node_capacity, whole.total_nodes), reserved_.nodes);
        whole.vertex_capacity = std::max(grown(data_->vertex_capacity, whole.total_vertices), reserved_.vertices);
        template_zone_.forget();
        HMSM_TRY(backend_->upload(whole));
        *data_ = std::move(whole);
        ++full_uploads_;
        instance_wind_dirty_ = true;
        const uint64_t new_live = data_->total_chains;
        for (size_t b = 0; b < carried.size(); ++b) {
            const uint32_t per = detail::shape_scalars(detail::buffer_info(carried[b]).shape);
            for (uint32_t h = 0; h < halves_of(carried[b]); ++h) {
                const size_t at = size_t(h * new_live * per);
                const void* src = scalar == detail::Scalar::f64 ? static_cast<const void*>(values64[b].data() + at)
                                                                : static_cast<const void*>(values32[b].data() + at);
                HMSM_TRY(backend_->write(carried[b], h * data_->chain_capacity, new_live, src, scalar));
            }
        }
        instances_ = std::move(next);
        instance_list_laid_out();
    }
    instances_changed();
    header_dirty_ = program_dirty_ = true;

    if (!in_place) {
        // Every output buffer is new: passes 4, 6 and 7 from the carried pose, element for
        // element what they were.
        HMSM_TRY(recompute_outputs());
    }
    // The switched instances are posed from their angles.
    if (placed_) HMSM_TRY(run_at_rest_placed(switched, Pass::compose));
    else HMSM_TRY(run_at_rest(detail::slices_covering(*data_, switched), Pass::compose));
    return apply_pending();
}

Status Simulation::Impl::recompute_outputs() {
    std::vector<InstanceGroup> all;
    for (const InstanceGroup& g : data_->groups)
        all.push_back(detail::group_slice(*data_, g, g.instance_begin, g.instance_count));
    const uint32_t outputs = (1u << uint32_t(Pass::node_relative)) | (1u << uint32_t(Pass::node_world)) |
                             (1u << uint32_t(Pass::contour));
    return run_at_rest(all, Pass::node_relative, outputs);
}

Status Simulation::set_instance_lod(InstanceId id, uint32_t level) {
    return set_instance_lods({&id, 1}, {&level, 1});
}

Status Simulation::set_instance_lods(std::span<const InstanceId> ids, std::span<const uint32_t> levels) {
    const Impl& s = *impl_;
    if (ids.size() != levels.size())
        return {ErrorCode::invalid_argument, "set_instance_lods: " + std::to_string(ids.size()) + " ids but " +
                                                 std::to_string(levels.size()) + " levels"};
    std::vector<std::pair<uint32_t, uint32_t>> changes;  // (index, run model)
    std::vector<uint64_t> seen;
    seen.reserve(ids.size());
    for (size_t k = 0; k < ids.size(); ++k) {
        Result<uint64_t> index = index_of(ids[k]);
        if (!index) return {index.status().code(), "set_instance_lod: " + index.status().message()};
        seen.push_back(*index);
        const Impl::LodModel& now = s.lod_models_[s.instances_[*index].model];
        const std::vector<uint32_t>& run_models = s.levels_of_[now.scene_model];
        if (levels[k] >= run_models.size())
            return {ErrorCode::invalid_argument,
                    "set_instance_lod: " + id_name(ids[k]) + " (model '" + s.scene_.model_names[now.scene_model] +
                        "'): level " + std::to_string(levels[k]) + " does not exist (the model has levels 0 to " +
                        std::to_string(run_models.size() - 1) + ", Scene::lod_budgets)"};
        if (levels[k] != now.level) changes.emplace_back(uint32_t(*index), run_models[levels[k]]);
    }
    std::sort(seen.begin(), seen.end());
    if (auto twice = std::adjacent_find(seen.begin(), seen.end()); twice != seen.end())
        return {ErrorCode::invalid_argument,
                "set_instance_lod: " + id_name(s.instance_ids_[*twice]) + " is listed twice"};
    std::sort(changes.begin(), changes.end());
    HMSM_TRY(impl_->switch_models(changes));
    for (InstanceId id : ids)  // switched now: no fade goes on, its fade word is rewritten
        if (impl_->fades_.erase(uint64_t(id)) != 0) {
            const uint32_t index = uint32_t(impl_->live_index(uint64_t(id)));
            impl_->dirty_instances_.push_back(index);
            impl_->lod_tracker_.fade_dropped(index);
        }
    return {};
}

Result<uint32_t> Simulation::instance_lod(InstanceId id) const {
    Result<uint64_t> index = index_of(id);
    if (!index) return Status{index.status().code(), "instance_lod: " + index.status().message()};
    return impl_->lod_models_[impl_->instances_[*index].model].level;
}

uint32_t Simulation::lod_level_count(uint32_t model) const {
    return model < impl_->levels_of_.size() ? uint32_t(impl_->levels_of_[model].size()) : 0u;
}

Result<uint32_t> Simulation::lod_model(uint32_t model, uint32_t level) const {
    if (model >= impl_->levels_of_.size())
        return Status{ErrorCode::invalid_argument, "lod_model: model " + std::to_string(model) +
                                                       " does not exist (the scene has " +
                                                       std::to_string(impl_->levels_of_.size()) + " models)"};
    const std::vector<uint32_t>& run_models = impl_->levels_of_[model];
    if (level >= run_models.size())
        return Status{ErrorCode::invalid_argument, "lod_model: model '" + impl_->scene_.model_names[model] +
                                                       "' has no level " + std::to_string(level) +
                                                       " (levels 0 to " + std::to_string(run_models.size() - 1) + ")"};
    return run_models[level];
}

Status Simulation::set_lod_bands(const LodBands& bands) {
    if (!std::isfinite(bands.hysteresis) || bands.hysteresis < 0.0 || bands.hysteresis >= 1.0)
        return {ErrorCode::invalid_argument,
                "set_lod_bands: hysteresis " + std::to_string(bands.hysteresis) + " is not in [0, 1)"};
    for (size_t k = 0; k < bands.edges.size(); ++k) {
        const double edge = bands.edges[k];
        if (!std::isfinite(edge) || edge <= 0.0 || (k > 0 && edge <= bands.edges[k - 1]))
            return {ErrorCode::invalid_argument, "set_lod_bands: edge " + std::to_string(k) + " (" +
                                                     std::to_string(edge) +
                                                     " m) is not finite, positive and above the edge before"};
    }
    if (bands.fade_steps > kMaxLodFadeSteps)
        return {ErrorCode::invalid_argument, "set_lod_bands: fade_steps " + std::to_string(bands.fade_steps) +
                                                 " is above " + std::to_string(kMaxLodFadeSteps)};
    if (!std::isfinite(bands.fade_bound_m) || bands.fade_bound_m < 0.0 || bands.fade_bound_m > 1.0)
        return {ErrorCode::invalid_argument,
                "set_lod_bands: fade_bound_m " + std::to_string(bands.fade_bound_m) + " m is not in [0, 1]"};
    impl_->lod_bands_ = bands;
    impl_->lod_tracker_.invalidate();
    return {};
}

const LodBands& Simulation::lod_bands() const { return impl_->lod_bands_; }

}  // namespace hmsm
