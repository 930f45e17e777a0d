// Batched launches on the host: the block -> entry search and block counting that the kernels
// share (src/common/batch_index.h), and the launch plan of a step program (src/cuda/
// launch_plan.h). Needs no GPU.
#include "common/batch_index.h"
#include "cuda/launch_plan.h"

#include <gtest/gtest.h>

#include <cstring>
#include <map>
#include <vector>

namespace hmsm::cuda_test {
namespace {

using detail::BatchBlock;
using detail::Dispatch;
using detail::cuda::LaunchPlan;
using detail::cuda::PlannedLaunch;

TEST(BatchIndex, EveryBlockFindsTheEntryWhoseRangeHoldsIt) {
    // Entry 1 and entry 4 have no blocks: their neighbours' blocks pass them over.
    const std::vector<uint32_t> begin = {0, 3, 3, 7, 10, 10, 11};
    const uint32_t entries = uint32_t(begin.size()) - 1;
    for (uint32_t block = 0; block < begin.back(); ++block) {
        uint32_t expected = 0;
        while (!(begin[expected] <= block && block < begin[expected + 1])) ++expected;
        const BatchBlock b = detail::batch_block(begin.data(), entries, block);
        EXPECT_EQ(b.entry, expected) << "block " << block;
        EXPECT_EQ(b.block, block - begin[expected]);
        EXPECT_EQ(b.blocks, begin[expected + 1] - begin[expected]);
    }
    const uint32_t one[] = {0, 5};
    EXPECT_EQ(detail::batch_entry(one, 1, 4), 0u);
}

TEST(BatchIndex, BlocksAreTheSingleLaunchsCappedForEachForm) {
    gpu::PassConstants pc{};
    pc.element_count = 1000;
    pc.model_chain_count = 250;
    pc.model_vertex_count = 250;
    EXPECT_EQ(detail::capped_blocks(1000, 64, 1u << 16), 16u);
    EXPECT_EQ(detail::capped_blocks(1024, 64, 1u << 16), 16u);
    EXPECT_EQ(detail::capped_blocks(1000, 64, 3), 3u);
    pc.kind = HMSM_DISPATCH_JUMP_ROUND;
    EXPECT_EQ(detail::dispatch_blocks(pc, 64, 1u << 16), 16u);
    EXPECT_EQ(detail::dispatch_blocks(pc, 64, 3), 3u);
    pc.kind = HMSM_DISPATCH_JUMP_ROUNDS_IN_DISPATCH;  // one block per instance, not capped by max_blocks
    EXPECT_EQ(detail::dispatch_items(pc), 4u);
    EXPECT_EQ(detail::dispatch_blocks(pc, 256, 3), 4u);
    pc.kind = HMSM_DISPATCH_CONTOUR_SEPARATE;
    EXPECT_EQ(detail::dispatch_blocks(pc, 256, 1u << 16), 4u);
    pc.kind = HMSM_DISPATCH_CONTOUR_PACKED;  // 4 instances: one group of 8 -> 250 items
    EXPECT_EQ(detail::dispatch_items(pc), 250u);
    EXPECT_EQ(detail::dispatch_blocks(pc, 64, 1u << 16), 4u);
    pc.element_count = 0;
    EXPECT_EQ(detail::dispatch_blocks(pc, 64, 1u << 16), 0u);
}

Dispatch dispatch_of(Pass pass, uint32_t kind, uint32_t instance_begin, uint32_t instances, uint32_t chains) {
    Dispatch d{pass, {}};
    d.constants.kind = kind;
    d.constants.instance_begin = instance_begin;
    d.constants.chain_begin = instance_begin * 1000;
    d.constants.model_chain_count = chains;
    d.constants.model_node_count = chains;
    d.constants.model_vertex_count = chains;
    d.constants.element_count = instances * chains;
    if (kind == HMSM_DISPATCH_JUMP_ROUNDS_IN_DISPATCH) d.constants.round = 3;
    return d;
}

/// Which (entry, item) each thread of every block of `launch` visits, by the kernels' loop.
std::map<std::pair<uint32_t, uint64_t>, int> visits(const LaunchPlan& plan, const PlannedLaunch& launch) {
    const detail::BatchLaunch batch = plan.batch(launch, plan.constants.data(), plan.block_begin.data(), 0);
    std::map<std::pair<uint32_t, uint64_t>, int> seen;
    for (uint32_t g = 0; g < launch.shape.blocks; ++g) {
        const BatchBlock block = detail::batch_block(batch.block_begin, batch.entries, g);
        const uint64_t items = detail::dispatch_items(batch.constants[block.entry]);
        for (uint32_t t = 0; t < launch.shape.threads; ++t)
            for (uint64_t i = uint64_t(block.block) * launch.shape.threads + t; i < items;
                 i += uint64_t(block.blocks) * launch.shape.threads)
                ++seen[{block.entry, i}];
    }
    return seen;
}

TEST(LaunchPlan, ARunOfManyGroupsIsOneLaunchCoveringEveryElementOnce) {
    std::vector<Dispatch> program;
    for (uint32_t g = 0; g < 7; ++g) program.push_back(dispatch_of(Pass::wind_force, HMSM_DISPATCH_PER_ELEMENT, g, 1 + g % 3, 157 + 60 * (g % 2)));
    program[4].constants.params.w = 1.0f;  // covers paused instances
    for (uint32_t max_blocks : {1u << 16, 3u}) {
        const LaunchPlan plan = detail::cuda::plan_launches(program, true, max_blocks);
        ASSERT_EQ(plan.launches.size(), 1u);
        const PlannedLaunch& launch = plan.launches[0];
        EXPECT_EQ(launch.entries, 7u);
        EXPECT_TRUE(launch.reads_wind_slot);
        EXPECT_TRUE(launch.shape.may_pause);
        EXPECT_EQ(launch.shape.threads, uint32_t(HMSM_WORKGROUP_SIZE));
        for (uint32_t e = 0; e < 7; ++e) {
            EXPECT_EQ(plan.constants[launch.entry_begin + e].instance_begin, e);
            const uint32_t blocks = plan.block_begin[launch.prefix_begin + e + 1] - plan.block_begin[launch.prefix_begin + e];
            EXPECT_EQ(blocks, detail::capped_blocks(program[e].constants.element_count, HMSM_WORKGROUP_SIZE, max_blocks));
        }
        const auto seen = visits(plan, launch);
        uint64_t elements = 0;
        for (const Dispatch& d : program) elements += d.constants.element_count;
        EXPECT_EQ(seen.size(), elements);
        for (const auto& [item, count] : seen) {
            EXPECT_EQ(count, 1) << "entry " << item.first << " element " << item.second;
            EXPECT_LT(item.second, program[item.first].constants.element_count);
        }
        // The wind slot of the step replaces every entry's.
        const detail::BatchLaunch batch = plan.batch(launch, plan.constants.data(), plan.block_begin.data(), 17);
        EXPECT_EQ(detail::batch_constants(batch, 3).wind_slot, 17u);
    }
    const LaunchPlan unbatched = detail::cuda::plan_launches(program, false, 1u << 16);
    ASSERT_EQ(unbatched.launches.size(), program.size());
    for (uint32_t i = 0; i < program.size(); ++i) {
        EXPECT_EQ(unbatched.launches[i].entries, 0u);
        EXPECT_EQ(unbatched.launches[i].dispatch, i);
    }
}

TEST(LaunchPlan, RunsOfOneDispatchKeepTheirOwnLaunchAndTheSlotOnlyWhereRead) {
    std::vector<Dispatch> program = {dispatch_of(Pass::wind_force, HMSM_DISPATCH_PER_ELEMENT, 0, 2, 100),
                                     dispatch_of(Pass::node_relative, HMSM_DISPATCH_PER_ELEMENT, 0, 2, 100),
                                     dispatch_of(Pass::node_relative, HMSM_DISPATCH_PER_ELEMENT, 2, 1, 300),
                                     dispatch_of(Pass::node_relative, HMSM_DISPATCH_PER_ELEMENT, 3, 0, 300),
                                     dispatch_of(Pass::node_world, HMSM_DISPATCH_PER_ELEMENT, 0, 2, 100)};
    const LaunchPlan plan = detail::cuda::plan_launches(program, true, 1u << 16);
    ASSERT_EQ(plan.launches.size(), 3u);
    EXPECT_EQ(plan.launches[0].entries, 0u);
    EXPECT_EQ(plan.launches[0].dispatch, 0u);
    EXPECT_EQ(plan.launches[1].entries, 2u);  // the empty dispatch takes no entry
    EXPECT_FALSE(plan.launches[1].reads_wind_slot);
    EXPECT_EQ(plan.launches[1].shape.blocks,
              detail::capped_blocks(200, 64, 1u << 16) + detail::capped_blocks(300, 64, 1u << 16));
    const detail::BatchLaunch batch = plan.batch(plan.launches[1], plan.constants.data(), plan.block_begin.data(), 9);
    EXPECT_EQ(batch.sets_wind_slot, 0u);
    EXPECT_EQ(plan.launches[2].entries, 0u);
    EXPECT_EQ(plan.launches[2].dispatch, 4u);
}

TEST(LaunchPlan, InDispatchRoundsLaunchOncePerBlockSize) {
    // Chains 50, 100, 50, 300, 100, 40: sizes 64, 128, 64, 512, 128, 64.
    std::vector<Dispatch> program;
    const uint32_t chains[] = {50, 100, 50, 300, 100, 40};
    for (uint32_t g = 0; g < 6; ++g)
        program.push_back(dispatch_of(Pass::compose, HMSM_DISPATCH_JUMP_ROUNDS_IN_DISPATCH, g, 2 + g, chains[g]));
    const LaunchPlan plan = detail::cuda::plan_launches(program, true, 3);
    ASSERT_EQ(plan.launches.size(), 3u);
    const PlannedLaunch &small = plan.launches[0], &middle = plan.launches[1], &large = plan.launches[2];
    EXPECT_EQ(small.shape.threads, 64u);
    EXPECT_EQ(small.entries, 3u);
    EXPECT_EQ(middle.shape.threads, 128u);
    EXPECT_EQ(middle.entries, 2u);
    EXPECT_EQ(large.entries, 0u);  // one dispatch of its size: its own launch
    EXPECT_EQ(large.dispatch, 3u);
    // One block per instance, in the run's order within a size.
    const uint32_t small_groups[] = {0, 2, 5};
    for (uint32_t e = 0; e < 3; ++e) {
        EXPECT_EQ(plan.constants[small.entry_begin + e].instance_begin, small_groups[e]);
        EXPECT_EQ(plan.block_begin[small.prefix_begin + e + 1] - plan.block_begin[small.prefix_begin + e], 2 + small_groups[e]);
    }
    EXPECT_EQ(small.shape.blocks, 2u + 4u + 7u);
}

// Planning into a plan that held another program (the backend reuses its plans' memory as the
// program changes) gives the plan made afresh.
TEST(LaunchPlan, APlanMadeOverAnotherEqualsOneMadeAfresh) {
    std::vector<Dispatch> large, small;
    for (uint32_t g = 0; g < 40; ++g) large.push_back(dispatch_of(Pass::wind_force, HMSM_DISPATCH_PER_ELEMENT, g, 1 + g % 3, 77));
    for (uint32_t g = 0; g < 6; ++g)
        small.push_back(dispatch_of(Pass::compose, HMSM_DISPATCH_JUMP_ROUNDS_IN_DISPATCH, g, 2 + g, g % 2 ? 100 : 50));
    LaunchPlan reused;
    for (const std::vector<Dispatch>* program : {&large, &small, &large}) {
        detail::cuda::plan_launches(*program, true, 5, reused);
        const LaunchPlan fresh = detail::cuda::plan_launches(*program, true, 5);
        ASSERT_EQ(reused.launches.size(), fresh.launches.size());
        for (size_t i = 0; i < fresh.launches.size(); ++i) {
            EXPECT_EQ(reused.launches[i].entries, fresh.launches[i].entries);
            EXPECT_EQ(reused.launches[i].entry_begin, fresh.launches[i].entry_begin);
            EXPECT_EQ(reused.launches[i].shape.blocks, fresh.launches[i].shape.blocks);
        }
        EXPECT_EQ(reused.block_begin, fresh.block_begin);
        ASSERT_EQ(reused.constants.size(), fresh.constants.size());
        EXPECT_EQ(std::memcmp(reused.constants.data(), fresh.constants.data(),
                              fresh.constants.size() * sizeof(gpu::PassConstants)),
                  0);
    }
}

}  // namespace
}  // namespace hmsm::cuda_test
