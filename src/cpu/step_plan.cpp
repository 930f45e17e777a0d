// Building the step plan: chunk sizes from per-pass cost weights, chunk k of every dispatch in
// sequence k (which one thread runs at a time), and the waits between chunks of different threads, derived from the pass table.
//
// What makes two chunks independent (docs/model.md 3.7): every pass reads and writes only the
// state of the instance its work item belongs to (an instance's ancestors are its own), so
// chunks of disjoint instances never conflict; and a pass that is not hierarchical reads and
// writes the state buffers of its own domain (chain, node or vertex state) only at its own
// element, so two such passes of one domain conflict through those buffers only where their
// element ranges overlap. wind_force and integrate, both per chain over the same chains, are
// split alike and so run back to back on each thread with no wait between them. Hierarchical
// passes read parents and jump targets anywhere in the instance: their chunks wait for every
// earlier conflicting chunk of the instances they touch, which on a single tree is a barrier.
#include "step_plan.h"

#include "../pass_table.h"

#include <algorithm>
#include <cstring>
#include <map>
#include <thread>
#include <tuple>


namespace hmsm::detail::cpu {
namespace {

/// Whether a dispatch reads anywhere within its instances (a hierarchical pass's parents and
/// jump targets), so that its chunks are planned by instance, not by element.
bool instance_wide(const Dispatch& d) { return is_hierarchical(d.pass) || reads_across_chains(d); }

/// Work items per instance of a dispatch (a dispatch covers whole instances of one group).
uint32_t items_per_instance(const Dispatch& d) {
    return runs_rounds_in_dispatch(d) || sweeps_instances(d) ? 1 : threads_per_instance(d);
}

/// The first state element of a non-hierarchical dispatch's domain: its item i is element
/// base + i of the domain's state buffers.
uint64_t element_base(const Dispatch& d) {
    const gpu::PassConstants& pc = d.constants;
    const uint64_t per_domain[] = {pc.chain_begin, pc.node_begin, pc.vertex_begin};
    return per_domain[uint32_t(pass_domain(d.pass))];
}

/// The state buffers of a domain: chain state (both halves of the ping-pong buffers count as
/// the chain's element), node state or vertex outputs.
constexpr uint32_t domain_state_buffers(PassDomain domain) {
    uint32_t mask = 0;
    for (const BufferInfo& b : kBufferTable) {
        const bool in_domain = domain == PassDomain::chain ? b.scope == Scope::chain || b.scope == Scope::chain_halves
                               : domain == PassDomain::node ? b.scope == Scope::node
                                                            : b.scope == Scope::vertex;
        if (in_domain) mask |= buffer_bit(b.id);
    }
    return mask;
}

/// What a chunk touches: global instances [instance_begin, instance_end) and, for a pass that
/// is not hierarchical, the state elements [element_begin, element_end) of its domain.
struct Footprint {
    uint32_t dispatch, thread, position;  // position: index in its thread's tasks of a step
    uint64_t instance_begin, instance_end;
    uint64_t element_begin, element_end;
};

/// Dispatches above which the plan puts a barrier between dispatches instead of searching for
/// each chunk's conflicts, which takes time quadratic in the chunks (at 128 dispatches of 16
/// chunks, about ten milliseconds, once per program).
constexpr size_t kMaxConflictSearchDispatches = 128;

bool overlap(uint64_t a0, uint64_t a1, uint64_t b0, uint64_t b1) { return a0 < b1 && b0 < a1; }

/// Whether chunks x and y (in either order) must not run concurrently: one writes a buffer the
/// other reads or writes, at elements both may touch.
bool conflict(const Dispatch& dx, const Footprint& x, const Dispatch& dy, const Footprint& y) {
    const uint32_t shared = (dispatch_writes(dx) & (dispatch_reads(dy) | dispatch_writes(dy))) |
                            (dispatch_reads(dx) & dispatch_writes(dy));
    if (shared == 0) return false;
    if (!overlap(x.instance_begin, x.instance_end, y.instance_begin, y.instance_end)) return false;
    const PassDomain domain = pass_domain(dx.pass);
    if (!instance_wide(dx) && !instance_wide(dy) && domain == pass_domain(dy.pass) &&
        (shared & ~domain_state_buffers(domain)) == 0)
        return overlap(x.element_begin, x.element_end, y.element_begin, y.element_end);
    return true;
}

}  // namespace

double pass_cost_weight(Pass pass) {
    // Serial float times per element on a Xeon host for paper-1 (2,345 chains, 4,291 nodes,
    // 78,565 vertices, 3 rounds), relative to one chain of one compose round (about 13 ns).
    switch (pass) {
    case Pass::wind_force: return 8.0;
    case Pass::integrate: return 4.6;
    case Pass::compose: return 1.0;
    case Pass::node_relative: return 0.6;
    case Pass::root_positions: return 1.1;
    case Pass::node_world: return 0.4;
    case Pass::contour: return 1.6;
    }
    return 1.0;
}

StepPlan::StepPlan(std::span<const Dispatch> program, uint32_t threads, uint32_t min_chunk_cost)
    : program_(program.begin(), program.end()) {
    threads = std::max(1u, threads);
    const double min_cost = std::max(1.0, double(min_chunk_cost));
    auto cost = [](const Dispatch& d) {
        return double(work_items(d.pass, d.constants)) * elements_per_item(d.pass, d.constants) *
               pass_cost_weight(d.pass);
    };
    // Passes that are not hierarchical over the same elements (wind_force and integrate, or
    // node_relative and node_world, of one group) are split alike, for their summed cost, so
    // that a thread's chunks of both cover the same elements.
    using ElementsKey = std::tuple<uint32_t, uint64_t, uint32_t>;
    std::map<ElementsKey, double> summed;
    auto key = [](const Dispatch& d) {
        return ElementsKey{uint32_t(pass_domain(d.pass)), element_base(d), d.constants.element_count};
    };
    for (const Dispatch& d : program_)
        if (!instance_wide(d)) summed[key(d)] += cost(d);

    chunk_begin_.push_back(0);
    tasks_.resize(threads);
    std::vector<Footprint> footprints;
    for (uint32_t i = 0; i < program_.size(); ++i) {
        const Dispatch& d = program_[i];
        const uint32_t items = work_items(d.pass, d.constants);
        const double total = instance_wide(d) ? cost(d) : summed[key(d)];
        const uint32_t by_cost = uint32_t(std::min<double>(threads, std::max(1.0, total / min_cost)));
        const uint32_t chunks = std::max(1u, std::min(by_cost, items));
        // Chunks end on instance boundaries where that costs little balance (at least four
        // instances per chunk): then every dispatch of a group is split alike and a thread
        // touches only its own instances, with no wait on any other thread in a whole forest.
        const uint32_t per = std::max(1u, items_per_instance(d));
        const uint32_t instances = items / per;
        const bool whole_instances = per == 1 || instances >= 4 * chunks;
        for (uint32_t k = 0; k < chunks; ++k) {
            auto bound = [&](uint32_t j) {
                return whole_instances ? uint32_t(uint64_t(j) * instances / chunks) * per
                                       : uint32_t(uint64_t(j) * items / chunks);
            };
            const Range r{bound(k), k + 1 == chunks ? items : bound(k + 1)};
            dispatch_chunks_.push_back(r);
            if (r.begin == r.end) continue;
            const uint64_t base = instance_wide(d) ? 0 : element_base(d);
            footprints.push_back({i, k, uint32_t(tasks_[k].size()), d.constants.instance_begin + r.begin / per,
                                  d.constants.instance_begin + (r.end - 1) / per + 1, base + r.begin,
                                  base + r.end});
            tasks_[k].push_back({i, r, 0, 0});
        }
        chunk_begin_.push_back(uint32_t(dispatch_chunks_.size()));
        threads_ = std::max(threads_, chunks);
    }
    tasks_.resize(threads_);

    // Per thread, its footprints in program order (footprints are in program order).
    std::vector<std::vector<const Footprint*>> by_thread(threads_);
    for (const Footprint& f : footprints) by_thread[f.thread].push_back(&f);
    // For each chunk and each other thread: the latest earlier chunk of that thread it
    // conflicts with, in this step (earlier dispatches) or else in the previous step (this
    // dispatch and later ones). Each dispatch runs every step on the same thread over the same
    // items, so a conflict further back is covered by the same chunk one step later.
    std::vector<std::vector<Wait>> raw(footprints.size());
    // The search below is quadratic in the chunks. A program of many dispatches (a forest
    // whose paused instances split it into many runs) gets a barrier between dispatches
    // instead: each chunk waits for every other thread's chunks of all earlier dispatches of
    // the step (or, in the first dispatch, of the whole previous step). Correct for any
    // program, and planned in linear time.
    const bool barriers = program_.size() > kMaxConflictSearchDispatches;
    if (barriers) {
        std::vector<uint32_t> finished(threads_, 0);  // per thread: its tasks in earlier dispatches
        size_t x = 0;
        for (uint32_t i = 0; i < program_.size(); ++i) {
            const size_t first = x;
            for (; x < footprints.size() && footprints[x].dispatch == i; ++x)
                for (uint32_t u = 0; u < threads_; ++u)
                    if (u != footprints[x].thread) raw[x].push_back({u, int32_t(finished[u])});
            for (size_t y = first; y < x; ++y) ++finished[footprints[y].thread];
        }
    }
    for (size_t x = 0; x < footprints.size() && !barriers; ++x) {
        const Footprint& fx = footprints[x];
        for (uint32_t u = 0; u < threads_; ++u) {
            if (u == fx.thread) continue;
            const auto& list = by_thread[u];
            const auto split = std::lower_bound(list.begin(), list.end(), fx.dispatch,
                                                [](const Footprint* f, uint32_t d) { return f->dispatch < d; });
            auto latest = [&](auto first, auto last) -> const Footprint* {
                for (auto it = last; it != first;) {
                    --it;
                    if (conflict(program_[fx.dispatch], fx, program_[(*it)->dispatch], **it)) return *it;
                }
                return nullptr;
            };
            if (const Footprint* y = latest(list.begin(), split))
                raw[x].push_back({u, int32_t(y->position + 1)});
            else if (const Footprint* y = latest(split, list.end()))
                raw[x].push_back({u, int32_t(y->position + 1) - int32_t(list.size())});
        }
    }
    // A thread runs its chunks in order, so a wait already done by an earlier chunk of the
    // same thread (in this step, or in the previous one, one step's tasks back) is dropped.
    for (uint32_t t = 0; t < threads_; ++t) {
        std::vector<int64_t> known(threads_, INT64_MIN);
        for (size_t x = 0; x < footprints.size(); ++x) {
            if (footprints[x].thread != t) continue;
            for (const Wait& w : raw[x]) known[w.thread] = std::max<int64_t>(known[w.thread], w.done);
        }
        for (uint32_t u = 0; u < threads_; ++u)
            if (known[u] != INT64_MIN) known[u] -= int64_t(tasks_[u].size());
        for (size_t x = 0; x < footprints.size(); ++x) {
            const Footprint& fx = footprints[x];
            if (fx.thread != t) continue;
            Task& task = tasks_[t][fx.position];
            task.wait_begin = uint32_t(waits_.size());
            for (const Wait& w : raw[x]) {
                if (w.done <= known[w.thread]) continue;
                known[w.thread] = w.done;
                waits_.push_back(w);
            }
            task.wait_end = uint32_t(waits_.size());
        }
    }
    progress_ = std::make_unique<Progress[]>(threads_);
}

bool StepPlan::matches(std::span<const Dispatch> program) const {
    if (program.size() != program_.size()) return false;
    for (size_t i = 0; i < program.size(); ++i)
        if (program[i].pass != program_[i].pass ||
            std::memcmp(&program[i].constants, &program_[i].constants, sizeof(gpu::PassConstants)) != 0)
            return false;
    return true;
}

bool StepPlan::ready(uint32_t t, uint64_t done) const {
    const std::vector<Task>& tasks = tasks_[t];
    const Task& task = tasks[done % tasks.size()];
    const int64_t step = int64_t(done / tasks.size());
    for (uint32_t w = task.wait_begin; w < task.wait_end; ++w) {
        const Wait& wait = waits_[w];
        const int64_t target = step * int64_t(tasks_[wait.thread].size()) + wait.done;
        if (target > 0 && progress_[wait.thread].done.load(std::memory_order_acquire) < uint64_t(target)) return false;
    }
    return true;
}

bool StepPlan::claim(uint32_t t, uint32_t thread) {
    if (t >= threads_) return false;
    uint32_t unclaimed = kUnclaimed;
    return progress_[t].owner.load(std::memory_order_relaxed) == kUnclaimed &&
           progress_[t].owner.compare_exchange_strong(unclaimed, thread, std::memory_order_acq_rel);
}

bool StepPlan::claim_any(uint32_t thread) {
    for (uint32_t t = 0; t < threads_; ++t)
        if (claim(t, thread)) return true;
    return false;
}

void StepPlan::pause(uint32_t idle) {
    if ((idle & 63) == 0) std::this_thread::yield();
    else cpu_relax();
}

}  // namespace hmsm::detail::cpu
