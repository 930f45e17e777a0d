// A scene flattened into the 1-D arrays of gpu_layout.h, in double precision. Built once by the
// Simulation from the hierarchies and meshes; every backend uploads it (converting to its own
// precision) and never sees trees or chains again.
#pragma once

#include "buffers.h"

#include <hmsm/hierarchy.h>
#include <hmsm/mesh.h>
#include <hmsm/options.h>
#include <hmsm/scene.h>
#include <hmsm/config.h>

#include <glm/mat3x3.hpp>
#include <glm/vec2.hpp>
#include <glm/vec4.hpp>

#include <cstdint>
#include <utility>
#include <span>
#include <vector>

namespace hmsm::detail {

/// Static data of one model, as offsets into the concatenated model arrays.
struct ModelRange {
    uint32_t chain_begin = 0, chain_count = 0;
    /// The model's state nodes (stepped_nodes): its tree's nodes, or with joints alone only the
    /// chains' attach nodes.
    uint32_t node_begin = 0, node_count = 0;
    uint32_t vertex_begin = 0, vertex_count = 0;
    /// Model chains of each depth level: [level_begin[d], level_begin[d + 1]).
    std::vector<uint32_t> level_begin;
};

/// A run of consecutive instances of one model: the unit of one dispatch.
struct InstanceGroup {
    uint32_t model = 0;
    uint32_t instance_begin = 0, instance_count = 0;
    uint32_t chain_begin = 0, node_begin = 0, vertex_begin = 0;  // state offsets
    /// Some of its instances are paused: its dispatches skip them (gpu_layout.h PassConstants.params).
    bool covers_paused = false;
    /// A listed group (listed_groups): its instances are entries [instance_begin, instance_begin
    /// + instance_count) of the instance table, wherever they lie; the state offsets are unused.
    bool listed = false;
};

struct SceneData {
    // Model-scope arrays (every model's data concatenated).
    std::vector<int32_t> chain_parent;
    std::vector<int32_t> chain_jump;  // jump_rounds x total_model_chains, round-major
    std::vector<int32_t> chain_walk;  // HMSM_WALK_RECORD_INTS per model chain (gpu_layout.h)
    /// Each chain's attach node as a model node of node_owner and node_local (stepped_nodes).
    std::vector<int32_t> chain_attach;
    std::vector<glm::dmat3> chain_rest_rotation;
    /// Per model chain: its keep rank, the rank of the coarsest level of its scene model that
    /// keeps it (gpu_layout.h HMSM_FADE_*; the simulation fills it, empty reads as 0).
    std::vector<uint32_t> chain_keep_level;
    std::vector<glm::dvec4> chain_constants;  // (I, K, D, A)
    /// Dynamics::coupled: HMSM_CHAIN_DYNAMICS_VEC4S x 4 scalars per model chain (gpu_layout.h);
    /// empty under the paper's dynamics.
    std::vector<double> chain_dynamics;
    /// Exchange::articulated: HMSM_CHAIN_ARTICULATED_VEC4S x 4 scalars per model chain
    /// (gpu_layout.h; on the devices in chain_dynamics' place); empty otherwise.
    std::vector<double> chain_articulated;
    /// Per model node (the model's stepped_nodes, in that order): owner chain and l_n.
    std::vector<int32_t> node_owner;
    std::vector<glm::dvec4> node_local;
    std::vector<glm::ivec2> vertex_chain;
    std::vector<glm::dvec4> vertex_rest_position;
    std::vector<glm::dvec4> vertex_rest_normal;
    std::vector<glm::dvec4> vertex_parent_position;
    std::vector<glm::dvec4> vertex_parent_normal;
    // Instance-scope arrays.
    std::vector<glm::dvec4> instance_origin;  // (origin, 0)
    std::vector<glm::dvec4> instance_yaw;     // (cos, sin, 0, 0)
    /// 36 scalars per instance (gpu_layout.h HMSM_BINDING_INSTANCE_WIND), filled by the
    /// simulation's wind (live_wind.h); zero from flatten_scene.
    std::vector<double> instance_wind;

