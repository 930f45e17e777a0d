// Schedules against a run (docs/model.md 4, 3.9): validation before any step runs (application:
// schedule_apply.cpp).
#include <hmsm/schedule.h>

#include "model/input_limits.h"

#include <algorithm>
#include <cmath>
#include <map>

namespace hmsm {

Wind WindChange::applied_to(const Wind& wind) const {
    Wind out = wind;
    if (profile) out.profile = *profile;
    if (direction) out.direction = *direction;
    if (strength) out.strength = *strength;
    if (speed) out.strength = wind_strength_for_speed(*speed);
    if (frequency) out.frequency = *frequency;
    if (front_speed) out.front_speed = *front_speed;
    if (turbulence) out.turbulence = *turbulence;
    if (seed) out.seed = *seed;
    return out;
}

namespace {

Status bad(size_t event, const ScheduleEvent& e, const std::string& what) {
    return {ErrorCode::invalid_argument,
            "schedule: events[" + std::to_string(event) + "] (step " + std::to_string(e.step) + "): " + what};
}

/// A limit's status with the event named.
Status prefixed(size_t event, const ScheduleEvent& e, const Status& status) {
    return status ? status : bad(event, e, status.message());
}

bool finite(const Vec3& v) { return std::isfinite(v.x) && std::isfinite(v.y) && std::isfinite(v.z); }

std::string model_list(std::span<const std::string> names) {
    std::string list;
    for (size_t m = 0; m < names.size(); ++m) list += (m ? ", " : "") + ("\"" + names[m] + "\"");
    return detail::quote_input(list);
}

}  // namespace

std::vector<std::string> scheduled_model_names(const Schedule& schedule) {
    std::vector<std::string> names;
    for (const ScheduleEvent& e : schedule.events)
        for (const ScheduledInstance& a : e.add)
            if (std::find(names.begin(), names.end(), a.model) == names.end()) names.push_back(a.model);
    return names;
}

Status validate_schedule(const Schedule& schedule, std::span<const std::string> model_names,
                         uint64_t instance_count, const Wind& initial_wind) {
    Wind wind = initial_wind;
    uint64_t count = instance_count;
    for (size_t i = 0; i < schedule.events.size(); ++i) {
        const ScheduleEvent& e = schedule.events[i];
        if (e.step < 1) return bad(i, e, "step must be >= 1");
        if (i > 0 && e.step < schedule.events[i - 1].step)
            return bad(i, e, "events must be in non-decreasing step order");
        if (e.wind) {
            if (e.wind->strength && e.wind->speed) return bad(i, e, "wind: give strength or speed, not both");
            if (e.wind->speed && !(*e.wind->speed >= 0.0 && std::isfinite(*e.wind->speed)))
                return bad(i, e, "wind.speed must be finite and >= 0 m/s");
            wind = e.wind->applied_to(wind);
            Status valid = validate(wind);
            if (!valid) return bad(i, e, "wind: " + valid.message());
            if (!(wind.turbulence >= 0.0 && wind.turbulence <= 2.0))
                return bad(i, e, "wind.turbulence must be within [0, 2]");
            if (wind.front_speed > 0.0 && wind.front_speed < 0.01)
                return bad(i, e, "wind.front_speed must be 0 or >= 0.01 m/s");
        }
        if (e.forces) {
            // validate_force_fields' checks (the limits' own), here so that the parsers link
            // without a simulation.
            if (e.forces->size() > kMaxForceFields)
                return bad(i, e, "forces: " + std::to_string(e.forces->size()) + " force fields, at most " +
                                     std::to_string(kMaxForceFields) + " may act at once");
            for (size_t k = 0; k < e.forces->size(); ++k) {
                const ForceField& f = (*e.forces)[k];
                const std::string at = "forces[" + std::to_string(k) + "]: ";
                if (f.kind != ForceField::Kind::directional && f.kind != ForceField::Kind::radial)
                    return bad(i, e, at + "kind must be directional or radial");
                if (Status range = detail::check_force_field("forces[" + std::to_string(k) + "]", f.center,
                                                             f.radius, f.directional, f.radial);
                    !range)
                    return bad(i, e, range.message());
            }
        }
        std::map<uint64_t, bool> named;
        for (const InstanceChange& c : e.instances) {
            if (c.instance >= count)
                return bad(i, e, "instances: instance " + std::to_string(c.instance) + " does not exist (" +
                                     std::to_string(count) + " instance(s) before this event)");
            if (!named.emplace(c.instance, true).second)
                return bad(i, e, "instances: instance " + std::to_string(c.instance) + " is named twice");
            if (c.wind_scale)
                if (Status range = detail::check_wind_scale(
                        "instances: wind_scale of instance " + std::to_string(c.instance), *c.wind_scale);
                    !range)
                    return bad(i, e, range.message());
            if (c.wind_phase && !std::isfinite(*c.wind_phase))
                return bad(i, e, "instances: wind_phase of instance " + std::to_string(c.instance) +
                                     " must be finite");
        }
        std::map<uint64_t, bool> removed;
        for (uint64_t r : e.remove) {
            if (r >= count)
                return bad(i, e, "remove: instance " + std::to_string(r) + " does not exist (" +
                                     std::to_string(count) + " instance(s) before this event)");
            if (!removed.emplace(r, true).second)
                return bad(i, e, "remove: instance " + std::to_string(r) + " is removed twice");
        }
        count -= e.remove.size();
        for (size_t k = 0; k < e.add.size(); ++k) {
            const ScheduledInstance& a = e.add[k];
            const std::string at = "add[" + std::to_string(k) + "]: ";
            if (std::find(model_names.begin(), model_names.end(), a.model) == model_names.end())
                return bad(i, e, at + "model \"" + detail::quote_input(a.model) + "\" is not one of the run's models (" +
                                     model_list(model_names) + ")");
            if (!finite(a.origin) || !std::isfinite(a.yaw) || !std::isfinite(a.wind_phase))
                return bad(i, e, at + "origin, yaw and wind_phase must be finite");
            HMSM_TRY(prefixed(i, e, detail::check_coordinate(at + "origin", a.origin)));
            HMSM_TRY(prefixed(i, e, detail::check_wind_scale(at + "wind_scale", a.wind_scale)));
        }
        count += e.add.size();
        if (count == 0)
            return bad(i, e, "removes every instance: a simulation keeps at least one (deactivate it instead)");
    }
    return {};
}

std::optional<uint64_t> next_schedule_step(const Schedule& schedule, uint64_t after) {
    for (const ScheduleEvent& e : schedule.events)
        if (e.step > after) return e.step;
    return std::nullopt;
}

}  // namespace hmsm
