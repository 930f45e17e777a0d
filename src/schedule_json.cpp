// hmsm-schedule JSON v1 (docs/model.md 4): syntax, keys and numbers. What depends on the run
// (model names, instance indices, the wind a change is applied to) is checked by
// validate_schedule (schedule.cpp).
#include <hmsm/schedule.h>

#include "model/json_util.h"
#include "model/input_limits.h"

#include <cmath>
#include <initializer_list>
#include <set>

namespace hmsm {

namespace {

using nlohmann::json;

class Reader {
public:
    explicit Reader(std::string_view source) : source_(source) {}

    Status error(const std::string& where, const std::string& what) const {
        return {ErrorCode::invalid_argument, detail::one_line(source_ + ": " + where + ": " + what)};
    }

    /// An object whose keys are all in `allowed`.
    Status object(const json& j, const std::string& where, std::initializer_list<const char*> allowed) const {
        if (!j.is_object()) return error(where, "expected a JSON object, got " + shown(j));
        for (auto it = j.begin(); it != j.end(); ++it) {
            bool known = false;
            for (const char* key : allowed) known = known || it.key() == key;
            if (!known) return error(where, "unknown key \"" + detail::quote_input(it.key()) + "\"");
        }
        return {};
    }

    Status number(const json& j, const std::string& where, double& out) const {
        if (!j.is_number()) return error(where, "expected a number, got " + shown(j));
        out = j.get<double>();
        if (!std::isfinite(out)) return error(where, "number " + shown(j) + " is not finite");
        return {};
    }

    /// An integer literal in [0, 2^64 - 1]. nlohmann's lexer reads a token without fraction or
    /// exponent with strtoull and keeps it as an unsigned integer exactly when it fits; a
    /// negative, fractional, exponent or larger literal arrives as another number type.
    Status unsigned_integer(const json& j, const std::string& where, uint64_t& out) const {
        if (!j.is_number_unsigned())
            return error(where, "expected an integer in [0, 18446744073709551615], got " + shown(j));
        out = j.get<uint64_t>();
        return {};
    }

    Status vec3(const json& j, const std::string& where, Vec3& out) const {
        if (!j.is_array() || j.size() != 3) return error(where, "expected an array of 3 numbers, got " + shown(j));
        for (int k = 0; k < 3; ++k) HMSM_TRY(number(j[k], where + "[" + std::to_string(k) + "]", out[k]));
        return {};
    }

    Status boolean(const json& j, const std::string& where, bool& out) const {
        if (!j.is_boolean()) return error(where, "expected true or false, got " + shown(j));
        out = j.get<bool>();
        return {};
    }