    std::vector<ModelRange> models;
    std::vector<InstanceGroup> groups;

    uint32_t jump_rounds = 1;
    uint64_t total_chains = 0, total_nodes = 0, total_vertices = 0;  // state element counts
    /// Allocated state (>= the live counts above; flatten_scene makes them equal): instances
    /// may be added up to these without reallocating (live_control.cpp). The two ping-pong
    /// halves of chain_rotation and chain_origin lie chain_capacity elements apart.
    uint64_t chain_capacity = 0, node_capacity = 0, vertex_capacity = 0;
    uint32_t instance_capacity = 0;
    /// The placed layout (SimulationConfig::instance_layout, instance_placements.h): one past
    /// the highest element an instance's slot holds, per scope, free slots included; 0 in the
    /// packed layout, where the live totals end the elements held.
    uint64_t placed_chain_end = 0, placed_node_end = 0, placed_vertex_end = 0;
    /// The elements below which every instance lies (what a growth keeps, what read() reads).
    uint64_t chains_held() const { return placed_chain_end > total_chains ? placed_chain_end : total_chains; }
    uint64_t nodes_held() const { return placed_node_end > total_nodes ? placed_node_end : total_nodes; }
    uint64_t vertices_held() const { return placed_vertex_end > total_vertices ? placed_vertex_end : total_vertices; }
    /// Takes `laid`'s instance layout (lay_out_instances: instance origins, yaws and winds,
    /// groups and the live totals), keeping these models and capacities.
    void take_instance_layout(SceneData&& laid) {
        instance_origin = std::move(laid.instance_origin);
        instance_yaw = std::move(laid.instance_yaw);
        instance_wind = std::move(laid.instance_wind);
        groups = std::move(laid.groups);
        total_chains = laid.total_chains;
        total_nodes = laid.total_nodes;
        total_vertices = laid.total_vertices;
        placed_chain_end = placed_node_end = placed_vertex_end = 0;  // packed anew
    }
    /// Capacities equal to the live counts (flatten_scene; tests that build a SceneData).
    void fit_capacity() {
        chain_capacity = total_chains;
        node_capacity = total_nodes;
        vertex_capacity = total_vertices;
        instance_capacity = instance_count();
    }
    /// Whether `live` counts fit in this scene's capacities.
    bool holds(const SceneData& live) const {
        return live.total_chains <= chain_capacity && live.total_nodes <= node_capacity &&
               live.total_vertices <= vertex_capacity && live.instance_count() <= instance_capacity;
    }
    uint32_t instance_count() const { return static_cast<uint32_t>(instance_origin.size()); }
    uint32_t total_model_chains() const { return static_cast<uint32_t>(chain_parent.size()); }

    // Uniforms (double; GPU backends use the float copies in PassConstants).
    double dt = 1.0 / 120.0;
    double max_angle = 0.8;
    double fix_weight = 0.5;
    WindProfile profile = WindProfile::none;
    Dynamics dynamics = Dynamics::paper;
    Exchange exchange = Exchange::held;
    bool coupled() const { return dynamics == Dynamics::coupled; }
    bool articulated() const { return coupled() && exchange == Exchange::articulated; }
    /// Whether chain_load holds the held exchange's loads, which a step reads from the last one
    /// (the articulated exchange keeps only scratch of a step there).
    bool holds_loads() const { return coupled() && !articulated(); }
    /// The contour pass's output layout; packed leaves vertex_normal without elements.
    VertexLayout vertex_layout = VertexLayout::separate;
    bool packed_vertices() const { return vertex_layout == VertexLayout::packed; }
    /// What a step produces: without nodes node_world has no elements and each model keeps
    /// only its stepped_nodes (node_relative then holds the chains' attach nodes alone), without
    /// vertices the vertex-scope state buffers have none.
    Outputs outputs = Outputs::all;
    bool produces_nodes() const { return outputs != Outputs::joints; }
    bool produces_vertices() const { return outputs == Outputs::all; }

