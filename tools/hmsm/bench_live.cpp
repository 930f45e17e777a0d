// Live-control costs (src/live_control.cpp): removing instances moves the survivors' state on
// the device (all those after the first hole in order, or only the fillers of a swap removal),
// adding them back within the capacity writes only the added ones, adding past the
// capacity grows it once by half (on the device, or by re-uploading the scene where the backend
// cannot or HMSM_DEVICE_GROWTH=0); switching instances between levels of detail; a wind change between two steps; and pausing and resuming a tenth of the forest.
#include "bench_live.h"

#include "bench_frames.h"
#include "simulation_access.h"

#include <algorithm>
#include <cstdio>
#include <chrono>
#include <numeric>

namespace hmsm::cli::bench {
namespace {

using Clock = std::chrono::steady_clock;

double seconds_since(Clock::time_point start) {
    return std::chrono::duration<double>(Clock::now() - start).count();
}

/// Mean seconds of a whole frame over the `frames` asked for.
double seconds_per_frame(const FrameTimes& times, uint32_t frames) {
    return std::accumulate(times.whole.begin(), times.whole.end(), 0.0) / frames;
}

}  // namespace

nlohmann::json measure_live_control(const TreeModel& model, const std::vector<BackendKind>& backends,
                                    uint32_t forest, double spacing) {
    nlohmann::json results = nlohmann::json::array();
    auto scene = grid_scene(model, forest, spacing, 1);
    if (!scene) return results;
    scene->lod_budgets = {{256, 64, 16, 1}};  // levels for the switch rows; the state is per level run
    for (BackendKind kind : backends) {
        SimulationConfig config;
        config.backend = kind;
        config.parameters = Parameters{};
        auto sim = Simulation::create(*scene, config);
        if (!sim) {
            results.push_back({{"backend", to_string(kind)}, {"instances", forest},
                               {"skipped", sim.status().message()}});
            continue;
        }
        Simulation& s = **sim;
        (void)s.step(2);
        for (uint32_t count : {1u, 10u, 100u}) {
            if (count >= forest) continue;
            // Remove `count` instances spread over the forest, then add them back at the end;
            // the same by swap removal.
            std::vector<uint64_t> indices(count);
            std::vector<Instance> removed;
            for (uint32_t k = 0; k < count; ++k) indices[k] = uint64_t(k) * (forest / count);
            for (uint64_t i : indices) removed.push_back(s.instances()[i]);
            const uint64_t uploads = detail::full_uploads_of(s);
            auto start = Clock::now();
            Status status = s.remove_instances(indices);
            const double remove_seconds = seconds_since(start);
            start = Clock::now();
            if (status) status = s.add_instances(removed);
            const double add_seconds = seconds_since(start);
            std::vector<InstanceId> ids;
            for (uint64_t i : indices) ids.push_back(s.instance_ids()[i]);
            start = Clock::now();
            if (status) status = s.swap_remove_instances(ids);
            const double swap_remove_seconds = seconds_since(start);
            if (status) status = s.add_instances(removed);
            start = Clock::now();
            if (status) status = s.step();
            const double first_step_seconds = seconds_since(start);
            nlohmann::json entry = {{"backend", to_string(kind)}, {"device", s.device_name()},
                                    {"instances", forest}, {"changed", count}};
            if (!status) {
                entry["failed"] = status.message();
            } else {
                entry["remove_seconds"] = remove_seconds;
                entry["add_seconds"] = add_seconds;
                entry["swap_remove_seconds"] = swap_remove_seconds;
                // 0 when both happened in place (no scene upload).
                entry["scene_uploads"] = detail::full_uploads_of(s) - uploads;
                entry["first_step_seconds"] = first_step_seconds;
            }
            results.push_back(entry);
        }
        // Levels of detail: `count` instances spread over the forest switched to 16 joints and
        // back to the whole tree, each in one set_instance_lods call; then update_lod with
        // nothing to switch (the scan over every instance).
        for (uint32_t count : {1u, 10u, 100u}) {
            if (count >= forest) continue;
            std::vector<InstanceId> ids;
            for (uint32_t k = 0; k < count; ++k) ids.push_back(s.instance_ids()[uint64_t(k) * (forest / count)]);
            const uint64_t uploads = detail::full_uploads_of(s);
            auto start = Clock::now();
            Status status = s.set_instance_lods(ids, std::vector<uint32_t>(count, 3));
            const double coarser = seconds_since(start);
            start = Clock::now();
            if (status) status = s.set_instance_lods(ids, std::vector<uint32_t>(count, 0));
            const double finer = seconds_since(start);
            start = Clock::now();
            Result<uint64_t> unchanged = status ? s.update_lod(Vec3(0.0)) : Result<uint64_t>(status);
            const double scan = seconds_since(start);
            nlohmann::json entry = {{"backend", to_string(kind)}, {"instances", forest}, {"lod_switched", count}};
            if (!unchanged) {
                entry["failed"] = unchanged.status().message();
            } else {
                entry["lod_coarser_seconds"] = coarser;
                entry["lod_finer_seconds"] = finer;
                entry["update_lod_unchanged_seconds"] = scan;
                entry["scene_uploads"] = detail::full_uploads_of(s) - uploads;
            }
            results.push_back(entry);
        }
        // A wind change between two steps against a plain step.
        auto start = Clock::now();
        (void)s.step();
        const double plain = seconds_since(start);
        // Then one step per call, as an engine's frames call it, nothing changed in between
        // (on CUDA a forest then takes the angles the step before integrated ahead).
        constexpr uint32_t kCalls = 10;
        const auto step = blocking_step();
        FrameTimes unchanged;
        (void)time_frames(s, *step, kCalls, nullptr, unchanged);
        const double per_call = seconds_per_frame(unchanged, kCalls);
        // And with a force field moved before each call (a character walking through the forest).
        ForceField field;
        field.radius = 10.0;
        field.directional = {0.0, 0.0, 5.0};
        FrameTimes walking;
        (void)time_frames(s, *step, kCalls, [&field](Simulation& sim, uint32_t k) {
            field.center = {2.0 * k, 2.0, 0.0};
            return sim.set_force_fields({&field, 1});
        }, walking);
        const double moving_field = seconds_per_frame(walking, kCalls);
        (void)s.set_force_fields({});
        Wind wind = s.wind();
        wind.profile = WindProfile::turbulent;
        start = Clock::now();
        Status status = s.set_wind(wind);
        if (status) status = s.step();
        const double changed = seconds_since(start);
        if (status)
            results.push_back({{"backend", to_string(kind)}, {"instances", forest}, {"set_wind_step_seconds", changed},
                               {"plain_step_seconds", plain}, {"step_per_call_seconds", per_call},
                               {"moving_field_step_seconds", moving_field}});
        // Pausing a tenth of the forest (the step program is rebuilt over the active runs),
        // the next step, and resuming them.
        {
            const uint64_t paused = std::max<uint64_t>(1, s.instances().size() / 10);
            start = Clock::now();
            for (uint64_t i = 0; status && i < paused; ++i) status = s.set_instance_active(i * 10 % s.instances().size(), false);
            const double pause = seconds_since(start);
            start = Clock::now();
            if (status) status = s.step();
            const double paused_step = seconds_since(start);  // with the new step program's setup
            constexpr uint32_t kPausedSteps = 10;
            start = Clock::now();
            if (status) status = s.step(kPausedSteps);
            const double paused_steps = seconds_since(start) / kPausedSteps;
            start = Clock::now();
            for (uint64_t i = 0; status && i < paused; ++i) status = s.set_instance_active(i * 10 % s.instances().size(), true);
            const double resume = seconds_since(start);
            if (status)
                results.push_back({{"backend", to_string(kind)}, {"instances", forest}, {"paused", paused},
                                   {"pause_seconds", pause}, {"paused_step_seconds", paused_step},
                                   {"paused_steps_seconds", paused_steps},
                                   {"resume_seconds", resume}});
        }
        // Adding past the capacity (one growth by half: on the device, or by a re-upload where
        // the backend cannot or HMSM_DEVICE_GROWTH=0), then as many again, which now fit.
        const std::vector<Instance> more(std::max(1u, forest / 10), s.instances()[0]);
        const uint64_t uploads = detail::full_uploads_of(s);
        const uint64_t growths = detail::device_growths_of(s);
        start = Clock::now();
        status = s.add_instances(more);
        const double grow = seconds_since(start);
        start = Clock::now();
        if (status) status = s.add_instances(more);
        const double fit = seconds_since(start);
        if (status)
            results.push_back({{"backend", to_string(kind)}, {"instances", forest}, {"added", more.size()},
                               {"add_past_capacity_seconds", grow}, {"add_within_capacity_seconds", fit},
                               {"scene_uploads", detail::full_uploads_of(s) - uploads},
                               {"device_growths", detail::device_growths_of(s) - growths}});
        // One instance past the capacity, once the room is filled: the single call that pays
        // for the growth.
        {
            const detail::SceneData& d = detail::scene_data_of(s);
            const uint64_t per = d.models.empty() ? 1 : std::max<uint64_t>(1, d.models[0].chain_count);
            const uint64_t room = std::min<uint64_t>(d.instance_capacity - d.instance_count(),
                                                     (d.chain_capacity - d.total_chains) / per);
            if (status && room > 0) status = s.add_instances(std::vector<Instance>(room, s.instances()[0]));
            const uint64_t before = detail::full_uploads_of(s);
            const uint64_t grown_before = detail::device_growths_of(s);
            start = Clock::now();
            const Instance one = s.instances()[0];
            if (status) status = s.add_instances({&one, 1});
            const double one_past = seconds_since(start);
            if (status)
                results.push_back({{"backend", to_string(kind)}, {"instances", s.instances().size() - 1},
                                   {"add_one_past_capacity_seconds", one_past},
                                   {"scene_uploads", detail::full_uploads_of(s) - before},
                                   {"device_growths", detail::device_growths_of(s) - grown_before}});
        }
    }
    return results;
}

std::string render_live_control(const nlohmann::json& rows) {
    if (!rows.is_array() || rows.empty()) return "";
    std::string out =
        "\n### Live control on a forest (ms of wall time per call)\n\n"
        "| backend | instances | change | ms | scene uploads |\n"
        "|---|--:|---|--:|--:|\n";
    auto ms = [](const nlohmann::json& r, const char* key) {
        char cell[32];
        std::snprintf(cell, sizeof cell, "%.3f", r.value(key, 0.0) * 1e3);
        return std::string(cell);
    };
    for (const nlohmann::json& r : rows) {
        const std::string head = "| " + r.value("backend", std::string()) + " | " +
                                 std::to_string(r.value("instances", 0ull)) + " | ";
        std::string uploads = r.contains("scene_uploads") ? std::to_string(r["scene_uploads"].get<uint64_t>()) : "";
        if (r.value("device_growths", 0ull) > 0)
            uploads += " (" + std::to_string(r["device_growths"].get<uint64_t>()) + " grown on the device)";
        auto line = [&](const std::string& change, const std::string& cell, const std::string& up) {
            out += head + change + " | " + cell + " | " + up + " |\n";
        };
        if (r.contains("skipped") || r.contains("failed")) {
            line("–", r.value("skipped", r.value("failed", std::string())), "");
        } else if (r.contains("remove_seconds")) {
            const std::string n = std::to_string(r.value("changed", 0ull));
            line("remove " + n, ms(r, "remove_seconds"), uploads);
            line("add " + n + " back", ms(r, "add_seconds"), "");
            if (r.contains("swap_remove_seconds")) line("swap-remove " + n, ms(r, "swap_remove_seconds"), "");
            line("first step after", ms(r, "first_step_seconds"), "");
        } else if (r.contains("lod_coarser_seconds")) {
            const std::string n = std::to_string(r.value("lod_switched", 0ull));
            line("switch " + n + " to 16 joints (set_instance_lods)", ms(r, "lod_coarser_seconds"), uploads);
            line("switch " + n + " back to the whole tree", ms(r, "lod_finer_seconds"), "");
            line("update_lod, nothing to switch", ms(r, "update_lod_unchanged_seconds"), "");
        } else if (r.contains("set_wind_step_seconds")) {
            line("set_wind + step", ms(r, "set_wind_step_seconds"), "");
            line("plain step", ms(r, "plain_step_seconds"), "");
            if (r.contains("step_per_call_seconds"))
                line("each of 10 more steps, one per call", ms(r, "step_per_call_seconds"), "");
            if (r.contains("moving_field_step_seconds"))
                line("each of 10 steps, a force field moved before each", ms(r, "moving_field_step_seconds"), "");
        } else if (r.contains("pause_seconds")) {
            const std::string n = std::to_string(r.value("paused", 0ull));
            line("pause " + n, ms(r, "pause_seconds"), "");
            line("step with " + n + " paused", ms(r, "paused_step_seconds"), "");
            line("each of the next steps", ms(r, "paused_steps_seconds"), "");
            line("resume " + n, ms(r, "resume_seconds"), "");
        } else if (r.contains("add_past_capacity_seconds")) {
            const std::string n = std::to_string(r.value("added", 0ull));
            line("add " + n + " past the capacity, then " + n + " within",
                 ms(r, "add_past_capacity_seconds") + ", " + ms(r, "add_within_capacity_seconds"), uploads);
        } else if (r.contains("add_one_past_capacity_seconds")) {
            line("add 1 past the capacity (the scene grows by half)", ms(r, "add_one_past_capacity_seconds"), uploads);
        }
    }
    return out;
}

}  // namespace hmsm::cli::bench
