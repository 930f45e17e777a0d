// hmsm bench --open-world (bench_open_world.h): an endless grid of trees streamed around a
// moving viewer, levels of detail by distance bands, one step per frame.
#include "bench_open_world.h"

#include "bench_model.h"
#include "bench_frames.h"
#include "bench_open_world_grid.h"
#include "bench_open_world_probe.h"
#include "simulation_access.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <numbers>
#include <unordered_map>
#include <unordered_set>

namespace hmsm::cli::bench {
namespace {

using nlohmann::json;
using Clock = std::chrono::steady_clock;

double seconds(Clock::time_point a, Clock::time_point b) { return std::chrono::duration<double>(b - a).count(); }

struct Calls {
    std::vector<double> update_lod, remove, add, step, frame;
};

json distribution(const std::vector<double>& v) {
    json d = {{"calls", v.size()}};
    if (v.empty()) return d;
    d["median_seconds"] = percentile(v, 0.5);
    d["p99_seconds"] = percentile(v, 0.99);
    d["max_seconds"] = *std::max_element(v.begin(), v.end());
    d["over_1ms"] = std::count_if(v.begin(), v.end(), [](double s) { return s > 1e-3; });
    return d;
}

bool uses_host_memory(BackendKind kind, const std::string& device) {
    if (kind == BackendKind::cpu || kind == BackendKind::cpu64 || kind == BackendKind::cpu_parallel) return true;
    for (const char* cpu_driver : {"llvmpipe", "lavapipe", "SwiftShader"})
        if (device.find(cpu_driver) != std::string::npos) return true;
    return false;
}

/// One open world on one backend.
class OpenWorld {
public:
    /// `sim` holds one tree: that of cell (0, 0), under the viewer.
    OpenWorld(Simulation& sim, const Grid& grid) : sim_(sim), grid_(grid) {
        live_[Grid::key(0, 0)] = sim.instance_ids()[0];
    }

    /// Streams the trees around `viewer` in, nearest first, in batches, each tree on its level.
    Status populate(glm::dvec2 viewer, uint64_t batch_chains) {
        std::vector<Cell> cells;
        const auto [j0, j1] = grid_.rows(viewer.y, viewer.y);
        for (int64_t j = j0; j <= j1; ++j) {
            const auto [a, b] = grid_.row(j, viewer.x, viewer.y);
            for (int64_t i = a; i <= b; ++i)
                if (!live_.contains(Grid::key(i, j))) cells.push_back({i, j});
        }
        auto distance = [&](const Cell& c) {
            return std::hypot(double(c.i) * grid_.spacing - viewer.x, double(c.j) * grid_.spacing - viewer.y);
        };
        std::sort(cells.begin(), cells.end(), [&](const Cell& a, const Cell& b) { return distance(a) < distance(b); });
        const uint64_t whole = std::max<uint64_t>(1, sim_.hierarchy(0).chains.size());
        const size_t batch = size_t(std::max<uint64_t>(1, batch_chains / whole));
        viewer_ = viewer;
        for (size_t at = 0; at < cells.size(); at += batch) {
            const std::vector<Cell> part(cells.begin() + at, cells.begin() + std::min(cells.size(), at + batch));
            HMSM_TRY(add(part));
            HMSM_TRY(sim_.update_lod(eye()).status());
        }
        return {};
    }

    /// Adds the trees of `cells`, each on its band's level, and records their handles.
    Status add(const std::vector<Cell>& cells) {
        record_added();
        if (cells.empty()) return {};
        const std::vector<Instance> trees = trees_of(cells);
        std::vector<InstanceId> ids(cells.size());
        HMSM_TRY(sim_.add_instances(trees, ids));
        for (size_t k = 0; k < cells.size(); ++k) live_[Grid::key(cells[k].i, cells[k].j)] = ids[k];
        return {};
    }

    /// Swap-removes the trees of `cells` by handle.
    Status remove(const std::vector<Cell>& cells) {
        std::vector<InstanceId> ids;
        HMSM_TRY(take_handles(cells, ids));
        return ids.empty() ? Status{} : sim_.swap_remove_instances(ids);
    }

