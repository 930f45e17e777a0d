// Pass 1: generalized wind force per chain (chain_math.cuh), R and O of the previous step read
// from the pose half src_half (path walk: from the joint matrix); pc.wind_slot is the step's slot
// of the wind table (gpu_layout.h), which holds tau and the turbulent phases reduced on the host.
#include "articulated_math.cuh"

namespace hmsm::detail::cuda {

static HMSM_HOST_DEVICE void wind_force_element(const BufferPointers& b,
                                                const gpu::PassConstants& pc, uint32_t i) {
    const Element e = element_of(i, pc.model_chain_count);
    if (instance_paused(b, pc, e.instance)) return;
    const uint64_t chain = pc.chain_begin + i;
    // The articulated exchange: the impulse alone, which integrate's sweeps take (alone or as a
    // path walk's wind pair, whose pose is the joint matrix's).
    if (pc.dynamics == HMSM_PASS_DYNAMICS_ARTICULATED) {
        const uint64_t half = half_begin(pc, pc.src_half) + chain;
        const Pose pose = pc.kind == HMSM_DISPATCH_WIND_PAIR
                              ? load_joint(b, chain)
                              : Pose{load_mat3(b.chain_rotation, half), xyz(load(b.chain_origin + half))};
        const float3 wind = instance_wind_vector(b, pc, e.instance, pc.wind_slot);
        articulated_impulse(b, pc, e.index, chain, chain_local_wind(b, pose.origin, pose.rotation, wind));
        return;
    }
    // The wind pair (path walk): the previous pose is the joint matrix (the walk writes no R or O half), and
    // integrate's step follows in the same launch with g in hand; only the angles are stored
    // (the walk computes T from them; pass_table.h walk_reads, walk_writes).
    if (pc.kind == HMSM_DISPATCH_WIND_PAIR) {
        const Pose pose = load_joint(b, chain);
        const float2 g = chain_wind_force(b, pc, e.instance, e.index, pose.origin, pose.rotation);
        integrate_angles(b, pc, e.instance, pc.model_chain_begin + e.index, chain, g);
        return;
    }
    const uint64_t pose = half_begin(pc, pc.src_half) + chain;
    b.chain_force[chain] = chain_wind_force(b, pc, e.instance, e.index, xyz(load(b.chain_origin + pose)),
                                            load_mat3(b.chain_rotation, pose));
}

HMSM_CUDA_PASS(wind_force)

}  // namespace hmsm::detail::cuda
