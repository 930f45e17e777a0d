#include "test_trees.h"

#include <gtest/gtest.h>

#include <cmath>

namespace hmsm::test {

TreeModel make_tree(std::initializer_list<NodeSpec> nodes) {
    TreeModel tree;
    for (const NodeSpec& n : nodes) tree.nodes.push_back({n.parent, {n.x, n.y, n.z}, n.radius});
    return tree;
}

TreeModel rod(int segments, double length, double radius) {
    TreeModel tree;
    tree.nodes.push_back({-1, {0, 0, 0}, radius});
    for (int i = 1; i <= segments; ++i)
        tree.nodes.push_back({i - 1, {0, length * i / segments, 0}, radius});
    return tree;
}

TreeModel broom(uint32_t branches) {
    TreeModel tree;
    tree.nodes.push_back({-1, {0, 0, 0}, 0.3});
    tree.nodes.push_back({0, {0, 10, 0}, 0.2});
    for (uint32_t b = 0; b < branches; ++b) {
        const double a = 0.001 * b;
        tree.nodes.push_back({1, {std::cos(a), 10.0 + 1e-4 * b, std::sin(a)}, 0.01});
    }
    return tree;
}

TreeModel small_tree() {
    // Node 0 is listed with parent 3 to check that parents may come after children.
    TreeModel tree = make_tree({
        {3, 0.0, 6.0, 0.1, 0.12},     // 0: top of the trunk
        {-1, 0.0, 0.0, 0.0, 0.30},    // 1: root
        {1, 0.0, 2.0, 0.0, 0.25},     // 2
        {2, 0.0, 4.0, 0.05, 0.20},    // 3
        {2, 1.0, 3.0, 0.0, 0.10},     // 4: branch at 2
        {4, 2.0, 3.6, 0.2, 0.08},     // 5
        {5, 2.6, 3.5, 0.7, 0.04},     // 6
        {3, -1.0, 5.0, 0.5, 0.10},    // 7: branch at 3
        {7, -1.6, 5.3, 1.0, 0.06},    // 8
        {5, 2.4, 4.4, -0.2, 0.03},    // 9: twig at 5 (depth 2)
        {9, 2.7, 5.0, -0.3, 0.02},    // 10
        {10, 2.9, 5.5, -0.1, 0.015},  // 11
        {10, 3.2, 5.2, -0.6, 0.012},  // 12: depth 3
        {1, 0.8, 0.6, 0.3, 0.09},     // 13: second child of the root
        {6, 3.1, 3.6, 1.0, 0.02},     // 14: continues chain [6]
        {6, 2.7, 3.9, 1.1, 0.015},    // 15: depth 3
    });
    tree.leaves.push_back({11, {0, 0.05, 0}, {0, 0, 1}, {0, 1, 0}, {0.08, 0.12}});
    tree.leaves.push_back({6, {0.02, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0.1, 0.1}});
    tree.leaves.push_back({12, {0, 0, 0}, {0.3, 0.2, 1}, {0, 1, 0}, {0.07, 0.09}});
    return tree;
}

TreeModel deep_tree(int depth) {
    TreeModel tree;
    tree.nodes.push_back({-1, {0, 0, 0}, 0.4});
    int32_t attach = 0;
    glm::dvec3 base(0.0);
    double radius = 0.35;
    for (int level = 0; level <= depth; ++level) {
        // A chain of 3 segments leaning a little further sideways each level.
        glm::dvec3 dir = glm::normalize(glm::dvec3(0.3 * level, 1.0, 0.1 * level));
        int32_t previous = attach;
        int32_t mid = -1;
        for (int s = 1; s <= 3; ++s) {
            glm::dvec3 p = base + dir * (1.5 * s / (level + 1.0));
            tree.nodes.push_back({previous, p, radius * (1.0 - 0.2 * s / 3.0)});
            previous = int32_t(tree.nodes.size() - 1);
            if (s == 2) mid = previous;
        }
        attach = mid;
        base = tree.nodes[mid].position;
        radius *= 0.6;
    }
    return tree;
}

Scene small_and_deep_with_levels(uint32_t small_trees) {
    Scene scene = *grid_scene(small_tree(), small_trees, 5.0, 11);
    scene.models.push_back(deep_tree(4));
    scene.model_names.push_back("deep");
    scene.instances.push_back({1, {9, 0, -3}, 1.9, 0.7, 0.3});
    const std::vector<int32_t> budgets = {6, 3, 1};
    scene.lod_budgets = {budgets, budgets};
    return scene;
}

std::unique_ptr<Simulation> create_simulation_or_skip(const Scene& scene, SimulationConfig config,
                                                      BackendKind kind, std::string& skip) {
    config.backend = kind;
    auto sim = Simulation::create(scene, config);
    if (!sim.ok()) {
        if (sim.status().code() == ErrorCode::no_device) skip = sim.status().message();
        else ADD_FAILURE() << to_string(kind) << ": " << sim.status().message();
        return nullptr;
    }
    return std::move(sim).value();
}

double max_abs_difference(const std::vector<double>& a, const std::vector<double>& b) {
    if (a.size() != b.size()) return INFINITY;
    double worst = 0.0;
    for (size_t i = 0; i < a.size(); ++i) {
        double d = std::abs(a[i] - b[i]);
        if (!(d <= worst)) worst = d;  // NaN propagates as a failure
        if (std::isnan(d)) return INFINITY;
    }
    return worst;
}

bool all_finite(const std::vector<double>& values) {
    for (double v : values)
        if (!std::isfinite(v)) return false;
    return true;
}

std::vector<std::vector<float>> every_output(const Simulation& sim) {
    std::vector<std::vector<float>> out;
    for (Output o : kEveryOutput) {
        out.emplace_back();
        const Status read = sim.read(o, out.back());
        EXPECT_TRUE(read.ok()) << "output " << int(o) << ": " << read.message();
    }
    return out;
}

std::vector<double> read_output(const Simulation& sim, Output output) {
    std::vector<double> values;
    const Status read = sim.read(output, values);
    EXPECT_TRUE(read.ok()) << "output " << int(output) << ": " << read.message();
    return values;
}

std::vector<double> released_record(Simulation& sim, uint32_t bend_steps, uint32_t record_steps,
                                    const std::function<double(const Simulation&)>& probe) {
    std::vector<double> record;
    const Status bent = sim.step(bend_steps);
    EXPECT_TRUE(bent.ok()) << bent.message();
    Wind calm = sim.wind();
    calm.profile = WindProfile::none;
    const Status calmed = sim.set_wind(calm);
    EXPECT_TRUE(calmed.ok()) << calmed.message();
    if (!bent.ok() || !calmed.ok()) return record;
    for (uint32_t i = 0; i < record_steps; ++i) {
        const Status stepped = sim.step(1);
        EXPECT_TRUE(stepped.ok()) << stepped.message();
        if (!stepped.ok()) break;
        record.push_back(probe(sim));
    }
    return record;
}

std::vector<uint64_t> first_elements(const Simulation& sim, Output output) {
    std::vector<uint64_t> first{0};
    for (const Instance& inst : sim.instances()) {
        uint64_t elements = sim.hierarchy(inst.model).chains.size();
        switch (output) {
            case Output::node_positions: elements = sim.hierarchy(inst.model).node_owner.size(); break;
            case Output::vertex_positions:
            case Output::vertex_normals: elements = sim.mesh(inst.model).vertices.size(); break;
            default: break;
        }
        first.push_back(first.back() + elements);
    }
    return first;
}

std::vector<std::vector<std::vector<float>>> outputs_by_instance(const Simulation& sim) {
    const std::vector<std::vector<float>> all = every_output(sim);
    std::vector<std::vector<std::vector<float>>> out(sim.instance_count());
    for (size_t o = 0; o < all.size(); ++o) {
        const std::vector<uint64_t> first = first_elements(sim, kEveryOutput[o]);
        for (size_t i = 0; i < out.size(); ++i) out[i].push_back(instance_slice(all[o], first, i, kEveryOutput[o]));
    }
    return out;
}

}  // namespace hmsm::test
