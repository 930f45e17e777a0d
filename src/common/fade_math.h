// Fades to a coarser level in pass 2 (docs/model.md 3.12, fading to a coarser level), shared by
// the CPU passes and the CUDA kernels; shaders/glsl/chain_math.glsl (faded_state) mirrors it.
// The words are those of gpu_layout.h HMSM_FADE_*: integers the host stores in floats.
#pragma once

#include "gpu_layout.h"
#include "host_device.h"

#include <cstdint>

namespace hmsm::detail {

/// Whether an instance's fade (word `word`, 0: none) relaxes a chain of keep rank `keep`: the
/// level it fades to folds the chain.
HMSM_HOST_DEVICE bool fade_relaxes(uint32_t word, uint32_t keep) {
    return word != 0u && keep < (word >> HMSM_FADE_LEVEL_SHIFT);
}

/// The factor sigma = m / (m + 1) of the step with clock `clock` (n mod HMSM_FADE_PERIOD), m the
/// fade's steps left after it; 0 from its last step on.
template <class T>
HMSM_HOST_DEVICE T fade_factor(uint32_t word, uint32_t clock) {
    const uint32_t left = ((word & HMSM_FADE_END_MASK) - clock) & HMSM_FADE_END_MASK;
    return left != 0u && left < HMSM_FADE_HORIZON ? T(left) / T(left + 1u) : T(0);
}

}  // namespace hmsm::detail
