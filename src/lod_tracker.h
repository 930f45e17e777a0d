// Which instances update_lod examines (docs/driving.md, levels of detail): an instance's level
// can change only once the viewer has travelled, summed over the calls, as far as the
// instance's distance lies from the nearest edge of its band (with hysteresis). Each instance
// waits in a heap under the travel at which that can first happen; a call examines only the
// instances whose travel came, so a moving viewer costs in proportion to the instances near a
// band edge, not to the scene.
#pragma once

#include <hmsm/types.h>

#include <algorithm>
#include <cstdint>
#include <functional>
#include <limits>
#include <vector>

namespace hmsm::detail {

struct LodTracker {
    /// An instance (by id) to examine once the travel reaches `key`.
    struct Entry {
        double key = 0.0;
        uint64_t id = 0;
        bool operator>(const Entry& o) const { return key > o.key; }
    };
    /// False: the next update_lod examines every instance and builds the heap.
    bool valid = false;
    /// Per instance (by index): the key of its live entry; entries whose key differs are stale.
    std::vector<double> key;
    std::vector<Entry> heap;  // a min-heap on key
    double travelled = 0.0;   // the viewer's travel summed over the calls since the heap was built
    Vec3 viewer{0.0};
    uint64_t calls = 0;       // calls since the heap was built (bounds the rounding of `travelled`)

    void invalidate() {
        valid = false;
        key.clear();
        heap.clear();
    }
    void push(double at, uint64_t id) {
        heap.push_back({at, id});
        std::push_heap(heap.begin(), heap.end(), std::greater<>());
    }
    /// Instance `index` (id `id`) is examined at the next call (added, or switched by hand).
    void examine_next(uint32_t index, uint64_t id) {
        if (!valid) return;
        key[index] = -std::numeric_limits<double>::infinity();
        push(key[index], id);
    }
    /// An instance appended with id `id`.
    void append(uint64_t id) {
        if (!valid) return;
        key.push_back(-std::numeric_limits<double>::infinity());
        push(key.back(), id);
    }
};

}  // namespace hmsm::detail
