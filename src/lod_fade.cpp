// Fades to coarser levels of detail (docs/model.md 3.12, fading to a coarser level): a
// coarsening request keeps the instance on its level while the chains the coarser level folds
// relax to rest relative to their parents, S and V scaled by (n - 1) / n with n the steps left
// after each step, and switches it once the deflection left, bounded by
// D = max_c sum_{folded k on the path to c} (|theta_x,k| + |theta_z,k|) e_k, is within
// LodBands::fade_bound_m. The folded chains' state goes through the host (cost in proportion to
// the fading instances, read and written run by run as a switch does), and the fading instances
// are posed from their relaxed angles (passes 3-7), so read() shows what the next step starts
// from.
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

/// One fading instance's chains as read: its state S (θx, θz, ωx, ωz) and local transforms T
/// (mat3x4, columns of four) from `first` on, as the backend stores them.
template <class V>
struct ChainValues {
    std::vector<V> state, local;
};

/// Scales the folded chains' S and V by `factor` and sets their T = Q Rz(θz) Rx(θx) (no folded
/// chain is a trunk); returns D, the bound of the vertex displacement the switch would make.
template <class V>
double relax_instance(V* state, V* local, const Hierarchy& h, const std::vector<uint8_t>& folded,
                      const std::vector<double>& extent, double factor, bool scale) {
    std::vector<double> path(h.chains.size(), 0.0);
    double largest = 0.0;
    for (size_t c = 0; c < h.chains.size(); ++c) {
        if (!folded[c]) continue;
        V* s = state + 4 * c;
        if (scale) {
            for (int k = 0; k < 4; ++k) s[k] = factor == 0.0 ? V(0) : V(double(s[k]) * factor);
            const double cx = std::cos(double(s[0])), sx = std::sin(double(s[0]));
            const double cz = std::cos(double(s[1])), sz = std::sin(double(s[1]));
            const glm::dmat3 rx(1, 0, 0, 0, cx, sx, 0, -sx, cx), rz(cz, sz, 0, -sz, cz, 0, 0, 0, 1);
            const glm::dmat3 t = glm::dmat3(h.chains[c].rest_rotation) * rz * rx;
            V* m = local + 12 * c;
            for (int col = 0; col < 3; ++col)
                for (int row = 0; row < 3; ++row) m[4 * col + row] = V(t[col][row]);
        }
        const int32_t parent = h.chains[c].parent;
        const double above = parent >= 0 && folded[size_t(parent)] ? path[size_t(parent)] : 0.0;
        path[c] = above + (std::abs(double(s[0])) + std::abs(double(s[1]))) * extent[c];
        largest = std::max(largest, path[c]);
    }
    return largest;
}

}  // namespace

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

Status Simulation::Impl::relax_fades(const std::vector<uint32_t>& indices, bool scale) {
    if (indices.empty()) return {};
    const detail::Scalar scalar = backend_->kind() == BackendKind::cpu64 ? detail::Scalar::f64 : detail::Scalar::f32;
    // The first state chain of instance i, and one past its last, from the group holding it.
    const std::vector<detail::InstanceGroup>& groups = data_->groups;
    auto chain_of = [&](uint32_t i) -> uint64_t {
        auto g = std::upper_bound(groups.begin(), groups.end(), i,
                                  [](uint32_t at, const detail::InstanceGroup& group) { return at < group.instance_begin; });
        --g;
        return uint64_t(g->chain_begin) + uint64_t(i - g->instance_begin) * data_->models[g->model].chain_count;
    };
    auto end_of = [&](uint32_t i) { return chain_of(i) + data_->models[instances_[i].model].chain_count; };
    auto run = [&](auto zero) -> Status {
        using V = decltype(zero);
        // Every run's chains in one read and one write per buffer, back to back.
        const std::vector<IndexRun> runs = index_runs(indices);
        std::vector<detail::ElementRange> ranges;
        uint64_t total = 0;
        for (const IndexRun& r : runs) {
            ranges.push_back({chain_of(r.first), end_of(r.end - 1) - chain_of(r.first)});
            total += ranges.back().count;
        }
        std::vector<V> state(size_t(total * 4)), local(size_t(total * 12));
        HMSM_TRY(backend_->read_ranges(BufferId::chain_state, ranges, state.data(), scalar));
        if (scale) HMSM_TRY(backend_->read_ranges(BufferId::chain_local, ranges, local.data(), scalar));
        uint64_t packed = 0;  // the run's first chain in state and local
        for (size_t k = 0; k < runs.size(); packed += ranges[k].count, ++k) {
            const IndexRun& r = runs[k];
            const uint64_t first = ranges[k].first;
            for (uint32_t i = r.first; i < r.end; ++i) {
                LodFade& fade = fades_.at(uint64_t(instance_ids_[i]));
                const uint32_t model = instances_[i].model;
                const std::vector<uint8_t> folded =
                    folded_chains(lod_models_[model].source_chain, lod_models_[fade.target_model].source_chain);
                const double factor = scale ? double(fade.steps_left - 1) / double(fade.steps_left) : 1.0;
                const size_t at = size_t(packed + chain_of(i) - first);
                const double left = relax_instance(state.data() + 4 * at, local.data() + 12 * at, hierarchies_[model],
                                                   folded, subtree_extent(model), factor, scale);
                if (scale) --fade.steps_left;
                fade.ready = left <= lod_bands_.fade_bound_m || fade.steps_left == 0;
            }
        }
        if (scale) {
            HMSM_TRY(backend_->write_ranges(BufferId::chain_state, ranges, state.data(), scalar));
            HMSM_TRY(backend_->write_ranges(BufferId::chain_local, ranges, local.data(), scalar));
        }
        return {};
    };
    HMSM_TRY(scalar == detail::Scalar::f64 ? run(0.0) : run(0.0f));
    if (!scale) return {};
    // The angles integrated ahead are not the relaxed ones: the next step integrates from the
    // state as written (the fade's own change each step is not counted as a live change).
    ahead_schedule_.forget();
    const detail::RunStep at_rest[1] = {};
    return backend_->run(program_for(detail::slices_covering(*data_, indices), Pass::compose), at_rest);
}

