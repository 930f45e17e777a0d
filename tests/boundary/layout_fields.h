// The public structs and their members whose layout must not depend on the consumer's GLM
// settings: X(struct, member) for each, compiled once with GLM's defaults (as the library is)
// and once with GLM_FORCE_* (layout_test.cpp).
#pragma once

#include <hmsm/hmsm.h>

#include <cstddef>
#include <vector>

#define HMSM_LAYOUT_FIELDS(X)                                                              \
    X(TreeNode, parent) X(TreeNode, position) X(TreeNode, radius)                          \
    X(TreeLeaf, node) X(TreeLeaf, offset) X(TreeLeaf, normal) X(TreeLeaf, up) X(TreeLeaf, size) \
    X(Instance, model) X(Instance, origin) X(Instance, yaw) X(Instance, wind_scale)        \
    X(Instance, wind_phase) X(Instance, active)                                            \
    X(Wind, profile) X(Wind, direction) X(Wind, strength) X(Wind, frequency)               \
    X(Wind, front_speed) X(Wind, turbulence) X(Wind, seed)                                 \
    X(Parameters, density) X(Parameters, dt) X(Parameters, max_frequency)                  \
    X(Parameters, material) X(Parameters, foliage) X(Parameters, wood_drag_coefficient)    \
    X(ModelOptions, ring_sides) X(ModelOptions, fix_weight) X(ModelOptions, dynamics)      \
    X(ForceField, kind) X(ForceField, center) X(ForceField, radius)                        \
    X(ForceField, directional) X(ForceField, radial)                                       \
    X(Chain, members) X(Chain, frame) X(Chain, rest_rotation) X(Chain, length)             \
    X(Chain, capped) X(Chain, dynamics) X(ChainDynamics, wind_moment)                      \
    X(ChainDynamics, first_child)                                                          \
    X(Hierarchy, node_owner) X(Hierarchy, node_local) X(Hierarchy, max_depth)              \
    X(MeshVertex, position) X(MeshVertex, normal) X(MeshVertex, parent_position)           \
    X(MeshVertex, parent_normal)                                                           \
    X(MeshTemplate, indices) X(MeshTemplate, leaf_count)                                   \
    X(SimulationConfig, model) X(SimulationConfig, parameters) X(SimulationConfig, wind)   \
    X(SimulationConfig, composition) X(SimulationConfig, profile_passes)                   \
    X(Scene, instances) X(Scene, joint_budgets) X(Scene, lod_budgets)                      \
    X(LodBands, edges) X(LodBands, hysteresis) X(LodBands, fade_steps)                     \
    X(LodBands, fade_bound_m)                                                              \
    X(DetailLevel, hierarchy) X(DetailLevel, chain_of) X(DetailLevel, geometric_error_m)

#define HMSM_LAYOUT_STRUCTS(X)                                                             \
    X(TreeNode) X(TreeLeaf) X(TreeModel) X(Instance) X(Scene) X(Wind) X(Parameters)        \
    X(ModelOptions) X(Material) X(Foliage) X(ForceField) X(ChainDynamics) X(Chain) X(Hierarchy) X(MeshVertex) X(MeshTemplate)      \
    X(SimulationConfig) X(PassTimes) X(DetailLevel) X(LodBands) X(Vec2) X(Vec3) X(Mat3)

/// sizeof and alignof of every struct, then offsetof of every field, in list order.
#define HMSM_LAYOUT_SIZE(s) sizeof(hmsm::s), alignof(hmsm::s),
#define HMSM_LAYOUT_OFFSET(s, m) offsetof(hmsm::s, m),
#define HMSM_LAYOUT_VALUES {HMSM_LAYOUT_STRUCTS(HMSM_LAYOUT_SIZE) HMSM_LAYOUT_FIELDS(HMSM_LAYOUT_OFFSET)}

/// The layout as seen with GLM's defaults and with the consumer's GLM_FORCE_* settings, and the
/// node positions of one simulation whose scene and config were built in each.
std::vector<size_t> layout_default();
std::vector<size_t> layout_forced();
std::vector<double> simulate_default();
std::vector<double> simulate_forced();
