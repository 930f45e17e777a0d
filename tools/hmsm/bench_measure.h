// hmsm bench: timing one simulation (medians over repeated batches after warm-up) and the
// progress line on stderr.
#pragma once

#include <hmsm/hmsm.h>

#include <array>
#include <cstdint>
#include <string>

namespace hmsm::cli::bench {

struct Settings {
    uint32_t steps = 100;        ///< steps per timed batch
    uint32_t warmup = 20;        ///< steps before the first timed batch
    uint32_t repeats = 5;        ///< timed batches per figure (the median is reported)
    double case_budget = 20.0;   ///< seconds one case may take; slow cases get fewer steps
    Composition forest_composition = Composition::automatic;  ///< of the forest rows
    WindProfile wind = WindProfile::y1;  ///< the wind profile of every case (docs/model.md 3.5)
};

/// What to time on one simulation.
enum Measure : unsigned {
    kBatched = 1,   ///< step(steps): all steps in one call, outputs left on the device
    kPerCall = 2,   ///< step(1) per step, as an engine calls it once per frame
    kReadback = 4,  ///< step(1) + read(vertex_positions) per step: the paper's setting
    kPasses = 8,    ///< step(steps) with device timers on: per-pass seconds per step
};

struct CaseResult {
    uint32_t steps = 0, repeats = 0;  ///< as run (the budget may lower them)
    bool reduced = false;             ///< steps or repeats were lowered to fit the budget
    double warmup_seconds_per_step = 0.0;
    // Median steps per second; 0 = not measured.
    double batched = 0.0, per_call = 0.0, readback = 0.0;
    bool has_passes = false;          ///< false when the backend reports no device times
    std::array<double, kPassCount> pass_seconds{};  ///< median device seconds per step
    double device_seconds = 0.0;      ///< median of the per-batch sum over passes, per step
    double profiled = 0.0;            ///< median steps per second of the kPasses batches (timers on)
};

/// Warms `sim` up, then times what `what` asks for. Device timers are turned off for the
/// throughput batches and on for the kPasses batches.
Result<CaseResult> measure(Simulation& sim, const Settings& settings, unsigned what);

/// A progress bar on stderr: redrawn in place ("\r") when stderr is a terminal, one line per
/// case otherwise (so long runs in CI logs still show where they are), silent when disabled.
class Progress {
public:
    Progress(size_t total, bool enabled);
    ~Progress();
    void begin(const std::string& label);  ///< starts the next case
    void note(const std::string& line);    ///< a line that must stay (skips), between redraws
    void finish();

private:
    void draw();
    size_t total_, done_ = 0;
    bool enabled_, tty_;
    std::string label_;
    double start_;
};

}  // namespace hmsm::cli::bench
