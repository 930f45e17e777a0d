// The per-chain math of the coupled dynamics (docs/model.md 3.13), shared by the CPU passes
// (src/cpu/coupled_dynamics.cpp) and the CUDA kernels (kernels/cuda/coupled_math.cuh);
// shaders/glsl/coupled_math.glsl mirrors it line by line. `record` is a chain's
// HMSM_CHAIN_DYNAMICS_VEC4S vec4 (gpu_layout.h) as 4 * HMSM_CHAIN_DYNAMICS_VEC4S scalars, with
// the per-step quotients folded in on the host: nothing here divides. Pairs are (axis x, axis z)
// = (theta_x, theta_z).
#pragma once

#include "gpu_layout.h"
#include "host_device.h"

#include <cmath>
#include <cstdint>

namespace hmsm::detail {

/// Scalar j of vec4 v of a chain's record.
template <class T>
HMSM_HOST_DEVICE T coupled_field(const T* record, uint32_t v, uint32_t j) {
    return record[4 * v + j];
}

/// The wind torque (q_ref M) x w_local about the joint, its x and z components, into g.
template <class T>
HMSM_HOST_DEVICE void coupled_wind_torque(const T* record, T wx, T wy, T wz, T g[2]) {
    const T mx = coupled_field(record, 4, 0), my = coupled_field(record, 4, 1), mz = coupled_field(record, 4, 2);
    g[0] = my * wz - wy * mz;
    g[1] = mx * wy - wx * my;
}

/// The model-local ids [first, first + count) of the chain's children.
template <class T>
HMSM_HOST_DEVICE void coupled_children(const T* record, int32_t& first, int32_t& count) {
    first = int32_t(coupled_field(record, 3, 2));
    count = int32_t(coupled_field(record, 3, 3));
}

/// Adds a child's load (load_x, load_z) of the last step, which its joint passes on, rotated
/// from the child's frame into this one by the child's rest rotation Q: `passing` is vec4
/// HMSM_CHAIN_DYNAMICS_PASSING of the child's record, (Q_00, Q_02, Q_20, Q_22) (the load has no
/// y component, and only its x and z are wanted).
template <class T>
HMSM_HOST_DEVICE void coupled_add_child_load(const T passing[4], T load_x, T load_z, T g[2]) {
    g[0] += passing[0] * load_x + passing[1] * load_z;
    g[1] += passing[2] * load_x + passing[3] * load_z;
}

/// Subtracts the aerodynamic damping D_a = aero_a (sqrt(|w|) + eta |V_a|), the wind's and
/// that of the chain's own motion in the air, held as the torque that takes from the rate what
/// exp(-x) with x = D_a dt / I_a would over one step: (I_a / dt) (1 - exp(-x)) per unit rate,
/// never more than the rate itself; x (1 - x / 2) for x so small that 1 - exp(-x) cancels.
/// `wind_dot` is |w_local|^2.
template <class T>
HMSM_HOST_DEVICE void coupled_subtract_aero_damping(const T* record, T wind_dot, const T rate[2], T g[2]) {
#ifndef __CUDA_ARCH__
    using std::abs;
    using std::exp;  // the float overloads on the host; CUDA's device overloads are global
    using std::sqrt;
#endif
    const T speed = sqrt(sqrt(wind_dot));
    const T motion_ratio = coupled_field(record, 4, 3);
    for (int a = 0; a < 2; ++a) {
        const T x = coupled_field(record, 3, a) * (speed + motion_ratio * abs(rate[a]));
        const T taken = x > T(1e-4) ? T(1) - exp(-x) : x * (T(1) - T(0.5) * x);
        g[a] -= coupled_field(record, 2, a) * taken * rate[a];
    }
}

/// Pass 2's step about axis j: exact over dt for the force g held, the offset from the
/// equilibrium g / K turning by the axis's transition; clamped at max_angle (the rate zeroed at
/// the stop).
template <class T>
HMSM_HOST_DEVICE void coupled_step_axis(const T* record, uint32_t j, T g, T max_angle, T& angle, T& rate) {
#ifndef __CUDA_ARCH__
    using std::abs;
    using std::copysign;
#endif
    const T equilibrium = g * coupled_field(record, 2, 2 + j);
    const T offset = angle - equilibrium;
    const T next_rate = coupled_field(record, j, 2) * offset + coupled_field(record, j, 3) * rate;
    angle = equilibrium + coupled_field(record, j, 0) * offset + coupled_field(record, j, 1) * rate;
    rate = next_rate;
    if (abs(angle) > max_angle) {
        angle = copysign(max_angle, angle);
        rate = T(0);
    }
}

}  // namespace hmsm::detail
