// Progress of a long run on stderr (simulate, export, analyze): "done/total" with the rate and
// the time left, redrawn in place once the run has taken more than a few seconds, only when
// stderr is a terminal and --no-progress is not given. Logs and pipes never see it.
#pragma once

#include <unistd.h>

#include <chrono>
#include <cinttypes>
#include <cstdint>
#include <cstdio>
#include <string>

namespace hmsm::cli {

class StepProgress {
public:
    /// `unit`: what is counted ("step", "frame").
    StepProgress(uint64_t total, bool enabled, std::string unit = "step")
        : total_(total), enabled_(enabled && isatty(2)), unit_(std::move(unit)) {}
    ~StepProgress() { finish(); }
    void update(uint64_t done) {
        if (!enabled_) return;
        const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start_).count();
        if (seconds < 3.0 || seconds - shown_ < 0.25) return;
        shown_ = seconds;
        const double rate = double(done) / seconds;
        std::fprintf(stderr, "\rhmsm: %s %" PRIu64 "/%" PRIu64 "  %.0f %ss/s  eta %.0f s   ", unit_.c_str(), done,
                     total_, rate, unit_.c_str(), rate > 0.0 && total_ > done ? double(total_ - done) / rate : 0.0);
        std::fflush(stderr);
        drawn_ = true;
    }
    /// Ends the line (before anything else is printed).
    void finish() {
        if (drawn_) std::fputc('\n', stderr);
        drawn_ = false;
    }

private:
    uint64_t total_;
    bool enabled_;
    std::string unit_;
    bool drawn_ = false;
    double shown_ = 0.0;
    std::chrono::steady_clock::time_point start_ = std::chrono::steady_clock::now();
};

}  // namespace hmsm::cli