    /// The engine's own work before a frame's calls, not timed: the viewer moves by `move`; the
    /// cells that left the radius and those that came, the handles of the trees leaving and
    /// the trees coming, each on the level of the band its distance falls in.
    Status prepare(glm::dvec2 move) {
        record_added();
        const glm::dvec2 to = viewer_ + move;
        stream_cells(grid_, viewer_, to, leaving_, entering_);
        viewer_ = to;
        HMSM_TRY(take_handles(leaving_, gone_));
        coming_ = trees_of(entering_);
        coming_cells_ = entering_;
        return {};
    }

    /// A frame's calls after prepare(): the trees that left are swap-removed by handle, those
    /// that came are added (first, so that update_lod puts them on their level before the
    /// step); update_lod. Each call's wall time goes to `calls` (when given); `changes`
    /// receives the trees added, removed and switched.
    Status calls(Calls* calls, uint64_t* changes, uint64_t* switched) {
        const auto t0 = Clock::now();
        if (!gone_.empty()) HMSM_TRY(sim_.swap_remove_instances(gone_));
        const auto t1 = Clock::now();
        coming_ids_.resize(coming_.size());
        if (!coming_.empty()) HMSM_TRY(sim_.add_instances(coming_, coming_ids_));
        const auto t2 = Clock::now();
        Result<uint64_t> lod = sim_.update_lod(eye());
        HMSM_TRY(lod.status());
        const auto t3 = Clock::now();
        if (calls) {
            if (!gone_.empty()) calls->remove.push_back(seconds(t0, t1));
            if (!coming_.empty()) calls->add.push_back(seconds(t1, t2));
            calls->update_lod.push_back(seconds(t2, t3));
        }
        if (changes) *changes = gone_.size() + coming_.size() + *lod;
        if (switched) *switched = *lod;
        pending_ = true;  // the added trees' handles, recorded by the next prepare()
        return {};
    }

    /// One frame: prepare(), then its calls and one step (Simulation::step, blocking); the
    /// frame's time is that of the calls.
    Status frame(glm::dvec2 move, Calls* calls, uint64_t* changes, uint64_t* switched) {
        HMSM_TRY(prepare(move));
        const auto t0 = Clock::now();
        HMSM_TRY(this->calls(calls, changes, switched));
        const auto t3 = Clock::now();
        HMSM_TRY(sim_.step(1));
        const auto t4 = Clock::now();
        if (calls) {
            calls->step.push_back(seconds(t3, t4));
            calls->frame.push_back(seconds(t0, t4));
        }
        return {};
    }

