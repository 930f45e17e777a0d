// Throughput of the CUDA backend on forests of paper-1 trees (1 to 10,000 instances): steps per
// second with the step graph (profiling off, outputs left on the device) and per-pass device
// times from a profiled run. Run by tools/gpu/run.sh on the lent GPU; `hmsm bench` is the
// cross-backend benchmark.
//
//   hmsm_cuda_throughput [COMPOSITION [N,N,...]]   (default: pointer_jumping 1,10,100,1000,10000)
#include <hmsm/hmsm.h>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <vector>

namespace {

hmsm::Composition composition = hmsm::Composition::pointer_jumping;

hmsm::SimulationConfig cuda_config(bool profile) {
    hmsm::SimulationConfig config;
    config.backend = hmsm::BackendKind::cuda;
    config.profile_passes = profile;
    config.composition = composition;
    return config;
}

std::vector<uint32_t> parse_counts(const char* text) {
    std::vector<uint32_t> counts;
    for (const char* p = text; *p;) {
        char* end = nullptr;
        counts.push_back(uint32_t(std::strtoul(p, &end, 10)));
        p = *end == ',' ? end + 1 : end;
        if (end == p && *p) break;
    }
    return counts;
}

}  // namespace

int main(int argc, char** argv) {
    if (argc > 1) {
        auto parsed = hmsm::parse_composition(argv[1]);
        if (!parsed) {
            std::fprintf(stderr, "cuda_throughput: unknown composition '%s'\n", argv[1]);
            return 2;
        }
        composition = *parsed;
    }
    const std::vector<uint32_t> counts =
        argc > 2 ? parse_counts(argv[2]) : std::vector<uint32_t>{1, 10, 100, 1000, 10000};
    std::printf("composition %s\n", hmsm::to_string(composition));
    auto tree = hmsm::generate_preset("paper-1");
    if (!tree) {
        std::fprintf(stderr, "cuda_throughput: %s\n", tree.status().message().c_str());
        return 1;
    }
    std::printf("%9s %12s %10s %10s %12s |", "instances", "vertices", "steps/s", "ms/step", "Gvertex/s");
    for (hmsm::Pass pass : hmsm::kAllPasses) std::printf(" %14.14s", std::string(hmsm::pass_name(pass)).c_str());
    std::printf("   (device us per step)\n");
    for (uint32_t instances : counts) {
        auto scene = instances == 1 ? hmsm::Result<hmsm::Scene>(hmsm::single_tree_scene(*tree))
                                    : hmsm::grid_scene(*tree, instances, 15.0, 1);
        if (!scene) return 1;
        const uint32_t steps = instances <= 10 ? 2000 : instances <= 100 ? 500 : instances <= 1000 ? 100 : 20;
        double steps_per_second = 0.0, vertices = 0.0;
        {
            auto sim = hmsm::Simulation::create(*scene, cuda_config(false));
            if (!sim) {
                std::printf("%9u  %s\n", instances, sim.status().message().c_str());
                continue;
            }
            vertices = double((*sim)->vertex_count());
            if (!(*sim)->step(10).ok()) return 1;  // capture and warm up
            const auto start = std::chrono::steady_clock::now();
            const hmsm::Status status = (*sim)->step(steps);
            const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
            if (!status.ok()) {
                std::fprintf(stderr, "cuda_throughput: %s\n", status.message().c_str());
                return 1;
            }
            steps_per_second = steps / seconds;
        }
        hmsm::PassTimes times;
        {
            auto sim = hmsm::Simulation::create(*scene, cuda_config(true));
            if (!sim || !(*sim)->step(std::max(steps / 4, 5u)).ok()) return 1;
            times = (*sim)->pass_times();
        }
        std::printf("%9u %12.0f %10.1f %10.3f %12.2f |", instances, vertices, steps_per_second,
                    1e3 / steps_per_second, vertices * steps_per_second * 1e-9);
        for (double seconds : times.seconds) std::printf(" %14.2f", 1e6 * seconds / double(times.steps));
        std::printf("\n");
        std::fflush(stdout);
    }
    return 0;
}
