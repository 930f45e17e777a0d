// Each dispatch of each pass alone, Vulkan against the cpu64 oracle, on random states of random
// scenes: odd sizes, several models and instance groups, every pointer-jumping round and every
// level separately, both ping-pong directions.
#include "random_scene.h"
#include "vulkan_test_support.h"

namespace hmsm::test {
namespace {

struct SceneSpec {
    const char* name;
    std::vector<ModelShape> models;
    std::vector<uint32_t> instance_models;
    uint32_t max_group_instances;
};

std::vector<SceneSpec> scene_specs() {
    return {
        {"two_models_many_groups", {{67, 131, 1001}, {5, 9, 77}}, {0, 0, 0, 1, 1, 0, 1}, 2},
        {"one_chain_model", {{1, 3, 65}}, {0, 0, 0, 0, 0}, 3},
        {"wide_and_deep", {{300, 701, 5003}, {129, 200, 999}}, {0, 1, 1, 0}, 8},
    };
}

class VulkanPassAgreement : public VulkanTest,
                            public ::testing::WithParamInterface<std::tuple<Pass, Composition>> {};

TEST_P(VulkanPassAgreement, EachDispatchMatchesCpu64OnRandomStates) {
    const auto [pass, composition] = GetParam();
    std::mt19937 rng(1000 + 17 * uint32_t(pass) + uint32_t(composition));
    for (const SceneSpec& spec : scene_specs()) {
        SCOPED_TRACE(spec.name);
        detail::SceneData data = random_scene_data(rng, spec.models, spec.instance_models,
                                                   spec.max_group_instances);
        std::string skip;
        auto vulkan = create_vulkan_or_skip(skip);
        if (!skip.empty()) GTEST_SKIP() << skip;
        ASSERT_TRUE(vulkan);
        auto oracle = detail::create_cpu_backend(true);
        ASSERT_TRUE(oracle.ok());
        ASSERT_TRUE(vulkan->upload(data).ok());
        ASSERT_TRUE(oracle.value()->upload(data).ok());

        const auto variants = pass_variants(data, pass, composition, rng);
        ASSERT_FALSE(variants.empty());
        for (size_t v = 0; v < variants.size(); ++v) {
            SCOPED_TRACE("variant " + std::to_string(v));
            randomize_state(data, *vulkan, *oracle.value(), rng);
            const double wind_x[1] = {uniform_wind_phase(rng)};
            Status run = vulkan->run(variants[v], wind_x);
            ASSERT_TRUE(run.ok()) << run.message();
            ASSERT_TRUE(oracle.value()->run(variants[v], wind_x).ok());
            for (const auto& info : detail::kBufferTable) {
                if (!(detail::pass_writes(pass) & (1u << uint32_t(info.id)))) continue;
                uint64_t count = data.element_count(info.id);
                EXPECT_LE(relative_difference(read_buffer(*vulkan, info.id, count),
                                              read_buffer(*oracle.value(), info.id, count)),
                          2e-5)
                    << info.name;
            }
        }
    }
}

std::string variant_name(const ::testing::TestParamInfo<std::tuple<Pass, Composition>>& info) {
    const bool hierarchical = std::get<0>(info.param) == Pass::compose ||
                              std::get<0>(info.param) == Pass::root_positions;
    if (!hierarchical) return std::string(pass_name(std::get<0>(info.param)));
    return std::string(pass_name(std::get<0>(info.param))) + "_" + to_string(std::get<1>(info.param));
}

/// Every pass; compose and root_positions also with every round in one dispatch and level by level.
std::vector<std::tuple<Pass, Composition>> pass_compositions() {
    std::vector<std::tuple<Pass, Composition>> params;
    for (Pass pass : kAllPasses) {
        params.push_back({pass, Composition::pointer_jumping});
        if (pass == Pass::compose || pass == Pass::root_positions) {
            params.push_back({pass, Composition::pointer_jumping_in_dispatch});
            params.push_back({pass, Composition::level_by_level});
        }
    }
    return params;
}

INSTANTIATE_TEST_SUITE_P(Passes, VulkanPassAgreement, ::testing::ValuesIn(pass_compositions()),
                         variant_name);

}  // namespace
}  // namespace hmsm::test
