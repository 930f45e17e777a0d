// Each dispatch of each pass alone, every backend against the cpu64 oracle, on random states
// of random scenes (docs/model.md 7): odd sizes, several models and instance groups, every
// pointer-jumping round and every level separately, both ping-pong directions. One body per
// (backend, pass, composition); a backend without a device skips with the reason.
#include "pass_agreement.h"
#include "random_scene.h"

#include <gtest/gtest.h>

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

struct PassCase {
    const BackendUnderTest* backend;
    Pass pass;
    PassForm form;
};

/// Failure messages name the case, not its bytes.
void PrintTo(const PassCase& c, std::ostream* os) {
    *os << c.backend->name << " " << pass_name(c.pass) << " " << name_of(c.form);
}

class PassAgreement : public ::testing::TestWithParam<PassCase> {};

TEST_P(PassAgreement, EachDispatchMatchesCpu64OnRandomStates) {
    const auto [backend_under_test, pass, form] = GetParam();
    // The same seed for every backend: all see the same scenes, states and wind phases.
    std::mt19937 rng(1000 + 17 * uint32_t(pass) + uint32_t(form));
    // Each scene with another wind profile with mode phases: y1, turbulent, atmospheric.
    const WindProfile profiles[] = {WindProfile::y1, WindProfile::turbulent, WindProfile::atmospheric};
    size_t scene_index = 0;
    for (const SceneSpec& spec : scene_specs()) {
        SCOPED_TRACE(spec.name);
        detail::SceneData data = random_scene_data(rng, spec.models, spec.instance_models,
                                                   spec.max_group_instances);
        data.profile = profiles[scene_index++ % 3];
        auto backend = backend_under_test->create();
        if (!backend.ok() && backend.status().code() == ErrorCode::no_device)
            GTEST_SKIP() << backend.status().message();
        ASSERT_TRUE(backend.ok()) << backend.status().message();
        auto oracle = detail::create_backend(BackendKind::cpu64);
        ASSERT_TRUE(oracle.ok());
        ASSERT_TRUE(backend.value()->upload(data).ok());
        ASSERT_TRUE(oracle.value()->upload(data).ok());

        const auto variants = pass_variants(data, pass, form, rng);
        ASSERT_FALSE(variants.empty());
        for (size_t v = 0; v < variants.size(); ++v) {
            SCOPED_TRACE("variant " + std::to_string(v));
            randomize_state(data, *backend.value(), *oracle.value(), rng);
            const detail::RunStep step[1] = {{uniform_wind_slot(rng)}};
            const Status run = backend.value()->run(variants[v], step);
            ASSERT_TRUE(run.ok()) << run.message();
            ASSERT_TRUE(oracle.value()->run(variants[v], step).ok());
            uint32_t writes = 0;  // of the passes the dispatches run (a path-walk one runs two)
            for (const detail::Dispatch& dispatch : variants[v]) writes |= detail::dispatch_writes(dispatch);
            for (const auto& info : detail::kBufferTable) {
                if (!(writes & (1u << uint32_t(info.id)))) continue;
                uint64_t first = 0, count = data.element_count(info.id);
                std::vector<double> expected(count * detail::shape_scalars(info.shape)), actual(expected.size());
                ASSERT_TRUE(oracle.value()->read(info.id, first, count, expected.data(), detail::Scalar::f64).ok());
                ASSERT_TRUE(backend.value()->read(info.id, first, count, actual.data(), detail::Scalar::f64).ok());
                EXPECT_LE(nmse(expected, actual), kMaxPassNmse) << info.name;
            }
        }
    }
}

std::vector<PassCase> pass_cases() {
    std::vector<PassCase> cases;
    for (const BackendUnderTest& backend : backends_under_test())
        for (Pass pass : kAllPasses)
            for (PassForm form : forms_of(pass)) cases.push_back({&backend, pass, form});
    return cases;
}

std::string case_name(const ::testing::TestParamInfo<PassCase>& info) {
    std::string name = info.param.backend->name + "_" + std::string(pass_name(info.param.pass));
    if (detail::is_hierarchical(info.param.pass) || info.param.form == PassForm::path_walk)
        name += "_" + std::string(name_of(info.param.form));
    return name;
}

INSTANTIATE_TEST_SUITE_P(Backends, PassAgreement, ::testing::ValuesIn(pass_cases()), case_name);

}  // namespace
}  // namespace hmsm::test
