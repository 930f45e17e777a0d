// Which buffers each pass reads and writes: GPU backends place barriers from this table only
// where a later dispatch reads (or overwrites) what an earlier one wrote.
#include "backend.h"

namespace hmsm::detail {
namespace {
constexpr uint32_t bit(BufferId id) { return 1u << static_cast<uint32_t>(id); }
}  // namespace

uint32_t pass_reads(Pass pass) {
    using B = BufferId;
    switch (pass) {
        case Pass::wind_force:
            return bit(B::chain_rotation) | bit(B::chain_origin) | bit(B::chain_constants) |
                   bit(B::instance_wind) | bit(B::wind_table);
        case Pass::integrate:
            return bit(B::chain_force) | bit(B::chain_state) | bit(B::chain_constants) |
                   bit(B::chain_rest_rotation) | bit(B::chain_parent) | bit(B::instance_yaw);
        case Pass::compose:
            return bit(B::chain_local) | bit(B::chain_rotation) | bit(B::chain_jump) |
                   bit(B::chain_parent);
        case Pass::node_relative:
            return bit(B::chain_rotation) | bit(B::node_owner) | bit(B::node_local);
        case Pass::root_positions:
            return bit(B::node_relative) | bit(B::chain_origin) | bit(B::chain_jump) |
                   bit(B::chain_parent) | bit(B::chain_attach) | bit(B::instance_origin) |
                   bit(B::chain_rotation);
        case Pass::node_world:
            return bit(B::chain_origin) | bit(B::node_relative) | bit(B::node_owner);
        case Pass::contour:
            return bit(B::chain_rotation) | bit(B::chain_origin) | bit(B::vertex_chain) |
                   bit(B::vertex_rest_position) | bit(B::vertex_rest_normal) |
                   bit(B::vertex_parent_position) | bit(B::vertex_parent_normal);
    }
    return 0;
}

uint32_t pass_writes(Pass pass) {
    using B = BufferId;
    switch (pass) {
        case Pass::wind_force: return bit(B::chain_force);
        case Pass::integrate: return bit(B::chain_state) | bit(B::chain_local);
        case Pass::compose: return bit(B::chain_rotation);
        case Pass::node_relative: return bit(B::node_relative);
        // With the final O_c it writes the joint matrix [R_c | O_c] (R_c from compose).
        case Pass::root_positions: return bit(B::chain_origin) | bit(B::joint_matrix);
        case Pass::node_world: return bit(B::node_world);
        // In the packed vertex layout vertex_normal has no elements and is not written.
        case Pass::contour: return bit(B::vertex_position) | bit(B::vertex_normal);
    }
    return 0;
}

uint64_t SceneData::element_count(BufferId id) const {
    switch (buffer_info(id).scope) {
        case Scope::model_chain: return chain_parent.size();
        case Scope::model_chain_jump: return chain_jump.size();
        case Scope::model_node: return node_owner.size();
        case Scope::model_vertex: return vertex_chain.size();
        case Scope::instance: return instance_origin.size();
        case Scope::chain: return total_chains;
        case Scope::chain_halves: return 2 * total_chains;
        case Scope::node: return id == BufferId::node_world && !produces_nodes() ? 0 : total_nodes;
        case Scope::vertex:
            if (!produces_vertices()) return 0;
            return id == BufferId::vertex_normal && packed_vertices() ? 0 : total_vertices;
        case Scope::wind: return HMSM_WIND_TABLE_ELEMENTS;
    }
    return 0;
}

}  // namespace hmsm::detail
