// Which instances update_lod examines (docs/driving.md, levels of detail): an instance's level
// can change only once the viewer has travelled, summed over the calls, as far as the
// instance's distance lies from the nearest edge of its band (with hysteresis). Each instance
// waits in a queue under the travel at which that can first happen; a call examines only the
// instances whose travel came, so a moving viewer costs in proportion to the instances near a
// band edge, not to the scene. The queue keeps its entries in buckets of a metre of travel (a
// binary heap over half a million trees cost a cache miss per level of every pop: about 8 ms
// a frame in the open-world bench). Entries name instances by index, not id (a lookup of the id
// per entry was a third of update_lod): an entry is live while its key is the one `key` holds
// for its index; a swap removal queues the instance it moves again under its new index, and
// whatever entry a later instance at an old index inherits at most examines that instance early,
// which changes nothing but the work.
#pragma once

#include <hmsm/types.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <map>
#include <vector>

namespace hmsm::detail {

/// An instance (by index) to examine once the travel reaches `key`.
struct TravelEntry {
    double key = 0.0;
    uint32_t index = 0;
};

/// Entries by key, in buckets of kBucketMetres of travel: a push costs O(1) (a ring of
/// kRingBuckets buckets from the lowest untaken one; keys past it wait in an ordered overflow
/// until the ring reaches them), taking the entries whose key is at most t costs O(entries
/// taken + those left in t's own bucket + buckets passed). Entries of key +infinity (an
/// instance no band edge can reach) are not kept; keys below the ring (-infinity: the next
/// call) are taken by the next take_until.
class TravelQueue {
public:
    static constexpr double kBucketMetres = 1.0;
    static constexpr int64_t kRingBuckets = 4096;  // a power of two
    void push(const TravelEntry& e) {
        if (e.key == std::numeric_limits<double>::infinity()) return;
        const int64_t bucket = bucket_of(e.key);
        if (bucket <= base_) due_.push_back(e);  // the next take_until looks at every one of them
        else if (bucket < base_ + kRingBuckets) ring_[size_t(bucket & (kRingBuckets - 1))].push_back(e);
        else overflow_[bucket].push_back(e);
        ++size_;
    }
    /// Calls `take(entry)` for every entry of key <= t and drops it (in no particular order);
    /// `take` must not push. t never decreases between clear()s.
    template <class Take>
    void take_until(double t, Take&& take) {
        const int64_t last = bucket_of(t);
        // The buckets up to t's become due (t's own may hold keys above t).
        if (last - base_ >= kRingBuckets) {  // all of the ring at once
            for (std::vector<TravelEntry>& bucket : ring_) {
                due_.insert(due_.end(), bucket.begin(), bucket.end());
                bucket.clear();
            }
            base_ = last;
        }
        while (base_ < last) {
            ++base_;
            std::vector<TravelEntry>& bucket = ring_[size_t(base_ & (kRingBuckets - 1))];
            due_.insert(due_.end(), bucket.begin(), bucket.end());
            bucket.clear();
        }
        refill_from_overflow();
        size_t kept = 0;
        for (const TravelEntry& e : due_) {
            if (e.key <= t) take(e);
            else due_[kept++] = e;
        }
        size_ -= due_.size() - kept;
        due_.resize(kept);
    }
    /// Asks for the memory a push of `key` will write (a push misses the cache at its bucket's
    /// end; a loop of pushes hides those misses by asking a few entries ahead).
    void prefetch(double key) const {
        const int64_t bucket = bucket_of(key);
        if (bucket <= base_ || bucket >= base_ + kRingBuckets) return;
        const std::vector<TravelEntry>& b = ring_[size_t(bucket & (kRingBuckets - 1))];
        __builtin_prefetch(b.data() + b.size(), 1);
    }
    size_t size() const { return size_; }
    void clear() {
        for (std::vector<TravelEntry>& bucket : ring_) bucket.clear();
        due_.clear();
        overflow_.clear();
        base_ = kLowestBase;
        size_ = 0;
    }

private:
    static int64_t bucket_of(double key) {
        if (!(key > -1e15)) return std::numeric_limits<int64_t>::min();  // -infinity: the next call
        return int64_t(std::floor(std::min(key, 1e15) / kBucketMetres));
    }
    /// Overflow buckets the ring now reaches move into it.
    void refill_from_overflow() {
        while (!overflow_.empty() && overflow_.begin()->first < base_ + kRingBuckets) {
            auto first = overflow_.begin();
            std::vector<TravelEntry>& into =
                first->first <= base_ ? due_ : ring_[size_t(first->first & (kRingBuckets - 1))];
            into.insert(into.end(), first->second.begin(), first->second.end());
            overflow_.erase(first);
        }
    }
    std::vector<std::vector<TravelEntry>> ring_ = std::vector<std::vector<TravelEntry>>(kRingBuckets);
    static constexpr int64_t kLowestBase = std::numeric_limits<int64_t>::min() / 2;
    int64_t base_ = kLowestBase;    // buckets <= base_ are due
    std::vector<TravelEntry> due_;  // entries of buckets <= base_ (their keys may still exceed t)
    std::map<int64_t, std::vector<TravelEntry>> overflow_;
    size_t size_ = 0;
};

struct LodTracker {
    using Entry = TravelEntry;
    /// False: the next update_lod examines every instance and builds the queue.
    bool valid = false;
    /// Per instance (by index): the key of its live entry; entries whose key differs are stale.
    std::vector<double> key;
    /// Per instance (by index): 0 where it certainly has no fade, so that update_lod looks up
    /// only the others' fades (set when a fade starts, cleared when a lookup finds none).
    std::vector<uint8_t> may_fade;
    TravelQueue queue;
    double travelled = 0.0;   // the viewer's travel summed over the calls since the queue was built
    Vec3 viewer{0.0};
    uint64_t calls = 0;       // calls since the queue was built (bounds the rounding of `travelled`)

    void invalidate() {
        valid = false;
        key.clear();
        may_fade.clear();
        queue.clear();
    }
    void push(double at, uint32_t index) { queue.push({at, index}); }
    /// Whether `e` is the live entry of its instance (`count` instances now).
    bool live(const TravelEntry& e, size_t count) const { return e.index < count && key[e.index] == e.key; }
    /// Instance `index` is examined at the next call (added, or switched by hand).
    void examine_next(uint32_t index) {
        if (!valid) return;
        key[index] = -std::numeric_limits<double>::infinity();
        push(key[index], index);
    }
    /// An instance appended at the end.
    void append() {
        if (!valid) return;
        key.push_back(-std::numeric_limits<double>::infinity());
        may_fade.push_back(0);
        push(key.back(), uint32_t(key.size() - 1));
    }
    /// A swap removal moved the instance at `from` to `to`: it keeps its key under its new index.
    void moved(uint32_t from, uint32_t to) {
        if (!valid) return;
        key[to] = key[from];
        may_fade[to] = may_fade[from];
        push(key[to], to);
    }
    /// The instances past `count` were removed.
    void resize(size_t count) {
        if (!valid) return;
        key.resize(count);
        may_fade.resize(count);
    }
    /// Instance `index` started a fade.
    void fade_started(uint32_t index) {
        if (valid) may_fade[index] = 1;
    }
    /// Instance `index`'s fade was dropped (folded, switched or given up): no lookup needed.
    void fade_dropped(uint32_t index) {
        if (valid) may_fade[index] = 0;
    }
};

}  // namespace hmsm::detail
