// The worker threads of the cpu-parallel backend: a fixed pool that runs one job at a time.
// A job is shared, not assigned: the caller runs it and so does every worker that wakes while
// it is open, each claiming pieces of the work until none is left (src/cpu/step_plan.h claims
// whole chunk sequences). So a job never waits for a thread that is asleep or descheduled: if
// no worker comes in time, the caller does all the work itself. The pool belongs to one
// backend; its threads start on the first job that needs them and are joined when the backend
// is destroyed, so a program that never runs cpu-parallel never starts a thread.
#pragma once

#include <atomic>
#include <condition_variable>
#include <cstdint>
#include <mutex>
#include <thread>
#include <type_traits>
#include <vector>

namespace hmsm::detail::cpu {

/// A pause between polls of a spinning thread (no-op where the architecture has none).
void cpu_relax();

class ThreadPool {
public:
    /// `threads` >= 1 counts the calling thread: threads - 1 workers are started.
    explicit ThreadPool(uint32_t threads) : threads_(threads < 1 ? 1 : threads) {}
    ~ThreadPool();
    ThreadPool(const ThreadPool&) = delete;
    ThreadPool& operator=(const ThreadPool&) = delete;

    uint32_t threads() const { return threads_; }

    /// Calls body(begin, end) on disjoint contiguous ranges covering [0, count), each of at
    /// least `min_chunk` items (but one), at most one range per thread, and returns when every
    /// call has returned. Range k is [k * count / n, (k + 1) * count / n) for n ranges, so the
    /// split depends only on count, min_chunk and threads(); which thread runs a range does
    /// not. With one range the caller runs it alone and no worker is woken. Not reentrant;
    /// `body` must not throw.
    template <class F>
    void parallel_for(uint32_t count, uint32_t min_chunk, F&& body) {
        const uint32_t ranges = range_count(count, min_chunk);
        if (ranges <= 1) {
            if (count > 0) body(0u, count);
            return;
        }
        for_each(ranges, [&](uint32_t k) {
            const uint32_t begin = uint32_t(uint64_t(k) * count / ranges);
            const uint32_t end = uint32_t(uint64_t(k + 1) * count / ranges);
            if (begin < end) body(begin, end);
        });
    }

    /// Calls body(k) once for each k in [0, count), on whichever of the caller and the woken
    /// workers claims k first, and returns when every call has returned. The calls must be
    /// independent of each other (none may wait for another). Not reentrant; `body` must not
    /// throw.
    template <class F>
    void for_each(uint32_t count, F&& body) {
        if (count <= 1 || threads_ <= 1) {
            for (uint32_t k = 0; k < count; ++k) body(k);
            return;
        }
        std::atomic<uint32_t> next{0};
        share(count - 1, [&](uint32_t) {
            for (uint32_t k; (k = next.fetch_add(1, std::memory_order_relaxed)) < count;) body(k);
        });
    }

    /// Calls body(thread) on the caller (thread 0) and on each worker (thread in [1, threads()))
    /// that wakes while the job is open; the job closes when the caller's call returns, and
    /// share() returns once every worker that joined has returned. A worker may join late or
    /// not at all, so the bodies must divide the work among themselves as they come (claim it)
    /// such that the caller's call alone can finish it, and a body may wait for another only
    /// for work that body has claimed. At most `helpers` sleeping workers are woken (those
    /// spinning join anyway): more could find nothing to claim and only take cores from the
    /// others where threads outnumber cores. Not reentrant; `body` must not throw.
    template <class F>
    void share(uint32_t helpers, F&& body) {
        if (threads_ <= 1) {
            body(0u);
            return;
        }
        using Body = std::remove_reference_t<F>;
        run(+[](void* f, uint32_t k) { (*static_cast<Body*>(f))(k); }, &body, helpers);
    }

    /// How many ranges parallel_for(count, min_chunk) uses.
    uint32_t range_count(uint32_t count, uint32_t min_chunk) const;

private:
    using Trampoline = void (*)(void*, uint32_t);
    void run(Trampoline call, void* body, uint32_t helpers);
    void start_workers();
    void worker(uint32_t index);

    const uint32_t threads_;
    std::vector<std::thread> workers_;

    // The current job: written by the caller while no worker is inside a job, before `job_`
    // opens it (seq_cst); a worker reads them only after announcing itself in `inside_` and
    // then seeing the job still open (both seq_cst), so the caller, which closes the job and
    // then waits for inside_ == 0, never rewrites them under a worker.
    Trampoline call_ = nullptr;
    void* body_ = nullptr;

    std::atomic<uint64_t> job_{0};      // generation << 1 | open
    std::atomic<uint32_t> inside_{0};   // workers between joining a job and leaving it
    std::atomic<uint32_t> sleepers_{0};  // workers asleep on wake_ (or about to be)
    std::atomic<bool> caller_asleep_{false};  // the caller asleep on left_ (or about to be)
    std::mutex mutex_;
    std::condition_variable wake_;  // workers wait here for an open job or stop
    std::condition_variable left_;  // the caller waits here for inside_ == 0
    bool stop_ = false;             // guarded by mutex_
};

}  // namespace hmsm::detail::cpu
