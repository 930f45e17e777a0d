// Simulates a two-segment tree through the installed library and checks that it moved.
#include <hmsm/hmsm.h>

#include <cstdio>

int main() {
    hmsm::TreeModel tree;
    tree.nodes = {{-1, {0, 0, 0}, 0.2}, {0, {0, 2, 0}, 0.15}, {1, {0.3, 4, 0}, 0.1}};
    hmsm::SimulationConfig config;
    config.backend = hmsm::BackendKind::cpu;
    config.wind.profile = hmsm::WindProfile::constant;
    auto sim = hmsm::Simulation::create(hmsm::single_tree_scene(tree), config);
    if (!sim) {
        std::fprintf(stderr, "%s\n", sim.status().message().c_str());
        return 1;
    }
    if (!(*sim)->step(60)) return 1;
    std::vector<float> nodes;
    if (!(*sim)->read(hmsm::Output::node_positions, nodes)) return 1;
    std::printf("tip x after 0.5 s: %f\n", nodes[6]);
    return nodes[6] != 0.3f ? 0 : 1;
}
