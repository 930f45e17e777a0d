// Per-chain constants of the coupled dynamics (docs/model.md 3.13): tapered mass and drag-area
// moments from the chain's own radii, children lumped at their attach nodes, the stiffness that
// gives the rigid link the first frequency of the tapered cantilever it stands for, and the
// transition of the exact oscillator step.
#include "coupled_constants.h"

#include "chain_bodies.h"

#include <glm/geometric.hpp>
#include <glm/matrix.hpp>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <numbers>
#include <string>
#include <vector>

namespace hmsm::detail {

namespace {

constexpr double kPi = std::numbers::pi;
/// Pieces per segment of the cantilever's static deflection (docs/model.md 3.13).
constexpr int kPiecesPerSegment = 8;

/// Squared distance of a point from the chain's local x axis (index 0) or z axis (index 1).
double axis_distance2(const glm::dvec3& x, int axis) {
    return axis == 0 ? x.y * x.y + x.z * x.z : x.x * x.x + x.y * x.y;
}

/// Cubed distance from the axis: a drag area at it, moving with the chain's rate V, meets the
/// air at V times the distance and turns it with V^2 times the cube.
double axis_distance3(const glm::dvec3& x, int axis) {
    const double d2 = axis_distance2(x, axis);
    return d2 * std::sqrt(d2);
}

/// What a chain's cantilever carries at one path node: point masses, their first mass moment
/// along the path's tangent there (a rigid load whose centroid lies beyond or before the node:
/// the lateral load's couple, and the displacement w + theta * lever of its centroid), and their
/// rotational inertia about the node across each bending axis.
struct NodeLoad {
    double mass = 0.0, lever = 0.0;
    std::array<double, 2> rotary{0.0, 0.0};
};

/// Unit tangent of a chain's path at node j: the mean direction of the segments beside it.
glm::dvec3 path_tangent(const ChainPath& path, size_t j) {
    glm::dvec3 t(0.0);
    if (j > 0) t += glm::normalize(path.p[j] - path.p[j - 1]);
    if (j + 1 < path.p.size()) t += glm::normalize(path.p[j + 1] - path.p[j]);
    const double n = glm::length(t);
    return n > 0.0 ? t / n : glm::dvec3(0.0, 1.0, 0.0);
}

bool float_safe(double v, bool may_be_zero) {
    if (v == 0.0) return may_be_zero;
    return std::isfinite(v) && std::abs(v) >= 1e-30 && std::abs(v) <= 1e30;
}

/// Twice the product of the parts perpendicular to the local x axis (index 0) or z axis (index 1)
/// of two vectors: the cross term 2 (a . b)_perp of |a + b|_perp^2.
double axis_cross2(const glm::dvec3& a, const glm::dvec3& b, int axis) {
    return 2.0 * (axis == 0 ? a.y * b.y + a.z * b.z : a.x * b.x + a.y * b.y);
}

/// The child's inertia about its joint (axes x, z of its own frame) seen about the parent's axis
/// `axis` (x or z of the parent frame): I_x (x_k . e)^2 + I_z (z_k . e)^2, Q_k = [x_k y_k z_k].
double projected_inertia(const Chain& child, int axis) {
    const int e = axis == 0 ? 0 : 2;
    const glm::dmat3& q = child.rest_rotation;
    return child.dynamics.inertia[0] * q[0][e] * q[0][e] + child.dynamics.inertia[1] * q[2][e] * q[2][e];
}

/// The first natural frequency (rad/s) about each axis of chain c as a tapered cantilever
/// carrying its leaves and children, by Rayleigh's quotient with the static deflection shape
/// (docs/model.md 3.13); and the tapered beam's tip stiffness K_beam.
void cantilever(const ChainPath& path, const std::vector<NodeLoad>& node_load, const Material& material,
                double omega[2], double& beam_stiffness) {
    const size_t segments = path.p.size() - 1;
    const size_t boundaries = segments * kPiecesPerSegment + 1;
    std::vector<double> s(boundaries), r(boundaries), point(boundaries, 0.0), piece(boundaries, 0.0);
    std::vector<double> lever(boundaries, 0.0);
    std::vector<std::array<double, 2>> rotary(boundaries, {0.0, 0.0});
    for (size_t j = 0; j < segments; ++j) {
        for (int i = 0; i <= kPiecesPerSegment; ++i) {
            const size_t b = j * kPiecesPerSegment + size_t(i);
            const double t = double(i) / kPiecesPerSegment;
            s[b] = path.s[j] + (path.s[j + 1] - path.s[j]) * t;
            r[b] = path.r[j] + (path.r[j + 1] - path.r[j]) * t;
        }
    }
    for (size_t j = 0; j <= segments; ++j) {
        point[j * kPiecesPerSegment] += node_load[j].mass;
        lever[j * kPiecesPerSegment] = node_load[j].lever;
        rotary[j * kPiecesPerSegment] = node_load[j].rotary;
    }
    const double L = s.back();
    double compliance = 0.0;  // int (L - s)^2 / (E J) ds
    for (size_t b = 0; b + 1 < boundaries; ++b) {
        const double ds = s[b + 1] - s[b], rm = 0.5 * (r[b] + r[b + 1]), sm = 0.5 * (s[b] + s[b + 1]);
        piece[b] = material.density * kPi * rm * rm * ds;
        compliance += (L - sm) * (L - sm) / (material.modulus * kPi * rm * rm * rm * rm / 4.0) * ds;
    }
    beam_stiffness = L * L / compliance;
    // Static deflection under the loads (unit gravity across the chain): bending moment from
    // the tip down (each rigid load's couple, its lever, included below its node), curvature
    // M / (E J), slope and deflection from the clamped base up.
    std::vector<double> moment(boundaries, 0.0), slope(boundaries, 0.0), deflection(boundaries, 0.0);
    double beyond = 0.0;  // load strictly beyond boundary b + 1
    for (size_t b = boundaries - 1; b-- > 0;) {
        const double ds = s[b + 1] - s[b];
        moment[b] = moment[b + 1] + (beyond + point[b + 1]) * ds + piece[b] * 0.5 * ds + lever[b + 1];
        beyond += point[b + 1] + piece[b];
    }
    // moment[b] is the moment just beyond boundary b; just before it, a couple there adds on.
    auto curvature = [&](size_t b, double m) { return m / (material.modulus * kPi * std::pow(r[b], 4) / 4.0); };
    for (size_t b = 0; b + 1 < boundaries; ++b) {
        const double ds = s[b + 1] - s[b];
        slope[b + 1] = slope[b] + 0.5 * (curvature(b, moment[b]) + curvature(b + 1, moment[b + 1] + lever[b + 1])) * ds;
        deflection[b + 1] = deflection[b] + 0.5 * (slope[b] + slope[b + 1]) * ds;
    }
    double work = 0.0, kinetic = 0.0, rotational[2] = {0.0, 0.0};
    for (size_t b = 0; b < boundaries; ++b) {
        // A rigid load's centroid moves by w + theta * lever: work m w + S theta, kinetic energy
        // m w^2 + 2 S w theta + I theta^2 (I about the node).
        work += point[b] * deflection[b] + lever[b] * slope[b];
        kinetic += point[b] * deflection[b] * deflection[b] + 2.0 * lever[b] * deflection[b] * slope[b];
        for (int a = 0; a < 2; ++a) rotational[a] += rotary[b][a] * slope[b] * slope[b];
        if (b + 1 < boundaries) {
            const double w = 0.5 * (deflection[b] + deflection[b + 1]);
            work += piece[b] * w;
            kinetic += piece[b] * w * w;
        }
    }
    for (int a = 0; a < 2; ++a) omega[a] = std::sqrt(work / (kinetic + rotational[a]));
}

/// The links of split chain `first` (docs/model.md 3.13): the whole chain's cantilever gives f0;
/// joint j's compliance is int h_j(s) / (E J(s)) ds with h_j the hat function that is 1 at joint
/// j and 0 at the joints beside it (the base: 0 at joint 1 only; the tip: beyond the last);
/// K_j = 1 / compliance, I_j = K_j / omega0^2, D_j = 2 zeta sqrt(K_j I_j), and the aerodynamic
/// damping scaled with I_j by I_j / I_rigid.
void split_chain_constants(Hierarchy& h, size_t first, const std::vector<ChainPath>& paths,
                           const std::vector<std::vector<NodeLoad>>& node_loads, const Material& material,
                           double zeta) {
    std::vector<size_t> links{first};
    while (int32_t(links.size()) < h.chains[first].dynamics.link_count) {
        const ChainDynamics& d = h.chains[links.back()].dynamics;
        links.push_back(size_t(d.first_child + d.child_count - 1));  // the next link: last child
    }
    ChainPath whole;
    std::vector<NodeLoad> node_load;
    std::vector<double> joint_s;
    for (size_t link : links) {
        const ChainPath& path = paths[link];
        const size_t from = whole.s.empty() ? 0 : 1;  // a link's base is the last link's tip
        const double offset = whole.s.empty() ? 0.0 : whole.s.back();
        joint_s.push_back(offset);
        if (from == 1) {
            const NodeLoad& base = node_loads[link][0];
            node_load.back().mass += base.mass;
            node_load.back().lever += base.lever;
            for (int a = 0; a < 2; ++a) node_load.back().rotary[a] += base.rotary[a];
        }
        for (size_t j = from; j < path.s.size(); ++j) {
            whole.s.push_back(offset + path.s[j]);
            whole.r.push_back(path.r[j]);
            whole.p.push_back(glm::dvec3(0.0, offset + path.s[j], 0.0));
            node_load.push_back(node_loads[link][j]);
        }
    }
    double omega[2], beam_stiffness = 0.0;
    cantilever(whole, node_load, material, omega, beam_stiffness);
    // Joint compliances: the curvature M / (E J) between two joints is shared linearly by them.
    const size_t n = links.size();
    joint_s.push_back(whole.s.back());
    std::vector<double> compliance(n, 0.0);
    size_t joint = 0;
    for (size_t j = 0; j + 1 < whole.s.size(); ++j) {
        for (int i = 0; i < kPiecesPerSegment; ++i) {
            const double t0 = double(i) / kPiecesPerSegment, t1 = double(i + 1) / kPiecesPerSegment;
            const double ds = (whole.s[j + 1] - whole.s[j]) * (t1 - t0);
            const double sm = whole.s[j] + (whole.s[j + 1] - whole.s[j]) * 0.5 * (t0 + t1);
            const double rm = whole.r[j] + (whole.r[j + 1] - whole.r[j]) * 0.5 * (t0 + t1);
            while (joint + 1 < n && sm >= joint_s[joint + 1]) ++joint;
            const double u = (sm - joint_s[joint]) / (joint_s[joint + 1] - joint_s[joint]);
            const double w = ds / (material.modulus * kPi * rm * rm * rm * rm / 4.0);
            compliance[joint] += (1.0 - u) * w;
            if (joint + 1 < n) compliance[joint + 1] += u * w;
        }
    }
    for (size_t i = 0; i < n; ++i) {
        ChainDynamics& d = h.chains[links[i]].dynamics;
        d.beam_stiffness = beam_stiffness;
        for (int a = 0; a < 2; ++a) {
            d.frequency[a] = omega[a] / (2.0 * kPi);
            d.stiffness[a] = 1.0 / compliance[i];
            d.inertia[a] = d.stiffness[a] / (omega[a] * omega[a]);
            d.damping[a] = 2.0 * zeta * std::sqrt(d.stiffness[a] * d.inertia[a]);
            d.aero_damping[a] *= d.inertia[a] / d.rigid_inertia[a];
            d.motion_drag[a] *= d.inertia[a] / d.rigid_inertia[a];
        }
    }
}

Status out_of_range(size_t c, const Chain& chain, const char* what, double value) {
    char buf[160];
    std::snprintf(buf, sizeof buf, "%s %.3g", what, value);
    return Status{ErrorCode::invalid_argument,
                  "chain " + std::to_string(c) + " (attach node " + std::to_string(chain.attach_node) +
                      "): coupled constant out of the computable range [1e-30, 1e30] (" + buf +
                      "): radius, segment length, material or dt too extreme"};
}

}  // namespace

double uniform_cantilever_frequency(double length, double radius, const Material& material) {
    const double beta = 1.87510407;  // first root of 1 + cos(b) cosh(b) = 0
    const double j = kPi * std::pow(radius, 4) / 4.0, mu = material.density * kPi * radius * radius;
    return beta * beta / (2.0 * kPi) * std::sqrt(material.modulus * j / (mu * std::pow(length, 4)));
}

std::array<double, 4> oscillator_transition(double inertia, double stiffness, double damping, double dt) {
    // exp(A dt): scale A dt down by 2^k below norm 1/8, sum the Taylor series, square k times.
    double a[4] = {0.0, dt, -stiffness / inertia * dt, -damping / inertia * dt};
    double norm = std::max(std::abs(a[0]) + std::abs(a[1]), std::abs(a[2]) + std::abs(a[3]));
    int squarings = 0;
    while (norm > 0.125 && squarings < 200) {
        norm *= 0.5;
        ++squarings;
    }
    const double scale = std::ldexp(1.0, -squarings);
    for (double& v : a) v *= scale;
    double result[4] = {1.0, 0.0, 0.0, 1.0}, term[4] = {1.0, 0.0, 0.0, 1.0};
    for (int k = 1; k <= 20; ++k) {
        const double t[4] = {(term[0] * a[0] + term[1] * a[2]) / k, (term[0] * a[1] + term[1] * a[3]) / k,
                             (term[2] * a[0] + term[3] * a[2]) / k, (term[2] * a[1] + term[3] * a[3]) / k};
        for (int i = 0; i < 4; ++i) {
            term[i] = t[i];
            result[i] += t[i];
        }
    }
    for (int k = 0; k < squarings; ++k) {
        const double m[4] = {result[0] * result[0] + result[1] * result[2], result[0] * result[1] + result[1] * result[3],
                             result[2] * result[0] + result[3] * result[2], result[2] * result[1] + result[3] * result[3]};
        for (int i = 0; i < 4; ++i) result[i] = m[i];
    }
    return {result[0], result[1], result[2], result[3]};
}

Status fill_coupled_constants(const TreeModel& tree, const Parameters& parameters, Hierarchy& h) {
    const Material& material = parameters.material;
    const size_t chain_count = h.chains.size();

    const ChainBodies bodies = chain_bodies(tree, h, parameters);
    const std::vector<ChainPath>& paths = bodies.paths;
    const std::vector<int32_t>& path_index = bodies.path_index;
    const std::vector<std::vector<PointLoad>>& leaves = bodies.leaves;

    // Children: breadth-first numbering makes them one contiguous id range (docs/model.md 3.2).
    for (size_t c = 1; c < chain_count; ++c) {
        ChainDynamics& parent = h.chains[h.chains[c].parent].dynamics;
        if (parent.child_count == 0) parent.first_child = int32_t(c);
        if (parent.first_child + parent.child_count != int32_t(c))
            return Status{ErrorCode::internal, "chain " + std::to_string(c) + ": children not contiguous"};
        ++parent.child_count;
    }

    const double wood_cd = parameters.wood_drag_coefficient;
    const double zeta = parameters.structural_damping;
    // The cantilever loads of each chain at its path nodes: leaves and children as rigid bodies
    // (a link's next link excluded: it lies on the same cantilever).
    std::vector<std::vector<NodeLoad>> node_loads(chain_count);
    // Each chain's subtree first mass moment about its joint, in its own frame: the parallel-axis
    // transport of its inertia to its parent's joint needs the subtree's centroid.
    std::vector<glm::dvec3> mass_moments(chain_count, glm::dvec3(0.0));
    // Children have larger ids than their parent: from the last chain up, every child is done.
    for (size_t c = chain_count; c-- > 0;) {
        Chain& chain = h.chains[c];
        ChainDynamics& d = chain.dynamics;
        const ChainPath& path = paths[c];
        double inertia[2] = {0.0, 0.0}, drag_moment2[2] = {0.0, 0.0}, drag_moment3[2] = {0.0, 0.0};
        glm::dvec3 moment(0.0), mass_moment(0.0);
        // Own wood (the drag's third moment, not a polynomial, to the Gauss rule's accuracy).
        // The own body (d.own_*), for the articulated exchange.
        auto add_own = [&](const glm::dvec3& x, double dm, double da) {
            d.own_mass_moment += Vec3(dm * x);
            d.own_inertia += Mat3(dm * (glm::dot(x, x) * glm::dmat3(1.0) - glm::outerProduct(x, x)));
            d.own_wind_moment += Vec3(da * x);
        };
        for_each_wood_point(path, material, wood_cd, [&](const glm::dvec3& x, double dm, double da) {
            add_own(x, dm, da);
            d.mass += dm;
            d.drag_area += da;
            moment += da * x;
            mass_moment += dm * x;
            for (int a = 0; a < 2; ++a) {
                inertia[a] += dm * axis_distance2(x, a);
                drag_moment2[a] += da * axis_distance2(x, a);
                drag_moment3[a] += da * axis_distance3(x, a);
            }
        });
        std::vector<NodeLoad>& node_load = node_loads[c];
        node_load.assign(path.p.size(), NodeLoad{});
        for (const PointLoad& leaf : leaves[c]) {
            add_own(leaf.x, leaf.mass, leaf.drag_area);
            d.mass += leaf.mass;
            d.drag_area += leaf.drag_area;
            moment += leaf.drag_area * leaf.x;
            mass_moment += leaf.mass * leaf.x;
            for (int a = 0; a < 2; ++a) {
                inertia[a] += leaf.mass * axis_distance2(leaf.x, a);
                drag_moment2[a] += leaf.drag_area * axis_distance2(leaf.x, a);
                drag_moment3[a] += leaf.drag_area * axis_distance3(leaf.x, a);
            }
            NodeLoad& at = node_load[size_t(leaf.path_index)];
            const glm::dvec3 offset = leaf.x - path.p[size_t(leaf.path_index)];
            at.mass += leaf.mass;
            at.lever += leaf.mass * glm::dot(offset, path_tangent(path, size_t(leaf.path_index)));
            for (int a = 0; a < 2; ++a) at.rotary[a] += leaf.mass * axis_distance2(offset, a);
        }
        d.subtree_mass = d.mass;
        d.subtree_drag_area = d.drag_area;
        for (int32_t k = d.first_child; k < d.first_child + d.child_count; ++k) {
            const Chain& child = h.chains[k];
            const glm::dvec3 a = h.node_local[child.attach_node];
            const size_t at = size_t(path_index[child.attach_node]);
            d.subtree_mass += child.dynamics.subtree_mass;
            d.subtree_drag_area += child.dynamics.subtree_drag_area;
            moment += child.dynamics.subtree_drag_area * a;
            // The child's subtree mass moment about its own joint, in this chain's frame.
            const glm::dvec3 child_moment = child.rest_rotation * mass_moments[size_t(k)];
            mass_moment += child.dynamics.subtree_mass * a + child_moment;
            const bool next_link = child.dynamics.link_index > 0;
            if (!next_link) {
                node_load[at].mass += child.dynamics.subtree_mass;
                node_load[at].lever += glm::dot(child_moment, path_tangent(path, at));
            }
            for (int ax = 0; ax < 2; ++ax) {
                const double rotary = projected_inertia(child, ax);
                // Parallel axis from the child's joint to this joint, the child's centroid not at
                // its joint: m d(a)^2 + 2 a . (m c) across the axis, plus its inertia about its joint.
                inertia[ax] += child.dynamics.subtree_mass * axis_distance2(a, ax) +
                               axis_cross2(a, child_moment, ax) + rotary;
                drag_moment2[ax] += child.dynamics.subtree_drag_area * axis_distance2(a, ax);
                drag_moment3[ax] += child.dynamics.subtree_drag_area * axis_distance3(a, ax);
                if (!next_link) node_load[at].rotary[ax] += rotary;
            }
        }
        d.wind_moment = moment;
        mass_moments[c] = mass_moment;
        for (int a = 0; a < 2; ++a) {
            d.inertia[a] = d.rigid_inertia[a] = inertia[a];
            d.aero_damping[a] = kAirDensity * kReferenceWindSpeed * drag_moment2[a];
            d.motion_drag[a] = 0.5 * kAirDensity * drag_moment3[a];
        }
        if (d.link_count > 1) continue;  // split_chain_constants, below
        double omega[2];
        cantilever(path, node_load, material, omega, d.beam_stiffness);
        for (int a = 0; a < 2; ++a) {
            d.frequency[a] = omega[a] / (2.0 * kPi);
            d.stiffness[a] = omega[a] * omega[a] * inertia[a];
            d.damping[a] = 2.0 * zeta * std::sqrt(d.stiffness[a] * inertia[a]);
        }
    }
    for (size_t c = 0; c < chain_count; ++c)
        if (h.chains[c].dynamics.link_index == 0 && h.chains[c].dynamics.link_count > 1)
            split_chain_constants(h, c, paths, node_loads, material, zeta);
    for (size_t c = chain_count; c-- > 0;) {
        Chain& chain = h.chains[c];
        const ChainDynamics& d = chain.dynamics;
        chain.inertia = d.inertia[0];
        chain.stiffness = d.stiffness[0];
        chain.damping = d.damping[0];
        chain.wind_area = kReferencePressure * glm::length(d.wind_moment);
        chain.capped = false;
        for (int a = 0; a < 2; ++a) {
            if (!float_safe(d.inertia[a], false)) return out_of_range(c, chain, "inertia", d.inertia[a]);
            if (!float_safe(d.stiffness[a], false)) return out_of_range(c, chain, "stiffness", d.stiffness[a]);
            if (!float_safe(parameters.dt / d.inertia[a], false))
                return out_of_range(c, chain, "dt/I", parameters.dt / d.inertia[a]);
            if (!float_safe(d.damping[a], true)) return out_of_range(c, chain, "damping", d.damping[a]);
            if (!float_safe(d.aero_damping[a], true))
                return out_of_range(c, chain, "aerodynamic damping", d.aero_damping[a]);
            if (!float_safe(d.motion_drag[a], true)) return out_of_range(c, chain, "motion drag", d.motion_drag[a]);
        }
        if (!float_safe(chain.wind_area, true)) return out_of_range(c, chain, "wind moment", chain.wind_area);
    }
    h.capped_chain_count = 0;
    return {};
}

}  // namespace hmsm::detail
