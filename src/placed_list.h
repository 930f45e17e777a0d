// The instance table of the placed layout's step program (instance_placements.h), kept under the
// changes of a streaming world instead of listed anew: one entry (first chain, node, vertex;
// index) per active instance, the entries of each run model together in a segment, segments in
// model order, so that each model is one listed dispatch per pass (listed_groups.h). An
// instance's entry moves only when it changes; an entry joining or leaving a segment moves one
// entry of each later segment (its first to its end, or its last to its start), and one that
// changes segment one entry of each segment between, so a change costs O(models) entry writes
// (two for a switch between neighbouring levels) and the table is written where it changed.
#pragma once

#include "instance_placements.h"
#include "listed_groups.h"
#include "scene_data.h"

#include <algorithm>
#include <cstdint>
#include <span>
#include <vector>

namespace hmsm::detail {

class PlacedList {
public:
    /// Every active instance of `instances` at its placement, in index order within its model's
    /// segment; the whole table is to be written.
    void build(std::span<const Instance> instances, const InstancePlacements& placed, uint32_t models) {
        entries_.clear();
        begin_.assign(size_t(models) + 1, 0);
        entry_of_.assign(instances.size(), kNone);
        for (const Instance& inst : instances)
            if (inst.active) ++begin_[inst.model + 1];
        for (uint32_t m = 0; m < models; ++m) begin_[m + 1] += begin_[m];
        entries_.resize(begin_[models]);
        std::vector<uint32_t> next(begin_.begin(), begin_.end() - 1);
        for (uint32_t i = 0; i < instances.size(); ++i)
            if (instances[i].active) put(next[instances[i].model]++, {placed[i], i});
        written_.clear();
        all_written_ = true;
    }
    /// Instance i (active, without an entry) of run model `model` at `at` takes an entry at the
    /// end of its model's segment.
    void insert(uint32_t i, uint32_t model, const ElementCounts& at) {
        if (i >= entry_of_.size()) entry_of_.resize(size_t(i) + 1, kNone);
        const uint32_t models = uint32_t(begin_.size() - 1);
        uint32_t free = uint32_t(entries_.size());
        entries_.emplace_back();
        for (uint32_t s = models; s-- > model + 1;) {  // each later segment moves one entry on
            if (begin_[s] != free) move(begin_[s], free);
            free = begin_[s]++;
        }
        ++begin_[models];
        put(free, {at, i});
    }
    /// Instance i's entry, if it has one, leaves.
    void erase(uint32_t i) {
        if (i >= entry_of_.size() || entry_of_[i] == kNone) return;
        const uint32_t e = entry_of_[i];
        entry_of_[i] = kNone;
        const uint32_t models = uint32_t(begin_.size() - 1);
        const uint32_t model = uint32_t(std::upper_bound(begin_.begin(), begin_.end(), e) - begin_.begin()) - 1;
        uint32_t free = begin_[model + 1] - 1;  // the segment's last entry fills the gap
        if (free != e) move(free, e);
        for (uint32_t s = model + 1; s < models; ++s) {  // each later segment moves one entry back
            if (begin_[s] < begin_[s + 1]) {
                const uint32_t last = begin_[s + 1] - 1;
                if (last != free) move(last, free);
                free = last;
            }
            --begin_[s];
        }
        --begin_[models];
        entries_.pop_back();
    }
    /// Instance i's entry (it has one) goes to run model `model`'s segment, at `at` (a level
    /// switch): the hole it leaves travels to that segment through those between, one entry of
    /// each moving to the hole's side, so a switch between neighbouring segments writes two
    /// entries where an erase and an insert wrote one for every later segment as well.
    void move_to(uint32_t i, uint32_t model, const ElementCounts& at) {
        uint32_t free = entry_of_[i];
        uint32_t from = uint32_t(std::upper_bound(begin_.begin(), begin_.end(), free) - begin_.begin()) - 1;
        for (; from < model; ++from) {  // free lies in segment `from`: its last entry fills it
            const uint32_t last = begin_[from + 1] - 1;
            if (last != free) move(last, free);
            free = last;
            --begin_[from + 1];  // and free is the next segment's first
        }
        for (; from > model; --from) {  // its first entry fills it
            const uint32_t first = begin_[from];
            if (first != free) move(first, free);
            free = first;
            ++begin_[from];  // and free is the previous segment's last
        }
        put(free, {at, i});
    }
    /// Instance `from`'s entry now names index `to` (a swap removal's filler taking a hole).
    void renumber(uint32_t from, uint32_t to) {
        if (from >= entry_of_.size() || entry_of_[from] == kNone) return;
        const uint32_t e = entry_of_[from];
        entry_of_[from] = kNone;
        if (to >= entry_of_.size()) entry_of_.resize(size_t(to) + 1, kNone);
        entries_[e].instance = to;
        entry_of_[to] = e;
        written_.push_back(e);
    }
    /// The instance list is cut to `n`.
    void resize(uint32_t n) { entry_of_.resize(n, kNone); }

    uint32_t entries() const { return uint32_t(entries_.size()); }
    /// The listed groups of the step program: each model's segment, split so that no dispatch
    /// exceeds kMaxGroupElements threads.
    void groups(const SceneData& d, std::vector<InstanceGroup>& into) const {
        into.clear();
        for (uint32_t model = 0; model + 1 < begin_.size(); ++model)
            append_listed_groups(d, model, begin_[model], begin_[model + 1], into);
    }
    /// The entries written since the last call (all of them after build), as ranges and their
    /// table words (4 scalars an entry, as Backend::write takes them for BufferId::instance_table).
    void take_writes(std::vector<ElementRange>& ranges, std::vector<double>& values) {
        ranges.clear();
        values.clear();
        if (all_written_) {
            if (!entries_.empty()) ranges.push_back({0, entries_.size()});
        } else {
            std::sort(written_.begin(), written_.end());
            for (uint32_t e : written_) {
                if (e >= entries_.size()) break;
                if (!ranges.empty() && ranges.back().first + ranges.back().count > e) continue;  // repeated
                if (!ranges.empty() && ranges.back().first + ranges.back().count == e) ++ranges.back().count;
                else ranges.push_back({e, 1});
            }
        }
        for (const ElementRange& r : ranges)
            for (uint64_t e = r.first; e < r.first + r.count; ++e) {
                const Entry& entry = entries_[e];
                values.insert(values.end(), {double(entry.at.chains), double(entry.at.nodes),
                                             double(entry.at.vertices), double(entry.instance)});
            }
        written_.clear();
        all_written_ = false;
    }
    /// The whole table is to be written again (another table took its place on the device).
    void write_all() { all_written_ = true; }
    bool pending() const { return all_written_ || !written_.empty(); }

private:
    static constexpr uint32_t kNone = ~0u;
    struct Entry {
        ElementCounts at;
        uint32_t instance = 0;
    };
    void put(uint32_t e, const Entry& entry) {
        entries_[e] = entry;
        entry_of_[entry.instance] = e;
        written_.push_back(e);
    }
    void move(uint32_t from, uint32_t to) { put(to, entries_[from]); }

    std::vector<Entry> entries_;
    std::vector<uint32_t> begin_;     // per run model, its segment's first entry; then the end
    std::vector<uint32_t> entry_of_;  // per instance, its entry or kNone (paused)
    std::vector<uint32_t> written_;   // entries written since take_writes
    bool all_written_ = true;
};

}  // namespace hmsm::detail
