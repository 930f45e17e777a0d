// Simulates a two-segment tree through the installed library and checks that it moved; then
// asks for every compiled backend, CUDA included: the consumer is built without the CUDA
// toolkit (tests/install_consumer/run.sh), so the library must carry its CUDA runtime, and on
// a machine without a GPU the backend must answer no_device rather than fail to load or crash.
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
    if (nodes[6] == 0.3f) return 1;
    for (hmsm::BackendKind kind : hmsm::compiled_backends()) {
        config.backend = kind;
        auto other = hmsm::Simulation::create(hmsm::single_tree_scene(tree), config);
        if (other) {
            if (!(*other)->step(2)) return 1;
            std::printf("%s: ran\n", hmsm::to_string(kind));
        } else if (other.status().code() == hmsm::ErrorCode::no_device) {
            std::printf("%s: no device (%s)\n", hmsm::to_string(kind), other.status().message().c_str());
        } else {
            std::fprintf(stderr, "%s: %s\n", hmsm::to_string(kind), other.status().message().c_str());
            return 1;
        }
    }
    return 0;
}
