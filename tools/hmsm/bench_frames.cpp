// hmsm bench --frames (bench_frames.h): per-frame call and frame times of one step per frame.
#include "bench_frames.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <string>

namespace hmsm::cli::bench {
namespace {

using Clock = std::chrono::steady_clock;

double seconds(Clock::time_point a, Clock::time_point b) { return std::chrono::duration<double>(b - a).count(); }

class BlockingStep final : public FrameDriver {
public:
    explicit BlockingStep(uint32_t steps) : steps_(steps) {}
    const char* path() const override { return "step"; }
    Status call(Simulation& simulation) override { return simulation.step(steps_); }
    Status finish(Simulation&) override { return {}; }

private:
    uint32_t steps_;
};

/// What changes before each frame's step.
enum class Change { none, set_wind, moving_field, stream_10 };
constexpr Change kChanges[] = {Change::none, Change::set_wind, Change::moving_field, Change::stream_10};
constexpr uint32_t kStreamed = 10;

const char* change_name(Change change) {
    switch (change) {
        case Change::none: return "none";
        case Change::set_wind: return "set_wind";
        case Change::moving_field: return "moving_field";
        case Change::stream_10: return "stream_10";
    }
    return "";
}

/// The live change of frame `frame`: a wind strength that alternates about `base_wind`'s, a
/// force field that walks through the forest, or ten instances (all of a smaller forest)
/// streamed: added at the end where the first ten stand, then the first ten removed.
Status apply_change(Simulation& s, Change change, uint32_t frame, const Wind& base_wind) {
    switch (change) {
        case Change::none: return {};
        case Change::set_wind: {
            Wind wind = base_wind;
            wind.strength *= frame % 2 ? 1.1 : 0.9;
            return s.set_wind(wind);
        }
        case Change::moving_field: {
            ForceField field;
            field.radius = 10.0;
            field.directional = {0.0, 0.0, 5.0};
            field.center = {0.5 * frame, 2.0, 0.0};
            return s.set_force_fields({&field, 1});
        }
        case Change::stream_10: {
            const uint64_t n = std::min<uint64_t>(kStreamed, s.instance_count());
            std::vector<Instance> streamed(s.instances().begin(), s.instances().begin() + n);
            std::vector<uint64_t> oldest(n);
            for (uint64_t i = 0; i < n; ++i) oldest[i] = i;
            HMSM_TRY(s.add_instances(streamed));
            return s.remove_instances(oldest);
        }
    }
    return {};
}

double percentile(std::vector<double> values, double p) {
    if (values.empty()) return 0.0;
    std::sort(values.begin(), values.end());
    const size_t rank = size_t(std::ceil(p * double(values.size())));
    return values[std::min(values.size(), std::max<size_t>(rank, 1)) - 1];
}

/// The median and p99 of a case's call and frame times into its row.
void put_times(nlohmann::json& row, const FrameTimes& times) {
    row["call_median_seconds"] = percentile(times.call, 0.5);
    row["call_p99_seconds"] = percentile(times.call, 0.99);
    row["frame_median_seconds"] = percentile(times.whole, 0.5);
    row["frame_p99_seconds"] = percentile(times.whole, 0.99);
    if (!times.device.empty()) {
        row["device_median_seconds"] = percentile(times.device, 0.5);
        row["device_p99_seconds"] = percentile(times.device, 0.99);
    }
}

/// The joint matrices read back after a step, `frames` times each way: read() (call = frame),
/// and request_read() (call) then take_read() (frame); with the bytes read per frame.
void measure_readback(Simulation& s, const nlohmann::json& head, uint32_t frames, nlohmann::json& rows) {
    std::vector<float> joints;
    for (const char* how : {"read", "request_take"}) {
        const bool requested = std::string(how) == "request_take";
        FrameTimes times{std::vector<double>(frames), std::vector<double>(frames), {}};
        Status status;
        for (uint32_t k = 0; status && k < frames + 2; ++k) {  // two warm-up reads grow the slots
            status = s.step(1);
            const auto start = Clock::now();
            if (status)
                status = requested ? s.request_read(Output::joint_matrices) : s.read(Output::joint_matrices, joints);
            const auto called = Clock::now();
            if (status && requested) status = s.take_read(Output::joint_matrices, joints);
            if (k >= 2) {
                times.call[k - 2] = seconds(start, called);
                times.whole[k - 2] = seconds(start, Clock::now());
            }
        }
        nlohmann::json row = head;
        row["change"] = std::string("readback_") + how;
        if (!status) {
            row["failed"] = status.message();
        } else {
            row["frames"] = frames;
            row["bytes"] = uint64_t(joints.size() * sizeof(float));
            put_times(row, times);
        }
        rows.push_back(row);
    }
}

/// One row per change for `driver` on `s`, frames as the budget allows; or one skipped row.
void measure_driver(Simulation& s, FrameDriver& driver, const nlohmann::json& head, const FrameSettings& settings,
                    nlohmann::json& rows) {
    const Wind base_wind = s.wind();
    auto change_of = [&](Change change) -> FrameChange {
        return [change, &base_wind](Simulation& sim, uint32_t k) { return apply_change(sim, change, k, base_wind); };
    };
    // Warm-up (graphs captured, pools started, staging allocated, capacity grown), then an
    // estimate of a frame. The first streamed frame grows the capacity (the scene uploaded
    // anew once): the last one is the steady cost, the slowest change.
    FrameTimes warm;
    Status status = time_frames(s, driver, 3, change_of(Change::none), warm);
    if (status) status = time_frames(s, driver, 3, change_of(Change::stream_10), warm);
    const double estimate = warm.whole.empty() ? 0.0 : warm.whole.back();
    auto skipped = [&](const std::string& why) {
        nlohmann::json row = head;
        row["skipped"] = why;
        rows.push_back(row);
    };
    if (!status) return skipped(status.message());
    const double per_change = settings.case_budget / double(std::size(kChanges));
    const uint32_t frames = uint32_t(std::min<double>(settings.frames, std::floor(per_change / std::max(estimate, 1e-9))));
    if (frames < 10) {
        char why[96];
        std::snprintf(why, sizeof why, "a frame takes %.3g s: 10 frames per change exceed --case-budget", estimate);
        return skipped(why);
    }
    for (Change change : kChanges) {
        FrameTimes times;
        status = time_frames(s, driver, frames, change_of(change), times);
        nlohmann::json row = head;
        row["change"] = change_name(change);
        if (!status) {
            row["failed"] = status.message();
            rows.push_back(row);
            return;
        }
        row["frames"] = frames;
        put_times(row, times);
        if (change == Change::stream_10) row["streamed"] = std::min<uint64_t>(kStreamed, s.instance_count());
        rows.push_back(row);
    }
    if (std::string(driver.path()) == "step") measure_readback(s, head, frames, rows);
}

}  // namespace

std::unique_ptr<FrameDriver> blocking_step(uint32_t steps) { return std::make_unique<BlockingStep>(steps); }

Status time_frames(Simulation& s, FrameDriver& driver, uint32_t frames, const FrameChange& change, FrameTimes& times,
                   const FrameChange& prepare) {
    for (uint32_t k = 0; k < frames; ++k) {
        if (prepare) HMSM_TRY(prepare(s, k));
        HMSM_TRY(driver.begin(s));
        const auto start = Clock::now();
        if (change) HMSM_TRY(change(s, k));
        HMSM_TRY(driver.call(s));
        const auto called = Clock::now();
        HMSM_TRY(driver.finish(s));
        times.call.push_back(seconds(start, called));
        times.whole.push_back(seconds(start, Clock::now()));
        if (const std::optional<double> device = driver.device_seconds()) times.device.push_back(*device);
    }
    return {};
}

nlohmann::json measure_frames(const TreeModel& model, const std::vector<BackendKind>& backends,
                              const FrameSettings& settings) {
    nlohmann::json rows = nlohmann::json::array();
    for (BackendKind kind : backends) {
        for (uint32_t count : settings.counts) {
            nlohmann::json head = {{"backend", to_string(kind)}, {"instances", count}, {"path", "step"}, {"steps", settings.steps}};
            auto scene = grid_scene(model, count, settings.spacing, 1);
            if (!scene) {
                head["skipped"] = scene.status().message();
                rows.push_back(head);
                continue;
            }
            SimulationConfig config;
            config.backend = kind;
            config.outputs = Outputs::joints;
            config.profile_passes = false;
            auto sim = Simulation::create(*scene, config);
            if (!sim) {
                head["skipped"] = sim.status().message();
                rows.push_back(head);
                continue;
            }
            head["device"] = (*sim)->device_name();
            measure_driver(**sim, *blocking_step(settings.steps), head, settings, rows);
            for (auto& driver : engine_drivers(**sim, settings.steps)) {
                head["path"] = driver->path();
                measure_driver(**sim, *driver, head, settings, rows);
            }
        }
    }
    return rows;
}

namespace {
/// "one step" or "N steps", as the rows say.
std::string steps_per_frame(const nlohmann::json& rows) {
    const uint32_t steps = rows.empty() ? 1u : rows.front().value("steps", 1u);
    return steps == 1 ? "one step" : std::to_string(steps) + " steps";
}
}  // namespace

std::string render_frames(const nlohmann::json& rows) {
    if (!rows.is_array() || rows.empty()) return "";
    std::string out =
        "\n### Frames: " + steps_per_frame(rows) +
        " per frame, joints only (µs: the frame's hmsm calls, until its outputs are ready, and on the device "
        "between the engine's marks around hmsm's work; median / p99)\n\n"
        "| backend | path | instances | change | frames | call median | call p99 | frame median | frame p99 | "
        "device median | device p99 |\n"
        "|---|---|--:|---|--:|--:|--:|--:|--:|--:|--:|\n";
    auto us = [](const nlohmann::json& r, const char* key) {
        char cell[32];
        if (!r.contains(key)) return std::string("–");
        std::snprintf(cell, sizeof cell, "%.1f", r.value(key, 0.0) * 1e6);
        return std::string(cell);
    };
    for (const nlohmann::json& r : rows) {
        out += "| " + r.value("backend", std::string()) + " | " + r.value("path", std::string()) + " | " +
               std::to_string(r.value("instances", 0ull)) + " | ";
        if (r.contains("skipped") || r.contains("failed")) {
            out += r.value("change", std::string("–")) + " | " + r.value("skipped", r.value("failed", std::string())) +
                   " | | | | | | |\n";
            continue;
        }
        std::string change = r.value("change", std::string());
        if (r.contains("bytes")) {  // a readback: its size and rate at the frame median
            char rate[64];
            std::snprintf(rate, sizeof rate, " (%.2f MB, %.2f GB/s)", r.value("bytes", 0.0) / 1e6,
                          r.value("bytes", 0.0) / std::max(r.value("frame_median_seconds", 0.0), 1e-12) / 1e9);
            change += rate;
        }
        out += change + " | " + std::to_string(r.value("frames", 0u)) + " | " +
               us(r, "call_median_seconds") + " | " + us(r, "call_p99_seconds") + " | " + us(r, "frame_median_seconds") +
               " | " + us(r, "frame_p99_seconds") + " | " + us(r, "device_median_seconds") + " | " +
               us(r, "device_p99_seconds") + " |\n";
    }
    return out;
}

}  // namespace hmsm::cli::bench
