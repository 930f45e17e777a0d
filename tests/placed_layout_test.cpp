// The placed layout (SimulationConfig::instance_layout): a level switch, an add and a swap removal
// move only the instances they touch, and every other instance keeps its slot; outputs are bit
// for bit those of the packed layout (live_stream_test.cpp runs the long random sequence in
// both); instance_placement says where an instance's elements lie, in both layouts; a backend
// that cannot list its instances keeps the packed layout.
#include "forwarding_backend.h"
#include "instance_placements.h"
#include "placed_list.h"
#include "simulation_access.h"
#include "test_trees.h"

#include <hmsm/hmsm.h>

#include <gtest/gtest.h>

#include <algorithm>
#include <memory>
#include <random>
#include <string>
#include <vector>

namespace hmsm {
namespace {

using detail::ElementCounts;
using detail::SceneData;

TEST(InstancePlacements, FreedSlotsServeTheirModelAndTheEndGrowsOtherwise) {
    std::vector<detail::ModelRange> models(2);
    models[0].chain_count = 3, models[0].node_count = 4, models[0].vertex_count = 5;
    models[1].chain_count = 2, models[1].node_count = 2, models[1].vertex_count = 0;
    std::vector<Instance> instances(3);
    instances[1].model = 1;
    detail::InstancePlacements p;
    p.assign_packed(instances, models);
    EXPECT_EQ(p[1], (ElementCounts{3, 4, 5}));
    EXPECT_EQ(p[2], (ElementCounts{5, 6, 5}));
    const ElementCounts end{8, 10, 10};
    EXPECT_EQ(p.end(), end);
    const uint32_t both[] = {0, 1};
    EXPECT_EQ(p.end_after(both, models), end + detail::counts_of(models[0]) + detail::counts_of(models[1]));
    p.release(0, p[0]);
    const uint32_t two_of_model_0[] = {0, 0};
    EXPECT_EQ(p.end_after(two_of_model_0, models), end + detail::counts_of(models[0])) << "one free slot serves one";
    EXPECT_EQ(p.free_slots(), 1u);
    EXPECT_EQ(p.allocate(0, detail::counts_of(models[0])), (ElementCounts{0, 0, 0})) << "the freed slot";
    EXPECT_EQ(p.allocate(0, detail::counts_of(models[0])), end) << "then past the end";
    EXPECT_EQ(p.end(), end + detail::counts_of(models[0]));
    EXPECT_EQ(p.free_slots(), 0u);
}

// The step program's table under random inserts, erasures, renumberings and switches: every listed
// instance has one entry, in its model's segment, at its slot; the entries written since the
// last take, applied to a copy of the table as a device would hold it, give the whole table.
TEST(PlacedList, KeepsOneEntryPerListedInstanceAndWritesWhatChanged) {
    constexpr uint32_t kModels = 4;
    SceneData d;
    d.models.resize(kModels);
    for (uint32_t m = 0; m < kModels; ++m) d.models[m].chain_count = m + 1;
    std::mt19937 rng(7);
    std::vector<Instance> instances(40);
    detail::InstancePlacements slots;
    for (Instance& inst : instances) inst.model = rng() % kModels, inst.active = rng() % 5 != 0;
    slots.assign_packed(instances, d.models);
    detail::PlacedList list;
    list.build(instances, slots, kModels);
    std::vector<double> device;  // the table as written
    auto sync = [&] {
        std::vector<detail::ElementRange> ranges;
        std::vector<double> values;
        list.take_writes(ranges, values);
        device.resize(size_t(4) * list.entries());
        size_t v = 0;
        for (const detail::ElementRange& r : ranges)
            for (uint64_t e = r.first; e < r.first + r.count; ++e, v += 4) std::copy_n(&values[v], 4, &device[4 * e]);
    };
    std::vector<bool> listed(instances.size());
    for (size_t i = 0; i < instances.size(); ++i) listed[i] = instances[i].active;
    for (int round = 0; round < 400; ++round) {
        const uint32_t i = rng() % uint32_t(instances.size());
        const int op = int(rng() % 4);
        if (op == 0 && listed[i]) {
            list.erase(i);
            listed[i] = false;
        } else if (op == 1 && !listed[i]) {
            instances[i].model = rng() % kModels;
            list.insert(i, instances[i].model, slots[i]);
            listed[i] = true;
        } else if (op == 2 && listed[i]) {  // a swap removal's filler: i's entry names j
            const uint32_t j = rng() % uint32_t(instances.size());
            if (listed[j]) continue;
            list.renumber(i, j);
            instances[j] = instances[i];
            slots.set(j, slots[i]);
            listed[i] = false;
            listed[j] = true;
        } else if (op == 3 && listed[i]) {  // a level switch: i's entry changes segment and slot
            instances[i].model = rng() % kModels;
            detail::ElementCounts at = slots[i];
            at.chains += 1000;
            slots.set(i, at);
            list.move_to(i, instances[i].model, slots[i]);
        }
        if (round % 7 == 0) sync();
    }
    sync();
    std::vector<detail::InstanceGroup> groups;
    list.groups(d, groups);
    std::vector<int> seen(instances.size(), 0);
    for (const detail::InstanceGroup& g : groups)
        for (uint32_t e = g.instance_begin; e < g.instance_begin + g.instance_count; ++e) {
            const uint32_t i = uint32_t(device[4 * e + 3]);
            ASSERT_LT(i, instances.size());
            ++seen[i];
            EXPECT_EQ(instances[i].model, g.model) << "entry " << e;
            EXPECT_EQ(uint64_t(device[4 * e]), slots[i].chains) << "entry " << e;
        }
    for (size_t i = 0; i < instances.size(); ++i) EXPECT_EQ(seen[i], listed[i] ? 1 : 0) << "instance " << i;

    // A switch to the neighbouring segment writes two entries, however many segments follow.
    for (Instance& inst : instances) inst.active = true;
    instances[0].model = 0;
    list.build(instances, slots, kModels);
    sync();
    list.move_to(0, 1, slots[0]);
    std::vector<detail::ElementRange> ranges;
    std::vector<double> values;
    list.take_writes(ranges, values);
    EXPECT_EQ(values.size(), 2u * 4u);
}

/// Sums the elements the backend moves or copies (per buffer).
class MovedElements final : public test::ForwardingBackend {
public:
    using ForwardingBackend::ForwardingBackend;
    Status move_elements(detail::BufferId id, std::span<const detail::ElementMove> moves) override {
        for (const detail::ElementMove& m : moves) moved += m.count;
        return ForwardingBackend::move_elements(id, moves);
    }
    Status move_buffers(std::span<const detail::BufferMoves> buffers) override {
        for (const detail::BufferMoves& b : buffers)
            for (const detail::ElementMove& m : b.moves) moved += m.count;
        return ForwardingBackend::move_buffers(buffers);
    }
    Status copy_patterns(std::span<const detail::BufferId> ids, uint64_t capacity,
                         std::span<const detail::MovePattern> patterns,
                         std::span<const detail::PatternCopy> copies) override {
        for (const detail::PatternCopy& c : copies)
            for (const detail::ElementMove& m : patterns[c.pattern].moves) moved += m.count * ids.size();
        return ForwardingBackend::copy_patterns(ids, capacity, patterns, copies);
    }
    Status write_buffers(std::span<const detail::BufferRangesWrite> writes, detail::Scalar as) override {
        ++buffer_writes;  // templates (level_staging.h)
        return ForwardingBackend::write_buffers(writes, as);
    }
    uint64_t moved = 0;
    uint64_t buffer_writes = 0;
};

struct Forest {
    std::unique_ptr<Simulation> sim;
    MovedElements* backend = nullptr;
};

/// Twelve deep trees in a row, with three levels below the whole tree, swaying, on `kind` in
/// `layout`; null (with `skip` set) where the backend is absent.
Forest forest(BackendKind kind, InstanceLayout layout, std::string& skip) {
    Scene scene = single_tree_scene(test::deep_tree(4));
    scene.instances.clear();
    for (int k = 0; k < 12; ++k) scene.instances.push_back({0, {4.0 * k, 0.0, 0.0}, 0.3 * k, 1.0, 0.1 * k});
    scene.lod_budgets = {{6, 3, 1}};
    SimulationConfig config = test::windy_config();
    config.instance_layout = layout;
    auto inner = detail::create_backend(kind);
    if (!inner) {
        skip = std::string(to_string(kind)) + ": " + inner.status().message();
        return {};
    }
    auto counting = std::make_unique<MovedElements>(std::move(inner).value());
    Forest f;
    f.backend = counting.get();
    auto sim = detail::SimulationAccess::create(scene, config, std::move(counting));
    EXPECT_TRUE(sim.ok()) << sim.status().message();
    if (!sim) return {};
    f.sim = std::move(sim).value();
    EXPECT_TRUE(f.sim->step(30).ok());
    return f;
}

std::vector<InstancePlacement> placements_of(const Simulation& sim) {
    std::vector<InstancePlacement> all;
    for (InstanceId id : sim.instance_ids()) all.push_back(*sim.instance_placement(id));
    return all;
}

bool same_place(const InstancePlacement& a, const InstancePlacement& b) {
    return a.first_chain == b.first_chain && a.first_node == b.first_node && a.first_vertex == b.first_vertex;
}

/// Packed running sums of the instances' chains, nodes and vertices.
std::vector<InstancePlacement> packed_places(const Simulation& sim) {
    const detail::SceneData& d = detail::scene_data_of(sim);
    std::vector<InstancePlacement> all;
    InstancePlacement at;
    for (const Instance& inst : sim.instances()) {
        all.push_back(at);
        at.first_chain += d.models[inst.model].chain_count;
        at.first_node += d.models[inst.model].node_count;
        at.first_vertex += d.models[inst.model].vertex_count;
    }
    return all;
}

void expect_same_outputs(const Simulation& a, const Simulation& b) {
    for (Output output : test::kEveryOutput) {
        std::vector<double> x, y;
        ASSERT_TRUE(a.read(output, x).ok());
        ASSERT_TRUE(b.read(output, y).ok());
        EXPECT_TRUE(test::same_bits(x, y)) << "output " << uint32_t(output);
    }
}

class PlacedLayout : public ::testing::TestWithParam<BackendKind> {};

TEST_P(PlacedLayout, SwitchMovesOnlyTheSwitchedInstance) {
    std::string skip;
    Forest placed = forest(GetParam(), InstanceLayout::placed, skip);
    if (!skip.empty()) GTEST_SKIP() << skip;
    Forest packed = forest(GetParam(), InstanceLayout::packed, skip);
    ASSERT_TRUE(placed.sim && packed.sim);
    const std::vector<InstancePlacement> before = placements_of(*placed.sim);
    for (size_t i = 0; i < before.size(); ++i) EXPECT_TRUE(same_place(before[i], packed_places(*placed.sim)[i]));
    const InstanceId first = placed.sim->instance_ids()[0];
    placed.backend->moved = packed.backend->moved = 0;
    const uint32_t level[] = {2};
    ASSERT_TRUE(placed.sim->set_instance_lods({&first, 1}, level).ok());
    ASSERT_TRUE(packed.sim->set_instance_lods({&first, 1}, level).ok());
    const std::vector<InstancePlacement> after = placements_of(*placed.sim);
    EXPECT_GE(after[0].first_chain, before.back().first_chain + 1) << "a new slot past every other";
    for (size_t i = 1; i < after.size(); ++i) EXPECT_TRUE(same_place(after[i], before[i])) << "instance " << i;
    // The packed switch shifts the eleven trees behind; the placed one moves the switched tree's
    // chains only (through the staging, or by pattern straight into its new slot).
    EXPECT_GT(packed.backend->moved, 0u);
    EXPECT_LT(placed.backend->moved * 4, packed.backend->moved)
        << "placed " << placed.backend->moved << ", packed " << packed.backend->moved;
    expect_same_outputs(*placed.sim, *packed.sim);
    ASSERT_TRUE(placed.sim->step(20).ok());
    ASSERT_TRUE(packed.sim->step(20).ok());
    expect_same_outputs(*placed.sim, *packed.sim);
}

TEST_P(PlacedLayout, SwapRemovalMovesNothingAndAddsReuseFreedSlots) {
    std::string skip;
    Forest placed = forest(GetParam(), InstanceLayout::placed, skip);
    if (!skip.empty()) GTEST_SKIP() << skip;
    Forest packed = forest(GetParam(), InstanceLayout::packed, skip);
    ASSERT_TRUE(placed.sim && packed.sim);
    // Instance 3 on a coarser level, so that the last tree fills a hole of another size.
    const InstanceId third = placed.sim->instance_ids()[3], last = placed.sim->instance_ids()[11];
    ASSERT_TRUE(placed.sim->set_instance_lod(third, 1).ok());
    ASSERT_TRUE(packed.sim->set_instance_lod(third, 1).ok());
    const InstancePlacement last_place = *placed.sim->instance_placement(last);
    const InstancePlacement freed = *placed.sim->instance_placement(third);
    placed.backend->moved = packed.backend->moved = 0;
    ASSERT_TRUE(placed.sim->swap_remove_instances({&third, 1}).ok());
    ASSERT_TRUE(packed.sim->swap_remove_instances({&third, 1}).ok());
    EXPECT_EQ(placed.backend->moved, 0u) << "the last tree takes its slot along";
    EXPECT_GT(packed.backend->moved, 0u);
    EXPECT_EQ(*placed.sim->index_of(last), 3u);
    EXPECT_TRUE(same_place(*placed.sim->instance_placement(last), last_place));
    expect_same_outputs(*placed.sim, *packed.sim);
    // A tree of the freed slot's model and level takes that slot.
    Instance coming{0, {100.0, 0.0, 0.0}, 0.2, 1.0, 0.4};
    coming.level = 1;
    InstanceId id{};
    ASSERT_TRUE(placed.sim->add_instances({&coming, 1}, {&id, 1}).ok());
    ASSERT_TRUE(packed.sim->add_instances({&coming, 1}).ok());
    EXPECT_TRUE(same_place(*placed.sim->instance_placement(id), freed));
    ASSERT_TRUE(placed.sim->step(15).ok());
    ASSERT_TRUE(packed.sim->step(15).ok());
    expect_same_outputs(*placed.sim, *packed.sim);
}

TEST_P(PlacedLayout, OrderKeepingRemovalPacksTheLayout) {
    std::string skip;
    Forest placed = forest(GetParam(), InstanceLayout::placed, skip);
    if (!skip.empty()) GTEST_SKIP() << skip;
    Forest packed = forest(GetParam(), InstanceLayout::packed, skip);
    ASSERT_TRUE(placed.sim && packed.sim);
    for (Simulation* sim : {placed.sim.get(), packed.sim.get()}) {
        const InstanceId ids[] = {sim->instance_ids()[2], sim->instance_ids()[7]};
        const uint32_t levels[] = {3, 1};
        ASSERT_TRUE(sim->set_instance_lods(ids, levels).ok());
        ASSERT_TRUE(sim->step(5).ok());
    }
    const uint64_t removed[] = {4};
    ASSERT_TRUE(placed.sim->remove_instances(removed).ok());
    ASSERT_TRUE(packed.sim->remove_instances(removed).ok());
    const std::vector<InstancePlacement> now = placements_of(*placed.sim), packed_now = packed_places(*placed.sim);
    for (size_t i = 0; i < now.size(); ++i) EXPECT_TRUE(same_place(now[i], packed_now[i])) << "instance " << i;
    expect_same_outputs(*placed.sim, *packed.sim);
    ASSERT_TRUE(placed.sim->step(10).ok());
    ASSERT_TRUE(packed.sim->step(10).ok());
    expect_same_outputs(*placed.sim, *packed.sim);
}

TEST_P(PlacedLayout, TheBufferHoldsEachInstanceAtItsPlacement) {
    std::string skip;
    Forest placed = forest(GetParam(), InstanceLayout::placed, skip);
    if (!skip.empty()) GTEST_SKIP() << skip;
    ASSERT_TRUE(placed.sim);
    Simulation& sim = *placed.sim;
    const InstanceId ids[] = {sim.instance_ids()[0], sim.instance_ids()[5]};
    const uint32_t levels[] = {1, 3};
    ASSERT_TRUE(sim.set_instance_lods(ids, levels).ok());
    ASSERT_TRUE(sim.step(3).ok());
    std::vector<float> joints;
    ASSERT_TRUE(sim.read(Output::joint_matrices, joints).ok());
    const detail::SceneData& d = detail::scene_data_of(sim);
    uint64_t at = 0;  // the instance's first chain in read()'s order
    for (uint64_t i = 0; i < sim.instance_count(); ++i) {
        const uint64_t chains = d.models[sim.instances()[i].model].chain_count;
        const InstancePlacement place = *sim.instance_placement(sim.instance_ids()[i]);
        std::vector<float> raw(chains * 12);
        ASSERT_TRUE(detail::backend_of(sim).read(detail::BufferId::joint_matrix, place.first_chain, chains, raw.data(),
                                                 detail::Scalar::f32).ok());
        EXPECT_TRUE(std::equal(raw.begin(), raw.end(), joints.begin() + std::ptrdiff_t(at * 12))) << "instance " << i;
        at += chains;
    }
}

TEST_P(PlacedLayout, TemplatesStayOnTheDeviceUntilSlotsReachThem) {
    std::string skip;
    Forest placed = forest(GetParam(), InstanceLayout::placed, skip);
    if (!skip.empty()) GTEST_SKIP() << skip;
    Forest packed = forest(GetParam(), InstanceLayout::packed, skip);
    ASSERT_TRUE(placed.sim && packed.sim);
    if (!detail::backend_of(*placed.sim).capabilities().copies_patterns)
        GTEST_SKIP() << "the backend does not copy patterns (HMSM_PATTERN_COPIES=0)";
    auto both = [&](auto&& change) {
        for (Simulation* sim : {placed.sim.get(), packed.sim.get()}) ASSERT_TRUE(change(*sim).ok());
    };
    auto set_level = [&](uint32_t index, uint32_t level) {
        both([&](Simulation& sim) { return sim.set_instance_lod(sim.instance_ids()[index], level); });
    };
    both([](Simulation& sim) { return sim.reserve_instances(48); });  // no growth below
    for (uint32_t i : {1u, 4u, 8u}) set_level(i, 3);  // folds: no template
    both([](Simulation& sim) { return sim.step(6); });
    // The first unfolding switch writes the templates; the next ones copy from them.
    placed.backend->buffer_writes = 0;
    set_level(1, 0);
    EXPECT_EQ(placed.backend->buffer_writes, 1u);
    set_level(4, 1);
    both([](Simulation& sim) { return sim.step(4); });
    set_level(8, 0);
    EXPECT_EQ(placed.backend->buffer_writes, 1u) << "the templates were written again";
    expect_same_outputs(*placed.sim, *packed.sim);
    // Whole trees added past every slot until the slots reach the templates: an unfolding
    // switch then may not copy from what the adds overwrote.
    const detail::SceneData& d = detail::scene_data_of(*placed.sim);
    uint64_t zone = 0;
    for (const detail::ModelRange& m : d.models) zone += m.chain_count;
    const uint64_t capacity = d.chain_capacity;
    for (int k = 0; k < 36 && d.placed_chain_end <= capacity - zone; ++k) {
        const Instance tree{0, {60.0 + 4.0 * k, 0.0, 0.0}, 0.1 * k, 1.0, 0.2};
        both([&](Simulation& sim) { return sim.add_instances({&tree, 1}); });
        both([](Simulation& sim) { return sim.step(1); });
    }
    ASSERT_EQ(d.chain_capacity, capacity) << "the capacity grew";
    ASSERT_GT(d.placed_chain_end, capacity - zone) << "the slots never reached the templates";
    const uint32_t last = uint32_t(placed.sim->instance_count() - 1);
    set_level(last, 3);
    both([](Simulation& sim) { return sim.step(3); });
    set_level(last, 0);
    set_level(4, 0);
    expect_same_outputs(*placed.sim, *packed.sim);
    both([](Simulation& sim) { return sim.step(10); });
    expect_same_outputs(*placed.sim, *packed.sim);
}

std::string backend_name(const ::testing::TestParamInfo<BackendKind>& info) {
    std::string name = to_string(info.param);
    std::replace(name.begin(), name.end(), '-', '_');
    return name;
}

INSTANTIATE_TEST_SUITE_P(Backends, PlacedLayout, ::testing::Values(BackendKind::vulkan, BackendKind::cuda),
                         backend_name);

TEST(PlacedLayout, BackendsThatDoNotListKeepThePackedLayout) {
    std::string skip;
    Forest f = forest(BackendKind::cpu, InstanceLayout::placed, skip);
    ASSERT_TRUE(f.sim);
    const InstanceId first = f.sim->instance_ids()[0];
    ASSERT_TRUE(f.sim->set_instance_lod(first, 2).ok());
    const std::vector<InstancePlacement> now = placements_of(*f.sim), packed = packed_places(*f.sim);
    for (size_t i = 0; i < now.size(); ++i) EXPECT_TRUE(same_place(now[i], packed[i])) << "instance " << i;
}

TEST(PlacedLayout, PlacementOfAnUnknownIdIsRefused) {
    std::string skip;
    Forest f = forest(BackendKind::cpu, InstanceLayout::placed, skip);
    ASSERT_TRUE(f.sim);
    const InstanceId gone = f.sim->instance_ids()[1];
    ASSERT_TRUE(f.sim->swap_remove_instances({&gone, 1}).ok());
    Result<InstancePlacement> removed = f.sim->instance_placement(gone);
    ASSERT_FALSE(removed.ok());
    EXPECT_EQ(removed.status().code(), ErrorCode::invalid_argument);
    EXPECT_NE(removed.status().message().find("instance_placement: instance id 1 was removed"), std::string::npos)
        << removed.status().message();
    Result<InstancePlacement> never = f.sim->instance_placement(InstanceId(999));
    ASSERT_FALSE(never.ok());
    EXPECT_NE(never.status().message().find("999 was never given"), std::string::npos) << never.status().message();
}

TEST(PlacedLayout, UnknownLayoutIsRefused) {
    SimulationConfig config;
    config.backend = BackendKind::cpu;
    config.instance_layout = static_cast<InstanceLayout>(7);
    auto sim = Simulation::create(single_tree_scene(test::small_tree()), config);
    ASSERT_FALSE(sim.ok());
    EXPECT_NE(sim.status().message().find("instance_layout 7"), std::string::npos) << sim.status().message();
    EXPECT_EQ(parse_instance_layout("placed"), InstanceLayout::placed);
    EXPECT_EQ(std::string(to_string(InstanceLayout::packed)), "packed");
}

}  // namespace
}  // namespace hmsm
