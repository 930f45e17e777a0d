// hmsm bench --open-world: memory, LOD-switch pop and the standing step's profile
// (bench_open_world_probe.h).
#include "bench_open_world_probe.h"

#include "bench_frames.h"
#include "buffers.h"
#include "scene_data.h"
#include "simulation_access.h"

#include <glm/geometric.hpp>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <limits>
#include <string>

namespace hmsm::cli::bench {

using nlohmann::json;

std::vector<LevelShape> level_shapes(const Simulation& sim) {
    std::vector<LevelShape> levels;
    const detail::SceneData& d = detail::scene_data_of(sim);
    for (uint32_t k = 0; k < sim.lod_level_count(0); ++k) {
        Result<uint32_t> run = sim.lod_model(0, k);
        if (!run) break;
        levels.push_back({*run, sim.hierarchy(*run).chains.size(), d.models[*run].node_count,
                          sim.mesh(*run).vertices.size()});
    }
    return levels;
}

namespace {

/// VmHWM of /proc/self/status in bytes (the process's peak resident memory), or 0.
double host_peak_bytes() {
    std::ifstream in("/proc/self/status");
    std::string line;
    while (std::getline(in, line)) {
        double kib = 0.0;
        if (std::sscanf(line.c_str(), "VmHWM: %lf kB", &kib) == 1) return kib * 1024.0;
    }
    return 0.0;
}

}  // namespace

json memory_json(const Simulation& sim, const std::vector<LevelShape>& levels, std::span<const double> shares,
                 uint64_t trees) {
    using detail::Scope;
    const detail::SceneData& d = detail::scene_data_of(sim);
    double chain = 0.0, node = 0.0, vertex = 0.0, instance = 0.0, model = 0.0;
    for (const detail::BufferInfo& info : detail::kBufferTable) {
        const double bytes = double(d.element_count(info.id)) * 4.0 * detail::shape_scalars(info.shape);
        switch (info.scope) {
            case Scope::chain:
            case Scope::chain_halves: chain += bytes; break;
            case Scope::node: node += bytes; break;
            case Scope::vertex: vertex += bytes; break;
            case Scope::instance: instance += bytes; break;
            default: model += bytes; break;
        }
    }
    auto per = [](double bytes, uint64_t count) { return count > 0 ? bytes / double(count) : 0.0; };
    const double per_chain = per(chain, d.chain_capacity), per_node = per(node, d.node_capacity),
                 per_vertex = per(vertex, d.vertex_capacity), per_instance = per(instance, d.instance_capacity);
    auto tree_bytes = [&](const LevelShape& l) {
        return double(l.chains) * per_chain + double(l.nodes) * per_node + double(l.vertices) * per_vertex +
               per_instance;
    };
    double at_shares = 0.0;
    json per_level = json::array();
    for (size_t k = 0; k < levels.size(); ++k) {
        const double share = k < shares.size() ? shares[k] : 0.0;
        at_shares += double(trees) * share * tree_bytes(levels[k]);
        per_level.push_back({{"level", k}, {"chains", levels[k].chains}, {"nodes", levels[k].nodes},
                             {"mesh_vertices", levels[k].vertices}, {"bytes_per_tree", tree_bytes(levels[k])}});
    }
    json m = {{"device_bytes", chain + node + vertex + instance + model},
              {"chain_bytes", chain},
              {"node_bytes", node},
              {"vertex_bytes", vertex},
              {"instance_bytes", instance},
              {"model_bytes", model},
              {"bytes_per_chain", per_chain},
              {"bytes_per_node", per_node},
              {"bytes_per_vertex", per_vertex},
              {"bytes_per_instance", per_instance},
              {"levels", per_level},
              {"trees", trees},
              {"estimate_device_bytes", at_shares + model},
              {"estimate_whole_trees_device_bytes",
               levels.empty() ? 0.0 : double(trees) * tree_bytes(levels[0]) + model},
              {"host_peak_bytes", host_peak_bytes()}};
    // Simulation::create and add_instances count every instance's mesh vertices (where they
    // are produced) and state nodes against 32-bit element offsets.
    if (!levels.empty()) {
        const uint64_t limit = std::numeric_limits<uint32_t>::max();
        m["largest_trees_by_mesh_vertices"] = limit / std::max<uint64_t>(1, levels[0].vertices);
        m["largest_trees_by_nodes"] = limit / std::max<uint64_t>(1, levels[0].nodes);
    }
    return m;
}

Result<PopProbe> PopProbe::create(const Simulation& sim, const TreeModel& tree, std::span<const int32_t> budgets) {
    PopProbe probe;
    const Hierarchy& full = sim.hierarchy(0);
    const MeshTemplate& mesh = sim.mesh(0);
    const ModelOptions& options = sim.config().model;
    auto levels = build_levels(tree, full, sim.config().parameters,
                               std::vector<int32_t>(budgets.begin(), budgets.end()));
    if (!levels) return levels.status();
    probe.skins_.push_back(build_skin(tree, full, mesh, options));
    for (const DetailLevel& level : *levels) probe.skins_.push_back(build_skin(tree, full, mesh, options, level));
    for (uint32_t k = 0; k < probe.skins_.size(); ++k) {
        Result<uint32_t> run = sim.lod_model(0, k);
        if (!run) return run.status();
        if (probe.skins_[k].inverse_bind.size() != sim.hierarchy(*run).chains.size())
            return Status{ErrorCode::internal, "level " + std::to_string(k) + ": the skin has " +
                                                   std::to_string(probe.skins_[k].inverse_bind.size()) +
                                                   " joints, the simulation's level " +
                                                   std::to_string(sim.hierarchy(*run).chains.size()) + " chains"};
        if (probe.level_of_model_.size() <= *run) probe.level_of_model_.resize(*run + 1, -1);
        probe.level_of_model_[*run] = int32_t(k);
    }
    return probe;
}

int32_t PopProbe::level_of(uint32_t model) const {
    return model < level_of_model_.size() ? level_of_model_[model] : -1;
}

double PopProbe::largest_jump(std::span<const float> a, uint32_t level_a, std::span<const float> b,
                              uint32_t level_b) const {
    const size_t n = skins_[level_a].vertices.size();
    std::vector<float> pa(3 * n), pb(3 * n);
    if (!skin_vertices(skins_[level_a], a, pa).ok() || !skin_vertices(skins_[level_b], b, pb).ok())
        return std::numeric_limits<double>::quiet_NaN();
    double largest = 0.0;
    for (size_t v = 0; v < n; ++v) {
        const double dx = pa[3 * v] - pb[3 * v], dy = pa[3 * v + 1] - pb[3 * v + 1], dz = pa[3 * v + 2] - pb[3 * v + 2];
        largest = std::max(largest, std::sqrt(dx * dx + dy * dy + dz * dz));
    }
    return largest;
}

std::vector<uint64_t> chain_offsets(const Simulation& sim) {
    const std::span<const Instance> instances = sim.instances();
    std::vector<uint64_t> offsets(instances.size() + 1, 0);
    for (size_t i = 0; i < instances.size(); ++i)
        offsets[i + 1] = offsets[i] + sim.hierarchy(instances[i].model).chains.size();
    return offsets;
}

double percentile(std::vector<double> values, double p) {
    if (values.empty()) return 0.0;
    std::sort(values.begin(), values.end());
    const size_t rank = size_t(std::ceil(p * double(values.size())));
    return values[std::min(values.size(), std::max<size_t>(rank, 1)) - 1];
}

/// Largest vertex jump at a switch and the motion of that tree in one frame; medians of both;
/// the motion of fading trees over one frame.
json pop_json(const json& jumps, const std::vector<double>& fading) {
    json pop = {{"switches_measured", jumps.size()}, {"fading_trees_measured", fading.size()}};
    if (!fading.empty()) {
        pop["largest_fading_motion_m"] = *std::max_element(fading.begin(), fading.end());
        pop["median_fading_motion_m"] = percentile(fading, 0.5);
    }
    if (jumps.empty()) return pop;
    std::vector<double> jump, motion;
    size_t largest = 0;
    for (size_t k = 0; k < jumps.size(); ++k) {
        jump.push_back(jumps[k]["jump_m"].get<double>());
        motion.push_back(jumps[k]["motion_m"].get<double>());
        if (jump.back() > jump[largest]) largest = k;
    }
    pop["largest_jump_m"] = jump[largest];
    pop["motion_of_largest_m"] = motion[largest];
    pop["largest_jump_levels"] = {jumps[largest]["from"], jumps[largest]["to"]};
    pop["median_jump_m"] = percentile(jump, 0.5);
    pop["median_motion_m"] = percentile(motion, 0.5);
    // Per kind of switch ("3-4": from 16 joints to the trunk alone): the largest jump, the
    // motion of that tree, and how many were measured.
    json by_switch = json::object();
    for (size_t k = 0; k < jumps.size(); ++k) {
        const std::string kind = std::to_string(jumps[k]["from"].get<int>()) + "-" + std::to_string(jumps[k]["to"].get<int>());
        if (!by_switch.contains(kind)) by_switch[kind] = json::object();
        json& entry = by_switch[kind];
        entry["measured"] = entry.value("measured", 0) + 1;
        if (jump[k] >= entry.value("largest_jump_m", -1.0)) {
            entry["largest_jump_m"] = jump[k];
            entry["motion_m"] = motion[k];
        }
    }
    pop["by_switch"] = by_switch;
    return pop;
}

Status profile_standing_step(Simulation& sim, json& row) {
    // A GPU's clock follows its load: after frames that kept it mostly idle (the host-bound
    // frames before) it may run at a fraction of its clock for a while, and the steps below
    // would measure the governor, not the step (on an H200: 0.7-1.3 GHz after some moving
    // phases, 1.98 GHz after others; the same step 2x apart). Half a second of back-to-back
    // steps brings the clock up first.
    using Clock = std::chrono::steady_clock;
    const auto warm_until = Clock::now() + std::chrono::milliseconds(500);
    for (int batch = 0; batch < 1000 && Clock::now() < warm_until; ++batch)
        if (Status status = sim.step(10); !status) return status;
    // Where a standing step's device time goes: ten profiled steps (timers serialize the
    // passes, so their sum exceeds the unprofiled step).
    {
        detail::Backend& backend = detail::backend_of(sim);
        backend.set_profiling(true);
        const Status status = sim.step(10);
        backend.set_profiling(false);
        if (!status) return status;
        const PassTimes t = sim.pass_times();
        json per_pass = json::object();
        for (Pass p : kAllPasses)
            if (t.steps > 0 && t.seconds[uint32_t(p)] > 0.0)
                per_pass[std::string(pass_name(p))] = t.seconds[uint32_t(p)] / double(t.steps);
        row["still_pass_seconds"] = per_pass;
        // Groups are the runs of neighbouring instances of one model (level); every pass
        // dispatches once per group, or, where the program lists (src/listed_groups.h), once
        // per model.
        row["groups"] = detail::scene_data_of(sim).groups.size();
        const std::vector<detail::Dispatch>& program = detail::step_program_of(sim);
        row["dispatches_per_step"] = program.size();
        row["listed"] = std::any_of(program.begin(), program.end(),
                                    [](const detail::Dispatch& d) { return d.constants.instance_list != 0; });
    }
    // The same standing step as an engine issues it (CUDA: enqueued on its stream; Vulkan:
    // recorded into its command buffer): the host time of the call, and the whole frame until
    // the outputs are ready.
    {
        json engine = json::array();
        for (const std::unique_ptr<FrameDriver>& driver : engine_drivers(sim)) {
            FrameTimes times;
            if (Status status = time_frames(sim, *driver, 20, {}, times); !status) return status;
            engine.push_back({{"path", driver->path()},
                              {"call_median_seconds", percentile(times.call, 0.5)},
                              {"frame_median_seconds", percentile(times.whole, 0.5)}});
        }
        row["still_engine"] = engine;
    }
    return {};
}

}  // namespace hmsm::cli::bench
