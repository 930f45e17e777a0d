// Pass 2: symplectic Euler on the two joint angles S = (theta_x, theta_z) of each chain, then
// the local transform T (chain_math.cuh); under the articulated exchange an INSTANCE_SWEEP, one
// block per instance (articulated_math.cuh).
#include "articulated_math.cuh"

namespace hmsm::detail::cuda {

static HMSM_HOST_DEVICE void integrate_element(const BufferPointers& b,
                                               const gpu::PassConstants& pc, uint32_t i) {
    const Element e = element_of(i, pc.model_chain_count);
    if (instance_paused(b, pc, e.instance)) return;
    const uint64_t chain = pc.chain_begin + i;
    store_mat3(b.chain_local, chain, chain_integrate(b, pc, e.instance, e.index, chain, b.chain_force[chain]));
}

static HMSM_HOST_DEVICE void integrate_sweep(const BufferPointers& b, const gpu::PassConstants& pc, uint32_t k,
                                             uint32_t lane, uint32_t lanes) {
    articulated_sweep(b, pc, k, lane, lanes);
}

HMSM_CUDA_SWEEP_PASS(integrate)

}  // namespace hmsm::detail::cuda
