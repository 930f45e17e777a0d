// The step plan of the cpu-parallel backend: how the dispatches of one step program are split
// into chunks of work items, which sequence of chunks each belongs to, and which chunks of other
// sequences a chunk must wait for. A sequence holds one chunk of every dispatch in program
// order, step after step; one thread runs it inside one job of the pool per batch of steps:
// there is no job per dispatch, and a sequence waits only where a chunk reads (or
// overwrites) what a chunk of another sequence writes (or reads) — derived from the pass
// table's reads and writes and the chunks' instances and elements. Each element still gets the float operations of `cpu`, so the results are
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

    /// Sequences (each at least one chunk), at most the pool's threads; 1: the whole program
    /// runs on the caller.
    uint32_t threads() const { return threads_; }
    /// The chunks of dispatch `d`: chunk k belongs to sequence k.
    std::span<const Range> chunks(uint32_t d) const {
        return {dispatch_chunks_.data() + chunk_begin_[d], chunk_begin_[d + 1] - chunk_begin_[d]};
    }

    /// One chunk of a sequence: the waits [wait_begin, wait_end) first.
    struct Task {
        uint32_t dispatch;
        Range items;
        uint32_t wait_begin, wait_end;
    };
    /// Wait until sequence `thread` has finished step * (its tasks per step) + done tasks (done
    /// <= 0: a task of the previous step).
    struct Wait {
        uint32_t thread;
        int32_t done;
    };
    /// Sequence t's chunks of one step, in program order, and the waits before a chunk.
    std::span<const Task> tasks(uint32_t t) const { return tasks_[t]; }
    std::span<const Wait> waits(const Task& task) const {
        return {waits_.data() + task.wait_begin, task.wait_end - task.wait_begin};
    }

    /// Runs `steps` steps of the program: run_chunk(dispatch index, step, range) for every chunk,
    /// on the pool's threads. Thread t's chunk sequence (tasks(t)) is a unit of work that one
    /// thread claims and runs in order; the caller starts with sequence 0, a worker with its
    /// own, and a thread that cannot go on (its next chunk waits) claims another unclaimed
    /// sequence and interleaves it with its own. So the steps never wait for a worker that has
    /// not woken: the caller alone can run every sequence. A chunk's writes are visible to
    /// every later chunk that reads them (release on the writer's counter, acquire on the
    /// reader's wait).
    template <class F>
    void run(ThreadPool& pool, size_t steps, F&& run_chunk) {
        for (uint32_t t = 0; t < threads_; ++t) {
            progress_[t].done.store(0, std::memory_order_relaxed);
            progress_[t].owner.store(kUnclaimed, std::memory_order_relaxed);
        }
        auto share = [&](uint32_t thread) {
            bool any_owned = claim(thread, thread);
            for (uint32_t idle = 1;;) {
                bool progressed = false, unfinished = false;
                for (uint32_t t = 0; any_owned && t < threads_; ++t) {
                    Progress& p = progress_[t];
                    if (p.owner.load(std::memory_order_relaxed) != thread) continue;
                    const std::vector<Task>& tasks = tasks_[t];
                    const uint64_t total = uint64_t(steps) * tasks.size();
                    uint64_t done = p.done.load(std::memory_order_relaxed);
                    while (done < total && ready(t, done)) {
                        const Task& task = tasks[done % tasks.size()];
                        run_chunk(task.dispatch, size_t(done / tasks.size()), task.items);
                        p.done.store(++done, std::memory_order_release);
                        progressed = true;
                    }
                    unfinished |= done < total;
                }
                if (progressed) continue;
                if (claim_any(thread)) {
                    any_owned = true;
                    continue;
                }
                if (!unfinished) return;  // every sequence is claimed, this thread's are done
                pause(idle++);
            }
        };
        if (threads_ <= 1) share(0);  // no worker is woken (or started) for a plan of one sequence
        else pool.share(threads_ - 1, share);
    }

private:
    static constexpr uint32_t kUnclaimed = ~0u;
    struct alignas(64) Progress {
        std::atomic<uint64_t> done{0};  // tasks of this sequence finished in the current run
        std::atomic<uint32_t> owner{kUnclaimed};  // the pool thread running this sequence
    };

    /// Whether task `done` of sequence t (counted over the run's steps) may start: every chunk
    /// it waits for has finished.
    bool ready(uint32_t t, uint64_t done) const;
    /// Claims sequence `t` for pool thread `thread` if it exists and is unclaimed.
    bool claim(uint32_t t, uint32_t thread);
    /// Claims any unclaimed sequence for `thread`.
    bool claim_any(uint32_t thread);
    /// Waits a moment for other threads' progress (yields now and then, so that a thread
    /// waited for gets a core where threads outnumber cores).
    static void pause(uint32_t idle);

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
