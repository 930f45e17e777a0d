// Shared jobs over a fixed set of threads. Jobs follow each other within microseconds (the steps
// of a stepping loop, the dispatches of a profiled step), so a worker spins briefly on the job
// word before it sleeps on the condition variable; the caller wakes sleeping workers only when
// there are any, and never waits for one to wake: the work is claimed, not assigned.
#include "thread_pool.h"

#include <algorithm>
#include <chrono>

#if defined(__x86_64__) || defined(__i386__)
#include <immintrin.h>
#endif

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
        } else {
            cpu_relax();
        }
    }
}

constexpr uint64_t kOpen = 1;

}  // namespace

void cpu_relax() {
#if defined(__x86_64__) || defined(__i386__)
    _mm_pause();
#elif defined(__aarch64__)
    asm volatile("yield");
#endif
}

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

void ThreadPool::run(Trampoline call, void* body, uint32_t helpers) {
    if (workers_.empty()) start_workers();
    call_ = call;
    body_ = body;
    const uint64_t closed = job_.load(std::memory_order_relaxed) + 2;  // the next generation, closed
    job_.store(closed | kOpen, std::memory_order_seq_cst);
    // A worker registers in sleepers_ before it checks job_ under the mutex: either it sees the
    // open job, or this load sees it and the notify (under the mutex) reaches its wait.
    if (const uint32_t asleep = sleepers_.load(std::memory_order_seq_cst); asleep > 0 && helpers > 0) {
        std::lock_guard<std::mutex> lock(mutex_);
        if (helpers >= asleep) {
            wake_.notify_all();
        } else {
            for (uint32_t k = 0; k < helpers; ++k) wake_.notify_one();
        }
    }
    call(body, 0);
    job_.store(closed, std::memory_order_seq_cst);
    // Workers that joined are finishing work they claimed; a worker that joins from now on sees
    // the job closed and leaves without touching it.
    auto none_inside = [this] { return inside_.load(std::memory_order_seq_cst) == 0; };
    if (spin_until(none_inside)) return;
    std::unique_lock<std::mutex> lock(mutex_);
    caller_asleep_.store(true, std::memory_order_seq_cst);
    left_.wait(lock, none_inside);
    caller_asleep_.store(false, std::memory_order_relaxed);
}

void ThreadPool::worker(uint32_t index) {
    uint64_t seen = 0;  // the last job word this worker joined or passed
    auto fresh = [&] {
        const uint64_t job = job_.load(std::memory_order_seq_cst);
        return (job & kOpen) && job != seen;
    };
    for (;;) {
        if (!spin_until(fresh)) {
            std::unique_lock<std::mutex> lock(mutex_);
            sleepers_.fetch_add(1, std::memory_order_seq_cst);
            wake_.wait(lock, [&] { return stop_ || fresh(); });
            sleepers_.fetch_sub(1, std::memory_order_relaxed);
            if (stop_) return;
        }
        const uint64_t job = job_.load(std::memory_order_seq_cst);
        if (!(job & kOpen)) continue;
        seen = job;
        inside_.fetch_add(1, std::memory_order_seq_cst);
        if (job_.load(std::memory_order_seq_cst) == job) call_(body_, index);
        if (inside_.fetch_sub(1, std::memory_order_seq_cst) == 1 &&
            caller_asleep_.load(std::memory_order_seq_cst)) {
            // Taking the mutex orders this notify after the caller's check-then-wait.
            std::lock_guard<std::mutex> lock(mutex_);
            left_.notify_one();
        }
    }
}

}  // namespace hmsm::detail::cpu
