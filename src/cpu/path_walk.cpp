// Composition::path_walk on the CPU, passes 3 and 5 in one (gpu_layout.h HMSM_DISPATCH_POSE_WALK):
// each chain of the work items walks its ancestors from the trunk down, R = R_parent T and
// O = O_parent + R_parent l_attach, each T computed from the chain's new angles as integrate
// computes it (a walk step stores no T); the pose goes to the joint matrix alone. These are
// level by level's operations in level by level's order (its own offset R_parent l_attach is
// node_relative's u of the attach node), so the poses are level by level's bit for bit, without
// a dispatch per depth level.
#include "cpu_state.h"

namespace hmsm::detail::cpu {

template <class T>
void path_walk(State<T>& s, const gpu::PassConstants& pc, Range r) {
    using vec3 = typename State<T>::vec3;
    using vec4 = typename State<T>::vec4;
    for (uint32_t i = r.begin; i < r.end; ++i) {
        const Element e = element_of(i, pc.model_chain_count);
        if (instance_paused(s, pc, e.instance)) continue;
        const int32_t c = int32_t(e.index);
        // The walk record (gpu_layout.h): depth, ancestors and attach nodes; further up than it
        // holds, through the 2^round-th ancestors of chain_jump and chain_attach. (The GPU kernels
        // gather the same values from chain_parent in a forest, a POSE_WALK rather than a
        // POSE_WALK_FROM_RECORDS dispatch, where reading the records costs them L2 traffic; on
        // the CPU the record is the cheaper way for both kinds.)
        const int32_t* record = &s.chain_walk[uint64_t(HMSM_WALK_RECORD_INTS) * (pc.model_chain_begin + c)];
        const uint32_t depth = uint32_t(record[0]);
        auto ancestor = [&](uint32_t up) {
            if (up == 0) return c;
            if (up <= HMSM_WALK_PATH_CAPACITY) return record[up];
            int32_t a = c;
            for (uint32_t round = 0; up != 0; ++round, up >>= 1)
                if (up & 1u) a = s.chain_jump[uint64_t(round) * pc.total_model_chains + pc.model_chain_begin + a];
            return a;
        };
        auto attach = [&](uint32_t up) {
            return up < HMSM_WALK_ATTACH_CAPACITY ? record[HMSM_WALK_ATTACH(up)]
                                                  : s.chain_attach[pc.model_chain_begin + ancestor(up)];
        };
        // T of chain x from its new angles (integrate's local transform, as integrate gives it).
        auto local_of = [&](int32_t x) {
            const auto& state = s.chain_state[state_chain(pc, e.instance, x)];
            return local_transform(s, pc.model_chain_begin + uint32_t(x), pc.instance_begin + e.instance,
                                   typename State<T>::vec2(state.x, state.y));
        };
        auto rotation = local_of(ancestor(depth));
        const auto& o = s.instance_origin[pc.instance_begin + e.instance];
        vec4 origin{o.x, o.y, o.z, T(0)};
        for (uint32_t level = 1; level <= depth; ++level) {
            const int32_t x = ancestor(depth - level);
            const auto& local = s.node_local[pc.model_node_begin + attach(depth - level)];
            const vec3 u = rotation * vec3(local);
            origin += vec4{u, T(0)};
            rotation = rotation * local_of(x);
        }
        store_joint(s, state_chain(pc, e.instance, c), rotation, origin);
    }
}

template void path_walk<float>(State<float>&, const gpu::PassConstants&, Range);
template void path_walk<double>(State<double>&, const gpu::PassConstants&, Range);

}  // namespace hmsm::detail::cpu
