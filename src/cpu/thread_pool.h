// The worker threads of the cpu-parallel backend: a fixed pool that runs one fork-join job at a
// time, either a loop split into contiguous ranges or one body per participating thread (the
// caller included) that stays on it for a whole batch of steps (src/cpu/step_plan.h). The
// pool belongs to one backend; its threads start on the first job that needs them and are
// joined when the backend is destroyed, so a program that never runs cpu-parallel never starts
// a thread.
#pragma once

#include <atomic>
#include <condition_variable>
#include <cstdint>
#include <mutex>
#include <thread>
#include <type_traits>
#include <vector>

namespace hmsm::detail::cpu {

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
    /// split depends only on count, min_chunk and threads(). With one range the caller runs it
    /// alone and no worker is woken. Not reentrant; `body` must not throw.
    template <class F>
    void parallel_for(uint32_t count, uint32_t min_chunk, F&& body) {
        const uint32_t ranges = range_count(count, min_chunk);
        if (ranges <= 1) {
            if (count > 0) body(0u, count);
            return;
        }
        run_on_all(ranges, [&](uint32_t k) {
            const uint32_t begin = uint32_t(uint64_t(k) * count / ranges);
            const uint32_t end = uint32_t(uint64_t(k + 1) * count / ranges);
            if (begin < end) body(begin, end);
        });
    }

    /// Calls body(k) once for each k in [0, participants) (at most threads()), k = 0 on the
    /// calling thread, each other k on its own worker, and returns when every call has returned.
    /// The calls run concurrently, so a body may wait for another's progress (the step plan's
    /// per-chunk counters); with one participant the caller runs it alone and no worker is
    /// woken. Not reentrant; `body` must not throw.
    template <class F>
    void run_on_all(uint32_t participants, F&& body) {
        participants = participants < threads_ ? participants : threads_;
        if (participants <= 1) {
            body(0u);
            return;
        }
        using Body = std::remove_reference_t<F>;
        run(participants, [](void* f, uint32_t k) { (*static_cast<Body*>(f))(k); }, &body);
    }

    /// How many ranges parallel_for(count, min_chunk) uses.
    uint32_t range_count(uint32_t count, uint32_t min_chunk) const;

private:
    using Trampoline = void (*)(void*, uint32_t);
    void run(uint32_t participants, Trampoline call, void* body);
    void start_workers();
    void worker(uint32_t index);

    const uint32_t threads_;
    std::vector<std::thread> workers_;

    // The current job: written by the caller under `mutex_` before `generation_` is bumped
    // (release); workers read it after seeing the new generation (acquire).
    Trampoline call_ = nullptr;
    void* body_ = nullptr;
    uint32_t participants_ = 0;

    std::mutex mutex_;
    std::condition_variable wake_;      // workers wait here for a new generation or stop
    std::condition_variable finished_;  // the caller waits here for pending_ == 0
    std::atomic<uint64_t> generation_{0};
    std::atomic<uint32_t> pending_{0};  // workers that have not finished the current job
    bool stop_ = false;                 // guarded by mutex_
};

}  // namespace hmsm::detail::cpu