    /// The same frame with the switches measured: the largest vertex jump of switched trees
    /// that were live before the frame against their motion in the step before (a fade that
    /// ended in that step switches in update_lod). `fading` receives the motion over the step of
    /// trees that were fading.
    Status pop_frame(glm::dvec2 move, const PopProbe& probe, json& jumps, std::vector<double>& fading) {
        std::vector<float> before, stepped, after;
        // Fades that ended in the frame before switch now (step() would switch them first), so
        // that the step below keeps the layout the reads around it share.
        HMSM_TRY(sim_.request_instance_lods({}, {}).status());
        HMSM_TRY(sim_.read(Output::joint_matrices, before));
        const std::vector<uint64_t> old_offsets = chain_offsets(sim_);
        const std::vector<InstanceId> old_ids(sim_.instance_ids().begin(), sim_.instance_ids().end());
        std::vector<uint32_t> old_models;
        for (const Instance& t : sim_.instances()) old_models.push_back(t.model);
        std::vector<uint32_t> fading_before;
        for (uint32_t i = 0; i < old_ids.size() && sim_.fading_instance_count() > 0; ++i)
            if (*sim_.instance_lod_target(old_ids[i]) != *sim_.instance_lod(old_ids[i])) fading_before.push_back(i);
        HMSM_TRY(sim_.step(1));
        HMSM_TRY(sim_.read(Output::joint_matrices, stepped));
        auto span_of = [](const std::vector<float>& all, const std::vector<uint64_t>& off, uint32_t at) {
            return std::span<const float>(all.data() + 12 * off[at], 12 * (off[at + 1] - off[at]));
        };
        constexpr size_t kMeasured = 64;  // trees skinned per frame, spread over those measured
        for (size_t k = 0; k < fading_before.size(); k += std::max<size_t>(1, fading_before.size() / kMeasured)) {
            const uint32_t o = fading_before[k];
            const int32_t level = probe.level_of(old_models[o]);
            if (level < 0 || sim_.instances()[o].model != old_models[o]) continue;  // switched in the step
            fading.push_back(probe.largest_jump(span_of(before, old_offsets, o), uint32_t(level),
                                                span_of(stepped, old_offsets, o), uint32_t(level)));
        }
        const glm::dvec2 to = viewer_ + move;
        stream_cells(grid_, viewer_, to, leaving_, entering_);
        viewer_ = to;
        HMSM_TRY(remove(leaving_));
        HMSM_TRY(add(entering_));
        std::vector<uint32_t> models;
        for (const Instance& t : sim_.instances()) models.push_back(t.model);
        HMSM_TRY(sim_.update_lod(eye()).status());
        HMSM_TRY(sim_.read(Output::joint_matrices, after));
        const std::vector<uint64_t> offsets = chain_offsets(sim_);
        std::unordered_map<uint64_t, uint32_t> old_index;
        for (uint32_t i = 0; i < old_ids.size(); ++i) old_index.emplace(uint64_t(old_ids[i]), i);
        std::vector<std::pair<uint32_t, uint32_t>> switched;  // (old index, index)
        for (uint32_t i = 0; i < models.size(); ++i) {
            if (sim_.instances()[i].model == models[i]) continue;
            auto was = old_index.find(uint64_t(sim_.instance_ids()[i]));
            if (was != old_index.end()) switched.emplace_back(was->second, i);
        }
        const size_t stride = std::max<size_t>(1, switched.size() / kMeasured);
        for (size_t k = 0; k < switched.size(); k += stride) {
            const auto [o, i] = switched[k];
            const int32_t from = probe.level_of(old_models[o]), into = probe.level_of(sim_.instances()[i].model);
            if (from < 0 || into < 0) return Status{ErrorCode::internal, "open world: a tree on no level of model 0"};
            const double motion = probe.largest_jump(span_of(before, old_offsets, o), uint32_t(from),
                                                     span_of(stepped, old_offsets, o), uint32_t(from));
            const double jump = probe.largest_jump(span_of(stepped, old_offsets, o), uint32_t(from),
                                                   span_of(after, offsets, i), uint32_t(into));
            jumps.push_back({{"from", from}, {"to", into}, {"jump_m", jump}, {"motion_m", motion}});
        }
        return sim_.step(1);
    }

    Vec3 eye() const { return Vec3(viewer_.x, 0.0, viewer_.y); }

private:
    /// The trees of `cells`, each on the level its distance to the viewer falls in (the bands
    /// without hysteresis, as an engine streaming trees in would ask).
    std::vector<Instance> trees_of(const std::vector<Cell>& cells) const {
        std::vector<Instance> trees;
        trees.reserve(cells.size());
        const std::vector<double>& edges = sim_.lod_bands().edges;
        for (const Cell& c : cells) {
            Instance tree = grid_.tree(c.i, c.j);
            const double distance = glm::length(glm::dvec3(tree.origin) - glm::dvec3(eye()));
            const auto band = uint32_t(std::upper_bound(edges.begin(), edges.end(), distance) - edges.begin());
            tree.level = std::min(band, sim_.lod_level_count(tree.model) - 1);
            trees.push_back(tree);
        }
        return trees;
    }
    /// The handles of the trees of `cells`, which are no longer live once the caller removes them.
    Status take_handles(const std::vector<Cell>& cells, std::vector<InstanceId>& ids) {
        record_added();
        ids.clear();
        ids.reserve(cells.size());
        for (const Cell& c : cells) {
            auto found = live_.find(Grid::key(c.i, c.j));
            if (found == live_.end()) return Status{ErrorCode::internal, "open world: a leaving tree is not live"};
            ids.push_back(found->second);
            live_.erase(found);
        }
        return {};
    }
    /// The handles the last calls() added, by their cells.
    void record_added() {
        if (!pending_) return;
        for (size_t k = 0; k < coming_cells_.size(); ++k)
            live_[Grid::key(coming_cells_[k].i, coming_cells_[k].j)] = coming_ids_[k];
        pending_ = false;
    }

