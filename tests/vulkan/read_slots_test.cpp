// Reads of outputs on Vulkan (src/vulkan/read_slots.h): read() and request_read/take_read copy
// each output with one command into a host-visible buffer of a read slot; outputs past one
// allocation go through the staging chunks instead. Both give the same bits, and a slot grows
// with the scene. Scenes split into windows (a ping-pong buffer read across segments) are read
// the same way and checked against unsplit ones in window_test.cpp.
#include "simulation_access.h"
#include "test_trees.h"
#include "vulkan_test_support.h"

#include "vulkan/read_slots.h"
#include "vulkan/vulkan_backend.h"

namespace hmsm::test {
namespace {

/// Outputs of more than `bytes` go through the staging chunks while it lives.
struct ReadSlotLimit {
    explicit ReadSlotLimit(uint64_t bytes) { detail::vulkan_set_read_slot_bytes(bytes); }
    ~ReadSlotLimit() { detail::vulkan_set_read_slot_bytes(0); }
};

/// Every output read with read() and with request_read then take_read, as float.
std::vector<std::vector<float>> read_both_ways(Simulation& sim) {
    std::vector<std::vector<float>> values = every_output(sim);
    for (Output output : kEveryOutput) {
        std::vector<float> taken;
        EXPECT_TRUE(sim.request_read(output).ok()) << int(output);
        EXPECT_TRUE(sim.take_read(output, taken).ok()) << int(output);
        values.push_back(std::move(taken));
    }
    return values;
}

TEST_F(VulkanTest, OutputsReadInOneCopyEqualTheStagingChunks) {
    std::string skip;
    auto sim = create_simulation_or_skip(*grid_scene(small_tree(), 5, 4.0, 1), windy_config(), BackendKind::vulkan, skip);
    if (!skip.empty()) GTEST_SKIP() << skip;
    ASSERT_TRUE(sim);
    ASSERT_TRUE(sim->step(7).ok());
    const auto& backend = dynamic_cast<const detail::vk::VulkanBackend&>(detail::backend_of(*sim));
    ASSERT_TRUE(backend.capabilities().reads_async);
    const uint64_t before = backend.submissions();
    const std::vector<std::vector<float>> one_copy = read_both_ways(*sim);
    // One submission per output read, each way.
    EXPECT_EQ(backend.submissions() - before, 2 * std::size(kEveryOutput));
    std::vector<std::vector<float>> chunked;
    {
        ReadSlotLimit limit(64);
        chunked = read_both_ways(*sim);
    }
    EXPECT_TRUE(same_bits(one_copy, chunked));
    // A slot grows with the scene: more trees, the same bits as the chunks.
    const Instance added[] = {{0, {30.0, 0.0, 2.0}, 0.3}, {0, {34.0, 0.0, 2.0}, 1.1}};
    for (int k = 0; k < 3; ++k) ASSERT_TRUE(sim->add_instances(added).ok());
    ASSERT_TRUE(sim->step(3).ok());
    const std::vector<std::vector<float>> grown = read_both_ways(*sim);
    ReadSlotLimit limit(64);
    EXPECT_TRUE(same_bits(grown, read_both_ways(*sim)));
    EXPECT_GT(grown.back().size(), one_copy.back().size());
}

}  // namespace
}  // namespace hmsm::test
