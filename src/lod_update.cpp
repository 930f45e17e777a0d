// update_lod (docs/driving.md, levels of detail): each instance's level from its distance to the
// viewer through the distance bands with hysteresis. The first call after the instance list
// was laid out anew (or the bands changed) examines every instance; later calls examine only
// those whose band edge the viewer's travel since their last examination may have reached
// (lod_tracker.h), and give the same switches as examining every instance.
#include "simulation_impl.h"

#include <glm/geometric.hpp>

#include <algorithm>
#include <cmath>
#include <limits>
#include <string>

namespace hmsm {

namespace {

/// Calls after which the summed travel is rebuilt from a full examination, so that its
/// rounding stays far below the margin below.
constexpr uint64_t kCallsBeforeRebuild = 1000000;

/// Instances examined per range on the readback threads (Impl::in_ranges): an examination is
/// a few cache misses, so a range of this many outweighs waking a thread.
constexpr uint64_t kExaminedPerRange = 256;

/// How far ahead the examinations request their instances' memory.
constexpr size_t kAhead = 8;

/// What examining one instance gives: its level at this viewer and how far the viewer may
/// travel before that level can change (less a margin over the rounding of the distances and
/// of the summed travel, so that the queue never examines an instance too late).
struct Examined {
    uint32_t level = 0;
    double slack = 0.0;
    uint32_t heading = 0;  // the level it runs on or fades to before the call
};

}  // namespace

Result<uint64_t> Simulation::update_lod(Vec3 viewer) {
    Impl& s = *impl_;
    if (!std::isfinite(viewer.x) || !std::isfinite(viewer.y) || !std::isfinite(viewer.z))
        return Status{ErrorCode::invalid_argument, "update_lod: the viewer position is not finite"};
    // The fades that ended switch with this call's changes; until then they head for their
    // targets, so they are examined at the level they fold to.
    std::vector<std::pair<uint32_t, uint32_t>> ended = s.ended_fades();
    const std::vector<double>& edges = s.lod_bands_.edges;
    const double h = s.lod_bands_.hysteresis;
    detail::LodTracker& tracker = s.lod_tracker_;
    const double infinity = std::numeric_limits<double>::infinity();
    // A fading instance's bands are those of the level it fades to. The tracker knows the
    // instances that certainly have no fade (a lookup per examined instance was a third of a
    // call) and learns of more from every lookup that finds none.
    auto heading = [&](uint32_t i) {
        const uint32_t level = s.lod_models_[s.instances_[i].model].level;
        if (s.fades_.empty() || (tracker.valid && tracker.may_fade[i] == 0)) return level;
        auto fade = s.fades_.find(uint64_t(s.instance_ids_[i]));
        if (fade == s.fades_.end()) {
            if (tracker.valid) tracker.may_fade[i] = 0;
            return level;
        }
        return s.lod_models_[fade->second.target_model].level;
    };
    auto examine = [&](uint32_t i, double travelled) {
        const Impl::LodModel& now = s.lod_models_[s.instances_[i].model];
        const std::vector<uint32_t>& run_models = s.levels_of_[now.scene_model];
        const uint32_t top = uint32_t(std::min<size_t>(run_models.size() - 1, edges.size()));
        const double distance = glm::length(glm::dvec3(s.instances_[i].origin) - glm::dvec3(viewer));
        const uint32_t from = heading(i);
        uint32_t level = std::min(from, top);
        while (level < top && distance > edges[level] * (1.0 + h)) ++level;
        while (level > 0 && distance < edges[level - 1] * (1.0 - h)) --level;
        // The level stays while distance <= edges[level] (1 + h) and >= edges[level - 1] (1 - h),
        // and the distance changes by at most the viewer's travel.
        const double up = level < top ? edges[level] * (1.0 + h) - distance : infinity;
        const double down = level > 0 ? distance - edges[level - 1] * (1.0 - h) : infinity;
        const double margin = 1e-9 * (1.0 + distance + travelled + glm::length(glm::dvec3(viewer)));
        return Examined{level, std::max(0.0, std::min(up, down) - margin), from};
    };
    const uint32_t n = uint32_t(s.instances_.size());
    std::vector<std::pair<uint32_t, uint32_t>> changes;  // (index, level): request_lods switches or fades
    auto change_of = [&](uint32_t i, const Examined& e) {
        if (e.level != e.heading) changes.emplace_back(i, e.level);
    };

    // Examinations read the scene and write only their own instance's may_fade flag and
    // result, so ranges of them run on the readback threads; the results are taken in order.
    if (!tracker.valid || tracker.calls >= kCallsBeforeRebuild) {
        std::vector<Examined> all(n);
        s.in_ranges(n, kExaminedPerRange, [&](uint64_t begin, uint64_t end) {
            for (uint64_t i = begin; i < end; ++i) all[i] = examine(uint32_t(i), 0.0);
        });
        std::vector<double> keys(n);
        for (uint32_t i = 0; i < n; ++i) {
            change_of(i, all[i]);
            keys[i] = all[i].slack;
        }
        tracker.invalidate();
        Result<uint64_t> changed = s.request_lods(changes, std::move(ended));
        if (!changed) return changed.status();
        tracker.key = std::move(keys);
        tracker.may_fade.assign(n, 0);
        for (const auto& [id, fade] : s.fades_) {
            Result<uint64_t> index = index_of(InstanceId(id));
            if (index) tracker.may_fade[*index] = 1;
        }
        for (uint32_t i = 0; i < n; ++i) tracker.push(tracker.key[i], i);
        tracker.travelled = 0.0;
        tracker.viewer = viewer;
        tracker.calls = 0;
        tracker.valid = true;
        return *changed;
    }

    for (const auto& [i, model] : ended) tracker.examine_next(i);  // as a fold would
    tracker.travelled += glm::length(glm::dvec3(viewer) - glm::dvec3(tracker.viewer));
    tracker.viewer = viewer;
    ++tracker.calls;
    // The entries due, then their instances examined with the memory of those a few entries
    // ahead requested early: each is a cache miss in arrays over the whole scene, and in the
    // queue's order they follow one another only through the loop.
    std::vector<detail::LodTracker::Entry> due;
    tracker.queue.take_until(tracker.travelled, [&](const detail::LodTracker::Entry& entry) { due.push_back(entry); });
    for (size_t k = 0; k < std::min(kAhead, due.size()); ++k)
        if (due[k].index < n) __builtin_prefetch(&tracker.key[due[k].index]);
    std::vector<uint32_t> live;  // indices
    live.reserve(due.size());
    for (size_t k = 0; k < due.size(); ++k) {
        if (k + kAhead < due.size() && due[k + kAhead].index < n) {
            __builtin_prefetch(&tracker.key[due[k + kAhead].index]);
            __builtin_prefetch(&s.instances_[due[k + kAhead].index]);
        }
        if (!tracker.live(due[k], n)) continue;  // a stale entry
        tracker.key[due[k].index] = std::numeric_limits<double>::quiet_NaN();  // later entries of it are stale
        live.push_back(due[k].index);
    }
    std::vector<Examined> results(live.size());
    s.in_ranges(live.size(), kExaminedPerRange, [&](uint64_t begin, uint64_t end) {
        for (uint64_t k = begin; k < end; ++k) {
            if (k + kAhead < end) __builtin_prefetch(&tracker.may_fade[live[k + kAhead]]);
            results[k] = examine(live[k], tracker.travelled);
        }
    });
    std::vector<std::pair<uint32_t, double>> examined;  // (index, slack)
    examined.reserve(live.size());
    for (size_t k = 0; k < live.size(); ++k) {
        change_of(live[k], results[k]);
        examined.emplace_back(live[k], results[k].slack);
    }
    // The queue hands entries over in no particular order; the switches below and the keys
    // pushed back do not depend on it (request_lods sorts its requests).
    std::sort(changes.begin(), changes.end());
    Result<uint64_t> changed = s.request_lods(changes, std::move(ended));
    if (!changed) {
        tracker.invalidate();
        return changed.status();
    }
    if (tracker.valid) {  // a switch past the capacity lays the list out anew: the next call examines all
        for (size_t k = 0; k < examined.size(); ++k) {
            if (k + kAhead < examined.size()) {  // each push misses twice: its key and its bucket
                __builtin_prefetch(&tracker.key[examined[k + kAhead].first], 1);
                tracker.queue.prefetch(tracker.travelled + examined[k + kAhead].second);
            }
            const auto [i, slack] = examined[k];
            tracker.key[i] = tracker.travelled + slack;
            tracker.push(tracker.key[i], i);
        }
        if (tracker.queue.size() > 2 * size_t(n) + 1024) {  // stale entries: rebuilt from the keys
            tracker.queue.clear();
            for (uint32_t i = 0; i < n; ++i) tracker.push(tracker.key[i], i);
        }
    }
    return *changed;
}

}  // namespace hmsm
