// Y(x) of docs/model.md 3.5, shared by the C++ model, the CPU passes and the CUDA kernels (the GLSL
// twin is shaders/glsl/common.glsl). All profiles have period 2 in x, so callers pass x mod 2.
#pragma once

#include "gpu_layout.h"
#include "host_device.h"

#include <cmath>

namespace hmsm::detail {

template <class T>
HMSM_HOST_DEVICE T wind_profile_y(unsigned profile, T x) {
    const T pi = T(3.14159265358979323846);
    switch (profile) {
        case HMSM_WIND_PROFILE_CONSTANT: return T(1);
        case HMSM_WIND_PROFILE_Y1:
            return cos(pi * x) * cos(3 * pi * x) * cos(5 * pi * x) * cos(7 * pi * x) -
                   T(0.1) * sin(25 * pi * x);
        case HMSM_WIND_PROFILE_Y2:
            return (sin(pi * x) + sin(3 * pi * x) + sin(5 * pi * x) + sin(7 * pi * x)) / T(4);
        case HMSM_WIND_PROFILE_Y3: {
            T c = cos(pi * x);
            return c * c * cos(3 * pi * x) * cos(5 * pi * x) - T(0.02) * sin(25 * pi * x);
        }
        case HMSM_WIND_PROFILE_Y4: {
            T c = cos(pi * x);
            return c * c * cos(3 * pi * x) * cos(5 * pi * x) - T(0.1) * sin(25 * pi * x);
        }
        default: return T(0);  // none
    }
}

/// Yt of docs/model.md 3.5 from the reduced phases of one step and one instance (gpu_layout.h):
/// 1 + sum_k a_k cos(2 pi (step_k + instance_k)) with step_k = frac(m_k tau + u_k) and
/// instance_k = frac(m_k phi); their sum is reduced to [0, 1) before the cosine.
template <class T>
HMSM_HOST_DEVICE T turbulent_y(const T* amplitude, const T* step_phase, const T* instance_phase) {
    const T two_pi = T(6.28318530717958647692);
    T y = T(1);
    for (int k = 0; k < 32; ++k) {
        T phase = step_phase[k] + instance_phase[k];
        phase -= floor(phase);
        y += amplitude[k] * cos(two_pi * phase);
    }
    return y;
}

/// The atmospheric profile's (1 + u', v', w') of docs/model.md 3.5 from the reduced phases of one
/// step and one instance (gpu_layout.h): each component sums its modes' a_k cos(2 pi (step_k +
/// instance_k)), the sum reduced to [0, 1) before the cosine; modes [0, 16) are u', [16, 24)
/// v', [24, 32) w'.
template <class T>
struct WindComponents {
    T along, lateral, vertical;
};
template <class T>
HMSM_HOST_DEVICE WindComponents<T> atmospheric_components(const T* amplitude, const T* step_phase,
                                                          const T* instance_phase) {
    const T two_pi = T(6.28318530717958647692);
    T sum[3] = {T(1), T(0), T(0)};
    for (int k = 0; k < 32; ++k) {
        T phase = step_phase[k] + instance_phase[k];
        phase -= floor(phase);
        sum[k < 4 * HMSM_WIND_MODES_U_VEC4S ? 0 : k < 4 * (HMSM_WIND_MODES_U_VEC4S + HMSM_WIND_MODES_V_VEC4S) ? 1 : 2] +=
            amplitude[k] * cos(two_pi * phase);
    }
    return {sum[0], sum[1], sum[2]};
}

}  // namespace hmsm::detail