    /// Elements allocated for buffer `id` (vec4/mat/int elements, not scalars): state and
    /// instance buffers are sized by the capacities.
    uint64_t element_count(BufferId id) const;
};

}  // namespace hmsm::detail

namespace hmsm::detail {

/// The tree nodes of `h` whose state a step that produces `outputs` keeps, ascending: every
/// node where node positions are produced; with joints alone the distinct attach nodes of the
/// chains, the only nodes the passes then read (root_positions gathers u of each chain's attach
/// node, the path walks read its l; node_world, which reads every node, does not run).
std::vector<int32_t> stepped_nodes(const Hierarchy& h, Outputs outputs);

/// Flattens models and instances (docs/model.md 2: ordered chain-by-depth, instance-major state),
/// each model with its stepped_nodes for `outputs` (and d.outputs = `outputs`). `instances`
/// name the models they run (hierarchies' indices: a level's run model where they start on
/// one). Groups are runs of consecutive instances of one model, split so that no dispatch
/// exceeds `max_group_elements` threads.
SceneData flatten_scene(std::span<const Instance> instances, const std::vector<Hierarchy>& hierarchies,
                        const std::vector<MeshTemplate>& meshes, const Parameters& parameters,
                        const ModelOptions& options, const Wind& wind, Outputs outputs,
                        uint64_t max_group_elements = (1ull << 31));

/// Lays out `instances` over d's models: instance_origin, instance_yaw, a zero instance_wind,
/// groups and the total chain, node and vertex counts (flatten_scene's instance part; a live
/// change lays out the new list without flattening the models again).
void lay_out_instances(SceneData& d, std::span<const Instance> instances,
                       uint64_t max_group_elements = (1ull << 31));

/// lay_out_instances' groups and total chain, node and vertex counts alone, leaving the
/// instance arrays as they are: for a change that keeps every instance's place, origin and yaw
/// (a level switch).
void lay_out_groups(SceneData& d, std::span<const Instance> instances, uint64_t max_group_elements = (1ull << 31));

/// The largest dispatch lay_out_groups' default makes: threads of one group.
inline constexpr uint64_t kMaxGroupElements = uint64_t(1) << 31;

/// d.groups and the live totals after a change of the instance list from the one d.groups
/// describes to `instances`: the instances `changed` (ascending, each below instances.size())
/// may have another model, every instance past the old list is listed, the old list may be cut
/// to instances.size(), and every other instance keeps its model. Gives lay_out_groups'
/// groups (under its default largest dispatch) in O(groups + changed), reading `instances`
/// only at `changed`.
void relay_groups(SceneData& d, std::span<const Instance> instances, std::span<const uint32_t> changed);

/// The part of `group` (a group of d) covering its instances [first, first + count), with its
/// state offsets. Its covers_paused is false: its dispatches read no paused flag, so paused
/// instances in it are computed too.
InstanceGroup group_slice(const SceneData& d, const InstanceGroup& group, uint32_t first, uint32_t count);

/// The slices of d's groups covering the instances `indices` (ascending, each once, each below
/// d.instance_count()), neighbours in one group as one slice (group_slice: paused instances are
/// computed too). Costs O(indices log groups).
std::vector<InstanceGroup> slices_covering(const SceneData& d, std::span<const uint32_t> indices);

/// The constants every dispatch over `group` shares (offsets, counts, wind, parameters), with
/// kind per_element and `final_half` as both halves; a dispatch then sets its own kind, element
/// count, round, halves and level.
gpu::PassConstants group_constants(const SceneData& scene, const InstanceGroup& group,
                                   uint32_t final_half);

/// Pointer-jumping rounds for a maximum chain depth: max(1, ceil(log2(depth + 1))).
uint32_t jump_rounds_for_depth(int32_t max_depth);
/// Fills d.chain_walk from d.chain_parent and d.chain_attach of every model (gpu_layout.h
/// HMSM_WALK_RECORD_INTS).
void fill_walk_records(SceneData& d);

}  // namespace hmsm::detail
