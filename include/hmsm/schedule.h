// The hmsm-schedule file (docs/model.md 4): live control (docs/model.md 3.9) written down step by
// step, so that a run driven from the CLI or a test is reproducible.
//
// A schedule is parsed (parse_schedule / load_schedule: syntax, keys, numbers), then checked
// against the scene it will drive (validate_schedule: model names, instance indices tracked
// through every add and remove, the wind after every change), and only then applied, one step's
// events at a time (apply_schedule_events), so that nothing invalid is found after a step ran.
#pragma once

#include <hmsm/export.h>
#include <hmsm/options.h>
#include <hmsm/scene.h>
#include <hmsm/simulation.h>
#include <hmsm/status.h>

#include <cstdint>
#include <optional>
#include <span>
#include <string>
#include <string_view>
#include <vector>

namespace hmsm {

/// The keys a schedule's `wind` object names; every other part of the wind in force stays.
struct WindChange {
    std::optional<WindProfile> profile;
    std::optional<Vec3> direction;
    std::optional<double> strength;
    std::optional<double> speed;  ///< m/s >= 0, instead of strength: strength (speed / 6)^2
    std::optional<double> frequency;
    std::optional<double> front_speed;
    std::optional<double> turbulence;
    std::optional<uint64_t> seed;

    /// `wind` with the named keys replaced (speed converted with wind_strength_for_speed).
    Wind applied_to(const Wind& wind) const;
};

/// Changes of one instance, by its index in the instance list as it is before the event.
struct InstanceChange {
    uint64_t instance = 0;
    std::optional<double> wind_scale;
    std::optional<double> wind_phase;
    std::optional<bool> active;
};

/// An instance to append, naming its model by the scene's model name (a forest key; `tree` for
/// a tree given on its own). Defaults are those of a forest instance.
struct ScheduledInstance {
    std::string model;
    Vec3 origin{0.0};
    double yaw = 0.0;
    double wind_scale = 1.0;
    double wind_phase = 0.0;
    bool active = true;
};

/// One event: applies before step `step` (>= 1) runs, in the order wind, forces, instances,
/// remove, add.
struct ScheduleEvent {
    uint64_t step = 1;
    std::optional<WindChange> wind;
    std::optional<std::vector<ForceField>> forces;  ///< replaces the list (empty: no fields)
    std::vector<InstanceChange> instances;
    std::vector<uint64_t> remove;  ///< indices before the event, applied before `add`
    std::vector<ScheduledInstance> add;
};

/// Events in non-decreasing step order, applied in file order.
struct Schedule {
    std::vector<ScheduleEvent> events;
};

/// Parses an hmsm-schedule JSON v1 text. Rejects (ErrorCode::invalid_argument, naming `source`,
/// the event and the key) anything but JSON of the documented shape: unknown keys at any level,
/// a step that is not an integer >= 1 or out of order, non-finite numbers, both `speed` and
/// `strength`, a `seed` that is not an integer literal in [0, 2^64 - 1] (read exactly from the
/// JSON token, never through a double), more than kMaxForceFields forces, a force with both or
/// neither of `directional` and `radial`, a radius <= 0, repeated instance indices in one event.
HMSM_API Result<Schedule> parse_schedule(std::string_view json, std::string_view source = "schedule");
/// Reads and parses a schedule file (I/O errors are ErrorCode::io).
HMSM_API Result<Schedule> load_schedule(const std::string& path);

/// The distinct model names that the schedule's events add instances of, in first-use order
/// (the models a forest must build for it: load_forest's extra_models).
HMSM_API std::vector<std::string> scheduled_model_names(const Schedule& schedule);

/// Checks a parsed schedule against the run it will drive: `model_names` (all_model_names),
/// the instance count and the wind in force at step 1. Tracks the instance count through every
/// remove and add, so an index that does not exist when its event applies is rejected, and
/// validates the wind after every change (validate(const Wind&)), every force list, every
/// instance setting and every added instance. Events after `last_step` (when given) are checked
/// too: a file is valid or not whatever the run's length.
HMSM_API Status validate_schedule(const Schedule& schedule, std::span<const std::string> model_names,
                         uint64_t instance_count, const Wind& initial_wind);

/// Applies, in file order, every event whose step is `step` (call it before running step `step`,
/// for step = steps_done() + 1). Model names resolve through find_model(simulation.scene(), name).
/// Validate the schedule first: an error here is a rejected live-control call, reported as is.
HMSM_API Status apply_schedule_events(const Schedule& schedule, uint64_t step, Simulation& simulation);

/// The first step > `after` at which some event applies, if any (to run the steps in between
/// as one batch).
HMSM_API std::optional<uint64_t> next_schedule_step(const Schedule& schedule, uint64_t after);

}  // namespace hmsm
