// Simulation::request_read / take_read on every backend (one without a device skips): take_read returns
// bit for bit what read() returned at the request, whatever ran since (steps, live changes,
// instances removed); a request stays until the next one; bad requests change nothing. More on
// the CUDA backend's copy path (an engine stream, slot growth) is tests/cuda/cuda_frame_test.cpp.
#include "test_trees.h"

#include <hmsm/hmsm.h>

#include <gtest/gtest.h>

using namespace hmsm;
using test::kEveryOutput;
using test::same_bits;

namespace {

class ReadAsync : public ::testing::TestWithParam<std::tuple<BackendKind, VertexLayout>> {};

}  // namespace

TEST_P(ReadAsync, TakeReturnsTheValuesOfTheRequest) {
    const auto [backend, layout] = GetParam();
    auto scene = grid_scene(test::small_tree(), 6, 5.0, 2);
    ASSERT_TRUE(scene.ok());
    SimulationConfig config;
    config.backend = backend;
    config.vertex_layout = layout;
    config.wind.strength = 12.0;
    auto created = Simulation::create(*scene, config);
    if (!created && (created.status().code() == ErrorCode::no_device || created.status().code() == ErrorCode::unsupported))
        GTEST_SKIP() << created.status().message();
    ASSERT_TRUE(created.ok()) << created.status().message();
    Simulation& sim = **created;
    std::vector<float> values;
    EXPECT_EQ(sim.take_read(Output::joint_matrices, values).code(), ErrorCode::invalid_argument);
    EXPECT_EQ(sim.request_read(static_cast<Output>(99)).code(), ErrorCode::invalid_argument);
    EXPECT_EQ(sim.take_read(static_cast<Output>(99), values).code(), ErrorCode::invalid_argument);
    EXPECT_TRUE(values.empty());
    ASSERT_TRUE(sim.step(20).ok());

    std::vector<std::vector<float>> at_request(std::size(kEveryOutput));
    std::vector<std::vector<double>> at_request64(std::size(kEveryOutput));
    for (size_t i = 0; i < std::size(kEveryOutput); ++i) {
        ASSERT_TRUE(sim.request_read(kEveryOutput[i]).ok());
        ASSERT_TRUE(sim.read(kEveryOutput[i], at_request[i]).ok());
        ASSERT_TRUE(sim.read(kEveryOutput[i], at_request64[i]).ok());
    }
    // Steps, a live change and a removed instance before the take.
    Wind wind = sim.wind();
    wind.strength = 3.0;
    ASSERT_TRUE(sim.set_wind(wind).ok());
    ASSERT_TRUE(sim.step(7).ok());
    const uint64_t first = 0;
    ASSERT_TRUE(sim.remove_instances({&first, 1}).ok());
    ASSERT_TRUE(sim.step(1).ok());
    for (size_t i = 0; i < std::size(kEveryOutput); ++i) {
        SCOPED_TRACE("output " + std::to_string(int(kEveryOutput[i])));
        std::vector<float> taken, again;
        std::vector<double> taken64;
        ASSERT_TRUE(sim.take_read(kEveryOutput[i], taken).ok());
        ASSERT_TRUE(sim.take_read(kEveryOutput[i], taken64).ok());
        ASSERT_TRUE(sim.take_read(kEveryOutput[i], again).ok());  // the request stays
        EXPECT_TRUE(same_bits(taken, at_request[i]));
        EXPECT_TRUE(same_bits(taken64, at_request64[i]));
        EXPECT_TRUE(same_bits(again, taken));
        std::vector<float> now;
        ASSERT_TRUE(sim.read(kEveryOutput[i], now).ok());
        EXPECT_FALSE(same_bits(now, taken)) << "the simulation did not move, the test proves nothing";
    }
    // A new request replaces the old one.
    ASSERT_TRUE(sim.request_read(Output::chain_angles).ok());
    std::vector<float> now, taken;
    ASSERT_TRUE(sim.read(Output::chain_angles, now).ok());
    ASSERT_TRUE(sim.take_read(Output::chain_angles, taken).ok());
    EXPECT_TRUE(same_bits(now, taken));
}

TEST(ReadAsyncOutputs, AnOutputTheSimulationDoesNotProduceIsRefused) {
    auto scene = grid_scene(test::small_tree(), 2, 5.0, 2);
    ASSERT_TRUE(scene.ok());
    SimulationConfig config;
    config.backend = BackendKind::cpu;
    config.outputs = Outputs::joints;
    auto sim = Simulation::create(*scene, config);
    ASSERT_TRUE(sim.ok());
    const Status refused = (*sim)->request_read(Output::vertex_positions);
    EXPECT_EQ(refused.code(), ErrorCode::invalid_argument);
    EXPECT_NE(refused.message().find("request_read: output vertex_positions is not produced"), std::string::npos)
        << refused.message();
    std::vector<float> values;
    EXPECT_EQ((*sim)->take_read(Output::vertex_positions, values).code(), ErrorCode::invalid_argument);
}

INSTANTIATE_TEST_SUITE_P(Backends, ReadAsync,
                         ::testing::Combine(::testing::Values(BackendKind::cpu, BackendKind::cpu64,
                                                              BackendKind::cpu_parallel, BackendKind::vulkan,
                                                              BackendKind::cuda),
                                            ::testing::Values(VertexLayout::separate, VertexLayout::packed)),
                         [](const auto& info) {
                             return test::backend_test_name(std::get<0>(info.param)) + "_" + to_string(std::get<1>(info.param));
                         });
