// Levels of detail (docs/model.md 3.12): the order in which a model's chains fold into their
// parents, the level hierarchies cut from it, their trunk frequency and geometric error.
#include <hmsm/levels.h>

#include "coupled_constants.h"

#include <glm/geometric.hpp>
#include <glm/matrix.hpp>

#include <algorithm>
#include <cmath>
#include <functional>
#include <iterator>
#include <numbers>
#include <queue>
#include <string>
#include <utility>

namespace hmsm {
namespace {

Status check_inputs(const TreeModel& tree, const Hierarchy& full, const Parameters& parameters) {
    HMSM_TRY(validate(parameters));
    if (full.chains.empty() || full.node_owner.size() != tree.nodes.size() ||
        full.node_local.size() != tree.nodes.size())
        return Status{ErrorCode::invalid_argument,
                      "levels: the hierarchy has " + std::to_string(full.node_owner.size()) + " nodes and " +
                          std::to_string(full.chains.size()) + " chains, the tree " +
                          std::to_string(tree.nodes.size()) + " nodes: pass build_hierarchy(tree, ...)"};
    return {};
}

Status check_budget(int32_t budget, const std::string& what) {
    if (budget < 1)
        return Status{ErrorCode::invalid_argument,
                      what + " " + std::to_string(budget) +
                          ": below the trunk-only level, the coarsest there is (1 joint)"};
    return {};
}

glm::dvec3 attach_position(const TreeModel& tree, const Hierarchy& h, size_t c) {
    return glm::dvec3(tree.nodes[size_t(h.chains[c].attach_node)].position);
}

/// The chain's static bend under a unit wind across it, A / K, at most θmax (rad).
double static_angle(const Chain& chain, double max_angle) {
    return std::min(max_angle, chain.wind_area / chain.stiffness);
}

/// Every chain but the trunk, in the order the levels fold them: always a chain none of whose
/// children is left, the one of least cost θ_c e_c first (ties: the higher id).
std::vector<int32_t> fold_order(const TreeModel& tree, const Hierarchy& h, const Parameters& parameters) {
    const size_t chains = h.chains.size();
    // e_c bounds the distance of every node of c's subtree from c's attach node: its own nodes
    // exactly, a child subtree k by |p_a(k) − p_a(c)| + e_k. Children have higher ids.
    std::vector<double> extent(chains, 0.0);
    for (size_t n = 0; n < tree.nodes.size(); ++n) {
        const size_t c = size_t(h.node_owner[n]);
        const double d = glm::length(glm::dvec3(tree.nodes[n].position) - attach_position(tree, h, c));
        extent[c] = std::max(extent[c], d);
    }
    std::vector<int32_t> open_children(chains, 0);
    for (size_t c = chains; c-- > 1;) {
        const size_t parent = size_t(h.chains[c].parent);
        const double lever = glm::length(attach_position(tree, h, c) - attach_position(tree, h, parent));
        extent[parent] = std::max(extent[parent], lever + extent[c]);
        ++open_children[parent];
    }
    using Entry = std::pair<double, int32_t>;  // (cost, id)
    auto later = [](const Entry& a, const Entry& b) {
        return a.first != b.first ? a.first > b.first : a.second < b.second;
    };
    std::priority_queue<Entry, std::vector<Entry>, decltype(later)> leaves(later);
    auto cost = [&](size_t c) { return static_angle(h.chains[c], parameters.max_angle) * extent[c]; };
    for (size_t c = 1; c < chains; ++c)
        if (open_children[c] == 0) leaves.emplace(cost(c), int32_t(c));
    std::vector<int32_t> order;
    order.reserve(chains - 1);
    while (!leaves.empty()) {
        const int32_t c = leaves.top().second;
        leaves.pop();
        order.push_back(c);
        const int32_t parent = h.chains[size_t(c)].parent;
        if (--open_children[size_t(parent)] == 0 && parent != 0) leaves.emplace(cost(size_t(parent)), parent);
    }
    return order;
}

glm::dmat3 rotation_x(double a) {
    const double c = std::cos(a), s = std::sin(a);
    return glm::dmat3(1, 0, 0, 0, c, s, 0, -s, c);  // columns
}

glm::dmat3 rotation_z(double a) {
    const double c = std::cos(a), s = std::sin(a);
    return glm::dmat3(c, s, 0, -s, c, 0, 0, 0, 1);
}

/// Node positions (root at the origin, yaw 0) in the static linear response of the full model
/// to a steady wind `wind`: each chain at θ = clamp(A (w_loc.z, −w_loc.x) / K, ±θmax) with
/// w_loc = B_cᵀ wind, composed as in passes 2-6; chains flagged in `folded` stay at θ = 0.
std::vector<glm::dvec3> static_pose(const Hierarchy& h, const Parameters& parameters, const glm::dvec3& wind,
                                    const std::vector<char>& folded) {
    const size_t chains = h.chains.size();
    std::vector<glm::dmat3> rotation(chains);
    std::vector<glm::dvec3> origin(chains, glm::dvec3(0.0));
    const double limit = parameters.max_angle;
    for (size_t c = 0; c < chains; ++c) {
        const Chain& chain = h.chains[c];
        double theta_x = 0.0, theta_z = 0.0;
        if (!folded[c]) {
            const glm::dvec3 local = glm::transpose(glm::dmat3(chain.frame)) * wind;
            theta_x = std::clamp(chain.wind_area * local.z / chain.stiffness, -limit, limit);
            theta_z = std::clamp(-chain.wind_area * local.x / chain.stiffness, -limit, limit);
        }
        const glm::dmat3 local_transform = glm::dmat3(chain.rest_rotation) * rotation_z(theta_z) * rotation_x(theta_x);
        if (chain.parent < 0) {
            rotation[c] = local_transform;
        } else {
            const size_t parent = size_t(chain.parent);
            rotation[c] = rotation[parent] * local_transform;
            origin[c] = origin[parent] + rotation[parent] * glm::dvec3(h.node_local[size_t(chain.attach_node)]);
        }
    }
    std::vector<glm::dvec3> nodes(h.node_owner.size());
    for (size_t n = 0; n < nodes.size(); ++n) {
        const size_t c = size_t(h.node_owner[n]);
        nodes[n] = origin[c] + rotation[c] * glm::dvec3(h.node_local[n]);
    }
    return nodes;
}

const glm::dvec3 kErrorWinds[] = {{1.0, 0.0, 0.0}, {0.0, 0.0, 1.0}};

double natural_frequency(const Chain& chain) {
    return std::sqrt(chain.stiffness / chain.inertia) / (2.0 * std::numbers::pi);
}

/// A chain's own body (ChainDynamics' mass, drag area and own_* moments) with the chains folded
/// into it, about its joint in its frame.
struct FoldedBody {
    double mass = 0.0, drag_area = 0.0;
    glm::dvec3 moment{0.0}, wind_moment{0.0};
    glm::dmat3 inertia{0.0};
};

/// Adds body b, given in a child's frame about the child's joint, which sits at `at` in this
/// frame turned by the child's rest rotation q: the parallel-axis transport of its moments.
void add_transported(FoldedBody& to, const FoldedBody& b, const glm::dmat3& q, const glm::dvec3& at) {
    const glm::dvec3 h = q * b.moment;
    const glm::dmat3 one(1.0);
    to.mass += b.mass;
    to.drag_area += b.drag_area;
    to.moment += b.mass * at + h;
    to.wind_moment += b.drag_area * at + q * b.wind_moment;
    to.inertia += q * b.inertia * glm::transpose(q) + b.mass * (glm::dot(at, at) * one - glm::outerProduct(at, at)) +
                  2.0 * glm::dot(at, h) * one - glm::outerProduct(at, h) - glm::outerProduct(h, at);
}

/// The coupled dynamics (docs/model.md 3.12, 3.13): a kept chain's record names its children
/// among the level's chains, and its wind moment M takes the drag of the subtrees folded into
/// it at their true lever arms, `Q_k M_sub(k)` with M_sub(k) = M_k + Σ_j Q_j M_sub(j) over the
/// whole folded subtree: the moment about the attach node that a full child's load carried.
/// I, K and D stay (the subtree's mass is lumped in I either way). Its own body, which the
/// articulated exchange turns, takes the folded chains' bodies rigidly. Paper hierarchies: no-op.
void fold_coupled_records(const Hierarchy& full, const std::vector<char>& folded, DetailLevel& level) {
    const size_t chains = full.chains.size();
    if (full.chains[0].dynamics.link_count == 0) return;
    std::vector<glm::dvec3> subtree_moment(chains);
    std::vector<FoldedBody> body(chains);
    for (size_t c = chains; c-- > 0;) {  // children have larger ids
        const ChainDynamics& d = full.chains[c].dynamics;
        glm::dvec3 moment(d.wind_moment);
        body[c] = {d.mass, d.drag_area, glm::dvec3(d.own_mass_moment), glm::dvec3(d.own_wind_moment),
                   glm::dmat3(d.own_inertia)};
        for (int32_t k = d.first_child; k < d.first_child + d.child_count; ++k) {
            const Chain& child = full.chains[size_t(k)];
            moment += glm::dmat3(child.rest_rotation) * subtree_moment[size_t(k)];
            if (folded[size_t(k)])
                add_transported(body[c], body[size_t(k)], glm::dmat3(child.rest_rotation),
                                glm::dvec3(full.node_local[size_t(child.attach_node)]));
        }
        subtree_moment[c] = moment;
    }
    for (size_t C = 0; C < level.hierarchy.chains.size(); ++C) {
        const ChainDynamics& kept = full.chains[size_t(level.source_chain[C])].dynamics;
        Chain& chain = level.hierarchy.chains[C];
        ChainDynamics& d = chain.dynamics;
        glm::dvec3 moment(kept.wind_moment);
        d.first_child = 0;
        d.child_count = 0;
        // The kept children of a breadth-first parent stay one contiguous id range.
        for (int32_t k = kept.first_child; k < kept.first_child + kept.child_count; ++k) {
            if (folded[size_t(k)]) {
                moment += glm::dmat3(full.chains[size_t(k)].rest_rotation) * subtree_moment[size_t(k)];
                continue;
            }
            if (d.child_count == 0) d.first_child = level.chain_of[size_t(k)];
            ++d.child_count;
        }
        d.wind_moment = Vec3(moment);
        chain.wind_area = detail::kReferencePressure * glm::length(moment);
        const FoldedBody& b = body[size_t(level.source_chain[C])];
        d.mass = b.mass;
        d.drag_area = b.drag_area;
        d.own_mass_moment = Vec3(b.moment);
        d.own_wind_moment = Vec3(b.wind_moment);
        d.own_inertia = Mat3(b.inertia);
    }
}

/// The level that keeps every chain not among the first `fold_count` entries of `order`.
DetailLevel cut_level(const TreeModel& tree, const Hierarchy& full, const Parameters& parameters,
                      const std::vector<int32_t>& order, int32_t budget,
                      const std::vector<std::vector<glm::dvec3>>& full_poses) {
    const size_t chains = full.chains.size();
    const size_t fold_count = chains - std::min(chains, size_t(budget));
    std::vector<char> folded(chains, 0);
    for (size_t i = 0; i < fold_count; ++i) folded[size_t(order[i])] = 1;

    DetailLevel level;
    level.budget = budget;
    Hierarchy& h = level.hierarchy;
    level.chain_of.assign(chains, -1);
    for (size_t c = 0; c < chains; ++c) {  // parents come before their children
        const Chain& chain = full.chains[c];
        if (folded[c]) {
            level.chain_of[c] = level.chain_of[size_t(chain.parent)];
            continue;
        }
        level.chain_of[c] = int32_t(h.chains.size());
        level.source_chain.push_back(int32_t(c));
        Chain kept = chain;
        if (chain.parent >= 0) kept.parent = level.chain_of[size_t(chain.parent)];
        h.chains.push_back(std::move(kept));
    }
    fold_coupled_records(full, folded, level);
    h.continuation = full.continuation;
    h.node_owner.resize(tree.nodes.size());
    h.node_local.resize(tree.nodes.size());
    for (size_t n = 0; n < tree.nodes.size(); ++n) {
        const int32_t owner = full.node_owner[n];
        const int32_t moved_by = level.chain_of[size_t(owner)];
        h.node_owner[n] = moved_by;
        if (level.source_chain[size_t(moved_by)] == owner) {
            h.node_local[n] = full.node_local[n];
        } else {  // a folded node, rigid in the frame of the chain that carries it
            const Chain& carrier = h.chains[size_t(moved_by)];
            const glm::dvec3 attach(tree.nodes[size_t(carrier.attach_node)].position);
            h.node_local[n] =
                glm::transpose(glm::dmat3(carrier.frame)) * (glm::dvec3(tree.nodes[n].position) - attach);
        }
    }
    for (const Chain& chain : h.chains) {
        h.max_depth = std::max(h.max_depth, chain.depth);
        if (chain.capped) ++h.capped_chain_count;
    }
    h.chains_per_depth.assign(size_t(h.max_depth) + 1, 0);
    for (const Chain& chain : h.chains) ++h.chains_per_depth[size_t(chain.depth)];

    level.full_trunk_frequency_hz = natural_frequency(full.chains[0]);
    level.trunk_frequency_hz = natural_frequency(h.chains[0]);
    for (size_t w = 0; w < std::size(kErrorWinds); ++w) {
        const std::vector<glm::dvec3> pose = static_pose(full, parameters, kErrorWinds[w], folded);
        for (size_t n = 0; n < pose.size(); ++n)
            level.geometric_error_m = std::max(level.geometric_error_m, glm::length(pose[n] - full_poses[w][n]));
    }
    return level;
}

std::vector<std::vector<glm::dvec3>> full_static_poses(const Hierarchy& full, const Parameters& parameters) {
    const std::vector<char> none(full.chains.size(), 0);
    std::vector<std::vector<glm::dvec3>> poses;
    for (const glm::dvec3& wind : kErrorWinds) poses.push_back(static_pose(full, parameters, wind, none));
    return poses;
}

}  // namespace

MeshTemplate build_level_mesh(const TreeModel& tree, const Hierarchy& full, const MeshTemplate& mesh,
                              const DetailLevel& level) {
    const Hierarchy& h = level.hierarchy;
    auto frame = [](const Hierarchy& in, int32_t c) { return glm::dmat3(in.chains[size_t(c)].frame); };
    auto attach = [&](const Hierarchy& in, int32_t c) {
        return glm::dvec3(tree.nodes[size_t(in.chains[size_t(c)].attach_node)].position);
    };
    // A rest point (direction) given in full chain c's frame, in level chain C's frame.
    auto point_in = [&](int32_t C, int32_t c, const glm::dvec3& local) {
        const glm::dvec3 rest = attach(full, c) + frame(full, c) * local;
        return glm::transpose(frame(h, C)) * (rest - attach(h, C));
    };
    auto direction_in = [&](int32_t C, int32_t c, const glm::dvec3& local) {
        return glm::transpose(frame(h, C)) * (frame(full, c) * local);
    };
    MeshTemplate out = mesh;
    for (MeshVertex& v : out.vertices) {
        const int32_t c = v.chain, f = v.fix_chain;
        const int32_t C = level.chain_of[size_t(c)];
        const int32_t F = f >= 0 ? level.chain_of[size_t(f)] : -1;
        if (level.source_chain[size_t(C)] != c) {
            v.position = point_in(C, c, glm::dvec3(v.position));
            v.normal = direction_in(C, c, glm::dvec3(v.normal));
        }
        v.chain = C;
        if (F < 0 || F == C) {  // rigid with one level chain
            v.fix_chain = -1;
            v.parent_position = Vec3(0.0);
            v.parent_normal = Vec3(0.0);
        } else {
            if (level.source_chain[size_t(F)] != f) {
                v.parent_position = point_in(F, f, glm::dvec3(v.parent_position));
                v.parent_normal = direction_in(F, f, glm::dvec3(v.parent_normal));
            }
            v.fix_chain = F;
        }
    }
    return out;
}

Result<DetailLevel> build_level(const TreeModel& tree, const Hierarchy& full, const Parameters& parameters,
                                int32_t max_joints) {
    HMSM_TRY(check_budget(max_joints, "joint budget"));
    HMSM_TRY(check_inputs(tree, full, parameters));
    const std::vector<int32_t> order = fold_order(tree, full, parameters);
    return cut_level(tree, full, parameters, order, max_joints, full_static_poses(full, parameters));
}

Result<std::vector<DetailLevel>> build_levels(const TreeModel& tree, const Hierarchy& full,
                                              const Parameters& parameters, const std::vector<int32_t>& budgets) {
    if (budgets.empty()) return Status{ErrorCode::invalid_argument, "joint budgets: the list is empty"};
    for (size_t i = 0; i < budgets.size(); ++i)
        HMSM_TRY(check_budget(budgets[i], "joint budgets[" + std::to_string(i) + "] ="));
    HMSM_TRY(check_inputs(tree, full, parameters));
    std::vector<int32_t> sorted = budgets;
    std::sort(sorted.begin(), sorted.end(), std::greater<>());
    sorted.erase(std::unique(sorted.begin(), sorted.end()), sorted.end());
    const std::vector<int32_t> order = fold_order(tree, full, parameters);
    const auto poses = full_static_poses(full, parameters);
    std::vector<DetailLevel> levels;
    for (int32_t budget : sorted) levels.push_back(cut_level(tree, full, parameters, order, budget, poses));
    return levels;
}

}  // namespace hmsm
