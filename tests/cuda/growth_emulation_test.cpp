// Growth past the capacity through the CUDA backend's copies (Backend::grow over the host
// images of tests/agreement/cuda_emulation_backend.h, laid out as src/cuda/device_buffers.cpp
// grows them) and the kernels run on the host: adds, level switches and swap removals past the
// capacity, with the walk that integrates ahead, give bit for bit what a simulation that reserved
// enough up front gives, and what one that uploads the scene anew gives. No GPU needed.
#include "simulation_access.h"
#include "cuda_emulation_backend.h"
#include "cuda_test_support.h"

#include <gtest/gtest.h>

#include <vector>

namespace hmsm::cuda_test {
namespace {

class CudaEmulationGrowth : public ::testing::TestWithParam<Dynamics> {};

TEST_P(CudaEmulationGrowth, GrowingOnTheDeviceEqualsReservingAndUploading) {
    const Scene scene = many_groups_scene(3, 6);
    SimulationConfig config = test_config(BackendKind::cuda, Composition::path_walk, false);
    config.model.dynamics = GetParam();
    test::EmulatedAheadSteps reserved_steps, device_steps, upload_steps;
    auto reserved = detail::SimulationAccess::create(scene, config, test::create_cuda_emulation_backend(&reserved_steps));
    auto device = detail::SimulationAccess::create(scene, config, test::create_cuda_emulation_backend(&device_steps));
    auto uploads = detail::SimulationAccess::create(scene, config, test::create_cuda_emulation_backend(&upload_steps));
    ASSERT_TRUE(reserved.ok() && device.ok() && uploads.ok());
    detail::SimulationAccess::impl(**uploads).device_growth_ = false;
    ASSERT_TRUE((*reserved)->reserve_instances(40).ok());
    Simulation* sims[] = {reserved->get(), device->get(), uploads->get()};
    uint64_t grown_by_switches = 0;
    for (uint32_t round = 0; round < 4; ++round) {
        for (Simulation* sim : sims) ASSERT_TRUE(sim->step(6).ok());
        // Every instance coarse, more added into the room that leaves (then coarse too), and
        // every instance fine: past the capacity.
        const std::vector<InstanceId> before_add((*device)->instance_ids().begin(), (*device)->instance_ids().end());
        for (Simulation* sim : sims)
            ASSERT_TRUE(sim->set_instance_lods(before_add, std::vector<uint32_t>(before_add.size(), 1)).ok());
        std::vector<Instance> added;
        for (uint32_t k = 0; k < 3 + round; ++k) added.push_back({k % 2, {4.0 * k, 0.0, -5.0 * round}, 0.4 * k});
        for (Simulation* sim : sims) ASSERT_TRUE(sim->add_instances(added).ok()) << "round " << round;
        const std::vector<InstanceId> ids((*device)->instance_ids().begin(), (*device)->instance_ids().end());
        for (Simulation* sim : sims) ASSERT_TRUE(sim->set_instance_lods(ids, std::vector<uint32_t>(ids.size(), 1)).ok());
        for (Simulation* sim : sims) ASSERT_TRUE(sim->step(3).ok());
        const uint64_t before = detail::device_growths_of(**device);
        for (Simulation* sim : sims) ASSERT_TRUE(sim->set_instance_lods(ids, std::vector<uint32_t>(ids.size(), 0)).ok());
        grown_by_switches += detail::device_growths_of(**device) - before;
        const InstanceId leaving[] = {ids[round], ids[ids.size() - 2]};
        for (Simulation* sim : sims) ASSERT_TRUE(sim->swap_remove_instances(leaving).ok());
        for (Simulation* sim : sims) ASSERT_TRUE(sim->step(4).ok());
        for (Output output : {Output::joint_matrices, Output::chain_angles, Output::node_positions}) {
            std::vector<float> expected, on_device, uploaded;
            ASSERT_TRUE((*reserved)->read(output, expected).ok());
            ASSERT_TRUE((*device)->read(output, on_device).ok());
            ASSERT_TRUE((*uploads)->read(output, uploaded).ok());
            EXPECT_EQ(on_device, expected) << "output " << int(output) << ", round " << round;
            EXPECT_EQ(uploaded, expected) << "output " << int(output) << ", round " << round;
        }
    }
    EXPECT_EQ(detail::full_uploads_of(**device), 0u);
    EXPECT_GE(detail::device_growths_of(**device), 2u);
    EXPECT_GE(grown_by_switches, 1u) << "a switch to the finer level grew the capacity";
    EXPECT_GE(detail::full_uploads_of(**uploads), 2u);
    EXPECT_GT(device_steps.taken, 0u) << "the walk ahead ran between the growths";
}

INSTANTIATE_TEST_SUITE_P(Dynamics, CudaEmulationGrowth, ::testing::Values(Dynamics::paper, Dynamics::coupled),
                         [](const ::testing::TestParamInfo<Dynamics>& info) {
                             return std::string(info.param == Dynamics::paper ? "paper" : "coupled");
                         });

}  // namespace
}  // namespace hmsm::cuda_test
