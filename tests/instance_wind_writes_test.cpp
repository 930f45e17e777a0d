// The per-instance changes of a frame (wind scales and phases, fade words of switched or fading
// instances, holes a swap removal filled) reach the device in one transfer: apply_pending writes
// every run of changed instances with one write_ranges, however scattered they are, so that a
// frame of an open world does not pay a transfer per run (on a device, a copy or submission
// each).
#include "forwarding_backend.h"
#include "live_wind.h"
#include "simulation_access.h"
#include "test_trees.h"

#include <gtest/gtest.h>

namespace hmsm {
namespace {

/// A backend that logs the calls writing instance winds, and the ranges each writes.
class WindWrites final : public test::ForwardingBackend {
public:
    using ForwardingBackend::ForwardingBackend;
    Status write(detail::BufferId id, uint64_t first, uint64_t count, const void* src, detail::Scalar as) override {
        if (id == detail::BufferId::instance_wind) calls.push_back({{first, count}});
        return ForwardingBackend::write(id, first, count, src, as);
    }
    Status write_ranges(detail::BufferId id, std::span<const detail::ElementRange> ranges, const void* src,
                        detail::Scalar as) override {
        if (id == detail::BufferId::instance_wind) calls.emplace_back(ranges.begin(), ranges.end());
        return ForwardingBackend::write_ranges(id, ranges, src, as);
    }
    std::vector<std::vector<detail::ElementRange>> calls;
};

TEST(InstanceWindWrites, ScatteredChangesOfAFrameGoInOneWrite) {
    auto backend = detail::create_backend(BackendKind::cpu);
    ASSERT_TRUE(backend.ok()) << backend.status().message();
    auto watched = std::make_unique<WindWrites>(std::move(backend).value());
    WindWrites* writes = watched.get();
    auto created = detail::SimulationAccess::create(*grid_scene(test::small_tree(), 60, 4.0, 3),
                                                    test::windy_config(), std::move(watched));
    ASSERT_TRUE(created.ok()) << created.status().message();
    Simulation& sim = **created;
    ASSERT_TRUE(sim.step(2).ok());
    writes->calls.clear();
    // Three instances far apart (farther than the gap rewritten as it is), one twice.
    for (uint64_t i : {50u, 0u, 25u, 0u}) ASSERT_TRUE(sim.set_instance_wind_scale(i, 0.5).ok());
    ASSERT_TRUE(sim.set_instance_wind_phase(26, 0.3).ok());
    ASSERT_TRUE(sim.step(1).ok());
    ASSERT_EQ(writes->calls.size(), 1u) << "one transfer for the frame's changes";
    const std::vector<detail::ElementRange>& ranges = writes->calls.front();
    ASSERT_EQ(ranges.size(), 3u);
    EXPECT_EQ(ranges[0].first, 0u);
    EXPECT_EQ(ranges[0].count, 1u);
    EXPECT_EQ(ranges[1].first, 25u);
    EXPECT_EQ(ranges[1].count, 2u);
    EXPECT_EQ(ranges[2].first, 50u);
    EXPECT_EQ(ranges[2].count, 1u);
    ASSERT_TRUE(sim.step(1).ok());
    EXPECT_EQ(writes->calls.size(), 1u) << "nothing changed since";
    // What was written is what the device holds: the instance winds of a simulation created
    // with these scales and phase.
    Scene scene = *grid_scene(test::small_tree(), 60, 4.0, 3);
    for (uint64_t i : {0u, 25u, 50u}) scene.instances[i].wind_scale = 0.5;
    scene.instances[26].wind_phase = 0.3;
    auto fresh = Simulation::create(scene, test::windy_config());
    ASSERT_TRUE(fresh.ok()) << fresh.status().message();
    std::vector<double> held, expected;
    const uint64_t count = sim.instances().size();
    held.resize(count * detail::kInstanceWindScalars);
    expected.resize(held.size());
    ASSERT_TRUE(detail::backend_of(sim).read(detail::BufferId::instance_wind, 0, count, held.data(), detail::Scalar::f64).ok());
    ASSERT_TRUE(detail::backend_of(**fresh).read(detail::BufferId::instance_wind, 0, count, expected.data(),
                                                 detail::Scalar::f64).ok());
    EXPECT_EQ(held, expected);
}

}  // namespace
}  // namespace hmsm
