// Step program ids (Backend::run): the simulation names each step program it runs with an id it
// gives to no other program, so that backends recognize a program they planned, captured or
// recorded without comparing every dispatch. A backend that trusted an id given to two
// different programs would step the second with the first's plan.
#include "simulation_access.h"
#include "forwarding_backend.h"
#include "test_trees.h"

#include <gtest/gtest.h>

#include <cstring>
#include <map>

namespace hmsm {
namespace {

/// Equal programs: the same passes and constants, byte for byte.
bool same_program(const std::vector<detail::Dispatch>& a, const std::vector<detail::Dispatch>& b) {
    if (a.size() != b.size()) return false;
    for (size_t i = 0; i < a.size(); ++i)
        if (a[i].pass != b[i].pass || std::memcmp(&a[i].constants, &b[i].constants, sizeof a[i].constants) != 0)
            return false;
    return true;
}

/// A backend that keeps every named program it is asked to run, by id.
class Named final : public test::ForwardingBackend {
public:
    using ForwardingBackend::ForwardingBackend;
    Status run(std::span<const detail::Dispatch> program, std::span<const detail::RunStep> steps,
               uint64_t program_id = 0) override {
        if (program_id != 0) {
            const std::vector<detail::Dispatch> dispatches(program.begin(), program.end());
            auto [seen, added] = programs.try_emplace(program_id, dispatches);
            if (!added && !same_program(seen->second, dispatches)) ++reused_for_another;
            ++named_runs;
        }
        return ForwardingBackend::run(program, steps, program_id);
    }

    std::map<uint64_t, std::vector<detail::Dispatch>> programs;
    uint64_t reused_for_another = 0, named_runs = 0;
};

// Every kind of live change that rebuilds the step program (pausing, adding, removing, switching
// levels, a new wind profile) gives the next step a new id, no id names two programs, and steps
// with nothing changed keep theirs.
TEST(StepProgramIds, NameOneProgramEachAndFollowEveryChange) {
    Scene scene = *grid_scene(test::deep_tree(4), 9, 6.0, 3);
    scene.lod_budgets = {{6, 3, 1}};
    SimulationConfig config = test::windy_config();
    config.backend = BackendKind::cpu_parallel;
    auto inner = detail::create_backend(BackendKind::cpu_parallel, 2);
    ASSERT_TRUE(inner.ok()) << inner.status().message();
    auto owned = std::make_unique<Named>(std::move(inner).value());
    Named& named = *owned;
    auto created = detail::SimulationAccess::create(scene, config, std::move(owned));
    ASSERT_TRUE(created.ok()) << created.status().message();
    Simulation& sim = **created;
    std::vector<InstanceId> ids;
    for (uint64_t i = 0; i < sim.instance_count(); ++i) ids.push_back(*sim.id_of(i));

    auto distinct_after = [&](const char* what, auto change) {
        const size_t before = named.programs.size();
        ASSERT_TRUE(sim.step(2).ok()) << what;
        EXPECT_EQ(named.programs.size(), before) << what << ": steps with nothing changed take a new id";
        change();
        ASSERT_TRUE(sim.step(2).ok()) << what;
        EXPECT_EQ(named.programs.size(), before + 1) << what << ": the rebuilt program keeps the old id";
    };
    ASSERT_TRUE(sim.step(1).ok());
    distinct_after("pause", [&] { ASSERT_TRUE(sim.set_instance_active(4, false).ok()); });
    distinct_after("add", [&] {
        const Instance added[] = {Instance{0, {40, 0, 40}, 0.5}, Instance{0, {46, 0, 40}, 1.0}};
        ASSERT_TRUE(sim.add_instances(added).ok());
    });
    distinct_after("switch", [&] {
        const uint32_t levels[] = {2, 1};
        ASSERT_TRUE(sim.set_instance_lods({ids.data() + 1, 2}, levels).ok());
    });
    distinct_after("swap removal", [&] { ASSERT_TRUE(sim.swap_remove_instances({ids.data() + 6, 1}).ok()); });
    distinct_after("wind profile", [&] {
        Wind wind = sim.wind();
        wind.profile = wind.profile == WindProfile::turbulent ? WindProfile::atmospheric : WindProfile::turbulent;
        ASSERT_TRUE(sim.set_wind(wind).ok());
    });
    EXPECT_EQ(named.reused_for_another, 0u);
    EXPECT_GE(named.named_runs, 11u);

}

}  // namespace
}  // namespace hmsm