Status Simulation::Impl::fold_ready_fades(bool every) {
    std::vector<std::pair<uint32_t, uint32_t>> folds;
    for (auto it = fades_.begin(); it != fades_.end();) {
        const int64_t index = live_index(it->first);
        const bool gone = index < 0 || instances_[size_t(index)].model != it->second.from_model;
        const bool folds_now = every || it->second.ready;
        if (!gone && folds_now) folds.emplace_back(uint32_t(index), it->second.target_model);
        it = gone || folds_now ? fades_.erase(it) : std::next(it);
    }
    std::sort(folds.begin(), folds.end());
    return switch_models(folds);
}

Status Simulation::Impl::step_fading(uint32_t count) {
    for (uint32_t k = 0; k < count; ++k) {
        HMSM_TRY(fold_ready_fades());
        if (fades_.empty()) return step(count - k);
        HMSM_TRY(step(1));
        std::vector<uint32_t> active;
        for (const auto& [id, fade] : fades_) {
            const int64_t index = live_index(id);
            if (index >= 0 && instances_[size_t(index)].model == fade.from_model && instances_[size_t(index)].active &&
                !fade.ready)
                active.push_back(uint32_t(index));
        }
        std::sort(active.begin(), active.end());
        HMSM_TRY(relax_fades(active, true));
    }
    return {};
}

Result<uint64_t> Simulation::Impl::request_lods(std::vector<std::pair<uint32_t, uint32_t>> requests) {
    std::sort(requests.begin(), requests.end());
    std::vector<std::pair<uint32_t, uint32_t>> switches;  // (index, run model), ascending
    std::vector<uint32_t> started;                         // fades to measure, ascending
    uint64_t changed = 0;
    for (const auto& [i, level] : requests) {
        const LodModel& now = lod_models_[instances_[i].model];
        const uint32_t run_model = levels_of_[now.scene_model][level];
        const uint64_t id = uint64_t(instance_ids_[i]);
        auto fade = fades_.find(id);
        if (level <= now.level) {
            if (fade != fades_.end()) {
                fades_.erase(fade);
                ++changed;
            }
            if (level < now.level) {
                switches.emplace_back(i, run_model);
                ++changed;
            }
        } else if (fade == fades_.end() || fade->second.target_model != run_model) {
            ++changed;
            if (lod_bands_.fade_steps == 0) {
                if (fade != fades_.end()) fades_.erase(fade);
                switches.emplace_back(i, run_model);
                continue;
            }
            fades_[id] = {instances_[i].model, run_model, lod_bands_.fade_steps, false};
            started.push_back(i);
        }
    }
    // A fade whose deflection is within the bound already (an instance at rest) switches now.
    HMSM_TRY(relax_fades(started, false));
    for (uint32_t i : started) {
        auto fade = fades_.find(uint64_t(instance_ids_[i]));
        if (!fade->second.ready) continue;
        switches.emplace_back(i, fade->second.target_model);
        fades_.erase(fade);
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
    HMSM_TRY(impl_->fold_ready_fades());
    return impl_->request_lods(std::move(requests));
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
