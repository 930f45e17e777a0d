// The per-chain math of the coupled dynamics' articulated exchange (docs/model.md 3.13, "The
// articulated exchange"), shared by the CPU passes (src/cpu/articulated_dynamics.cpp). `record`
// is a chain's HMSM_CHAIN_ARTICULATED_VEC4S vec4 (gpu_layout.h) as scalars, with dt and the
// quotients folded in on the host: nothing here divides. Spatial vectors are 6 scalars in the
// chain's rest frame about its joint, angular part first: motions (omega, v), forces (moment,
// force). Pairs are (axis x, axis z).
#pragma once

#include "gpu_layout.h"
#include "host_device.h"

#include <cmath>
#include <cstdint>

namespace hmsm::detail {

/// Scalar i of a chain's articulated record.
template <class T>
HMSM_HOST_DEVICE T articulated_field(const T* record, uint32_t i) {
    return record[i];
}

/// Pass 1: the chain's own wind impulse over the step (moment about the joint, force: 6
/// scalars) under the wind w_local in its frame, and the impulse of its aerodynamic damping per
/// axis, held as the share 1 - exp(-x) of the rate it takes over one step (coupled_math.h):
/// I (1 - exp(-x)) V with x = aero dt / I (sqrt(|w|) + eta |V|).
template <class T>
HMSM_HOST_DEVICE void articulated_wind_impulse(const T* record, T wx, T wy, T wz, const T rate[2], T impulse[8]) {
#ifndef __CUDA_ARCH__
    using std::abs;
    using std::exp;
    using std::sqrt;
#endif
    const T mx = articulated_field(record, 28), my = articulated_field(record, 29), mz = articulated_field(record, 30);
    const T area = articulated_field(record, 31);
    impulse[0] = my * wz - mz * wy;
    impulse[1] = mz * wx - mx * wz;
    impulse[2] = mx * wy - my * wx;
    impulse[3] = area * wx;
    impulse[4] = area * wy;
    impulse[5] = area * wz;
    const T speed = sqrt(sqrt(wx * wx + wy * wy + wz * wz));
    const T eta = articulated_field(record, 15);
    for (int a = 0; a < 2; ++a) {
        const T x = articulated_field(record, 40 + uint32_t(a)) * (speed + eta * abs(rate[a]));
        const T taken = x > T(1e-4) ? T(1) - exp(-x) : x * (T(1) - T(0.5) * x);
        impulse[6 + a] = articulated_field(record, 38 + uint32_t(a)) * taken * rate[a];
    }
}

/// The up sweep at one chain: with p the sum of its children's passed-on forces (in its frame)
/// minus its own wind impulse, the joint's free impulse u = b - S^T p (b from the springs,
/// dampers and aerodynamic damping at angles S, rates V), w = G u, and the force the chain passes
/// to its parent, X^T (p + U w), in the parent's frame.
template <class T>
HMSM_HOST_DEVICE void articulated_up(const T* record, const T angle[2], const T rate[2], const T impulse[8], T p[6],
                                     T w[2], T passed[6]) {
    for (int i = 0; i < 6; ++i) p[i] -= impulse[i];
    T u[2];
    for (int a = 0; a < 2; ++a) {
        const T b = -articulated_field(record, 32 + uint32_t(a)) * angle[a] -
                    articulated_field(record, 34 + uint32_t(a)) * rate[a] - impulse[6 + a];
        u[a] = b - p[2 * a];  // S^T p: the moment about the joint's x and z axes
    }
    w[0] = articulated_field(record, 12) * u[0] + articulated_field(record, 13) * u[1];
    w[1] = articulated_field(record, 13) * u[0] + articulated_field(record, 14) * u[1];
    T c[6];
    for (int i = 0; i < 6; ++i)
        c[i] = p[i] + articulated_field(record, uint32_t(i)) * w[0] + articulated_field(record, 6 + uint32_t(i)) * w[1];
    // X^T: n' = Q n + d x (Q f), f' = Q f; Q column j and d_j in scalars 16 + 4 j.
    T qn[3], qf[3];
    for (int r = 0; r < 3; ++r) {
        qn[r] = T(0);
        qf[r] = T(0);
        for (int j = 0; j < 3; ++j) {
            const T q = articulated_field(record, 16 + 4 * uint32_t(j) + uint32_t(r));
            qn[r] += q * c[j];
            qf[r] += q * c[3 + j];
        }
    }
    const T dx = articulated_field(record, 19), dy = articulated_field(record, 23), dz = articulated_field(record, 27);
    passed[0] = qn[0] + dy * qf[2] - dz * qf[1];
    passed[1] = qn[1] + dz * qf[0] - dx * qf[2];
    passed[2] = qn[2] + dx * qf[1] - dy * qf[0];
    passed[3] = qf[0];
    passed[4] = qf[1];
    passed[5] = qf[2];
}

/// The down sweep at one chain: its joint's change of rate dV = w - G U^T a' with a' = X a_parent
/// (the parent's spatial change of motion seen at this joint; zero for the trunk), and the
/// chain's own, a = a' + S dV. `parent` is null for the trunk.
template <class T>
HMSM_HOST_DEVICE void articulated_down(const T* record, const T* parent, const T w[2], T dv[2], T a[6]) {
    if (parent) {
        // X: omega = Q^T omega_p, v = Q^T (v_p + omega_p x d).
        const T dx = articulated_field(record, 19), dy = articulated_field(record, 23), dz = articulated_field(record, 27);
        const T v[3] = {parent[3] + parent[1] * dz - parent[2] * dy, parent[4] + parent[2] * dx - parent[0] * dz,
                        parent[5] + parent[0] * dy - parent[1] * dx};
        for (int j = 0; j < 3; ++j) {
            T omega = T(0), linear = T(0);
            for (int r = 0; r < 3; ++r) {
                const T q = articulated_field(record, 16 + 4 * uint32_t(j) + uint32_t(r));
                omega += q * parent[r];
                linear += q * v[r];
            }
            a[j] = omega;
            a[3 + j] = linear;
        }
    } else {
        for (int i = 0; i < 6; ++i) a[i] = T(0);
    }
    T ua[2] = {T(0), T(0)};
    for (int i = 0; i < 6; ++i) {
        ua[0] += articulated_field(record, uint32_t(i)) * a[i];
        ua[1] += articulated_field(record, 6 + uint32_t(i)) * a[i];
    }
    dv[0] = w[0] - (articulated_field(record, 12) * ua[0] + articulated_field(record, 13) * ua[1]);
    dv[1] = w[1] - (articulated_field(record, 13) * ua[0] + articulated_field(record, 14) * ua[1]);
    a[0] += dv[0];
    a[2] += dv[1];
}

/// The joint's step: S += dt V + theta dt dV, V += dV, clamped at max_angle (the rate zeroed
/// at the stop).
template <class T>
HMSM_HOST_DEVICE void articulated_step(const T* record, T dt, T max_angle, const T dv[2], T angle[2], T rate[2]) {
#ifndef __CUDA_ARCH__
    using std::abs;
    using std::copysign;
#endif
    for (int a = 0; a < 2; ++a) {
        angle[a] += dt * rate[a] + articulated_field(record, 36 + uint32_t(a)) * dv[a];
        rate[a] += dv[a];
        if (abs(angle[a]) > max_angle) {
            angle[a] = copysign(max_angle, angle[a]);
            rate[a] = T(0);
        }
    }
}

}  // namespace hmsm::detail
