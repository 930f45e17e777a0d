// Fades to coarser levels of detail (docs/model.md 3.12, fading to a coarser level): a
// coarsening request keeps the instance on its level for LodBands::fade_steps steps while pass
// 2, on the backend, scales S and V of the chains the coarser level folds by (n - 1) / n after
// each step, n the steps left (src/common/fade_math.h). The host writes an instance's fade word
// (gpu_layout.h HMSM_FADE_*, in instance_wind) only when its fade starts, ends, retargets,
// pauses or resumes; each step's clock travels in the wind table's step slot, so a fade costs
// no host round trip per step and step(n) runs its steps in one go. A fade is over after its
// last step, its folded chains then exactly at rest, and switches at the next call that folds
// (a call boundary). An instance at rest switches at the request: its deflection bound D,
// measured then through the host, is within LodBands::fade_bound_m. With fade_bound_m 0, and
// where the backend holds instance changes back for an engine's frames (Vulkan after
// record_steps), no request reads the state, and an instance at rest fades as any other.
#include "instance_moves.h"
#include "simulation_impl.h"

#include <glm/geometric.hpp>

#include <algorithm>
#include <cmath>
#include <string>

namespace hmsm {

namespace {

using detail::BufferId;
using detail::IndexRun;
using detail::index_runs;

/// Steps Simulation::step runs between two folds of the fades that are over (at most
/// HMSM_FADE_PERIOD - HMSM_FADE_HORIZON steps may pass after a fade's end before the host
/// switches it, or its word would read as a fade under way again).
constexpr uint32_t kStepsBetweenFolds = HMSM_FADE_HORIZON / 2;

/// Whether each chain of run model `from` is folded by run model `into` (both levels of one
/// scene model: the chains of `into` are a subset of those of `from`'s full model).
std::vector<uint8_t> folded_chains(const std::vector<int32_t>& from_source, const std::vector<int32_t>& into_source) {
    std::vector<uint8_t> folded(from_source.size(), 1);
    size_t k = 0;  // both source lists ascend
    for (size_t c = 0; c < from_source.size(); ++c) {
        while (k < into_source.size() && into_source[k] < from_source[c]) ++k;
        if (k < into_source.size() && into_source[k] == from_source[c]) folded[c] = 0;
    }
    return folded;
}

/// D, the bound of the vertex displacement a switch would make, from the instance's chain state
/// (θx, θz, ωx, ωz per chain): the largest P_c = (|θx| + |θz|) e_c + P_parent over the folded
/// chains. `path` is scratch of at least the model's chain count.
template <class V>
double deflection_bound(const V* state, const Hierarchy& h, const std::vector<uint8_t>& folded,
                        const std::vector<double>& extent, std::vector<double>& path) {
    double largest = 0.0;
    for (size_t c = 0; c < h.chains.size(); ++c) {
        if (!folded[c]) continue;  // a kept chain: no folded chain below it reads its path
        const V* s = state + 4 * c;
        const int32_t parent = h.chains[c].parent;
        const double above = parent >= 0 && folded[size_t(parent)] ? path[size_t(parent)] : 0.0;
        path[c] = above + (std::abs(double(s[0])) + std::abs(double(s[1]))) * extent[c];
        largest = std::max(largest, path[c]);
    }
    return largest;
}

}  // namespace

Result<std::vector<uint32_t>> Simulation::Impl::chain_keep_ranks() {
    // Every level of a scene model keeps the chains its budget leaves of one fold order, so the
    // levels, ranked by their chain count (finest first), are nested: a chain is kept by the
    // levels of rank up to its keep rank.
    fold_rank_.assign(lod_models_.size(), 0);
    std::vector<std::vector<uint32_t>> keep(lod_models_.size());
    for (const std::vector<uint32_t>& levels : levels_of_) {
        if (levels.size() > HMSM_MAX_LOD_LEVELS)
            return Status{ErrorCode::invalid_argument,
                          "model '" + scene_.model_names[lod_models_[levels[0]].scene_model] + "': " +
                              std::to_string(levels.size()) + " levels of detail, at most " +
                              std::to_string(HMSM_MAX_LOD_LEVELS) + " (level 0 included)"};
        std::vector<uint32_t> ranked = levels;
        std::stable_sort(ranked.begin(), ranked.end(), [&](uint32_t a, uint32_t b) {
            return lod_models_[a].source_chain.size() > lod_models_[b].source_chain.size();
        });
        for (uint32_t r = 0; r < ranked.size(); ++r) fold_rank_[ranked[r]] = r;
        for (uint32_t r = 1; r < ranked.size(); ++r) {
            const std::vector<uint8_t> folded =
                folded_chains(lod_models_[ranked[r]].source_chain, lod_models_[ranked[r - 1]].source_chain);
            if (std::find(folded.begin(), folded.end(), 1) != folded.end())
                return Status{ErrorCode::internal, "model '" + scene_.model_names[lod_models_[levels[0]].scene_model] +
                                                       "': its levels of detail are not nested"};
        }
        for (uint32_t m : levels) {
            keep[m].assign(lod_models_[m].source_chain.size(), 0);
            for (uint32_t r = 0; r < ranked.size(); ++r) {
                const std::vector<uint8_t> folded =
                    folded_chains(lod_models_[m].source_chain, lod_models_[ranked[r]].source_chain);
                for (size_t c = 0; c < folded.size(); ++c)
                    if (!folded[c]) keep[m][c] = r;
            }
        }
    }
    std::vector<uint32_t> flat;
    for (const std::vector<uint32_t>& k : keep) flat.insert(flat.end(), k.begin(), k.end());
    return flat;
}

int64_t Simulation::Impl::live_index(uint64_t id) const {
    if (ids_ascending_) {
        auto found = std::lower_bound(instance_ids_.begin(), instance_ids_.end(), InstanceId(id));
        return found != instance_ids_.end() && *found == InstanceId(id) ? int64_t(found - instance_ids_.begin()) : -1;
    }
    auto found = id_index_.find(id);
    return found != id_index_.end() ? int64_t(found->second) : -1;
}

const std::vector<double>& Simulation::Impl::subtree_extent(uint32_t model) const {
    if (subtree_extent_.size() < hierarchies_.size()) subtree_extent_.resize(hierarchies_.size());
    std::vector<double>& extent = subtree_extent_[model];
    if (!extent.empty()) return extent;
    const Hierarchy& h = hierarchies_[model];
    extent.assign(h.chains.size(), 0.0);
    for (size_t n = 0; n < h.node_owner.size(); ++n)
        extent[size_t(h.node_owner[n])] = std::max(extent[size_t(h.node_owner[n])], glm::length(glm::dvec3(h.node_local[n])));
    for (const MeshVertex& v : meshes_[model].vertices)
        extent[size_t(v.chain)] = std::max(extent[size_t(v.chain)], glm::length(glm::dvec3(v.position)));
    // Children after parents (breadth-first): e_parent >= |l_attach(c)| + e_c.
    for (size_t c = h.chains.size(); c-- > 1;) {
        const Chain& chain = h.chains[c];
        if (chain.parent < 0) continue;
        const double reach = glm::length(glm::dvec3(h.node_local[size_t(chain.attach_node)])) + extent[c];
        extent[size_t(chain.parent)] = std::max(extent[size_t(chain.parent)], reach);
    }
    return extent;
}


double Simulation::Impl::fade_word(uint32_t index) const {
    if (fades_.empty() || (lod_tracker_.valid && lod_tracker_.may_fade[index] == 0)) return 0.0;
    auto fade = fades_.find(uint64_t(instance_ids_[index]));
    if (fade == fades_.end() || instances_[index].model != fade->second.from_model) return 0.0;
    const uint64_t end = fade->second.end_step & HMSM_FADE_END_MASK;
    return double((uint64_t(fold_rank_[fade->second.target_model]) << HMSM_FADE_LEVEL_SHIFT) | end);
}

void Simulation::Impl::pause_fade(uint32_t index, bool active) {
    auto fade = fades_.find(uint64_t(instance_ids_[index]));
    if (fade == fades_.end()) return;
    LodFade& f = fade->second;
    // A paused instance runs no step: its fade waits, the steps left kept aside.
    if (active) {
        f.end_step = steps_done_ + f.paused_left;
        fade_ends_at(fade->first, f.end_step);
    } else {
        f.paused_left = uint32_t(f.end_step > steps_done_ ? f.end_step - steps_done_ : 0);
        if (f.paused_left == 0) fade_ends_at(fade->first, steps_done_);  // over while paused
    }
}

Result<std::vector<uint8_t>> Simulation::Impl::fades_at_rest(const std::vector<std::pair<uint32_t, uint32_t>>& fading) {
    std::vector<uint8_t> at_rest(fading.size(), 0);
    // With no bound, and under an engine's recording, the state is read by no request: every
    // coarsening fades.
    if (fading.empty() || lod_bands_.fade_bound_m == 0.0 || backend_->holds_back_instance_changes()) return at_rest;
    ++at_rest_reads_;
    const detail::Scalar scalar = backend_->kind() == BackendKind::cpu64 ? detail::Scalar::f64 : detail::Scalar::f32;
    // The first state chain of instance i, and one past its last, from the group holding it.
    const std::vector<detail::InstanceGroup>& groups = data_->groups;
    auto chain_of = [&](uint32_t i) -> uint64_t {
        if (placed_) return placements_[i].chains;
        auto g = std::upper_bound(groups.begin(), groups.end(), i,
                                  [](uint32_t at, const detail::InstanceGroup& group) { return at < group.instance_begin; });
        --g;
        return uint64_t(g->chain_begin) + uint64_t(i - g->instance_begin) * data_->models[g->model].chain_count;
    };
    auto end_of = [&](uint32_t i) { return chain_of(i) + data_->models[instances_[i].model].chain_count; };
    auto run = [&](auto zero) -> Status {
        using V = decltype(zero);
        // Every run's chains in one read, back to back (in the placed layout, each instance's
        // slot is a run of its own).
        std::vector<IndexRun> runs;
        if (placed_) {
            for (const auto& [i, target] : fading) runs.push_back({i, i + 1});
        } else {
            std::vector<uint32_t> indices;
            for (const auto& [i, target] : fading) indices.push_back(i);
            runs = index_runs(indices);
        }
        std::vector<detail::ElementRange> ranges;
        uint64_t total = 0;
        for (const IndexRun& r : runs) {
            ranges.push_back({chain_of(r.first), end_of(r.end - 1) - chain_of(r.first)});
            total += ranges.back().count;
        }
        std::vector<V> state(size_t(total * 4));
        HMSM_TRY(backend_->read_ranges(BufferId::chain_state, ranges, state.data(), scalar));
        std::unordered_map<uint64_t, std::vector<uint8_t>> folded_of;  // by (model, target): few a call
        std::vector<double> path;
        size_t k = 0;         // indices ascend, and so do their runs
        uint64_t packed = 0;  // the run's first chain in state
        for (size_t j = 0; j < runs.size(); packed += ranges[j].count, ++j) {
            const IndexRun& r = runs[j];
            const uint64_t first = ranges[j].first;
            for (uint32_t i = r.first; i < r.end; ++i, ++k) {
                const uint32_t model = instances_[i].model, target = fading[k].second;
                auto [folded, made] = folded_of.try_emplace((uint64_t(model) << 32) | target);
                if (made)
                    folded->second = folded_chains(lod_models_[model].source_chain, lod_models_[target].source_chain);
                const Hierarchy& h = hierarchies_[model];
                if (path.size() < h.chains.size()) path.resize(h.chains.size());
                const double d = deflection_bound(state.data() + 4 * (packed + chain_of(i) - first), h, folded->second,
                                                  subtree_extent(model), path);
                at_rest[k] = d <= lod_bands_.fade_bound_m;
            }
        }
        return {};
    };
    HMSM_TRY(scalar == detail::Scalar::f64 ? run(0.0) : run(0.0f));
    return at_rest;
}

std::vector<std::pair<uint32_t, uint32_t>> Simulation::Impl::ended_fades() {
    // The entries of the steps that came go: every fade found over is handed to request_lods,
    // which drops it from fades_ (a later entry of it then finds no fade).
    std::vector<std::pair<uint32_t, uint32_t>> ended;
    for (auto it = fade_ends_.begin(); it != fade_ends_.end() && it->first <= steps_done_; it = fade_ends_.erase(it)) {
        const uint64_t step = it->first;
        for (uint64_t id : it->second) {
            auto fade = fades_.find(id);
            if (fade == fades_.end()) continue;  // folded, switched or removed since
            const int64_t index = live_index(id);
            const bool gone = index < 0 || instances_[size_t(index)].model != fade->second.from_model;
            if (gone) {
                if (index >= 0) {
                    dirty_instances_.push_back(uint32_t(index));  // its fade word
                    lod_tracker_.fade_dropped(uint32_t(index));
                }
                fades_.erase(fade);
                continue;
            }
            const bool active = instances_[size_t(index)].active;
            const bool over = active ? fade->second.end_step <= steps_done_ : fade->second.paused_left == 0;
            // An entry of an earlier end, or of a fade paused with steps left (its resume adds one).
            if (!over || (active && fade->second.end_step != step)) continue;
            ended.emplace_back(uint32_t(index), fade->second.target_model);
        }
    }
    // A fade may have had two entries for one end (paused and resumed within a step).
    std::sort(ended.begin(), ended.end());
    ended.erase(std::unique(ended.begin(), ended.end()), ended.end());
    return ended;
}

Status Simulation::Impl::fold_ready_fades() {
    Result<uint64_t> folded = request_lods({}, ended_fades());
    return folded ? Status{} : folded.status();
}

Status Simulation::Impl::step_fading(uint32_t count) {
    uint32_t done = 0;
    do {
        HMSM_TRY(fold_ready_fades());
        if (fades_.empty()) return step(count - done);
        const uint32_t steps = std::min(count - done, kStepsBetweenFolds);
        HMSM_TRY(step(steps));
        done += steps;
    } while (done < count);
    return {};
}

Result<uint64_t> Simulation::Impl::request_lods(std::vector<std::pair<uint32_t, uint32_t>> requests,
                                                std::vector<std::pair<uint32_t, uint32_t>> ended) {
    std::sort(requests.begin(), requests.end());
    for (auto [i, model] : ended) {  // the ended fades fold: their fade words are rewritten
        fades_.erase(uint64_t(instance_ids_[i]));
        lod_tracker_.fade_dropped(i);
        dirty_instances_.push_back(i);
    }
    // An instance both folding and asked for a level folds first, as if asked after the fold;
    // otherwise the folds join this call's switches (one reshape of the state instead of two).
    std::vector<std::pair<uint32_t, uint32_t>> switches = std::move(ended);  // (index, run model)
    for (size_t a = 0, b = 0; a < switches.size() && b < requests.size();) {
        if (switches[a].first == requests[b].first) {
            HMSM_TRY(switch_models(switches));
            switches.clear();
            break;
        }
        switches[a].first < requests[b].first ? ++a : ++b;
    }
    std::vector<std::pair<uint32_t, uint32_t>> started;  // fades to measure (index, target), ascending
    uint64_t changed = 0;
    for (const auto& [i, level] : requests) {
        const LodModel& now = lod_models_[instances_[i].model];
        const uint32_t run_model = levels_of_[now.scene_model][level];
        const uint64_t id = uint64_t(instance_ids_[i]);
        auto fade = fade_of(i);
        if (level <= now.level) {
            if (fade != fades_.end()) {
                fades_.erase(fade);
                lod_tracker_.fade_dropped(i);
                dirty_instances_.push_back(i);  // its fade word
                ++changed;
            }
            if (level < now.level) {
                switches.emplace_back(i, run_model);
                ++changed;
            }
        } else if (fade == fades_.end() || fade->second.target_model != run_model) {
            ++changed;
            dirty_instances_.push_back(i);  // its fade word
            if (lod_bands_.fade_steps == 0) {
                if (fade != fades_.end()) fades_.erase(fade);
                lod_tracker_.fade_dropped(i);
                switches.emplace_back(i, run_model);
                continue;
            }
            const uint32_t steps = lod_bands_.fade_steps;
            fades_[id] = {instances_[i].model, run_model, steps_done_ + steps, steps};
            lod_tracker_.fade_started(i);
            fade_ends_at(id, steps_done_ + steps);
            started.emplace_back(i, run_model);
        }
    }
    // A fade whose deflection is within the bound already (an instance at rest) switches now.
    Result<std::vector<uint8_t>> at_rest = fades_at_rest(started);
    if (!at_rest) return at_rest.status();
    for (size_t k = 0; k < started.size(); ++k) {
        if (!(*at_rest)[k]) continue;
        fades_.erase(uint64_t(instance_ids_[started[k].first]));
        lod_tracker_.fade_dropped(started[k].first);
        switches.push_back(started[k]);
    }
    std::sort(switches.begin(), switches.end());
    HMSM_TRY(switch_models(switches));
    return changed;
}

Result<uint64_t> Simulation::request_instance_lods(std::span<const InstanceId> ids, std::span<const uint32_t> levels) {
    const Impl& s = *impl_;
    if (ids.size() != levels.size())
        return Status{ErrorCode::invalid_argument, "request_instance_lods: " + std::to_string(ids.size()) +
                                                       " ids but " + std::to_string(levels.size()) + " levels"};
    std::vector<std::pair<uint32_t, uint32_t>> requests;
    for (size_t k = 0; k < ids.size(); ++k) {
        Result<uint64_t> index = index_of(ids[k]);
        if (!index) return Status{index.status().code(), "request_instance_lods: " + index.status().message()};
        const uint32_t scene_model = s.lod_models_[s.instances_[*index].model].scene_model;
        const size_t count = s.levels_of_[scene_model].size();
        if (levels[k] >= count)
            return Status{ErrorCode::invalid_argument,
                          "request_instance_lods: instance id " + std::to_string(uint64_t(ids[k])) + " (model '" +
                              s.scene_.model_names[scene_model] + "'): level " + std::to_string(levels[k]) +
                              " does not exist (the model has levels 0 to " + std::to_string(count - 1) + ")"};
        requests.emplace_back(uint32_t(*index), levels[k]);
    }
    std::vector<std::pair<uint32_t, uint32_t>> sorted = requests;
    std::sort(sorted.begin(), sorted.end());
    for (size_t k = 1; k < sorted.size(); ++k)
        if (sorted[k].first == sorted[k - 1].first)
            return Status{ErrorCode::invalid_argument, "request_instance_lods: instance id " +
                                                           std::to_string(uint64_t(s.instance_ids_[sorted[k].first])) +
                                                           " is listed twice"};
    return impl_->request_lods(std::move(requests), impl_->ended_fades());
}

Result<uint32_t> Simulation::instance_lod_target(InstanceId id) const {
    Result<uint64_t> index = index_of(id);
    if (!index) return Status{index.status().code(), "instance_lod_target: " + index.status().message()};
    auto fade = impl_->fades_.find(uint64_t(id));
    const uint32_t model = fade != impl_->fades_.end() && impl_->instances_[*index].model == fade->second.from_model
                               ? fade->second.target_model
                               : impl_->instances_[*index].model;
    return impl_->lod_models_[model].level;
}

uint64_t Simulation::fading_instance_count() const { return impl_->fades_.size(); }

}  // namespace hmsm
