// The step plan of the cpu-parallel backend: how the dispatches of one step program are split
// into chunks of work items, which thread runs which chunk, and which chunks of other threads a
// chunk must wait for. Every thread runs its own chunks of every dispatch in program order, step
// after step, inside one job of the pool per batch of steps: there is no fork-join per dispatch,
// and a thread waits only where a chunk reads (or overwrites) what a chunk of another thread
// writes (or reads) — derived from the pass table's reads and writes and the chunks' instances
// and elements. Each element still gets the float operations of `cpu`, so the results are
// bitwise those of `cpu`.
#pragma once

#include "cpu_state.h"
#include "thread_pool.h"

#include <atomic>
#include <cstdint>
#include <memory>
#include <span>
#include <vector>

namespace hmsm::detail::cpu {

class StepPlan {
public:
    /// Splits `program` for `threads` threads; a dispatch is split only into chunks of at least
    /// `min_chunk_cost` cost units (pass_cost_weight), and never into more chunks than threads.
    StepPlan(std::span<const Dispatch> program, uint32_t threads, uint32_t min_chunk_cost);

    /// Whether this plan was built for `program` (same passes and constants, in order).
    bool matches(std::span<const Dispatch> program) const;

    /// Threads that run at least one chunk; 1: the whole program runs on the caller.
    uint32_t threads() const { return threads_; }
    /// The chunks of dispatch `d`: chunk k runs on thread k.
    std::span<const Range> chunks(uint32_t d) const {
        return {dispatch_chunks_.data() + chunk_begin_[d], chunk_begin_[d + 1] - chunk_begin_[d]};
    }

    /// One chunk as its thread runs it: the waits [wait_begin, wait_end) first.
    struct Task {
        uint32_t dispatch;
        Range items;
        uint32_t wait_begin, wait_end;
    };
    /// Wait until thread `thread` has finished step * (its tasks per step) + done tasks (done
    /// <= 0: a task of the previous step).
    struct Wait {
        uint32_t thread;
        int32_t done;
    };
    /// Thread t's chunks of one step, in program order, and the waits before a chunk.
    std::span<const Task> tasks(uint32_t t) const { return tasks_[t]; }
    std::span<const Wait> waits(const Task& task) const {
        return {waits_.data() + task.wait_begin, task.wait_end - task.wait_begin};
    }

    /// Runs `steps` steps of the program: run_chunk(dispatch index, step, range) for every chunk,
    /// on the pool's threads as planned. A chunk's writes are visible to every later chunk
    /// that reads them (release on the writer's counter, acquire on the reader's wait).
    template <class F>
    void run(ThreadPool& pool, size_t steps, F&& run_chunk) {
        for (uint32_t t = 0; t < threads_; ++t) progress_[t].done.store(0, std::memory_order_relaxed);
        pool.run_on_all(threads_, [&](uint32_t t) {
            const std::vector<Task>& tasks = tasks_[t];
            uint64_t done = 0;
            for (size_t step = 0; step < steps; ++step) {
                for (const Task& task : tasks) {
                    for (uint32_t w = task.wait_begin; w < task.wait_end; ++w) {
                        const Wait& wait = waits_[w];
                        const int64_t target = int64_t(step) * int64_t(tasks_[wait.thread].size()) + wait.done;
                        if (target > 0) wait_until(progress_[wait.thread].done, uint64_t(target));
                    }
                    run_chunk(task.dispatch, step, task.items);
                    progress_[t].done.store(++done, std::memory_order_release);
                }
            }
        });
    }

private:
    struct alignas(64) Progress {
        std::atomic<uint64_t> done{0};  // tasks this thread has finished in the current run
    };

    static void wait_until(const std::atomic<uint64_t>& done, uint64_t target);

    std::vector<Dispatch> program_;
    uint32_t threads_ = 1;
    std::vector<Range> dispatch_chunks_;
    std::vector<uint32_t> chunk_begin_;  // per dispatch, into dispatch_chunks_, and one past
    std::vector<std::vector<Task>> tasks_;  // per thread, in program order
    std::vector<Wait> waits_;
    std::unique_ptr<Progress[]> progress_;
};

/// Relative cost of one model element of `pass` (an in-dispatch work item counts its chains
/// times its rounds), in units of about one chain of one compose round.
double pass_cost_weight(Pass pass);

}  // namespace hmsm::detail::cpu
