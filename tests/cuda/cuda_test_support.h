// Scenes, configurations and comparisons shared by the CUDA tests.
#pragma once

#include <hmsm/hmsm.h>

#include "backend.h"

#include <gtest/gtest.h>

#include <string>
#include <vector>

namespace hmsm::cuda_test {

/// A random but valid tree: a trunk and `node_count` nodes in all, branching at random with
/// real-world sizes (about 10 m tall), and `leaf_count` leaf cards. Counts are chosen by the
/// callers so that no element count is a multiple of the block size.
TreeModel random_tree(uint64_t seed, int node_count, int leaf_count);

/// Two random models in five instances (model order 0 0 1 1 0: three dispatch groups), at
/// scattered origins and yaws.
Scene forest_scene(uint64_t seed);

/// An open world in small: `instances` instances alternating between the two models of
/// forest_scene, each model with one coarser level of detail (Scene::lod_budgets), at scattered
/// origins and yaws. With alternate_levels, consecutive instances never share a run model, so
/// every instance is a group of its own.
Scene many_groups_scene(uint64_t seed, uint32_t instances);

/// Puts every instance i with (i / 2) odd on its level 1: the run models go small, large, small
/// coarse, large coarse, ...
void alternate_levels(Simulation& sim);

/// Batched launches against single ones: steps `single` (runs dispatch by dispatch), `batched`
/// and the cpu64 `reference`, all of many_groups_scene, call by call (a few steps each; the
/// levels alternated first, one instance paused for the last calls, so that some entries cover
/// paused instances), and expects the batched outputs bit for bit the single ones and within
/// docs/model.md 7's bound of the reference's.
void expect_batches_match_single_launches(Simulation& single, Simulation& batched, Simulation& reference);

/// Wind strong enough that chains bend visibly, with a travelling front so every instance has
/// its own phase.
SimulationConfig test_config(BackendKind backend, Composition composition, bool profile);

/// The live changes the walk-ahead tests make between calls, each at its call: the wind made
/// stronger, a force field, an instance's wind scale, instance 1 paused and resumed, one instance
/// added, then a field that moves before every call from `moving_from` to `moving_to` (a
/// character walking) and calm again. Calls step once, every fourth three times, and the call
/// `long_call` runs `long_steps` steps.
struct LiveScript {
    uint32_t wind, field, scale, pause, resume, add, moving_from, moving_to, long_call, long_steps;
};

/// Makes call k's changes of `script` to `sim` (the added instance is scene's first) and steps it.
void run_live_call(Simulation& sim, const Scene& scene, const LiveScript& script, uint32_t k);

/// Message of the CUDA backend's no_device error, or empty when a CUDA device is present.
std::string no_cuda_device_reason();

/// Largest |a - b| over two arrays of the same size; infinity on a NaN or a size mismatch.
double max_abs_difference(const std::vector<double>& a, const std::vector<double>& b);

/// Rest-pose height of every model of the scene, the largest: docs/model.md 7's error scale.
double scene_height(const Scene& scene);

}  // namespace hmsm::cuda_test

/// Every CUDA test starts with this: without a device it skips and says why.
#define HMSM_SKIP_WITHOUT_CUDA()                                                       \
    do {                                                                              \
        const std::string hmsm_no_cuda_ = ::hmsm::cuda_test::no_cuda_device_reason();  \
        if (!hmsm_no_cuda_.empty()) GTEST_SKIP() << hmsm_no_cuda_;                     \
    } while (0)
