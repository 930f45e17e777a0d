// hmsm bench: the cases of one run (bench_run.h).
#include "bench_run.h"

#include "scene_data.h"
#include "simulation_access.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <map>
#include <utility>
#include <tuple>

namespace hmsm::cli::bench {

using nlohmann::json;

constexpr double kMiB = 1048576.0;

std::string format_seconds(double s) {
    char text[32];
    std::snprintf(text, sizeof text, s >= 10 ? "%.0f s" : s >= 0.01 ? "%.2f s" : "%.2e s", s);
    return text;
}

bool is_host_kind(BackendKind k) {
    return k == BackendKind::cpu || k == BackendKind::cpu_parallel || k == BackendKind::cpu64;
}

namespace {

/// Backends whose "device" memory is host memory: the CPU ones and Vulkan CPU drivers.
bool uses_host_memory(const BackendRun& b) {
    if (is_host_kind(b.kind)) return true;
    for (const char* cpu_driver : {"llvmpipe", "lavapipe", "SwiftShader"})
        if (b.device.find(cpu_driver) != std::string::npos) return true;
    return false;
}

/// Statuses that mean "this case does not fit here", reported as skips rather than failures.
bool is_skip(const Status& s) {
    return s.code() == ErrorCode::out_of_memory || s.code() == ErrorCode::unsupported;
}

/// Device seconds per pass. A dispatch that runs several passes reports its time under its first
/// pass (docs/architecture.md): under Composition::path_walk a pair's "LEADER+PARTNER"; the
/// passes that run on their own follow.
json pass_seconds_json(const CaseResult& r, Composition composition = Composition::pointer_jumping) {
    json seconds = json::object();
    uint32_t partners = 0;
    for (Pass p : kAllPasses) {
        const double s = r.pass_seconds[uint32_t(p)];
        const uint32_t walk = hmsm::detail::walk_passes(p);
        if (composition == Composition::path_walk && walk != 0) {
            const Pass partner = Pass(hmsm::detail::pass_info(p).walk);
            seconds[std::string(pass_name(p)) + "+" + std::string(pass_name(partner))] = s;
            partners |= 1u << uint32_t(partner);
        } else if (!(composition == Composition::path_walk && (partners >> uint32_t(p) & 1u))) {
            seconds[std::string(pass_name(p))] = s;
        }
    }
    return seconds;
}

}  // namespace

void put(json& j, const char* key, double value) {
    if (std::isfinite(value) && value > 0.0) j[key] = value;
}

std::unique_ptr<Simulation> BenchRun::create(const Scene& scene, BackendRun& b, Composition composition,
                                             json where, VertexLayout layout, detail::JumpingForm jumping_form) {
    SimulationConfig config;
    config.backend = b.kind;
    config.composition = composition;
    config.vertex_layout = layout;
    config.profile_passes = false;
    config.wind.profile = settings_.wind;
    auto sim = detail::SimulationAccess::create(scene, config, jumping_form);
    if (sim) {
        b.device = (*sim)->device_name();
        return std::move(sim).value();
    }
    const Status& s = sim.status();
    if (s.code() == ErrorCode::no_device) {
        b.available = false;
        skipped.push_back({{"section", "backend"}, {"backend", to_string(b.kind)},
                           {"reason", "not available: " + s.message()}});
        progress_.note(std::string(to_string(b.kind)) + " not available: " + s.message());
        return nullptr;
    }
    record_failure(where, s);
    return nullptr;
}

void BenchRun::record_failure(json where, const Status& s) {
    const bool skip = is_skip(s);
    where["reason"] = (skip ? "" : "failed: ") + s.message();
    if (!skip) ++failures;
    progress_.note((skip ? "skipped " : "FAILED ") + where.dump() );
    skipped.push_back(std::move(where));
}

void BenchRun::copy_bandwidth(BackendRun& b, Simulation& sim) {
    if (b.copy && b.copy->method != "host_transfer_estimate") return;
    if (b.copy && double(sim.vertex_count()) * 16.0 <= double(b.copy->bytes)) return;
    if (b.copy && double(sim.vertex_count()) * 16.0 > 2048.0 * kMiB) return;
    // A CPU Vulkan driver's device memory is host memory: its roofline is the host memcpy.
    // Measured once and shared, so host-memory backends are compared against the same figure.
    if (uses_host_memory(b) && !host_copy_) {
        Result<CopyBandwidth> host = host_memcpy_bandwidth(host_copy_bytes_, 5);
        if (host) host_copy_ = *host;
    }
    Result<CopyBandwidth> bw = uses_host_memory(b)
                                   ? (host_copy_ ? Result<CopyBandwidth>(*host_copy_)
                                                 : Status{ErrorCode::out_of_memory, "host memcpy failed"})
                                   : device_copy_bandwidth(sim, device_copy_bytes_);
    if (bw) b.copy = *bw;
    else progress_.note(std::string(to_string(b.kind)) + ": copy bandwidth: " + bw.status().message());
}

void BenchRun::preset_case(const Model& m, BackendRun& b) {
    const std::string backend = to_string(b.kind);
    const Scene scene = single_tree_scene(m.tree);
    json entry = {{"preset", m.name}, {"backend", backend}, {"instances", 1}};

    progress_.begin(m.name + " on " + backend + ", pointer jumping");
    auto sim = create(scene, b, Composition::pointer_jumping,
                      {{"section", "presets"}, {"preset", m.name}, {"backend", backend},
                       {"composition", "pointer_jumping"}});
    if (!sim) return;
    auto measured = measure(*sim, settings_, kBatched | kPerCall | kReadback | kPasses);
    if (!measured) return record_failure({{"section", "presets"}, {"preset", m.name}, {"backend", backend},
                                          {"composition", "pointer_jumping"}}, measured.status());
    const CaseResult& r = *measured;
    const Traffic traffic = step_traffic(*sim);
    entry["device"] = sim->device_name();
    entry["nodes"] = sim->node_count();
    entry["chains"] = sim->chain_count();
    entry["mesh_vertices"] = sim->vertex_count();
    entry["steps_per_batch"] = r.steps;
    entry["repeats"] = r.repeats;
    entry["budget_reduced"] = r.reduced;
    json rate = json::object();
    put(rate, "per_call", r.per_call);
    put(rate, "batched", r.batched);
    put(rate, "readback", r.readback);
    entry["steps_per_second"] = rate;
    json bytes = {{"state", traffic.state_bytes}, {"static", traffic.static_bytes}, {"total", traffic.total()}};
    json per_pass = json::object();
    for (Pass p : kAllPasses) per_pass[std::string(pass_name(p))] = traffic.pass_bytes[uint32_t(p)];
    bytes["per_pass"] = per_pass;
    entry["bytes_per_step"] = bytes;
    put(entry, "effective_bandwidth", traffic.total() * r.batched);
    json pj = {{"rounds", sim->jump_rounds()}};
    put(pj, "steps_per_second_batched", r.batched);
    put(pj, "steps_per_second_profiled", r.profiled);
    if (r.has_passes) {
        pj["pass_seconds_per_step"] = pass_seconds_json(r);
        put(pj, "device_seconds_per_step", r.device_seconds);
        put(pj, "device_effective_bandwidth", traffic.total() / r.device_seconds);
    }
    entry["pointer_jumping"] = pj;
    const uint32_t levels = uint32_t(hmsm::detail::scene_data_of(*sim).models[0].level_begin.size() - 1);
    const uint32_t rounds = sim->jump_rounds();
    copy_bandwidth(b, *sim);
    sim.reset();

    // Pointer jumping with every round in one dispatch (its internal form, whatever the size),
    // then the other compositions.
    using detail::JumpingForm;
    for (auto [composition, jumping_form, name, count_key, count] :
         {std::tuple{Composition::pointer_jumping, JumpingForm::in_dispatch, "pointer_jumping_in_dispatch", "rounds",
                     rounds},
          std::tuple{Composition::level_by_level, JumpingForm::by_size, "level_by_level", "levels", levels},
          std::tuple{Composition::path_walk, JumpingForm::by_size, "path_walk", "levels", levels}}) {
        progress_.begin(m.name + " on " + backend + ", " + name);
        json where = {{"section", "presets"}, {"preset", m.name}, {"backend", backend}, {"composition", name}};
        auto other = create(scene, b, composition, where, VertexLayout::separate, jumping_form);
        if (!other) continue;
        auto measured_other = measure(*other, settings_, kBatched | kPasses);
        if (!measured_other) {
            record_failure(where, measured_other.status());
            continue;
        }
        json c = {{count_key, count}};
        put(c, "steps_per_second_batched", measured_other->batched);
        put(c, "steps_per_second_profiled", measured_other->profiled);
        if (measured_other->has_passes) {
            c["pass_seconds_per_step"] = pass_seconds_json(*measured_other, composition);
            put(c, "device_seconds_per_step", measured_other->device_seconds);
            put(c, "device_effective_bandwidth", traffic.total() / measured_other->device_seconds);
        }
        entry[name] = c;
        entry["budget_reduced"] = entry["budget_reduced"].get<bool>() || measured_other->reduced;
    }
    presets.push_back(entry);
}

void BenchRun::forest_cases(const Model& model, BackendRun& b, const std::vector<uint32_t>& counts,
                  double spacing, double state_per_instance) {
    const std::string backend = to_string(b.kind);
    double last_per_step = 0.0;
    uint32_t last_count = 0;
    for (uint32_t n : counts) {
        if (!b.available) return;
        auto skip_size = [&](const std::string& reason) {
            for (VertexLayout layout : kVertexLayouts)
                skipped.push_back({{"section", "forest"}, {"backend", backend}, {"instances", n},
                                   {"layout", to_string(layout)}, {"reason", reason}});
            progress_.note("skipped " + std::to_string(n) + " x " + model.name + " on " + backend + ": " + reason);
        };
        const double available = host_available_memory();
        const double needed = state_per_instance * n * (is_host_kind(b.kind) ? 1.0 : 2.0);
        if (uses_host_memory(b) && available > 0.0 && needed > 0.8 * available) {
            char reason[160];
            std::snprintf(reason, sizeof reason, "needs about %.1f GB of host memory, %.1f GB available",
                          needed * 1e-9, available * 1e-9);
            skip_size(reason);
            continue;
        }
        if (last_count > 0) {
            // Linear extrapolation from the slowest layout of the last size; the least a
            // case runs is 1 warm-up + 3 x (batched + timed), once per layout.
            const double estimate = last_per_step * double(n) / double(last_count);
            if (estimate * 7.0 * double(kVertexLayouts.size()) > settings_.case_budget) {
                skip_size("about " + format_seconds(estimate) + " per step (extrapolated from " +
                          std::to_string(last_count) + " instances), over the " +
                          format_seconds(settings_.case_budget) + " case budget (--case-budget)");
                continue;
            }
        }
        auto scene = grid_scene(model.tree, n, spacing, 1);
        double slowest = 0.0;
        for (VertexLayout layout : kVertexLayouts) {
            if (!b.available) return;
            const std::string layout_name = to_string(layout);
            progress_.begin(std::to_string(n) + " x " + model.name + " on " + backend + ", " + layout_name);
            json where = {{"section", "forest"}, {"backend", backend}, {"instances", n}, {"layout", layout_name}};
            if (!scene) {
                record_failure(where, scene.status());
                continue;
            }
            auto sim = create(*scene, b, settings_.forest_composition, where, layout);
            if (!sim) continue;
            auto measured = measure(*sim, settings_, kBatched | kPasses);
            if (!measured) {
                record_failure(where, measured.status());
                continue;
            }
            const CaseResult& r = *measured;
            slowest = std::max(slowest, r.warmup_seconds_per_step);
            const Traffic traffic = step_traffic(*sim);
            json f = {{"backend", backend}, {"device", sim->device_name()}, {"instances", n},
                      {"layout", layout_name}, {"composition", to_string(sim->config().composition)},
                      {"mesh_vertices", sim->vertex_count()},
                      {"steps_per_batch", r.steps}, {"repeats", r.repeats}, {"budget_reduced", r.reduced},
                      {"bytes_per_step", traffic.total()}, {"state_bytes_per_step", traffic.state_bytes}};
            put(f, "steps_per_second", r.batched);
            put(f, "seconds_per_step", 1.0 / r.batched);
            put(f, "vertices_per_second", double(sim->vertex_count()) * r.batched);
            put(f, "effective_bandwidth", traffic.total() * r.batched);
            put(f, "steps_per_second_profiled", r.profiled);
            if (r.has_passes) {
                put(f, "device_seconds_per_step", r.device_seconds);
                put(f, "device_effective_bandwidth", traffic.total() / r.device_seconds);
                f["pass_seconds_per_step"] = pass_seconds_json(r, sim->config().composition);
            }
            copy_bandwidth(b, *sim);
            forest.push_back(f);
        }
        if (slowest > 0.0) {
            last_per_step = slowest;
            last_count = n;
        }
    }
}

namespace {

/// Rates of one case's CPU backends, per rate key: cpu's, and the best one's with its name.
struct CpuRates {
    std::map<std::string, double> cpu, best;
    std::map<std::string, std::string> best_backend;
    void add(const std::string& backend, const std::string& key, double rate) {
        if (backend == "cpu") cpu[key] = rate;
        if (rate > best[key]) {
            best[key] = rate;
            best_backend[key] = backend;
        }
    }
};

/// Writes speedup_over_cpu, speedup_over_best_cpu and best_cpu of `rates` (key -> steps/s).
void put_speedups(json& entry, const json& rates, const CpuRates& cpu, const std::vector<std::string>& keys,
                  const std::string& single_key = "") {
    json over_cpu = json::object(), over_best = json::object(), best = json::object();
    for (const std::string& key : keys) {
        if (!rates.contains(key) || !rates[key].is_number()) continue;
        const double rate = rates[key].get<double>();
        const std::string out = single_key.empty() ? key : single_key;
        if (auto c = cpu.cpu.find(key); c != cpu.cpu.end()) put(over_cpu, out.c_str(), rate / c->second);
        if (auto b = cpu.best.find(key); b != cpu.best.end() && b->second > 0.0) {
            put(over_best, out.c_str(), rate / b->second);
            best[out] = cpu.best_backend.at(key);
        }
    }
    if (single_key.empty()) {
        entry["speedup_over_cpu"] = over_cpu;
        entry["speedup_over_best_cpu"] = over_best;
        entry["best_cpu"] = best;
    } else {
        if (over_cpu.contains(single_key)) entry["speedup_over_cpu"] = over_cpu[single_key];
        if (over_best.contains(single_key)) {
            entry["speedup_over_best_cpu"] = over_best[single_key];
            entry["best_cpu"] = best[single_key];
        }
    }
}

}  // namespace

void add_speedups(json& presets, json& forest) {
    const std::vector<std::string> rate_keys = {"per_call", "batched", "readback"};
    std::map<std::string, CpuRates> by_preset;
    for (const json& p : presets) {
        if (!is_host_kind(*parse_backend_kind(p["backend"].get<std::string>()))) continue;
        for (const std::string& key : rate_keys)
            if (p["steps_per_second"].contains(key))
                by_preset[p["preset"].get<std::string>()].add(p["backend"], key, p["steps_per_second"][key]);
    }
    for (json& p : presets) {
        auto cpu = by_preset.find(p["preset"].get<std::string>());
        if (cpu != by_preset.end()) put_speedups(p, p["steps_per_second"], cpu->second, rate_keys);
    }
    using ForestCase = std::pair<uint64_t, std::string>;  // instances, layout
    std::map<ForestCase, CpuRates> by_case;
    for (const json& f : forest) {
        if (!is_host_kind(*parse_backend_kind(f["backend"].get<std::string>())) || !f.contains("steps_per_second"))
            continue;
        by_case[{f["instances"].get<uint64_t>(), f["layout"]}].add(f["backend"], "steps_per_second",
                                                                   f["steps_per_second"]);
    }
    for (json& f : forest) {
        auto cpu = by_case.find({f["instances"].get<uint64_t>(), f["layout"].get<std::string>()});
        if (cpu != by_case.end()) put_speedups(f, f, cpu->second, {"steps_per_second"}, "steps_per_second");
    }
}

}  // namespace hmsm::cli::bench
