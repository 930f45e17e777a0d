// Shared by the consumer programs: run a small hmsm simulation on one backend and check it.
#pragma once

#include <hmsm/hmsm.h>

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>

/// Steps a three-node tree 60 times on `backend`; 0 when it ran and the tip moved, 77 when the
/// backend has no device here (the caller decides whether that is acceptable), 1 otherwise.
inline int run_hmsm(hmsm::BackendKind backend) {
    hmsm::TreeModel tree;
    tree.nodes = {{-1, {0, 0, 0}, 0.2}, {0, {0, 2, 0}, 0.15}, {1, {0.3, 4, 0}, 0.1}};
    hmsm::SimulationConfig config;
    config.backend = backend;
    config.wind.profile = hmsm::WindProfile::constant;
    auto sim = hmsm::Simulation::create(hmsm::single_tree_scene(tree), config);
    if (!sim) {
        std::fprintf(stderr, "%s: %s\n", hmsm::to_string(backend), sim.status().message().c_str());
        return sim.status().code() == hmsm::ErrorCode::no_device ? 77 : 1;
    }
    std::vector<float> nodes;
    if (!(*sim)->step(60) || !(*sim)->read(hmsm::Output::node_positions, nodes)) return 1;
    std::printf("%s on %s: tip x after 0.5 s = %f\n", hmsm::to_string(backend),
                (*sim)->device_name().c_str(), nodes[6]);
    return std::isfinite(nodes[6]) && nodes[6] != 0.3f ? 0 : 1;
}

/// The CPU always, Vulkan where this machine has a device (HMSM_CONSUMER_REQUIRE_VULKAN=1 makes
/// its absence a failure).
inline int run_both() {
    if (run_hmsm(hmsm::BackendKind::cpu) != 0) return 1;
    const int vulkan = run_hmsm(hmsm::BackendKind::vulkan);
    const char* require = std::getenv("HMSM_CONSUMER_REQUIRE_VULKAN");
    if (vulkan == 77 && !(require && std::strcmp(require, "1") == 0)) return 0;
    return vulkan;
}
