// hmsm bench --open-world: an open world as an engine drives it. Trees stand on an endless
// square grid; those within a streaming radius of a moving viewer are simulated (about
// `trees` of them), joints only, with levels of detail chosen by distance bands. Each frame
// the viewer moves, the trees that left the radius are swap-removed by handle and those that
// entered are added, update_lod(viewer) puts every tree on its band's level, and one step
// runs. Per call the median, p99 and max wall time; the same frames with the viewer standing
// still; the LOD-switch pop against the per-frame motion; bytes per step against the copy
// roofline; and the memory the scene takes.
#pragma once

#include <hmsm/hmsm.h>

#include <nlohmann/json.hpp>

#include <cstdint>
#include <string>
#include <vector>

namespace hmsm::cli::bench {

/// Joint budgets of the open world's levels 1..4 (level 0 is the whole model).
inline constexpr int32_t kOpenWorldBudgets[] = {256, 64, 16, 1};
/// Share of the trees asked on each level 0..4, nearest first: 0.5 % whole, 2 % at 256 joints,
/// 10 % at 64, the rest split evenly between 16 joints and the trunk alone.
inline constexpr double kOpenWorldShares[] = {0.005, 0.02, 0.10, 0.4375, 0.4375};

struct OpenWorldSettings {
    uint32_t trees = 500000;   ///< trees within the streaming radius
    uint32_t frames = 300;     ///< timed frames with the viewer moving (and as many standing still, at most 100)
    uint32_t changes = 2000;   ///< streaming and LOD changes per frame the viewer's speed is set for
    double spacing = 25.0;     ///< grid spacing (m)
    uint32_t pop_frames = 3;   ///< frames whose switches are measured for the pop (untimed)
    /// LodBands::fade_steps of coarsening switches; 0: instantaneous switches
    uint32_t fade_steps = LodBands{}.fade_steps;
    /// LodBands::fade_bound_m: a coarsening tree deflected less switches at once (measured with a
    /// read of its state); 0, as an engine sets it for a world in wind: nothing is read, every
    /// coarsening fades
    double fade_bound_m = 0.0;
    InstanceLayout layout = InstanceLayout::placed;  ///< SimulationConfig::instance_layout
    uint64_t device_copy_bytes = 1 << 30, host_copy_bytes = 256 << 20;  ///< roofline block sizes
};

/// Settings from the --open-world-* flags (without `changes_given`: 2,000 per 500,000 trees);
/// a value out of range is invalid_argument naming the flag.
Result<OpenWorldSettings> open_world_settings(int64_t trees, int64_t frames, int64_t changes, bool changes_given,
                                              int64_t fade_steps = LodBands{}.fade_steps,
                                              double fade_bound_m = 0.0);

/// One JSON row per backend (or one skipped row naming why the case does not run there).
nlohmann::json measure_open_world(const TreeModel& model, const std::string& model_name,
                                  const std::vector<BackendKind>& backends, const OpenWorldSettings& settings);

/// The markdown tables of measure_open_world's rows ("" when there are none).
std::string render_open_world(const nlohmann::json& rows);

}  // namespace hmsm::cli::bench
