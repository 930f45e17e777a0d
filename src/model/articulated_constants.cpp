// See articulated_constants.h.
#include "articulated_constants.h"

#include "coupled_constants.h"

#include "../common/gpu_layout.h"

#include <glm/geometric.hpp>
#include <glm/mat3x3.hpp>
#include <glm/matrix.hpp>

#include <algorithm>
#include <array>
#include <cmath>
#include <numbers>

namespace hmsm::detail {

namespace {

/// A spatial 6x6 matrix, row-major, angular rows and columns first.
using Mat6 = std::array<double, 36>;

/// The body's spatial inertia about its joint: [[J, [h]x], [-[h]x, m 1]].
Mat6 body_inertia(double mass, const Vec3& h, const Mat3& j) {
    Mat6 m{};
    const double hx[3][3] = {{0, -h.z, h.y}, {h.z, 0, -h.x}, {-h.y, h.x, 0}};
    for (int r = 0; r < 3; ++r)
        for (int c = 0; c < 3; ++c) {
            m[size_t(6 * r + c)] = j[c][r];
            m[size_t(6 * r + 3 + c)] = hx[r][c];
            m[size_t(6 * (3 + r) + c)] = -hx[r][c];
        }
    for (int r = 0; r < 3; ++r) m[size_t(6 * (3 + r) + 3 + r)] = mass;
    return m;
}

Mat6 multiply(const Mat6& a, const Mat6& b) {
    Mat6 out{};
    for (int r = 0; r < 6; ++r)
        for (int k = 0; k < 6; ++k) {
            const double v = a[size_t(6 * r + k)];
            if (v == 0.0) continue;
            for (int c = 0; c < 6; ++c) out[size_t(6 * r + c)] += v * b[size_t(6 * k + c)];
        }
    return out;
}

Mat6 transpose(const Mat6& a) {
    Mat6 out{};
    for (int r = 0; r < 6; ++r)
        for (int c = 0; c < 6; ++c) out[size_t(6 * c + r)] = a[size_t(6 * r + c)];
    return out;
}

/// The motion transform from the parent's joint to the child's: [[Q^T, 0], [-Q^T [d]x, Q^T]].
Mat6 motion_transform(const Mat3& q, const Vec3& d) {
    Mat6 x{};
    const double dx[3][3] = {{0, -d.z, d.y}, {d.z, 0, -d.x}, {-d.y, d.x, 0}};
    for (int r = 0; r < 3; ++r)
        for (int c = 0; c < 3; ++c) {
            const double qt = q[r][c];  // (Q^T)[r][c] = Q[c][r] = glm q[r][c] (column r, row c)
            x[size_t(6 * r + c)] = qt;
            x[size_t(6 * (3 + r) + 3 + c)] = qt;
            double s = 0.0;
            for (int k = 0; k < 3; ++k) s += q[r][k] * dx[k][c];
            x[size_t(6 * (3 + r) + c)] = -s;
        }
    return x;
}

/// y = a x for a spatial 6-vector x.
std::array<double, 6> apply(const Mat6& a, const std::array<double, 6>& x) {
    std::array<double, 6> y{};
    for (int r = 0; r < 6; ++r)
        for (int c = 0; c < 6; ++c) y[size_t(r)] += a[size_t(6 * r + c)] * x[size_t(c)];
    return y;
}

/// y = a^T x.
std::array<double, 6> apply_transposed(const Mat6& a, const std::array<double, 6>& x) {
    std::array<double, 6> y{};
    for (int r = 0; r < 6; ++r)
        for (int c = 0; c < 6; ++c) y[size_t(c)] += a[size_t(6 * r + c)] * x[size_t(r)];
    return y;
}

/// Rayleigh's sway frequency (Hz) along the model direction `along`.
double sway_hz_along(const Hierarchy& h, const Vec3& along) {
    const size_t n = h.chains.size();
    std::vector<Vec3> local(n);                      // the direction in each chain's frame
    std::vector<Mat6> transform(n);                  // X_c from the parent's joint
    std::vector<std::array<double, 6>> force(n);     // the load each chain passes to its joint
    for (size_t c = 0; c < n; ++c) {
        const Chain& chain = h.chains[c];
        const Vec3 outer = chain.parent < 0 ? along : local[size_t(chain.parent)];
        local[c] = glm::transpose(chain.rest_rotation) * outer;
        const Vec3 attach = c == 0 ? Vec3(0.0) : h.node_local[size_t(chain.attach_node)];
        transform[c] = motion_transform(chain.rest_rotation, attach);
        const ChainDynamics& d = chain.dynamics;
        const Vec3 moment = glm::cross(d.own_mass_moment, local[c]);  // sum x cross m u
        force[c] = {moment.x, moment.y, moment.z, d.mass * local[c].x, d.mass * local[c].y, d.mass * local[c].z};
    }
    for (size_t c = n; c-- > 1;) {  // up: each chain's load includes its subtree's
        const std::array<double, 6> up = apply_transposed(transform[c], force[c]);
        std::array<double, 6>& parent = force[size_t(h.chains[c].parent)];
        for (int i = 0; i < 6; ++i) parent[size_t(i)] += up[size_t(i)];
    }
    double work = 0.0, kinetic = 0.0;
    std::vector<std::array<double, 6>> motion(n);
    for (size_t c = 0; c < n; ++c) {  // down: the static deflection q = K^-1 F as a motion
        const Chain& chain = h.chains[c];
        const ChainDynamics& d = chain.dynamics;
        std::array<double, 6> v = chain.parent < 0 ? std::array<double, 6>{}
                                                   : apply(transform[c], motion[size_t(chain.parent)]);
        const int column[2] = {0, 2};
        for (int a = 0; a < 2; ++a) {
            const double f = force[c][size_t(column[a])];
            const double q = d.stiffness[a] > 0.0 ? f / d.stiffness[a] : 0.0;
            work += q * f;
            v[size_t(column[a])] += q;
        }
        motion[c] = v;
        const std::array<double, 6> p = apply(body_inertia(d.mass, d.own_mass_moment, d.own_inertia), v);
        for (int i = 0; i < 6; ++i) kinetic += v[size_t(i)] * p[size_t(i)];
    }
    return kinetic > 0.0 && work > 0.0 ? std::sqrt(work / kinetic) / (2.0 * std::numbers::pi) : 0.0;
}

}  // namespace

double whole_tree_sway_hz(const Hierarchy& h) {
    if (h.chains.empty()) return 0.0;
    const double x = sway_hz_along(h, Vec3(1.0, 0.0, 0.0)), z = sway_hz_along(h, Vec3(0.0, 0.0, 1.0));
    if (x <= 0.0 || z <= 0.0) return std::max(x, z);
    return std::min(x, z);
}

double articulated_inertia_scale(double frequency, double dt) {
    const double x = std::min(std::numbers::pi * frequency * dt, 0.5);
    return x > 0.0 ? std::pow(x / std::tan(x), 2) : 1.0;
}

double articulated_theta(double frequency, double dt) {
    return std::clamp(std::numbers::pi * frequency * dt, 0.5, 1.0);
}

double articulated_damping(const ChainDynamics& d, int axis) {
    return d.inertia[axis] > 0.0 ? d.damping[axis] * std::sqrt(d.rigid_inertia[axis] / d.inertia[axis]) : d.damping[axis];
}

void append_articulated_records(const Hierarchy& h, double dt, std::vector<double>& out) {
    const size_t n = h.chains.size();
    std::vector<Mat6> articulated(n);
    const double scale = articulated_inertia_scale(whole_tree_sway_hz(h), dt);
    for (size_t c = 0; c < n; ++c) {
        const ChainDynamics& d = h.chains[c].dynamics;
        articulated[c] = body_inertia(d.mass, d.own_mass_moment, d.own_inertia);
        for (double& v : articulated[c]) v *= scale;
    }
    const size_t first = out.size();
    constexpr size_t record = 4 * HMSM_CHAIN_ARTICULATED_VEC4S;
    out.resize(first + n * record, 0.0);
    // The depths as ranges of chains (breadth first: a depth's chains follow the one above's).
    std::vector<uint32_t> depth(n, 0u);
    for (size_t c = 1; c < n; ++c) depth[c] = depth[size_t(h.chains[c].parent)] + 1u;
    for (size_t begin = 0; begin < n;) {
        size_t end = begin + 1;
        while (end < n && depth[end] == depth[begin]) ++end;
        for (size_t c = begin; c < end; ++c) {
            out[first + c * record + 44] = double(begin);
            out[first + c * record + 45] = double(end);
        }
        begin = end;
    }
    // From the last chain up: every child's articulated inertia is complete before its parent's.
    for (size_t c = n; c-- > 0;) {
        const Chain& chain = h.chains[c];
        const ChainDynamics& d = chain.dynamics;
        const Mat6& ia = articulated[c];
        double* r = &out[first + c * record];  // scalars as gpu_layout.h lists them
        const int column[2] = {0, 2};
        double theta[2], effective[2], dmat[2][2];
        for (int a = 0; a < 2; ++a) {
            theta[a] = articulated_theta(d.frequency[a], dt);
            effective[a] = ia[size_t(6 * column[a] + column[a])];
            for (int b = 0; b < 2; ++b) dmat[a][b] = ia[size_t(6 * column[a] + column[b])];
            dmat[a][a] += theta[a] * dt * articulated_damping(d, a) + theta[a] * theta[a] * dt * dt * d.stiffness[a];
            for (int i = 0; i < 6; ++i) r[6 * a + i] = ia[size_t(6 * i + column[a])];
        }
        const double det = dmat[0][0] * dmat[1][1] - dmat[0][1] * dmat[1][0];
        const double g[2][2] = {{dmat[1][1] / det, -dmat[0][1] / det}, {-dmat[1][0] / det, dmat[0][0] / det}};
        r[12] = g[0][0];
        r[13] = g[0][1];
        r[14] = g[1][1];
        // The aerodynamic damping of the rigid subtree (a link's record scales it to K / omega^2).
        double aero[2], motion[2];
        for (int a = 0; a < 2; ++a) {
            const double rigid = d.inertia[a] > 0.0 ? d.rigid_inertia[a] / d.inertia[a] : 1.0;
            aero[a] = d.aero_damping[a] * rigid;
            motion[a] = d.motion_drag[a] * rigid;
        }
        r[15] = aero[0] + aero[1] > 0.0 ? (motion[0] + motion[1]) / (aero[0] + aero[1]) : 0.0;
        const Vec3 attach = c == 0 ? Vec3(0.0) : h.node_local[size_t(chain.attach_node)];
        for (int j = 0; j < 3; ++j) {
            for (int row = 0; row < 3; ++row) r[16 + 4 * j + row] = chain.rest_rotation[j][row];
            r[16 + 4 * j + 3] = attach[j];
        }
        for (int i = 0; i < 3; ++i) r[28 + i] = dt * kReferencePressure * d.own_wind_moment[i];
        r[31] = dt * kReferencePressure * d.drag_area;
        for (int a = 0; a < 2; ++a) {
            r[32 + a] = dt * d.stiffness[a];
            r[34 + a] = dt * articulated_damping(d, a) + theta[a] * dt * dt * d.stiffness[a];
            r[36 + a] = theta[a] * dt;
            r[38 + a] = effective[a];
            r[40 + a] = aero[a] * dt / effective[a];
        }
        r[42] = double(d.first_child);
        r[43] = double(d.child_count);
        if (chain.parent < 0) continue;
        // The parent's share: X^T (I^A - U G U^T) X.
        Mat6 reduced = ia;
        for (int i = 0; i < 6; ++i)
            for (int k = 0; k < 6; ++k) {
                double s = 0.0;
                for (int a = 0; a < 2; ++a)
                    for (int b = 0; b < 2; ++b) s += r[6 * a + i] * g[a][b] * r[6 * b + k];
                reduced[size_t(6 * i + k)] -= s;
            }
        const Mat6 x = motion_transform(chain.rest_rotation, attach);
        const Mat6 share = multiply(transpose(x), multiply(reduced, x));
        Mat6& parent = articulated[size_t(chain.parent)];
        for (size_t i = 0; i < 36; ++i) parent[i] += share[i];
    }
}

}  // namespace hmsm::detail
