// Which instances update_lod examines (docs/driving.md, levels of detail): an instance's level
// can change only once the viewer has travelled, summed over the calls, as far as the
// instance's distance lies from the nearest edge of its band (with hysteresis). Each instance
// waits in a queue under the travel at which that can first happen; a call examines only the
// instances whose travel came, so a moving viewer costs in proportion to the instances near a
// band edge, not to the scene. The queue keeps its entries in buckets of a metre of travel (a
// binary heap over half a million trees cost a cache miss per level of every pop: about 8 ms
// a frame in the open-world bench).
#pragma once

#include <hmsm/types.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <map>
#include <vector>

namespace hmsm::detail {

/// An instance (by id) to examine once the travel reaches `key`.
struct TravelEntry {
    double key = 0.0;
    uint64_t id = 0;
};

/// Entries by key, in buckets of kBucketMetres of travel: a push costs O(log buckets), taking
/// the entries whose key is at most t costs O(entries taken + those left in t's own bucket).
/// Entries of key +infinity (an instance no band edge can reach) are not kept.
class TravelQueue {
public:
    static constexpr double kBucketMetres = 1.0;
    void push(const TravelEntry& e) {
        if (e.key == std::numeric_limits<double>::infinity()) return;
        buckets_[bucket_of(e.key)].push_back(e);
        ++size_;
    }
    /// Calls `take(entry)` for every entry of key <= t and drops it (in no particular order).
    template <class Take>
    void take_until(double t, Take&& take) {
        const int64_t last = bucket_of(t);
        while (!buckets_.empty() && buckets_.begin()->first <= last) {
            auto bucket = buckets_.begin();
            if (bucket->first < last) {  // every key below t
                for (const TravelEntry& e : bucket->second) take(e);
                size_ -= bucket->second.size();
                buckets_.erase(bucket);
                continue;
            }
            std::vector<TravelEntry>& entries = bucket->second;  // t's own bucket: keys on both sides
            size_t kept = 0;
            for (const TravelEntry& e : entries) {
                if (e.key <= t) take(e);
                else entries[kept++] = e;
            }
            size_ -= entries.size() - kept;
            entries.resize(kept);
            if (kept == 0) buckets_.erase(bucket);
            break;
        }
    }
    size_t size() const { return size_; }
    void clear() {
        buckets_.clear();
        size_ = 0;
    }

private:
    static int64_t bucket_of(double key) {
        if (!(key > -1e15)) return std::numeric_limits<int64_t>::min();  // -infinity: the next call
        return int64_t(std::floor(std::min(key, 1e15) / kBucketMetres));
    }
    std::map<int64_t, std::vector<TravelEntry>> buckets_;
    size_t size_ = 0;
};

struct LodTracker {
    using Entry = TravelEntry;
    /// False: the next update_lod examines every instance and builds the queue.
    bool valid = false;
    /// Per instance (by index): the key of its live entry; entries whose key differs are stale.
    std::vector<double> key;
    TravelQueue queue;
    double travelled = 0.0;   // the viewer's travel summed over the calls since the queue was built
    Vec3 viewer{0.0};
    uint64_t calls = 0;       // calls since the queue was built (bounds the rounding of `travelled`)

    void invalidate() {
        valid = false;
        key.clear();
        queue.clear();
    }
    void push(double at, uint64_t id) { queue.push({at, id}); }
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
