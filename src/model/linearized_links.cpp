// The linearized links and their lowest modes (linearized_links.h, docs/model.md 3.13).
#include "linearized_links.h"

#include "chain_bodies.h"

#include <glm/geometric.hpp>
#include <glm/matrix.hpp>

#include <algorithm>
#include <cmath>
#include <numbers>

namespace hmsm::detail {

void BodyInertia::add_point(const glm::dvec3& x, double m) {
    mass += m;
    moment += m * x;
    rotational += m * (glm::dot(x, x) * glm::dmat3(1.0) - glm::outerProduct(x, x));
}

LinearizedLinks linearize_links(const TreeModel& tree, const Hierarchy& h, const Parameters& parameters) {
    const ChainBodies bodies = chain_bodies(tree, h, parameters);
    LinearizedLinks out;
    out.links.resize(h.chains.size());
    for (size_t c = 0; c < h.chains.size(); ++c) {
        const Chain& chain = h.chains[c];
        LinkBody& link = out.links[c];
        link.parent = chain.parent;
        link.pivot = tree.nodes[size_t(chain.attach_node)].position;
        link.axis = {chain.frame[0], chain.frame[2]};
        auto add = [&](const glm::dvec3& local, double m) { link.body.add_point(link.pivot + chain.frame * local, m); };
        for_each_wood_point(bodies.paths[c], parameters.material, parameters.wood_drag_coefficient,
                            [&](const glm::dvec3& x, double dm, double) { add(x, dm); });
        for (const PointLoad& leaf : bodies.leaves[c]) add(leaf.x, leaf.mass);
        for (int a = 0; a < 2; ++a) {
            link.stiffness[size_t(a)] = chain.dynamics.stiffness[a];
            link.damping[size_t(a)] = chain.dynamics.damping[a];
        }
        out.total_mass += link.body.mass;
    }
    return out;
}

namespace {

/// A spatial vector as two 3-vectors: motion (omega, v0) or force (moment about the origin, force).
struct Spatial {
    glm::dvec3 angular{0.0}, linear{0.0};
};

/// The generalized force of spatial force f on joint `axis` of `link` (the power of f at the
/// joint's unit motion (u, p x u)).
double project(const LinkBody& link, int axis, const Spatial& f) {
    const glm::dvec3& u = link.axis[size_t(axis)];
    return glm::dot(u, f.angular) + glm::dot(glm::cross(link.pivot, u), f.linear);
}

/// Sums every chain's spatial force into its parent's (children have larger ids) and projects
/// each sum on its chain's two joints.
std::vector<double> gather_up(const LinearizedLinks& links, std::vector<Spatial>& force) {
    for (size_t c = links.links.size(); c-- > 1;) {
        Spatial& parent = force[size_t(links.links[c].parent)];
        parent.angular += force[c].angular;
        parent.linear += force[c].linear;
    }
    std::vector<double> out(links.joints());
    for (size_t c = 0; c < links.links.size(); ++c)
        for (int a = 0; a < 2; ++a) out[2 * c + size_t(a)] = project(links.links[c], a, force[c]);
    return out;
}

/// Eigenvalues and vectors (columns of v, row-major n x n) of the symmetric matrix a (row-major,
/// destroyed) by cyclic Jacobi rotations.
void symmetric_eigen(std::vector<double>& a, size_t n, std::vector<double>& values, std::vector<double>& v) {
    v.assign(n * n, 0.0);
    for (size_t i = 0; i < n; ++i) v[i * n + i] = 1.0;
    for (int sweep = 0; sweep < 100; ++sweep) {
        double off = 0.0, diag = 0.0;
        for (size_t i = 0; i < n; ++i)
            for (size_t j = 0; j < n; ++j) (i == j ? diag : off) += a[i * n + j] * a[i * n + j];
        if (off <= 1e-30 * diag) break;
        for (size_t p = 0; p < n; ++p)
            for (size_t q = p + 1; q < n; ++q) {
                const double apq = a[p * n + q];
                if (apq == 0.0) continue;
                const double theta = (a[q * n + q] - a[p * n + p]) / (2.0 * apq);
                const double t = (theta >= 0 ? 1.0 : -1.0) / (std::abs(theta) + std::sqrt(theta * theta + 1.0));
                const double c = 1.0 / std::sqrt(t * t + 1.0), s = t * c;
                for (size_t k = 0; k < n; ++k) {  // columns p, q
                    const double akp = a[k * n + p], akq = a[k * n + q];
                    a[k * n + p] = c * akp - s * akq;
                    a[k * n + q] = s * akp + c * akq;
                }
                for (size_t k = 0; k < n; ++k) {  // rows p, q
                    const double apk = a[p * n + k], aqk = a[q * n + k];
                    a[p * n + k] = c * apk - s * aqk;
                    a[q * n + k] = s * apk + c * aqk;
                }
                for (size_t k = 0; k < n; ++k) {
                    const double vkp = v[k * n + p], vkq = v[k * n + q];
                    v[k * n + p] = c * vkp - s * vkq;
                    v[k * n + q] = s * vkp + c * vkq;
                }
            }
    }
    values.resize(n);
    for (size_t i = 0; i < n; ++i) values[i] = a[i * n + i];
}

}  // namespace

void link_mass_times(const LinearizedLinks& links, const std::vector<double>& y, std::vector<double>& out) {
    const size_t n = links.links.size();
    std::vector<Spatial> momentum(n);
    std::vector<Spatial> velocity(n);
    for (size_t c = 0; c < n; ++c) {
        const LinkBody& link = links.links[c];
        Spatial v = link.parent >= 0 ? velocity[size_t(link.parent)] : Spatial{};
        for (int a = 0; a < 2; ++a) {
            const glm::dvec3& u = link.axis[size_t(a)];
            v.angular += y[2 * c + size_t(a)] * u;
            v.linear += y[2 * c + size_t(a)] * glm::cross(link.pivot, u);
        }
        velocity[c] = v;
        const BodyInertia& b = link.body;
        momentum[c] = {glm::cross(b.moment, v.linear) + b.rotational * v.angular,
                       b.mass * v.linear + glm::cross(v.angular, b.moment)};
    }
    out = gather_up(links, momentum);
}

std::vector<double> uniform_load(const LinearizedLinks& links, const glm::dvec3& direction) {
    std::vector<Spatial> force(links.links.size());
    for (size_t c = 0; c < links.links.size(); ++c) {
        const BodyInertia& b = links.links[c].body;
        force[c] = {glm::cross(b.moment, direction), b.mass * direction};
    }
    return gather_up(links, force);
}

LinkModes lowest_link_modes(const LinearizedLinks& links, int count, const std::array<glm::dvec3, 2>& directions) {
    LinkModes modes;
    const size_t n = links.joints();
    if (n == 0 || count <= 0) return modes;
    std::vector<double> stiffness(n);
    for (size_t c = 0; c < links.links.size(); ++c)
        for (size_t a = 0; a < 2; ++a) stiffness[2 * c + a] = links.links[c].stiffness[a];
    const double two_pi = 2.0 * std::numbers::pi;

    // The sway: Rayleigh's quotient with the static deflection q = K^-1 F.
    std::vector<std::vector<double>> loads;
    std::vector<double> mq;
    for (size_t d = 0; d < 2; ++d) {
        loads.push_back(uniform_load(links, directions[d]));
        std::vector<double> q(n);
        for (size_t i = 0; i < n; ++i) q[i] = loads[d][i] / stiffness[i];
        link_mass_times(links, q, mq);
        double work = 0.0, kinetic = 0.0;
        for (size_t i = 0; i < n; ++i) {
            work += q[i] * loads[d][i];
            kinetic += q[i] * mq[i];
        }
        modes.sway_hz[d] = kinetic > 0.0 ? std::sqrt(work / kinetic) / two_pi : 0.0;
    }

    // Subspace iteration on K^-1 M with Rayleigh-Ritz, p vectors for the `count` wanted.
    const size_t wanted = std::min(n, size_t(count));
    const size_t p = std::min(n, wanted + 8);
    std::vector<std::vector<double>> y(p, std::vector<double>(n));
    uint64_t state = 0x9e3779b97f4a7c15ull;  // a fixed start: the result does not depend on a seed
    for (auto& column : y)
        for (double& v : column) {
            state = state * 6364136223846793005ull + 1442695040888963407ull;
            v = double(state >> 11) / double(1ull << 53) - 0.5;
        }
    std::vector<double> previous(wanted, 0.0), values, vectors;
    std::vector<std::vector<double>> z(p), mz(p);
    for (modes.iterations = 1; modes.iterations <= 1000; ++modes.iterations) {
        for (size_t k = 0; k < p; ++k) {
            link_mass_times(links, y[k], z[k]);
            for (size_t i = 0; i < n; ++i) z[k][i] /= stiffness[i];
            link_mass_times(links, z[k], mz[k]);
        }
        // Reduced K and M: Kr = Z^T K Z, Mr = Z^T M Z; Mr = L L^T, then L^-1 Kr L^-T.
        std::vector<double> kr(p * p), mr(p * p);
        for (size_t a = 0; a < p; ++a)
            for (size_t b = 0; b <= a; ++b) {
                double ks = 0.0, ms = 0.0;
                for (size_t i = 0; i < n; ++i) {
                    ks += z[a][i] * stiffness[i] * z[b][i];
                    ms += z[a][i] * mz[b][i];
                }
                kr[a * p + b] = kr[b * p + a] = ks;
                mr[a * p + b] = mr[b * p + a] = ms;
            }
        std::vector<double> l(p * p, 0.0);
        for (size_t i = 0; i < p; ++i)
            for (size_t j = 0; j <= i; ++j) {
                double s = mr[i * p + j];
                for (size_t k = 0; k < j; ++k) s -= l[i * p + k] * l[j * p + k];
                l[i * p + j] = i == j ? std::sqrt(std::max(s, 1e-300)) : s / l[j * p + j];
            }
        // c = L^-1 Kr L^-T, column by column.
        std::vector<double> t(p * p), c(p * p);
        for (size_t col = 0; col < p; ++col)
            for (size_t i = 0; i < p; ++i) {
                double s = kr[i * p + col];
                for (size_t k = 0; k < i; ++k) s -= l[i * p + k] * t[k * p + col];
                t[i * p + col] = s / l[i * p + i];
            }
        for (size_t row = 0; row < p; ++row)
            for (size_t i = 0; i < p; ++i) {
                double s = t[row * p + i];
                for (size_t k = 0; k < i; ++k) s -= l[i * p + k] * c[row * p + k];
                c[row * p + i] = s / l[i * p + i];
            }
        symmetric_eigen(c, p, values, vectors);
        std::vector<size_t> order(p);
        for (size_t i = 0; i < p; ++i) order[i] = i;
        std::sort(order.begin(), order.end(), [&](size_t a, size_t b) { return values[a] < values[b]; });
        // Ritz vectors: Y = Z L^-T W (M-orthonormal).
        std::vector<std::vector<double>> next(p, std::vector<double>(n, 0.0));
        for (size_t k = 0; k < p; ++k) {
            std::vector<double> a(p);  // L^-T w_k
            for (size_t i = p; i-- > 0;) {
                double s = vectors[i * p + order[k]];
                for (size_t j = i + 1; j < p; ++j) s -= l[j * p + i] * a[j];
                a[i] = s / l[i * p + i];
            }
            for (size_t j = 0; j < p; ++j)
                for (size_t i = 0; i < n; ++i) next[k][i] += z[j][i] * a[j];
        }
        y = std::move(next);
        bool settled = true;
        for (size_t k = 0; k < wanted; ++k) {
            const double v = values[order[k]];
            if (!(std::abs(v - previous[k]) <= 1e-12 * std::abs(v))) settled = false;
            previous[k] = v;
        }
        if (settled) {
            modes.converged = true;
            break;
        }
    }
    for (size_t k = 0; k < wanted; ++k) {
        modes.frequency_hz.push_back(std::sqrt(std::max(previous[k], 0.0)) / two_pi);
        std::vector<double> my;
        link_mass_times(links, y[k], my);
        double norm = 0.0;
        for (size_t i = 0; i < n; ++i) norm += y[k][i] * my[i];
        std::array<double, 2> share{};
        for (size_t d = 0; d < 2; ++d) {
            double gamma = 0.0;
            for (size_t i = 0; i < n; ++i) gamma += y[k][i] * loads[d][i];
            share[d] = norm > 0.0 && links.total_mass > 0.0 ? gamma * gamma / norm / links.total_mass : 0.0;
        }
        modes.mass_share.push_back(share);
    }
    if (modes.iterations > 1000) modes.iterations = 1000;
    return modes;
}

}  // namespace hmsm::detail
