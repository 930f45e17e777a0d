// Direction-first chain decomposition (docs/model.md 3.2), frames (3.3) and constants (3.4).
#include <hmsm/hierarchy.h>
#include <hmsm/species.h>

#include "coupled_constants.h"

#include <glm/geometric.hpp>
#include <glm/matrix.hpp>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <numbers>

namespace hmsm {

namespace {

/// kappa(i) for every node: the child that continues i's chain, -1 for a node without children.
std::vector<int32_t> continuation_children(const TreeModel& tree,
                                           const std::vector<std::vector<int32_t>>& children,
                                           Grouping grouping) {
    const auto& nodes = tree.nodes;
    std::vector<int32_t> kappa(nodes.size(), -1);
    for (size_t i = 0; i < nodes.size(); ++i) {
        const auto& kids = children[i];
        if (kids.empty()) continue;
        glm::dvec3 d_in = nodes[i].parent < 0
                              ? glm::dvec3(0, 1, 0)
                              : glm::normalize(nodes[i].position - nodes[nodes[i].parent].position);
        int32_t best = kids[0];
        double best_score = 0.0;
        for (size_t j = 0; j < kids.size(); ++j) {
            int32_t k = kids[j];
            double score = grouping == Grouping::direction
                               ? glm::dot(d_in, glm::normalize(nodes[k].position - nodes[i].position))
                               : -std::abs(nodes[k].radius - nodes[i].radius);
            if (j == 0 || score > best_score) {  // ties keep the lowest index
                best = k;
                best_score = score;
            }
        }
        kappa[i] = best;
    }
    return kappa;
}

/// Zero, or a magnitude the float backends (cpu, Vulkan, CUDA) hold without flushing to zero or
/// overflowing in a product: outside [1e-30, 1e30] a step can turn into inf * 0 = NaN.
bool float_safe(double v, bool may_be_zero) {
    if (v == 0.0) return may_be_zero;
    return std::isfinite(v) && std::abs(v) >= 1e-30 && std::abs(v) <= 1e30;
}

glm::dmat3 rest_frame(const glm::dvec3& attach, const glm::dvec3& first_member) {
    glm::dvec3 y = glm::normalize(first_member - attach);
    glm::dvec3 ref = std::abs(y.z) > 0.9 ? glm::dvec3(1, 0, 0) : glm::dvec3(0, 0, 1);
    glm::dvec3 x = glm::normalize(glm::cross(y, ref));
    glm::dvec3 z = glm::cross(x, y);
    return glm::dmat3(x, y, z);
}

/// Arc length of the polyline from `attach` through `list`, node by node (docs/model.md 3.3).
std::vector<double> arc_lengths(const TreeModel& tree, int32_t attach, const std::vector<int32_t>& list) {
    std::vector<double> s;
    glm::dvec3 previous = tree.nodes[attach].position;
    double total = 0.0;
    for (int32_t m : list) {
        total += glm::length(tree.nodes[m].position - previous);
        previous = tree.nodes[m].position;
        s.push_back(total);
    }
    return s;
}

/// The links of a chain of the coupled dynamics (docs/model.md 3.13): n = min(members,
/// kMaxLinks, round(L / link_length)) links, at least one, each cut after the member whose arc
/// length is nearest to i L / n and holding at least one member.
std::vector<std::vector<int32_t>> split_into_links(const TreeModel& tree, int32_t attach,
                                                   const std::vector<int32_t>& list, double link_length) {
    const std::vector<double> s = arc_lengths(tree, attach, list);
    const int32_t m = int32_t(list.size());
    const double rounded = std::round(s.back() / link_length);
    const int32_t n = std::max(1, std::min({m, detail::kMaxLinks, rounded < double(m) ? int32_t(rounded) : m}));
    std::vector<std::vector<int32_t>> links;
    int32_t begin = 0;
    for (int32_t i = 1; i < n; ++i) {
        const double target = s.back() * double(i) / double(n);
        int32_t end = begin + 1;  // one past the link's last member
        for (int32_t e = end + 1; e <= m - (n - i); ++e)
            if (std::abs(s[size_t(e - 1)] - target) < std::abs(s[size_t(end - 1)] - target)) end = e;
        links.emplace_back(list.begin() + begin, list.begin() + end);
        begin = end;
    }
    links.emplace_back(list.begin() + begin, list.end());
    return links;
}

}  // namespace

Result<Hierarchy> build_hierarchy(const TreeModel& tree, const ModelOptions& options,
                                  const Parameters& parameters) {
    HMSM_TRY(validate(options));
    HMSM_TRY(validate(parameters));
    HMSM_TRY(validate_tree(tree));

    const auto& nodes = tree.nodes;
    const int32_t n = int32_t(nodes.size());
    std::vector<std::vector<int32_t>> children(n);
    int32_t root = -1;
    for (int32_t i = 0; i < n; ++i) {  // ascending index: children come out sorted
        if (nodes[i].parent < 0) root = i;
        else children[nodes[i].parent].push_back(i);
    }

    Hierarchy h;
    h.continuation = continuation_children(tree, children, options.grouping);
    const auto& kappa = h.continuation;
    auto follow = [&](int32_t k) {
        std::vector<int32_t> list;
        while (k >= 0) {
            list.push_back(k);
            if (options.max_chain_segments > 0 && int32_t(list.size()) >= options.max_chain_segments)
                break;
            k = kappa[k];
        }
        return list;
    };

    // Under coupled, each chain of the decomposition above is split into links of about the
    // trunk's length over kTrunkLinks (docs/model.md 3.13); the links still to open after
    // chain c, each a continuation, are pending[c].
    const bool coupled = options.dynamics == Dynamics::coupled;
    std::vector<std::vector<std::vector<int32_t>>> pending;
    const std::vector<int32_t> trunk_list = follow(kappa[root]);
    const double link_length = arc_lengths(tree, root, trunk_list).back() / detail::kTrunkLinks;
    auto open_chain = [&](Chain chain, const std::vector<int32_t>& list) {
        std::vector<std::vector<int32_t>> links =
            coupled ? split_into_links(tree, chain.attach_node, list, link_length)
                    : std::vector<std::vector<int32_t>>{list};
        chain.members = std::move(links.front());
        if (coupled) chain.dynamics.link_count = int32_t(links.size());
        links.erase(links.begin());
        h.chains.push_back(std::move(chain));
        pending.push_back(std::move(links));
    };

    h.node_owner.assign(n, -1);
    Chain trunk;
    trunk.attach_node = root;
    open_chain(std::move(trunk), trunk_list);
    h.node_owner[root] = 0;

    for (size_t c = 0; c < h.chains.size(); ++c) {
        for (int32_t m : h.chains[c].members) h.node_owner[m] = int32_t(c);
        std::vector<int32_t> order;
        if (c == 0) order.push_back(root);
        order.insert(order.end(), h.chains[c].members.begin(), h.chains[c].members.end());
        for (size_t j = 0; j < order.size(); ++j) {
            int32_t node = order[j];
            Chain child;
            child.parent = int32_t(c);
            child.depth = h.chains[c].depth + 1;
            child.attach_node = node;
            for (int32_t k : children[node])
                if (k != kappa[node]) open_chain(child, follow(k));
            if (j + 1 < order.size() || kappa[node] < 0) continue;
            if (pending[c].empty()) {  // cut by max_chain_segments
                open_chain(child, follow(kappa[node]));
                continue;
            }
            // The next link of a split chain, carrying the links after it.
            std::vector<std::vector<int32_t>> rest = std::move(pending[c]);
            child.members = std::move(rest.front());
            rest.erase(rest.begin());
            child.dynamics.link_index = h.chains[c].dynamics.link_index + 1;
            child.dynamics.link_count = h.chains[c].dynamics.link_count;
            h.chains.push_back(std::move(child));
            pending.push_back(std::move(rest));
        }
    }

    // Frames, local coordinates and constants.
    h.node_local.assign(n, glm::dvec3(0.0));
    const double dt = parameters.dt;
    // Frequency cap (docs/model.md 3.4): no chain sways faster than f_max, so a twig moves the
    // same at every dt small enough. The 1/(4 pi dt max(1, zeta)) bound keeps symplectic Euler
    // stable at larger dt: with x = omega dt, x <= 0.5 and D dt / I = 2 zeta x <= 1 (for heavy
    // damping the velocity update itself would otherwise overshoot and then diverge).
    const double zeta = parameters.damping_ratio;
    const double f_max = std::min(parameters.max_frequency,
                                  1.0 / (4.0 * std::numbers::pi * dt * std::max(1.0, zeta)));
    const double omega_max = 2.0 * std::numbers::pi * f_max;
    for (size_t c = 0; c < h.chains.size(); ++c) {
        Chain& chain = h.chains[c];
        const glm::dvec3 attach = nodes[chain.attach_node].position;
        const TreeNode& first = nodes[chain.members.front()];
        chain.frame = rest_frame(attach, first.position);
        chain.rest_rotation = chain.parent < 0
                                  ? chain.frame
                                  : glm::transpose(h.chains[chain.parent].frame) * chain.frame;
        glm::dvec3 previous = attach;
        for (int32_t m : chain.members) {
            chain.length += glm::length(nodes[m].position - previous);
            previous = nodes[m].position;
            h.node_local[m] = glm::transpose(chain.frame) * (nodes[m].position - attach);
        }
        chain.radius = first.radius;
        const double r = chain.radius, L = chain.length;
        chain.inertia = parameters.density * r * r * L * L * L;
        chain.stiffness = parameters.stiffness * r * r * r * r / L;
        const double floor = chain.stiffness / (omega_max * omega_max);
        if (chain.inertia < floor) {
            chain.inertia = floor;
            chain.capped = true;
            ++h.capped_chain_count;
        }
        chain.damping = 2.0 * parameters.damping_ratio * std::sqrt(chain.stiffness * chain.inertia);
        chain.wind_area = parameters.wind_gain * r * L * L;
        if (!float_safe(chain.inertia, false) || !float_safe(chain.stiffness, false) ||
            !float_safe(dt / chain.inertia, false) || !float_safe(chain.damping, true) ||
            !float_safe(chain.wind_area, true)) {
            char buf[200];
            std::snprintf(buf, sizeof buf, "inertia %.3g, stiffness %.3g, damping %.3g, wind area %.3g, dt/I %.3g",
                          chain.inertia, chain.stiffness, chain.damping, chain.wind_area, dt / chain.inertia);
            return Status{ErrorCode::invalid_argument,
                          "chain " + std::to_string(c) + " (attach node " + std::to_string(chain.attach_node) +
                              "): constants out of the computable range [1e-30, 1e30] (" + buf +
                              "): radius, segment length, density, stiffness or dt too extreme"};
        }
        h.max_depth = std::max(h.max_depth, chain.depth);
    }
    h.chains_per_depth.assign(h.max_depth + 1, 0);
    for (const Chain& chain : h.chains) ++h.chains_per_depth[chain.depth];
    // A tree's own material and leaf state take the place of the parameters' (docs/model.md 4.1).
    if (options.dynamics == Dynamics::coupled)
        HMSM_TRY(detail::fill_coupled_constants(tree, parameters_for_tree(tree, parameters), h));
    return h;
}

}  // namespace hmsm