    Simulation& sim_;
    Grid grid_;
    glm::dvec2 viewer_{0.0};
    std::unordered_map<uint64_t, InstanceId> live_;
    std::vector<Cell> leaving_, entering_, coming_cells_;
    std::vector<InstanceId> gone_, coming_ids_;
    std::vector<Instance> coming_;
    bool pending_ = false;  // coming_ids_ not yet in live_
};

json run_backend(const TreeModel& model, const std::string& model_name, BackendKind kind,
                 const OpenWorldSettings& s) {
    json row = {{"backend", to_string(kind)}, {"model", model_name}, {"trees_asked", s.trees}};
    auto stop = [&](const Status& status) {
        row[status.code() == ErrorCode::out_of_memory || status.code() == ErrorCode::unsupported ||
                    status.code() == ErrorCode::no_device
                ? "skipped"
                : "failed"] = status.message();
        return row;
    };
    Grid grid;
    grid.spacing = s.spacing > 0.0 ? s.spacing : 25.0;
    grid.radius = grid.spacing * std::sqrt(double(s.trees) / std::numbers::pi);
    // Band edges where the cumulative shares of a disc of trees around the viewer are reached.
    LodBands bands;
    bands.hysteresis = 0.05;
    bands.fade_steps = s.fade_steps;
    bands.fade_bound_m = s.fade_bound_m;
    double cumulative = 0.0;
    for (size_t k = 0; k + 1 < std::size(kOpenWorldShares); ++k) {
        cumulative += kOpenWorldShares[k];
        bands.edges.push_back(grid.radius * std::sqrt(cumulative));
    }
    // Speed: trees cross a circle of radius r moving by v at 4 r v / spacing^2 per frame (in and
    // out); streaming adds and removes at the radius (arrivals come on their level), and every
    // band edge switches its crossers.
    double crossing = 4.0 * grid.radius;
    for (double edge : bands.edges) crossing += 4.0 * edge;
    const double speed = double(s.changes) * grid.spacing * grid.spacing / crossing;
    const glm::dvec2 direction = glm::normalize(glm::dvec2(1.0, 0.31));
    row["spacing"] = grid.spacing;
    row["radius_m"] = grid.radius;
    row["band_edges_m"] = bands.edges;
    row["hysteresis"] = bands.hysteresis;
    row["fade_steps"] = bands.fade_steps;
    row["fade_bound_m"] = bands.fade_bound_m;
    row["viewer_m_per_frame"] = speed;
    row["changes_asked"] = s.changes;
    row["level_budgets"] = {0, kOpenWorldBudgets[0], kOpenWorldBudgets[1], kOpenWorldBudgets[2], kOpenWorldBudgets[3]};
    row["level_shares_asked"] = kOpenWorldShares;

    Scene scene = single_tree_scene(model);
    scene.instances.clear();
    scene.instances.push_back(grid.tree(0, 0));  // the tree under the viewer; the rest is streamed in
    scene.lod_budgets = {{std::begin(kOpenWorldBudgets), std::end(kOpenWorldBudgets)}};
    SimulationConfig config;
    config.backend = kind;
    config.outputs = Outputs::joints;
    config.instance_layout = s.layout;
    row["instance_layout"] = to_string(s.layout);
    auto created = Simulation::create(scene, config);
    if (!created) return stop(created.status());
    Simulation& sim = **created;
    row["device"] = sim.device_name();
    const std::vector<LevelShape> levels = level_shapes(sim);
    // The memory the case will take, from this one-tree simulation, before anything is added.
    const json estimate = memory_json(sim, levels, kOpenWorldShares, s.trees);
    row["memory"] = estimate;
    const double available = host_available_memory();
    if (uses_host_memory(kind, sim.device_name()) && available > 0.0 &&
        estimate["estimate_device_bytes"].get<double>() > 0.6 * available) {
        char reason[200];
        std::snprintf(reason, sizeof reason, "needs about %.1f GB of host memory, %.1f GB available",
                      estimate["estimate_device_bytes"].get<double>() * 1e-9, available * 1e-9);
        return stop(Status{ErrorCode::out_of_memory, reason});
    }
    if (Status status = sim.set_lod_bands(bands); !status) return stop(status);
    // Room up front, as an engine that knows its budget reserves it (docs/driving.md, streaming
    // budgets): twice each level's asked share of the trees, since a world's shares follow its
    // bands (on the H200's 500,000 trees 0.72-0.84 % full against 0.5 % asked) and a tree fading
    // to a coarser level holds both. Growth past the room is timed by the live-control case.
    std::vector<uint64_t> per_level;
    for (size_t k = 0; k < levels.size(); ++k)
        per_level.push_back(uint64_t(std::ceil(2.0 * double(s.trees) * kOpenWorldShares[k])));
    const auto reserving = Clock::now();
    if (Status status = sim.reserve_instances(per_level); !status) return stop(status);
    row["reserve_seconds"] = seconds(reserving, Clock::now());
    row["reserved_per_level"] = per_level;
    OpenWorld world(sim, grid);
    const auto setup = Clock::now();
    // Trees come in on their levels, in batches of half the chains the case will run.
    double expected_chains = 0.0;
    for (size_t k = 0; k < levels.size(); ++k) expected_chains += double(s.trees) * kOpenWorldShares[k] * double(levels[k].chains);
    if (Status status = world.populate({0.0, 0.0}, uint64_t(expected_chains / 2.0)); !status) return stop(status);
    row["setup_seconds"] = seconds(setup, Clock::now());

    // Warm-up frames moving (capacity grown, pools and graphs made), timed frames moving, timed
    // frames standing still.
    const glm::dvec2 move = direction * speed;
    const uint32_t warmup = std::min<uint32_t>(20, std::max<uint32_t>(2, s.frames / 5));
    for (uint32_t k = 0; k < warmup; ++k)
        if (Status status = world.frame(move, nullptr, nullptr, nullptr); !status) return stop(status);
    Calls moving, still;
    std::vector<double> changes, switched;
    const uint64_t uploads = detail::full_uploads_of(sim), growths = detail::device_growths_of(sim);
    for (uint32_t k = 0; k < s.frames; ++k) {
        uint64_t changed = 0, lod = 0;
        if (Status status = world.frame(move, &moving, &changed, &lod); !status) return stop(status);
        changes.push_back(double(changed));
        switched.push_back(double(lod));
    }
    row["scene_uploads"] = detail::full_uploads_of(sim) - uploads;
    row["device_growths"] = detail::device_growths_of(sim) - growths;
    // Standing still, untimed until the fades the moving frames started have ended and switched
    // (a frame then makes no change at all: the baseline the changes are measured against; at
    // most 1,000 frames, the fades still under way then reported).
    for (uint32_t k = 0; k <= std::min<uint32_t>(s.fade_steps, 1000) && sim.fading_instance_count() > 0; ++k)
        if (Status status = world.frame({0.0, 0.0}, nullptr, nullptr, nullptr); !status) return stop(status);
    row["fading_after_settling"] = sim.fading_instance_count();
    for (uint32_t k = 0; k < std::min<uint32_t>(s.frames, 100); ++k)
        if (Status status = world.frame({0.0, 0.0}, &still, nullptr, nullptr); !status) return stop(status);

    if (Status status = profile_standing_step(sim, row); !status) return stop(status);

    // Moving again as an engine drives its frames (CUDA: the step enqueued on its stream;
    // Vulkan: recorded into its command buffer, the changes held back and recorded with it),
    // after the standing frames of the same path: each frame's changes and step call, and the
    // frame until its outputs are ready.
    json engine_moving = json::array();
    for (const std::unique_ptr<FrameDriver>& driver : engine_drivers(sim)) {
        Calls calls;
        const FrameChange prepare = [&](Simulation&, uint32_t) { return world.prepare(move); };
        const FrameChange change = [&](Simulation&, uint32_t) { return world.calls(&calls, nullptr, nullptr); };
        FrameTimes warm, times;
        if (Status status = time_frames(sim, *driver, warmup, change, warm, prepare); !status) return stop(status);
        calls = {};
        const uint64_t uploads_before = detail::full_uploads_of(sim), growths_before = detail::device_growths_of(sim);
        if (Status status = time_frames(sim, *driver, std::min<uint32_t>(s.frames, 100), change, times, prepare); !status)
            return stop(status);
        double standing = 0.0;
        for (const json& e : row["still_engine"])
            if (e.value("path", std::string()) == driver->path()) standing = e.value("frame_median_seconds", 0.0);
        engine_moving.push_back({{"path", driver->path()},
                                 {"calls",
                                  {{"update_lod", distribution(calls.update_lod)},
                                   {"swap_remove", distribution(calls.remove)},
                                   {"add", distribution(calls.add)},
                                   {"changes_and_step_call", distribution(times.call)},
                                   {"frame", distribution(times.whole)}}},
                                 {"changes_add_seconds", percentile(times.whole, 0.5) - standing},
                                 {"scene_uploads", detail::full_uploads_of(sim) - uploads_before},
                                 {"device_growths", detail::device_growths_of(sim) - growths_before}});
    }
    row["engine_moving"] = engine_moving;

    row["frames"] = s.frames;
    row["warmup_frames"] = warmup;
    row["instances"] = sim.instance_count();
    row["chains"] = sim.chain_count();
    row["changes_per_frame"] = {{"median", percentile(changes, 0.5)},
                                {"max", *std::max_element(changes.begin(), changes.end())}};
    row["lod_switches_per_frame"] = {{"median", percentile(switched, 0.5)},
                                     {"max", *std::max_element(switched.begin(), switched.end())}};
    row["calls"] = {{"update_lod", distribution(moving.update_lod)}, {"swap_remove", distribution(moving.remove)},
                    {"add", distribution(moving.add)},               {"step", distribution(moving.step)},
                    {"frame", distribution(moving.frame)}};
    row["still"] = {{"update_lod", distribution(still.update_lod)}, {"step", distribution(still.step)},
                    {"frame", distribution(still.frame)}};
    row["changes_add_seconds"] = percentile(moving.frame, 0.5) - percentile(still.frame, 0.5);
    std::vector<double> shares(levels.size(), 0.0);
    for (const Instance& t : sim.instances())
        for (size_t k = 0; k < levels.size(); ++k)
            if (levels[k].run_model == t.model) shares[k] += 1.0 / double(sim.instance_count());
    row["level_shares"] = shares;
    // What the scene holds after the frames (host: the peak before the roofline's own blocks).
    json memory = memory_json(sim, levels, kOpenWorldShares, s.trees);
    memory.erase("levels");
    row["memory_after"] = memory;

    // Bytes per step of the passes that run (1-5) against the copy roofline.
    const Traffic traffic = step_traffic(sim);
    double bytes = 0.0;
    for (Pass p : kAllPasses)
        if (p != Pass::node_world && p != Pass::contour) bytes += traffic.pass_bytes[uint32_t(p)];
    row["bytes_per_step"] = bytes;
    const double step_median = percentile(still.step, 0.5);
    if (step_median > 0.0) row["effective_bandwidth"] = bytes / step_median;
    Result<CopyBandwidth> copy = uses_host_memory(kind, sim.device_name())
                                     ? host_memcpy_bandwidth(s.host_copy_bytes, 5)
                                     : device_copy_bandwidth(sim, s.device_copy_bytes);
    if (copy) {
        row["copy_bandwidth"] = copy->bytes_per_second;
        row["copy_method"] = copy->method;
        if (step_median > 0.0) row["copy_bandwidth_fraction"] = bytes / step_median / copy->bytes_per_second;
    }

    // The pop, on frames of their own (read-backs and host skinning are not timed).
    auto probe = PopProbe::create(sim, model, kOpenWorldBudgets);
    if (!probe) {
        row["pop"] = {{"failed", probe.status().message()}};
    } else {
        json jumps = json::array();
        std::vector<double> fading;
        for (uint32_t k = 0; k < s.pop_frames; ++k)
            if (Status status = world.pop_frame(move, *probe, jumps, fading); !status) return stop(status);
        row["pop"] = pop_json(jumps, fading);
    }
    return row;
}

}  // namespace

json measure_open_world(const TreeModel& model, const std::string& model_name,
                        const std::vector<BackendKind>& backends, const OpenWorldSettings& settings) {
    json rows = json::array();
    for (BackendKind kind : backends) rows.push_back(run_backend(model, model_name, kind, settings));
    return rows;
}

}  // namespace hmsm::cli::bench
