// hmsm bench: medians over repeated batches after warm-up, within a per-case time budget.
#include "simulation_access.h"
#include "bench_measure.h"

#include "backend.h"

#include <algorithm>
#include <bit>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <unistd.h>
#include <vector>

namespace hmsm::cli::bench {
namespace {

using clock_type = std::chrono::steady_clock;

double seconds_since(clock_type::time_point start) {
    return std::chrono::duration<double>(clock_type::now() - start).count();
}

double median(std::vector<double> v) {
    std::sort(v.begin(), v.end());
    const size_t n = v.size();
    return n == 0 ? 0.0 : n % 2 ? v[n / 2] : 0.5 * (v[n / 2 - 1] + v[n / 2]);
}

/// Turns device timers off on every exit path (they cost time in the throughput batches).
struct ProfilingOff {
    detail::Backend& backend;
    ~ProfilingOff() { backend.set_profiling(false); }
};

}  // namespace

Result<CaseResult> measure(Simulation& sim, const Settings& settings, unsigned what) {
    detail::Backend& backend = hmsm::detail::backend_of(sim);
    ProfilingOff profiling_off{backend};
    backend.set_profiling(false);
    CaseResult r;

    // Warm-up, one step per call, cut short when it would eat more than a quarter of the budget.
    const auto warm_start = clock_type::now();
    uint32_t warm = 0;
    double warm_seconds = 0.0;
    while (warm < std::max(1u, settings.warmup)) {
        HMSM_TRY(sim.step(1));
        ++warm;
        warm_seconds = seconds_since(warm_start);
        if (warm_seconds > settings.case_budget / 4.0) break;
    }
    const double per_step = warm_seconds / warm;
    r.warmup_seconds_per_step = per_step;

    std::vector<float> vertices;
    double read_seconds = 0.0;
    if (what & kReadback) {
        const auto start = clock_type::now();
        HMSM_TRY(sim.read(Output::vertex_positions, vertices));
        read_seconds = seconds_since(start);
    }

    // Fit steps (then repeats, down to 3 for a median) into what is left of the budget.
    const double cost_per_step = per_step * std::popcount(what) + ((what & kReadback) ? read_seconds : 0.0);
    const double left = std::max(0.0, settings.case_budget - warm_seconds - read_seconds);
    r.steps = std::max(1u, settings.steps);
    r.repeats = std::max(1u, settings.repeats);
    if (r.repeats * r.steps * cost_per_step > left) {
        r.reduced = true;
        r.steps = uint32_t(std::clamp(left / (r.repeats * cost_per_step), 1.0, double(r.steps)));
        if (r.steps == 1)
            r.repeats = uint32_t(std::clamp(left / cost_per_step, double(std::min(3u, r.repeats)),
                                            double(r.repeats)));
    }

    std::vector<double> batched, per_call, readback, profiled, device_total;
    std::array<std::vector<double>, kPassCount> passes;
    // Modes interleave within each repeat so slow drift (thermal, a noisy neighbour) hits all.
    for (uint32_t rep = 0; rep < r.repeats; ++rep) {
        if (what & kBatched) {
            const auto start = clock_type::now();
            HMSM_TRY(sim.step(r.steps));
            batched.push_back(r.steps / seconds_since(start));
        }
        if (what & kPerCall) {
            const auto start = clock_type::now();
            for (uint32_t k = 0; k < r.steps; ++k) HMSM_TRY(sim.step(1));
            per_call.push_back(r.steps / seconds_since(start));
        }
        if (what & kReadback) {
            const auto start = clock_type::now();
            for (uint32_t k = 0; k < r.steps; ++k) {
                HMSM_TRY(sim.step(1));
                HMSM_TRY(sim.read(Output::vertex_positions, vertices));
            }
            readback.push_back(r.steps / seconds_since(start));
        }
        if (what & kPasses) {
            backend.set_profiling(true);
            const auto start = clock_type::now();
            HMSM_TRY(sim.step(r.steps));
            profiled.push_back(r.steps / seconds_since(start));
            backend.set_profiling(false);
            const PassTimes t = sim.pass_times();
            if (t.steps > 0) {
                for (uint32_t p = 0; p < kPassCount; ++p) passes[p].push_back(t.seconds[p] / double(t.steps));
                device_total.push_back(t.total() / double(t.steps));
            }
        }
    }
    r.batched = median(batched);
    r.per_call = median(per_call);
    r.readback = median(readback);
    r.profiled = median(profiled);
    r.has_passes = !device_total.empty();
    for (uint32_t p = 0; p < kPassCount; ++p) r.pass_seconds[p] = median(passes[p]);
    r.device_seconds = median(device_total);
    return r;
}

Progress::Progress(size_t total, bool enabled)
    : total_(total), enabled_(enabled), tty_(isatty(fileno(stderr)) != 0) {
    start_ = std::chrono::duration<double>(clock_type::now().time_since_epoch()).count();
}

Progress::~Progress() { finish(); }

void Progress::begin(const std::string& label) {
    if (!enabled_) return;
    if (!label_.empty()) ++done_;
    label_ = label;
    if (tty_) draw();
    else std::fprintf(stderr, "hmsm bench: [%zu/%zu] %s\n", done_ + 1, total_, label.c_str());
}

void Progress::note(const std::string& line) {
    if (!enabled_) return;
    if (tty_) std::fprintf(stderr, "\r\033[K");
    std::fprintf(stderr, "hmsm bench: %s\n", line.c_str());
    if (tty_ && !label_.empty()) draw();
}

void Progress::draw() {
    constexpr int width = 24;
    const double fraction = total_ ? double(done_) / double(total_) : 1.0;
    const int filled = int(std::lround(fraction * width));
    const double elapsed =
        std::chrono::duration<double>(clock_type::now().time_since_epoch()).count() - start_;
    std::fprintf(stderr, "\r\033[K[%.*s%.*s] %zu/%zu %4.0fs  %s", filled, "########################",
                 width - filled, "........................", done_, total_, elapsed, label_.c_str());
    std::fflush(stderr);
}

void Progress::finish() {
    if (!enabled_ || label_.empty()) return;
    if (tty_) std::fprintf(stderr, "\r\033[K");
    std::fflush(stderr);
    label_.clear();
    done_ = total_;
}

}  // namespace hmsm::cli::bench
