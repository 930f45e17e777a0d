// hmsm bench --frames: what an engine sees once per frame. One step (--frame-steps) per frame
// on a joints-only forest, with nothing changed, a wind change, a moving force field or ten
// instances streamed in and out before it; per frame the wall time of the engine's hmsm calls
// (the change and the step call) and of the whole frame until the outputs are ready, median and
// p99. Each backend runs its blocking step(); CUDA also enqueues on an engine stream
// (hmsm/cuda.h enqueue_steps) and Vulkan records into an engine command buffer (hmsm/vulkan.h
// record_steps), where this build can; on those paths the engine also times its frame on the
// device (CUDA events, Vulkan timestamps around hmsm's work).
#pragma once

#include <hmsm/hmsm.h>

#include <nlohmann/json.hpp>

#include <functional>
#include <memory>
#include <optional>
#include <string>
#include <vector>

namespace hmsm::cli::bench {

/// How an engine issues one frame's step on a simulation and waits for its outputs.
class FrameDriver {
public:
    virtual ~FrameDriver() = default;
    /// "step" (Simulation::step, blocking), "enqueue" (CUDA), "record" (Vulkan).
    virtual const char* path() const = 0;
    /// The engine's own work before the frame's hmsm calls (untimed): beginning its command
    /// buffer, marking the start of its device time.
    virtual Status begin(Simulation&) { return {}; }
    /// The frame's step call: what the engine's thread spends in hmsm for it.
    virtual Status call(Simulation& simulation) = 0;
    /// Waits until the outputs of the call are ready (nothing for a blocking step).
    virtual Status finish(Simulation& simulation) = 0;
    /// Device seconds of the frame finish() waited for, from the engine's marks around hmsm's
    /// work; none where the path has no device of the engine's.
    virtual std::optional<double> device_seconds() const { return std::nullopt; }
};

/// The engine paths of a simulation of `kind` this build can drive (CUDA: an engine stream;
/// Vulkan: an engine command buffer), `steps` steps per call; empty where there is none.
std::vector<std::unique_ptr<FrameDriver>> engine_drivers(Simulation& simulation, uint32_t steps = 1);

/// Simulation::step(steps) as the frame's step call ("step"): returns when the steps are complete.
std::unique_ptr<FrameDriver> blocking_step(uint32_t steps = 1);

/// The frame's live change before its step call (frame counts from 0); none when empty.
using FrameChange = std::function<Status(Simulation& simulation, uint32_t frame)>;

/// Seconds per frame: of the engine's hmsm calls (the change and the step call), and of the
/// whole frame until its outputs are ready.
struct FrameTimes {
    std::vector<double> call, whole;
    std::vector<double> device;  // FrameDriver::device_seconds, where the driver has them
};

/// Runs `frames` frames of `change` then `driver`'s step on `simulation`, timing each (after
/// `prepare`, the engine's own work before its calls, not timed); stops at the first error,
/// which it returns (the times hold the frames before it).
Status time_frames(Simulation& simulation, FrameDriver& driver, uint32_t frames, const FrameChange& change,
                   FrameTimes& times, const FrameChange& prepare = {});

struct FrameSettings {
    std::vector<uint32_t> counts;  // forest sizes
    uint32_t frames = 200;         // frames per change, fewer where the case budget says so
    double case_budget = 20.0;     // seconds per (backend, path, size) over all changes
    double spacing = 25.0;
    uint32_t steps = 1;            // steps per frame
};

/// The frame table: one JSON row per backend, path, forest size and change (or one skipped
/// row per backend, path and size that does not fit the budget or the device).
nlohmann::json measure_frames(const TreeModel& model, const std::vector<BackendKind>& backends,
                              const FrameSettings& settings);

/// The markdown table of measure_frames' rows ("" when there are none).
std::string render_frames(const nlohmann::json& rows);

}  // namespace hmsm::cli::bench
