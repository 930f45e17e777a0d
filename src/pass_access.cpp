// Which buffers each pass reads and writes (the access columns of pass_table.h): GPU backends
// place barriers only where a later dispatch reads (or overwrites) what an earlier one wrote.
#include "backend.h"
#include "pass_table.h"

namespace hmsm::detail {
uint32_t pass_reads(Pass pass) { return pass_info(pass).reads; }
uint32_t pass_writes(Pass pass) { return pass_info(pass).writes; }

uint64_t SceneData::element_count(BufferId id) const {
    switch (buffer_info(id).scope) {
        case Scope::model_chain:
            // The exchange's records in 24-scalar elements (gpu_layout.h: the articulated record
            // is two of them).
            if (id == BufferId::chain_dynamics)
                return (articulated() ? chain_articulated : chain_dynamics).size() / (4 * HMSM_CHAIN_DYNAMICS_VEC4S);
            return chain_parent.size();
        case Scope::model_chain_jump: return chain_jump.size();
        case Scope::model_chain_walk: return chain_walk.size();
        case Scope::model_node: return node_owner.size();
        case Scope::model_vertex: return vertex_chain.size();
        case Scope::instance: return instance_capacity;
        case Scope::chain: return chain_capacity;
        case Scope::chain_halves: return id == BufferId::chain_load && !coupled() ? 0 : 2 * chain_capacity;
        case Scope::node: return id == BufferId::node_world && !produces_nodes() ? 0 : node_capacity;
        case Scope::vertex:
            if (!produces_vertices()) return 0;
            return id == BufferId::vertex_normal && packed_vertices() ? 0 : vertex_capacity;
        case Scope::wind: return HMSM_WIND_TABLE_ELEMENTS;
    }
    return 0;
}

}  // namespace hmsm::detail
