// hmsm bench: joints-only forest rows (bench_joints.h).
#include "bench_joints.h"

#include "bench_model.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <vector>

namespace hmsm::cli::bench {
namespace {

using nlohmann::json;

void put(json& j, const char* key, double value) {
    if (std::isfinite(value) && value > 0.0) j[key] = value;
}

bool uses_host_memory(BackendKind kind, const std::string& device) {
    if (kind == BackendKind::cpu || kind == BackendKind::cpu64) return true;
    for (const char* cpu_driver : {"llvmpipe", "lavapipe", "SwiftShader"})
        if (device.find(cpu_driver) != std::string::npos) return true;
    return false;
}

double median_of(std::vector<double> v) {
    std::sort(v.begin(), v.end());
    return v.empty() ? 0.0 : v[v.size() / 2];
}

/// read() of the joint matrices in GB/s, and a plain memcpy of as many bytes between two
/// warm host buffers (the host's copy roofline), each the median of a few repeats.
void measure_joint_read(const Simulation& sim, json& row) {
    std::vector<float> joints;
    if (!sim.read(Output::joint_matrices, joints).ok()) return;  // warm: the vector has its size
    const double bytes = double(joints.size() * sizeof(float));
    std::vector<double> read_seconds, copy_seconds;
    std::vector<float> copy(joints.size());
    for (int k = 0; k < 7; ++k) {
        auto start = std::chrono::steady_clock::now();
        if (!sim.read(Output::joint_matrices, joints).ok()) return;
        read_seconds.push_back(std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count());
        start = std::chrono::steady_clock::now();
        std::memcpy(copy.data(), joints.data(), size_t(bytes));
        copy_seconds.push_back(std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count());
    }
    row["read_bytes"] = bytes;
    put(row, "read_gb_per_s", bytes / median_of(read_seconds) * 1e-9);
    put(row, "memcpy_gb_per_s", bytes / median_of(copy_seconds) * 1e-9);
}

}  // namespace

int joint_forest_cases(BackendKind backend, const std::vector<JointForestCase>& cases, double spacing,
                       const Settings& settings, Progress& progress, json& rows, json& skipped) {
    const std::string name = to_string(backend);
    int failures = 0;
    double last_per_step = 0.0;  // of the last measured case, per instance
    std::string device;
    for (const JointForestCase& c : cases) {
        json where = {{"section", "forest_joints"}, {"backend", name}, {"model", c.model_name},
                      {"instances", c.count}};
        auto skip = [&](const std::string& reason, bool failure) {
            where["reason"] = (failure ? "failed: " : "") + reason;
            progress.note((failure ? "FAILED " : "skipped ") + where.dump());
            skipped.push_back(where);
            failures += failure ? 1 : 0;
        };
        progress.begin(std::to_string(c.count) + " x " + c.model_name + " on " + name + ", joints only");
        SimulationConfig config;
        config.backend = backend;
        config.outputs = Outputs::joints;
        config.wind.profile = settings.wind;
        config.composition = Composition::pointer_jumping;  // the first columns; then the path walk
        // Host memory: the state of one instance, from a one-instance simulation on the CPU.
        auto probe = Simulation::create(single_tree_scene(c.tree), [&] {
            SimulationConfig p = config;
            p.backend = BackendKind::cpu;
            return p;
        }());
        if (!probe) {
            skip(probe.status().message(), true);
            continue;
        }
        const double needed = state_bytes_per_instance(**probe) * c.count;
        const uint64_t chains_per_instance = (*probe)->chain_count();
        probe->reset();
        const double available = host_available_memory();
        if (uses_host_memory(backend, device) && available > 0.0 && needed > 0.8 * available) {
            char reason[160];
            std::snprintf(reason, sizeof reason, "needs about %.1f GB of host memory, %.1f GB available",
                          needed * 1e-9, available * 1e-9);
            skip(reason, false);
            continue;
        }
        if (last_per_step > 0.0 && last_per_step * c.count * 7.0 > settings.case_budget) {
            char reason[200];
            std::snprintf(reason, sizeof reason,
                          "about %.3g s per step (extrapolated), over the %.3g s case budget (--case-budget)",
                          last_per_step * c.count, settings.case_budget);
            skip(reason, false);
            continue;
        }
        auto scene = grid_scene(c.tree, c.count, spacing, 1);
        if (!scene) {
            skip(scene.status().message(), true);
            continue;
        }
        auto sim = Simulation::create(*scene, config);
        if (!sim) {
            const ErrorCode code = sim.status().code();
            skip(sim.status().message(), !(code == ErrorCode::out_of_memory || code == ErrorCode::unsupported ||
                                            code == ErrorCode::no_device));
            if (code == ErrorCode::no_device) return failures;
            continue;
        }
        device = (*sim)->device_name();
        auto measured = measure(**sim, settings, kBatched | kPasses);
        if (!measured) {
            skip(measured.status().message(), true);
            continue;
        }
        const CaseResult& r = *measured;
        last_per_step = r.warmup_seconds_per_step / double(c.count);
        // Bytes of the passes that run (1-5); step_traffic counts all seven.
        const Traffic traffic = step_traffic(**sim);
        double bytes = 0.0;
        for (Pass p : kAllPasses)
            if (p != Pass::node_world && p != Pass::contour) bytes += traffic.pass_bytes[uint32_t(p)];
        json row = {{"backend", name}, {"device", device}, {"model", c.model_name}, {"instances", c.count},
                    {"outputs", "joints"}, {"chains", (*sim)->chain_count()},
                    {"joint_bytes", 48 * (*sim)->chain_count()}, {"steps_per_batch", r.steps},
                    {"repeats", r.repeats}, {"budget_reduced", r.reduced},
                    {"bytes_per_step", bytes}};
        put(row, "steps_per_second", r.batched);
        put(row, "seconds_per_step", 1.0 / r.batched);
        put(row, "chains_per_second", double(chains_per_instance) * c.count * r.batched);
        put(row, "steps_per_second_profiled", r.profiled);
        if (r.has_passes) put(row, "device_seconds_per_step", r.device_seconds);
        measure_joint_read(**sim, row);
        sim->reset();
        // The same forest with passes 3 and 5 as path walks.
        for (Composition other : {Composition::path_walk}) {
            const std::string key = to_string(other);
            config.composition = other;
            auto other_sim = Simulation::create(*scene, config);
            if (!other_sim) {
                skip(key + ": " + other_sim.status().message(), true);
                continue;
            }
            auto result = measure(**other_sim, settings, kBatched | kPasses);
            if (!result) {
                skip(key + ": " + result.status().message(), true);
                continue;
            }
            json f = json::object();
            put(f, "steps_per_second", result->batched);
            put(f, "seconds_per_step", 1.0 / result->batched);
            put(f, "chains_per_second", double(chains_per_instance) * c.count * result->batched);
            put(f, "steps_per_second_profiled", result->profiled);
            if (result->has_passes) put(f, "device_seconds_per_step", result->device_seconds);
            row[key] = f;
        }
        rows.push_back(row);
    }
    return failures;
}

std::string render_joint_forest(const json& rows) {
    if (!rows.is_array() || rows.empty()) return "";
    std::string out =
        "\n### Forest scaling, joints only (passes 1-5)\n\n"
        "Pointer jumping; path walk: passes 3 and 5 in one dispatch each, every chain walking up its "
        "path to the root. read() GB/s: `Simulation::read` of every joint matrix after the steps "
        "(float, median of 7); memcpy GB/s: a plain host copy of as many bytes in the same run, the "
        "host's copy roofline.\n\n"
        "| backend | model | instances | chains | joint bytes | ms per step | device ms per step | Mchains/s "
        "| path walk ms per step | path walk device ms per step | path walk Mchains/s | read() GB/s | memcpy GB/s |\n"
        "|---|---|--:|--:|--:|--:|--:|--:|--:|--:|--:|--:|--:|\n";
    char line[500];
    for (const json& r : rows) {
        auto number_in = [](const json& j, const char* key, double scale) {
            return j.is_object() && j.contains(key) ? j[key].get<double>() * scale : 0.0;
        };
        auto number = [&](const char* key, double scale) { return number_in(r, key, scale); };
        const json walk = r.value("path_walk", json::object());
        std::snprintf(line, sizeof line,
                      "| %s | %s | %llu | %llu | %llu | %.3f | %.3f | %.1f | %.3f | %.3f | %.1f | %.2f | %.2f |\n",
                      r.value("backend", "").c_str(), r.value("model", "").c_str(),
                      (unsigned long long)r.value("instances", 0ull), (unsigned long long)r.value("chains", 0ull),
                      (unsigned long long)r.value("joint_bytes", 0ull), number("seconds_per_step", 1e3),
                      number("device_seconds_per_step", 1e3), number("chains_per_second", 1e-6),
                      number_in(walk, "seconds_per_step", 1e3),
                      number_in(walk, "device_seconds_per_step", 1e3), number_in(walk, "chains_per_second", 1e-6),
                      number("read_gb_per_s", 1.0), number("memcpy_gb_per_s", 1.0));
        out += line;
    }
    return out;
}

}  // namespace hmsm::cli::bench
