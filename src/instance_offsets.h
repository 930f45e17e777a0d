// Where each instance's elements begin in the instance-major state (docs/model.md 2), kept
// under the changes of a streaming world: a swap removal, an append or a level switch edits a
// few instances, and the first element of any instance is then found in O(log n) instead of
// summing the instances before it.
#pragma once

#include "scene_data.h"

#include <hmsm/scene.h>

#include <algorithm>
#include <cstdint>
#include <utility>
#include <vector>

namespace hmsm::detail {

/// Chains, nodes and vertices of an instance or of a run of instances. Sums wrap modulo 2^64,
/// so a difference of two counts adds as a delta.
struct ElementCounts {
    uint64_t chains = 0, nodes = 0, vertices = 0;
    ElementCounts& operator+=(const ElementCounts& o) {
        chains += o.chains;
        nodes += o.nodes;
        vertices += o.vertices;
        return *this;
    }
    ElementCounts& operator-=(const ElementCounts& o) {
        chains -= o.chains;
        nodes -= o.nodes;
        vertices -= o.vertices;
        return *this;
    }
    friend ElementCounts operator+(ElementCounts a, const ElementCounts& b) { return a += b; }
    friend ElementCounts operator-(ElementCounts a, const ElementCounts& b) { return a -= b; }
    bool operator==(const ElementCounts&) const = default;
};

inline ElementCounts counts_of(const ModelRange& m) { return {m.chain_count, m.node_count, m.vertex_count}; }

/// The first element of every instance as a Fenwick tree over the instances' element counts:
/// before(i), add(i, delta), push_back and pop_back cost O(log n), assign O(n).
class InstanceOffsets {
public:
    void assign(const std::vector<Instance>& instances, const std::vector<ModelRange>& models) {
        tree_.assign(instances.size(), {});
        for (size_t k = 1; k <= tree_.size(); ++k) {
            tree_[k - 1] += counts_of(models[instances[k - 1].model]);
            const size_t parent = k + (k & (~k + 1));
            if (parent <= tree_.size()) tree_[parent - 1] += tree_[k - 1];
        }
    }
    uint32_t size() const { return uint32_t(tree_.size()); }
    /// The elements of instances [0, i): instance i's first element.
    ElementCounts before(uint32_t i) const {
        ElementCounts sum;
        for (size_t k = i; k > 0; k &= k - 1) sum += tree_[k - 1];
        return sum;
    }
    /// Instance i gained `delta` elements (a difference of counts).
    void add(uint32_t i, const ElementCounts& delta) {
        for (size_t k = size_t(i) + 1; k <= tree_.size(); k += k & (~k + 1)) tree_[k - 1] += delta;
    }
    void push_back(const ElementCounts& counts) {
        const size_t k = tree_.size() + 1;
        // Entry k sums the instances (k - lowbit(k), k]: this one and those before it in range.
        tree_.push_back(counts + before(uint32_t(k - 1)) - before(uint32_t(k - (k & (~k + 1)))));
    }
    /// Drops the last instance: no other entry sums it.
    void pop_back() { tree_.pop_back(); }

private:
    std::vector<ElementCounts> tree_;  // tree_[k - 1] sums the instances (k - lowbit(k), k]
};

/// Values at a few instance indices (ascending), looked up by index in O(log k): offsets and
/// chain maps of the instances a change touches, without an entry for every instance.
template <class T>
class ByInstance {
public:
    /// Adds index i's value; indices come in ascending order (a repeated index keeps the first).
    void add(uint32_t i, T value) {
        if (entries_.empty() || entries_.back().first < i) entries_.emplace_back(i, std::move(value));
    }
    const T& operator[](uint32_t i) const {
        auto found = std::lower_bound(entries_.begin(), entries_.end(), i,
                                      [](const std::pair<uint32_t, T>& e, uint32_t at) { return e.first < at; });
        return found->second;  // callers look up only indices they added
    }

private:
    std::vector<std::pair<uint32_t, T>> entries_;
};

}  // namespace hmsm::detail
