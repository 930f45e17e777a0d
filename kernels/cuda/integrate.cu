// Pass 2: symplectic Euler on the two joint angles S = (theta_x, theta_z) of each chain, then
// the local transform T (chain_math.cuh).
#include "chain_math.cuh"

namespace hmsm::detail::cuda {

static HMSM_HOST_DEVICE void integrate_element(const BufferPointers& b,
                                               const gpu::PassConstants& pc, uint32_t i) {
    const Element e = element_of(i, pc.model_chain_count);
    if (instance_paused(b, pc, e.instance)) return;
    const uint64_t chain = pc.chain_begin + i;
    store_mat3(b.chain_local, chain, chain_integrate(b, pc, e.instance, e.index, chain, b.chain_force[chain]));
}

HMSM_CUDA_PASS(integrate)

}  // namespace hmsm::detail::cuda
