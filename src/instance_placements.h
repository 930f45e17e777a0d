// The placed layout of the instances' elements (SimulationConfig::instance_layout, docs/driving.md,
// streaming budgets): each instance's chains, nodes and vertices lie in a slot of its run model's
// size, which it keeps until it is removed or switches level, whatever other instances do. A
// freed slot waits for the next instance of the same run model; where none waits, a slot is
// taken past every slot held. An add, a swap removal or a level switch then moves only the
// state of the instances it touches, where the packed layout (instance i's elements behind
// those of instances 0 .. i - 1) shifts every instance behind the first one changed.
#pragma once

#include "instance_offsets.h"

#include <cstdint>
#include <span>
#include <vector>

namespace hmsm::detail {

class InstancePlacements {
public:
    /// The packed layout of `instances`: instance i at the running sums, no free slot.
    void assign_packed(std::span<const Instance> instances, const std::vector<ModelRange>& models) {
        first_.resize(instances.size());
        free_.assign(models.size(), {});
        ElementCounts at;
        for (size_t i = 0; i < instances.size(); ++i) {
            first_[i] = at;
            at += counts_of(models[instances[i].model]);
        }
        end_ = at;
    }
    /// Instance i's first chain, node and vertex.
    const ElementCounts& operator[](uint32_t i) const { return first_[i]; }
    uint32_t size() const { return uint32_t(first_.size()); }
    /// One past the highest element of any slot, free ones included.
    const ElementCounts& end() const { return end_; }
    /// Where end() would be after allocate() for each of `models` (run models, in order).
    ElementCounts end_after(std::span<const uint32_t> models, const std::vector<ModelRange>& sizes) const {
        std::vector<uint32_t> taken(free_.size(), 0);  // free slots taken per model
        ElementCounts end = end_;
        for (uint32_t m : models) {
            if (m < free_.size() && taken[m] < free_[m].size()) ++taken[m];
            else end += counts_of(sizes[m]);
        }
        return end;
    }
    /// A slot for an instance of run model `model` (`size` elements): a free one of that model
    /// if any (the last freed), else past end().
    ElementCounts allocate(uint32_t model, const ElementCounts& size) {
        if (model >= free_.size()) free_.resize(size_t(model) + 1);
        std::vector<ElementCounts>& slots = free_[model];
        if (!slots.empty()) {
            const ElementCounts at = slots.back();
            slots.pop_back();
            return at;
        }
        const ElementCounts at = end_;
        end_ += size;
        return at;
    }
    /// Frees the slot at `at` of run model `model` for its next instance.
    void release(uint32_t model, const ElementCounts& at) {
        if (model >= free_.size()) free_.resize(size_t(model) + 1);
        free_[model].push_back(at);
    }
    /// Free slots over all run models.
    uint64_t free_slots() const {
        uint64_t n = 0;
        for (const std::vector<ElementCounts>& slots : free_) n += slots.size();
        return n;
    }

    // The per-instance list follows the instance list.
    void push_back(const ElementCounts& at) { first_.push_back(at); }
    void set(uint32_t i, const ElementCounts& at) { first_[i] = at; }
    void resize(uint32_t n) { first_.resize(n); }

private:
    std::vector<ElementCounts> first_;               // per instance
    std::vector<std::vector<ElementCounts>> free_;   // per run model, its free slots
    ElementCounts end_;
};

}  // namespace hmsm::detail