    /// A short rendering of a value for messages (long arrays and objects are cut).
    static std::string shown(const json& j) { return detail::quote_input(j.dump()); }

private:
    std::string source_;
};

Status parse_wind(const Reader& r, const json& j, const std::string& where, WindChange& out) {
    HMSM_TRY(r.object(j, where, {"profile", "direction", "strength", "speed", "frequency", "front_speed",
                                 "turbulence", "seed"}));
    if (j.contains("strength") && j.contains("speed"))
        return r.error(where, "give strength or speed (m/s), not both");
    for (auto it = j.begin(); it != j.end(); ++it) {
        const std::string& key = it.key();
        const std::string at = where + "." + key;
        if (key == "profile") {
            if (!it->is_string()) return r.error(at, "expected a profile name, got " + Reader::shown(*it));
            auto profile = parse_wind_profile(it->get<std::string>());
            if (!profile)
                return r.error(at, "\"" + detail::quote_input(it->get<std::string>()) +
                                       "\": expected none, constant, y1, y2, y3, y4 or turbulent");
            out.profile = *profile;
        } else if (key == "direction") {
            Vec3 d;
            HMSM_TRY(r.vec3(*it, at, d));
            if (!(std::sqrt(d.x * d.x + d.y * d.y + d.z * d.z) > 1e-12)) return r.error(at, "must be non-zero");
            out.direction = d;
        } else if (key == "seed") {
            uint64_t seed = 0;
            HMSM_TRY(r.unsigned_integer(*it, at, seed));
            out.seed = seed;
        } else {
            double v = 0.0;
            HMSM_TRY(r.number(*it, at, v));
            if (key == "strength") {
                out.strength = v;
            } else if (key == "speed") {
                if (v < 0.0) return r.error(at, "wind speed must be >= 0 m/s");
                out.speed = v;
            } else if (key == "frequency") {
                if (v < 0.0) return r.error(at, "must be >= 0");
                out.frequency = v;
            } else if (key == "front_speed") {
                if (v < 0.0 || (v > 0.0 && v < 0.01)) return r.error(at, "must be 0 or >= 0.01 m/s");
                out.front_speed = v;
            } else {  // turbulence
                if (v < 0.0 || v > 2.0) return r.error(at, "must be within [0, 2]");
                out.turbulence = v;
            }
        }
    }
    return {};
}

Status parse_force(const Reader& r, const json& j, const std::string& where, ForceField& out) {
    HMSM_TRY(r.object(j, where, {"center", "radius", "directional", "radial"}));
    const bool directional = j.contains("directional"), radial = j.contains("radial");
    if (directional == radial)
        return r.error(where, "give exactly one of directional (a vector) and radial (a strength)");
    if (!j.contains("center")) return r.error(where + ".center", "missing");
    if (!j.contains("radius")) return r.error(where + ".radius", "missing");
    HMSM_TRY(r.vec3(j["center"], where + ".center", out.center));
    HMSM_TRY(r.number(j["radius"], where + ".radius", out.radius));
    if (!(out.radius > 0.0)) return r.error(where + ".radius", "must be > 0");
    if (Status range = detail::check_coordinate("center", out.center); !range) return r.error(where, range.message());
    if (Status range = detail::check_radius("radius", out.radius); !range) return r.error(where, range.message());
    if (directional) {
        out.kind = ForceField::Kind::directional;
        HMSM_TRY(r.vec3(j["directional"], where + ".directional", out.directional));
        if (Status range = detail::check_force("directional", out.directional); !range)
            return r.error(where, range.message());
    } else {
        out.kind = ForceField::Kind::radial;
        HMSM_TRY(r.number(j["radial"], where + ".radial", out.radial));
        if (Status range = detail::check_force("radial", out.radial); !range) return r.error(where, range.message());
    }
    return {};
}

Status parse_instance_change(const Reader& r, const json& j, const std::string& where, InstanceChange& out) {
    HMSM_TRY(r.object(j, where, {"instance", "wind_scale", "wind_phase", "active"}));
    if (!j.contains("instance")) return r.error(where + ".instance", "missing");
    HMSM_TRY(r.unsigned_integer(j["instance"], where + ".instance", out.instance));
    if (j.contains("wind_scale")) {
        double v = 0.0;
        HMSM_TRY(r.number(j["wind_scale"], where + ".wind_scale", v));
        if (Status range = detail::check_wind_scale("wind_scale", v); !range)
            return r.error(where + ".wind_scale", range.message());
        out.wind_scale = v;
    }
    if (j.contains("wind_phase")) {
        double v = 0.0;
        HMSM_TRY(r.number(j["wind_phase"], where + ".wind_phase", v));
        out.wind_phase = v;
    }
    if (j.contains("active")) {
        bool v = true;
        HMSM_TRY(r.boolean(j["active"], where + ".active", v));
        out.active = v;
    }
    return {};
}

Status parse_added(const Reader& r, const json& j, const std::string& where, ScheduledInstance& out) {
    HMSM_TRY(r.object(j, where, {"model", "origin", "yaw", "wind_scale", "wind_phase", "active"}));
    if (!j.contains("model")) return r.error(where + ".model", "missing");
    if (!j["model"].is_string()) return r.error(where + ".model", "expected a model name, got " + Reader::shown(j["model"]));
    out.model = j["model"].get<std::string>();
    if (j.contains("origin")) {
        HMSM_TRY(r.vec3(j["origin"], where + ".origin", out.origin));
        if (Status range = detail::check_coordinate("origin", out.origin); !range)
            return r.error(where + ".origin", range.message());
    }
    if (j.contains("yaw")) HMSM_TRY(r.number(j["yaw"], where + ".yaw", out.yaw));
    if (j.contains("wind_scale")) {
        HMSM_TRY(r.number(j["wind_scale"], where + ".wind_scale", out.wind_scale));
        if (Status range = detail::check_wind_scale("wind_scale", out.wind_scale); !range)
            return r.error(where + ".wind_scale", range.message());
    }
    if (j.contains("wind_phase")) HMSM_TRY(r.number(j["wind_phase"], where + ".wind_phase", out.wind_phase));
    if (j.contains("active")) HMSM_TRY(r.boolean(j["active"], where + ".active", out.active));
    return {};
}

Status parse_event(const Reader& r, const json& j, const std::string& where, ScheduleEvent& out) {
    HMSM_TRY(r.object(j, where, {"step", "wind", "forces", "instances", "remove", "add"}));
    if (!j.contains("step")) return r.error(where + ".step", "missing");
    const json& step = j["step"];
    if (step.is_number_integer() && !step.is_number_unsigned())
        return r.error(where + ".step", "is " + step.dump() + ", steps start at 1");
    HMSM_TRY(r.unsigned_integer(step, where + ".step", out.step));
    if (out.step < 1) return r.error(where + ".step", "is 0, steps start at 1");
    if (j.contains("wind")) HMSM_TRY(parse_wind(r, j["wind"], where + ".wind", out.wind.emplace()));
    if (j.contains("forces")) {
        const json& list = j["forces"];
        if (!list.is_array()) return r.error(where + ".forces", "expected an array of force fields");
        if (list.size() > kMaxForceFields)
            return r.error(where + ".forces", std::to_string(list.size()) + " force fields, at most " +
                                                  std::to_string(kMaxForceFields) + " may act at once");
        auto& forces = out.forces.emplace();
        forces.resize(list.size());
        for (size_t k = 0; k < list.size(); ++k)
            HMSM_TRY(parse_force(r, list[k], where + ".forces[" + std::to_string(k) + "]", forces[k]));
    }
    if (j.contains("instances")) {
        const json& list = j["instances"];
        if (!list.is_array()) return r.error(where + ".instances", "expected an array of instance changes");
        std::set<uint64_t> seen;
        out.instances.resize(list.size());
        for (size_t k = 0; k < list.size(); ++k) {
            const std::string at = where + ".instances[" + std::to_string(k) + "]";
            HMSM_TRY(parse_instance_change(r, list[k], at, out.instances[k]));
            if (!seen.insert(out.instances[k].instance).second)
                return r.error(at + ".instance", "instance " + std::to_string(out.instances[k].instance) +
                                                     " is named twice in one event");
        }
    }
    if (j.contains("remove")) {
        const json& list = j["remove"];
        if (!list.is_array()) return r.error(where + ".remove", "expected an array of instance indices");
        std::set<uint64_t> seen;
        out.remove.resize(list.size());
        for (size_t k = 0; k < list.size(); ++k) {
            const std::string at = where + ".remove[" + std::to_string(k) + "]";
            HMSM_TRY(r.unsigned_integer(list[k], at, out.remove[k]));
            if (!seen.insert(out.remove[k]).second)
                return r.error(at, "instance " + std::to_string(out.remove[k]) + " is removed twice");
        }
    }
    if (j.contains("add")) {
        const json& list = j["add"];
        if (!list.is_array()) return r.error(where + ".add", "expected an array of instances");
        out.add.resize(list.size());
        for (size_t k = 0; k < list.size(); ++k)
            HMSM_TRY(parse_added(r, list[k], where + ".add[" + std::to_string(k) + "]", out.add[k]));
    }
    return {};
}

}  // namespace

Result<Schedule> parse_schedule(std::string_view text, std::string_view source) {
    auto parsed = detail::parse_json(text, source);
    if (!parsed) return Status{ErrorCode::invalid_argument, parsed.status().message()};
    const json& doc = *parsed;
    const Reader r(source);
    if (!doc.is_object()) return r.error("document", "expected a JSON object");
    HMSM_TRY(r.object(doc, "document", {"format", "version", "events"}));
    if (!doc.contains("format")) return r.error("format", "missing");
    if (!doc["format"].is_string() || doc["format"].get<std::string>() != "hmsm-schedule")
        return r.error("format", "is " + Reader::shown(doc["format"]) + ", expected \"hmsm-schedule\"");
    if (!doc.contains("version")) return r.error("version", "missing");
    if (!doc["version"].is_number_integer() || doc["version"].get<int64_t>() != 1)
        return r.error("version", "is " + Reader::shown(doc["version"]) + ", only version 1 is supported");
    if (!doc.contains("events")) return r.error("events", "missing");
    const json& events = doc["events"];
    if (!events.is_array()) return r.error("events", "expected an array of events");
    Schedule schedule;
    // Sized from the counts before the events are allocated: each event and each instance it
    // changes, removes or adds is one entry (docs/model.md 3.11).
    uint64_t entries = events.size();
    for (const json& event : events)
        if (event.is_object())
            for (const char* key : {"instances", "remove", "add"})
                if (auto it = event.find(key); it != event.end() && it->is_array()) entries += it->size();
    if (Status counted = detail::check_count("entries (events and the instances they change)", entries,
                                             detail::size_limits().schedule_events);
        !counted)
        return r.error("events", counted.message());
    schedule.events.resize(events.size());
    for (size_t e = 0; e < events.size(); ++e) {
        const std::string where = "events[" + std::to_string(e) + "]";
        HMSM_TRY(parse_event(r, events[e], where, schedule.events[e]));
        if (e > 0 && schedule.events[e].step < schedule.events[e - 1].step)
            return r.error(where + ".step", "step " + std::to_string(schedule.events[e].step) +
                                                " comes after step " + std::to_string(schedule.events[e - 1].step) +
                                                ": events must be in non-decreasing step order");
    }
    return schedule;
}

Result<Schedule> load_schedule(const std::string& path) {
    auto text = detail::read_text_file(path);
    if (!text) return text.status();
    return parse_schedule(*text, path);
}

}  // namespace hmsm
