// hmsm bench --open-world: what the open-world case measures besides time (bench_open_world.h):
// the memory a scene takes, the vertex jump of a level switch, skinned on the host from the
// joint matrices as an engine skins them (hmsm/skin.h), and where a standing step's time goes.
#pragma once

#include <hmsm/hmsm.h>

#include <nlohmann/json.hpp>

#include <cstdint>
#include <span>
#include <vector>

namespace hmsm::cli::bench {

/// Per level of scene model 0: its run model and what one instance of it holds: chains, the
/// nodes its state keeps (with joints alone only the chains' attach nodes) and mesh vertices.
struct LevelShape {
    uint32_t run_model = 0;
    uint64_t chains = 0, nodes = 0, vertices = 0;
};
std::vector<LevelShape> level_shapes(const Simulation& sim);

/// Bytes the simulation allocates (state, instance and model buffers, at their capacities),
/// the bytes per chain, node, vertex and instance behind them, the estimate for `trees` trees
/// at the levels' `shares` and for as many whole trees, and the largest tree count the
/// library's element limits let this model reach. Host: the process's peak resident memory.
nlohmann::json memory_json(const Simulation& sim, const std::vector<LevelShape>& levels,
                           std::span<const double> shares, uint64_t trees);

/// The skins of every level of scene model 0, to pose switched trees on the host.
class PopProbe {
public:
    /// Fails when a level's skin does not match the simulation's level (joint counts).
    static Result<PopProbe> create(const Simulation& sim, const TreeModel& tree,
                                   std::span<const int32_t> budgets);
    /// The level of run model `model` (or none).
    int32_t level_of(uint32_t model) const;
    /// The largest distance a vertex moves between two poses of one tree: `a` on level
    /// `level_a` and `b` on `level_b`, each the tree's joint matrices (12 floats per chain).
    double largest_jump(std::span<const float> a, uint32_t level_a, std::span<const float> b,
                        uint32_t level_b) const;

private:
    std::vector<SkinTemplate> skins_;
    std::vector<int32_t> level_of_model_;
};

/// The value at rank ceil(p n) of `values` (p in (0, 1]; 0.5: the median), 0 when empty.
double percentile(std::vector<double> values, double p);

/// Summary of a run's level switches: `jumps` holds one object per measured switch (from, to,
/// jump_m, motion_m); `fading` the motion over one frame of trees that were fading.
nlohmann::json pop_json(const nlohmann::json& jumps, const std::vector<double>& fading);

/// Where a standing step's time goes, into `row`, after half a second of steps that bring a
/// GPU's clock up: ten profiled steps' device seconds per pass
/// (still_pass_seconds), the scene's groups and dispatches per step, and the step as an engine
/// issues it (still_engine: CUDA enqueued on its stream, Vulkan recorded into its command
/// buffer; the host time of the call and the whole frame, medians of 20).
Status profile_standing_step(Simulation& sim, nlohmann::json& row);

/// Per instance of `sim`, the first of its chains (instance-major), and the total at the end.
std::vector<uint64_t> chain_offsets(const Simulation& sim);

}  // namespace hmsm::cli::bench
