// Direction-first chain decomposition (DESIGN.md 3.2), frames (3.3) and constants (3.4).
#include <hmsm/hierarchy.h>

#include <glm/geometric.hpp>
#include <glm/matrix.hpp>

#include <algorithm>
#include <cmath>

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

glm::dmat3 rest_frame(const glm::dvec3& attach, const glm::dvec3& first_member) {
    glm::dvec3 y = glm::normalize(first_member - attach);
    glm::dvec3 ref = std::abs(y.z) > 0.9 ? glm::dvec3(1, 0, 0) : glm::dvec3(0, 0, 1);
    glm::dvec3 x = glm::normalize(glm::cross(y, ref));
    glm::dvec3 z = glm::cross(x, y);
    return glm::dmat3(x, y, z);
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

    h.node_owner.assign(n, -1);
    Chain trunk;
    trunk.attach_node = root;
    trunk.members = follow(kappa[root]);
    h.chains.push_back(std::move(trunk));
    h.node_owner[root] = 0;

    for (size_t c = 0; c < h.chains.size(); ++c) {
        for (int32_t m : h.chains[c].members) h.node_owner[m] = int32_t(c);
        std::vector<int32_t> order;
        if (c == 0) order.push_back(root);
        order.insert(order.end(), h.chains[c].members.begin(), h.chains[c].members.end());
        for (size_t j = 0; j < order.size(); ++j) {
            int32_t node = order[j];
            auto add_chain = [&](int32_t first) {
                Chain child;
                child.parent = int32_t(c);
                child.depth = h.chains[c].depth + 1;
                child.attach_node = node;
                child.members = follow(first);
                h.chains.push_back(std::move(child));
            };
            for (int32_t k : children[node])
                if (k != kappa[node]) add_chain(k);
            if (j + 1 == order.size() && kappa[node] >= 0) add_chain(kappa[node]);  // cut chain
        }
    }

    // Frames, local coordinates and constants.
    h.node_local.assign(n, glm::dvec3(0.0));
    const double dt = parameters.dt;
    for (Chain& chain : h.chains) {
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
        const double floor = chain.stiffness * (dt / 0.5) * (dt / 0.5);
        if (chain.inertia < floor) {
            chain.inertia = floor;
            chain.inertia_floored = true;
            ++h.floored_chain_count;
        }
        chain.damping = 2.0 * parameters.damping_ratio * std::sqrt(chain.stiffness * chain.inertia);
        chain.wind_area = parameters.wind_gain * r * L * L;
        h.max_depth = std::max(h.max_depth, chain.depth);
    }
    h.chains_per_depth.assign(h.max_depth + 1, 0);
    for (const Chain& chain : h.chains) ++h.chains_per_depth[chain.depth];
    return h;
}

}  // namespace hmsm
