// Listed groups (src/listed_groups.h): a fragmented scene's step program runs one group per
// model over the instance table. The table lists each model's active instances in index order
// with their state offsets; the rule lists only where the contiguous groups are many; and on
// the backends that run listed dispatches, a listed program gives bit for bit what the
// contiguous program gives, through adds, swap removals, pauses and level switches, and agrees
// with cpu64.
#include "test_trees.h"

#include "forwarding_backend.h"
#include "listed_groups.h"
#include "simulation_access.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <random>

namespace hmsm {
namespace {

using detail::InstanceGroup;

/// Gives the rule back to the environment however the test ends (a failed assertion returns
/// early), so that no later test in the process runs with listing forced.
struct ListingRuleRestored {
    ~ListingRuleRestored() { detail::set_listing_for_tests(-1); }
};

TEST(ListedGroups, ListEachModelsActiveInstancesInIndexOrderWithTheirOffsets) {
    detail::SceneData d;
    d.models.resize(2);
    d.models[0].chain_count = 3;
    d.models[0].node_count = 5;
    d.models[0].vertex_count = 7;
    d.models[1].chain_count = 2;
    d.models[1].node_count = 4;
    d.models[1].vertex_count = 1;
    // Instances 0 1 | 2 | 3 4 5 of models 0 | 1 | 0; instance 4 is paused, inside a group that
    // covers it.
    InstanceGroup a{0, 0, 2, 0, 0, 0};
    InstanceGroup b{1, 2, 1, 6, 10, 14};
    InstanceGroup c{0, 3, 3, 8, 14, 15};
    c.covers_paused = true;
    std::vector<Instance> instances(6);
    for (size_t i = 0; i < instances.size(); ++i) instances[i].model = i == 2 ? 1u : 0u;
    instances[4].active = false;
    const std::vector<InstanceGroup> groups = {a, b, c};

    detail::ListedGroups listed;
    detail::list_groups(d, groups, instances, listed);
    const std::vector<double> expected = {
        0, 0, 0, 0,     // model 0: instance 0
        3, 5, 7, 1,     //          instance 1
        8, 14, 15, 3,   //          instance 3
        14, 24, 29, 5,  //          instance 5 (4 is paused)
        6, 10, 14, 2,   // model 1: instance 2
    };
    EXPECT_EQ(listed.table, expected);
    ASSERT_EQ(listed.groups.size(), 2u);
    EXPECT_TRUE(listed.groups[0].listed && listed.groups[1].listed);
    EXPECT_EQ(listed.groups[0].model, 0u);
    EXPECT_EQ(listed.groups[0].instance_begin, 0u);
    EXPECT_EQ(listed.groups[0].instance_count, 4u);
    EXPECT_EQ(listed.groups[1].model, 1u);
    EXPECT_EQ(listed.groups[1].instance_begin, 4u);
    EXPECT_EQ(listed.groups[1].instance_count, 1u);

    // A listed group's dispatches carry the flag and the threads per instance.
    const std::vector<detail::Dispatch> program =
        detail::build_program(d, listed.groups, Composition::level_by_level, false, Pass::integrate,
                              1u << uint32_t(Pass::integrate));
    ASSERT_EQ(program.size(), 2u);
    EXPECT_EQ(program[0].constants.instance_list, 1u);
    EXPECT_EQ(program[0].constants.listed_threads, 3u);
    EXPECT_EQ(program[0].constants.element_count, 12u);
    EXPECT_EQ(program[1].constants.listed_threads, 2u);
    // Listed dispatches are never joined into one launch.
    EXPECT_EQ(detail::dispatch_batches(program).size(), 2u);
}

TEST(ListedGroups, ListOnlyWhereTheContiguousGroupsAreMany) {
    const ListingRuleRestored restored;
    detail::set_listing_for_tests(2);  // by size, whatever HMSM_LIST_INSTANCES says
    EXPECT_FALSE(detail::listing_pays(detail::kListedGroupsFrom - 1, 1));
    EXPECT_TRUE(detail::listing_pays(detail::kListedGroupsFrom, detail::kListedGroupsFrom / 4));
    EXPECT_FALSE(detail::listing_pays(detail::kListedGroupsFrom, detail::kListedGroupsFrom / 4 + 1));
    detail::set_listing_for_tests(1);
    EXPECT_TRUE(detail::listing_pays(2, 2));
    detail::set_listing_for_tests(0);
    EXPECT_FALSE(detail::listing_pays(100000, 1));
}

constexpr int32_t kBudgets[] = {6, 3, 1};

/// Two models on alternating places, each with three coarser levels.
Scene fragmented_scene() {
    Scene scene;
    scene.models = {test::small_tree(), test::deep_tree(4)};
    scene.model_names = {"small", "deep"};
    for (uint32_t i = 0; i < 13; ++i)
        scene.instances.push_back({i % 2, {3.0 * i, 0.0, 1.5 * (i % 3)}, 0.4 * i, 0.6 + 0.05 * i, 0.1 * i});
    scene.lod_budgets = {{std::begin(kBudgets), std::end(kBudgets)}, {std::begin(kBudgets), std::end(kBudgets)}};
    return scene;
}

bool lists(const Simulation& sim) {
    const auto& program = detail::step_program_of(sim);
    return std::any_of(program.begin(), program.end(),
                       [](const detail::Dispatch& d) { return d.constants.instance_list != 0; });
}

/// Listing forced on for `listed`, off for every other simulation (the rule is taken where a
/// program is built: at a step, and for the one-off programs that pose added, reset or
/// switched instances).
void force_listing_for(const Simulation* sim, const Simulation* listed) {
    detail::set_listing_for_tests(sim == listed ? 1 : 0);
}

/// A backend that counts the one-off programs (program id 0: posing added, reset or switched
/// instances) it runs listed.
class CountsListedOneOffs final : public test::ForwardingBackend {
public:
    using ForwardingBackend::ForwardingBackend;
    Status run(std::span<const detail::Dispatch> program, std::span<const detail::RunStep> steps,
               uint64_t program_id = 0) override {
        if (program_id == 0 && std::any_of(program.begin(), program.end(), [](const detail::Dispatch& d) {
                return d.constants.instance_list != 0;
            }))
            ++listed_one_offs;
        return ForwardingBackend::run(program, steps, program_id);
    }
    uint64_t listed_one_offs = 0;
};

class ListedSteps : public ::testing::TestWithParam<BackendKind> {};

TEST_P(ListedSteps, MatchTheContiguousProgramThroughStreamingAndAgreeWithCpu64) {
    const ListingRuleRestored restored;
    for (Composition composition : {Composition::automatic, Composition::pointer_jumping, Composition::level_by_level}) {
        SCOPED_TRACE(to_string(composition));
        SimulationConfig config = test::windy_config();
        config.composition = composition;
        std::string skip;
        auto contiguous = test::create_simulation_or_skip(fragmented_scene(), config, GetParam(), skip);
        if (!skip.empty()) GTEST_SKIP() << skip;
        auto oracle = test::create_simulation_or_skip(fragmented_scene(), config, BackendKind::cpu64, skip);
        auto inner = detail::create_backend(GetParam());
        ASSERT_TRUE(inner.ok()) << inner.status().message();
        auto counting = std::make_unique<CountsListedOneOffs>(std::move(inner).value());
        const CountsListedOneOffs& counted = *counting;
        auto created = detail::SimulationAccess::create(fragmented_scene(), config, std::move(counting));
        ASSERT_TRUE(created.ok()) << created.status().message();
        std::unique_ptr<Simulation> listed = std::move(created).value();
        ASSERT_TRUE(contiguous && oracle);
        ASSERT_TRUE(detail::backend_of(*listed).capabilities().runs_listed_groups);
        std::mt19937 rng(27);
        for (int frame = 0; frame < 24; ++frame) {
            // A swap removal, an arrival, a pause or resume and a switch every few frames, then
            // a step, each simulation with its own listing rule.
            const bool removes = frame % 3 == 1 && listed->instance_count() > 4;
            const InstanceId leaving = listed->instance_ids()[rng() % listed->instance_count()];
            const Instance coming{uint32_t(rng() % 2), {double(rng() % 40), 0.0, 2.0}, 1.0, 0.8, 0.2};
            const uint64_t paused = rng() % listed->instance_count();
            const bool active = rng() % 2 == 0;
            const uint32_t level = rng() % 4;
            const size_t switched = rng();
            for (Simulation* sim : {listed.get(), contiguous.get(), oracle.get()}) {
                force_listing_for(sim, listed.get());
                if (removes) ASSERT_TRUE(sim->swap_remove_instances({&leaving, 1}).ok());
                if (frame % 3 == 2) ASSERT_TRUE(sim->add_instances({&coming, 1}).ok());
                if (frame % 4 == 0) ASSERT_TRUE(sim->set_instance_active(paused % sim->instance_count(), active).ok());
                // Two instances apart, so that the one-off programs that reset or pose them
                // cover two slices, which the listed simulation lists.
                const uint32_t n = uint32_t(sim->instance_count()), first = uint32_t(switched % (n - 2));
                if (frame % 5 == 3) {
                    const uint32_t reset[] = {uint32_t(paused % (n - 2)), uint32_t(paused % (n - 2)) + 2};
                    ASSERT_TRUE(sim->reset_instances(reset).ok());
                }
                const InstanceId ids[] = {sim->instance_ids()[first], sim->instance_ids()[first + 2]};
                const uint32_t levels[] = {level, (level + 1) % 4};
                ASSERT_TRUE(sim->set_instance_lods(ids, levels).ok());
                ASSERT_TRUE(sim->step(1).ok());
            }
            detail::set_listing_for_tests(-1);
            ASSERT_TRUE(lists(*listed)) << "frame " << frame;
            ASSERT_FALSE(lists(*contiguous)) << "frame " << frame;
            ASSERT_TRUE(test::same_bits(test::every_output(*listed), test::every_output(*contiguous)))
                << "frame " << frame;
        }
        // The one-off programs that posed the switched, added and reset trees were listed too
        // (their outputs alone would match either way).
        EXPECT_GT(counted.listed_one_offs, 0u);
        // Agreement with the oracle at the end; the scene moved.
        for (Output o : {Output::node_positions, Output::vertex_positions, Output::chain_origins}) {
            const auto a = test::read_output(*listed, o), b = test::read_output(*oracle, o);
            ASSERT_EQ(a.size(), b.size());
            EXPECT_LE(test::max_abs_difference(a, b), 1e-3) << "output " << int(o);
        }
    }
}

INSTANTIATE_TEST_SUITE_P(Backends, ListedSteps, ::testing::Values(BackendKind::vulkan, BackendKind::cuda),
                         [](const auto& info) { return test::backend_test_name(info.param); });

}  // namespace
}  // namespace hmsm
