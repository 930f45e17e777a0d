// Fork-join over a fixed set of threads. Jobs follow each other within microseconds (the steps
// of a stepping loop, the dispatches of a profiled step), so a worker spins briefly on the job
// counter before it sleeps on the condition variable; a caller likewise spins briefly before it
// sleeps waiting for the last body.
#include "thread_pool.h"

#include <algorithm>
#include <chrono>

namespace hmsm::detail::cpu {
namespace {

/// How long a thread polls before it blocks: long enough to bridge the gap between two jobs,
/// short enough not to steal a core from others while idle.
constexpr std::chrono::microseconds kSpin{50};

template <class Done>
bool spin_until(Done done) {
    const auto until = std::chrono::steady_clock::now() + kSpin;
    for (uint32_t i = 0;; ++i) {
        if (done()) return true;
        if ((i & 63) == 63) {
            if (std::chrono::steady_clock::now() >= until) return false;
            std::this_thread::yield();
        }
    }
}

}  // namespace

ThreadPool::~ThreadPool() {
    {
        std::lock_guard<std::mutex> lock(mutex_);
        stop_ = true;
    }
    wake_.notify_all();
    for (std::thread& t : workers_) t.join();
}

uint32_t ThreadPool::range_count(uint32_t count, uint32_t min_chunk) const {
    const uint64_t by_size = uint64_t(count) / std::max<uint32_t>(1, min_chunk);
    return uint32_t(std::max<uint64_t>(1, std::min<uint64_t>(threads_, by_size)));
}

void ThreadPool::start_workers() {
    workers_.reserve(threads_ - 1);
    for (uint32_t i = 1; i < threads_; ++i) workers_.emplace_back([this, i] { worker(i); });
}

void ThreadPool::run(uint32_t participants, Trampoline call, void* body) {
    if (workers_.empty()) start_workers();
    {
        std::lock_guard<std::mutex> lock(mutex_);
        call_ = call;
        body_ = body;
        participants_ = participants;
        // Every worker acknowledges every job, those without a body too: then none can still
        // be reading this job's fields when the next one is written.
        pending_.store(uint32_t(workers_.size()), std::memory_order_relaxed);
        generation_.fetch_add(1, std::memory_order_release);
    }
    wake_.notify_all();
    call(body, 0);
    auto done = [this] { return pending_.load(std::memory_order_acquire) == 0; };
    if (spin_until(done)) return;
    std::unique_lock<std::mutex> lock(mutex_);
    finished_.wait(lock, done);
}

void ThreadPool::worker(uint32_t index) {
    uint64_t seen = 0;
    for (;;) {
        auto fresh = [&] { return generation_.load(std::memory_order_acquire) != seen; };
        if (!spin_until(fresh)) {
            std::unique_lock<std::mutex> lock(mutex_);
            wake_.wait(lock, [&] { return stop_ || fresh(); });
            if (stop_) return;
        }
        seen = generation_.load(std::memory_order_acquire);
        if (index < participants_) call_(body_, index);
        if (pending_.fetch_sub(1, std::memory_order_acq_rel) == 1) {
            // Taking the mutex orders this notify after the caller's check-then-wait.
            std::lock_guard<std::mutex> lock(mutex_);
            finished_.notify_one();
        }
    }
}

}  // namespace hmsm::detail::cpu
