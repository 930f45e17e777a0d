// What a level-of-detail switch costs (docs/driving.md, levels of detail): within the capacity
// nothing is read back and only a template of each level that unfolds chains is written; the
// switched instances are built in staging on the device, the others shift in an order that
// overwrites no source before it is read, and the result is bit for bit that of laying out
// every instance anew.
#include "forwarding_backend.h"
#include "instance_moves.h"
#include "simulation_access.h"
#include "test_trees.h"

#ifdef HMSM_HAVE_CUDA
#include "agreement/cuda_emulation_backend.h"
#endif

#include <gtest/gtest.h>

#include <algorithm>
#include <map>
#include <random>
#include <set>

namespace hmsm {
namespace {

using detail::BufferId;
using detail::ElementMove;

// Random layouts: every instance that is not resized finds its elements at its new place after
// the moves run one after another, each as if through a temporary (Backend::move_elements).
TEST(ShiftMoves, SequentialMovesCarryEveryInstanceThatKeepsItsSize) {
    std::mt19937 random(7);
    uint64_t up = 0, down = 0;
    for (int trial = 0; trial < 400; ++trial) {
        const uint32_t count = 1 + random() % 24;
        std::vector<uint64_t> old{0}, now{0};
        std::vector<uint32_t> resized;
        for (uint32_t i = 0; i < count; ++i) {
            const uint64_t size = 1 + random() % 6;
            const bool resize = random() % 3 == 0;
            if (resize) resized.push_back(i);
            old.push_back(old.back() + size);
            now.push_back(now.back() + (resize ? 1 + random() % 9 : size));
        }
        std::vector<int64_t> buffer(std::max(old.back(), now.back()), -1);
        for (uint64_t e = 0; e < old.back(); ++e) buffer[e] = int64_t(e);
        const std::vector<ElementMove> moves = detail::shift_moves(old, now, resized);
        EXPECT_LE(moves.size(), resized.size() + 1);
        for (const ElementMove& m : moves) {
            const std::vector<int64_t> temporary(buffer.begin() + std::ptrdiff_t(m.src),
                                                 buffer.begin() + std::ptrdiff_t(m.src + m.count));
            std::copy(temporary.begin(), temporary.end(), buffer.begin() + std::ptrdiff_t(m.dst));
            (m.dst > m.src ? up : down) += 1;
        }
        for (uint32_t i = 0, k = 0; i < count; ++i) {
            if (k < resized.size() && resized[k] == i) {
                ++k;
                continue;
            }
            for (uint64_t e = 0; e < old[i + 1] - old[i]; ++e)
                ASSERT_EQ(buffer[now[i] + e], int64_t(old[i] + e)) << "trial " << trial << " instance " << i;
        }
    }
    EXPECT_GT(up, 0u);
    EXPECT_GT(down, 0u);
}

/// A backend that logs the reads, writes and moves made while `recording` (single and batched), and
/// optionally refuses to reshape in place (every switch then lays out and uploads the scene anew).
class Watched final : public test::ForwardingBackend {
public:
    struct Range {
        BufferId id;
        uint64_t first, count;
    };
    Watched(std::unique_ptr<detail::Backend> inner, bool in_place)
        : ForwardingBackend(std::move(inner)), in_place_(in_place) {}
    Status read(BufferId id, uint64_t first, uint64_t count, void* dst, detail::Scalar as) const override {
        if (recording) reads.push_back({id, first, count});
        return ForwardingBackend::read(id, first, count, dst, as);
    }
    Status read_ranges(BufferId id, std::span<const detail::ElementRange> ranges, void* dst,
                       detail::Scalar as) const override {
        log_reads(id, ranges);
        return ForwardingBackend::read_ranges(id, ranges, dst, as);
    }
    Status read_buffers(std::span<const detail::BufferRangesRead> buffers, detail::Scalar as) const override {
        for (const detail::BufferRangesRead& r : buffers) log_reads(r.id, r.ranges);
        return ForwardingBackend::read_buffers(buffers, as);
    }
    Status write(BufferId id, uint64_t first, uint64_t count, const void* src, detail::Scalar as) override {
        if (recording) writes.push_back({id, first, count});
        return ForwardingBackend::write(id, first, count, src, as);
    }
    Status write_ranges(BufferId id, std::span<const detail::ElementRange> ranges, const void* src,
                        detail::Scalar as) override {
        log_writes(id, ranges);
        return ForwardingBackend::write_ranges(id, ranges, src, as);
    }
    Status write_buffers(std::span<const detail::BufferRangesWrite> buffers, detail::Scalar as) override {
        for (const detail::BufferRangesWrite& w : buffers) log_writes(w.id, w.ranges);
        return ForwardingBackend::write_buffers(buffers, as);
    }
    Status move_elements(BufferId id, std::span<const ElementMove> moves) override {
        if (!in_place_) return {ErrorCode::internal, "this backend moves nothing"};
        log_moves(id, moves);
        return ForwardingBackend::move_elements(id, moves);
    }
    Status move_buffers(std::span<const detail::BufferMoves> buffers) override {
        if (!in_place_) return {ErrorCode::internal, "this backend moves nothing"};
        for (const detail::BufferMoves& m : buffers) log_moves(m.id, m.moves);
        return ForwardingBackend::move_buffers(buffers);
    }
    detail::BackendCapabilities capabilities() const override {
        detail::BackendCapabilities can = ForwardingBackend::capabilities();
        can.reshapes_in_place = can.reshapes_in_place && in_place_;
        can.grows_on_device = can.grows_on_device && in_place_;
        return can;
    }

    bool recording = false;
    mutable std::vector<Range> reads;
    std::vector<Range> writes;
    std::vector<std::pair<BufferId, ElementMove>> moved;

private:
    void log_reads(BufferId id, std::span<const detail::ElementRange> ranges) const {
        if (recording)
            for (const detail::ElementRange& r : ranges) reads.push_back({id, r.first, r.count});
    }
    void log_writes(BufferId id, std::span<const detail::ElementRange> ranges) {
        if (recording)
            for (const detail::ElementRange& r : ranges) writes.push_back({id, r.first, r.count});
    }
    void log_moves(BufferId id, std::span<const ElementMove> moves) {
        if (recording)
            for (const ElementMove& m : moves) moved.push_back({id, m});
    }
    bool in_place_;
};

constexpr int32_t kBudgets[] = {6, 3, 1};

/// Sixteen instances of two models with four levels each, one of them paused.
Scene mixed_forest() {
    Scene scene = *grid_scene(test::deep_tree(4), 12, 6.0, 3);
    scene.models.push_back(test::small_tree());
    scene.model_names.push_back("small");
    for (int k = 0; k < 4; ++k)
        scene.instances.insert(scene.instances.begin() + 3 * k + 1, Instance{1, {-6.0 * k, 0, 8}, 0.3 * k});
    scene.instances[5].active = false;
    scene.lod_budgets = {{std::begin(kBudgets), std::end(kBudgets)}, {std::begin(kBudgets), std::end(kBudgets)}};
    return scene;
}

/// The backend under test by name: a registered kind (cuda: a real device) or "cuda_emulation"
/// (the CUDA kernels on the host); no_device where it is absent.
Result<std::unique_ptr<detail::Backend>> backend_named(const std::string& name) {
    if (name == "cuda_emulation") {
#ifdef HMSM_HAVE_CUDA
        return test::create_cuda_emulation_backend();
#else
        return Status{ErrorCode::no_device, "cuda emulation: this build of hmsm has no CUDA kernels"};
#endif
    }
    for (BackendKind kind :
         {BackendKind::cpu64, BackendKind::cpu, BackendKind::cpu_parallel, BackendKind::vulkan, BackendKind::cuda})
        if (name == to_string(kind)) return detail::create_backend(kind);
    return Status{ErrorCode::invalid_argument, "no backend " + name};
}

Watched* create_watched(const std::string& name, bool in_place, std::unique_ptr<Simulation>& sim,
                        std::string& skip, Dynamics dynamics = Dynamics::paper) {
    auto backend = backend_named(name);
    if (!backend) {
        skip = backend.status().message();
        return nullptr;
    }
    auto watched = std::make_unique<Watched>(std::move(backend).value(), in_place);
    Watched* handle = watched.get();
    SimulationConfig config = test::windy_config();
    config.model.dynamics = dynamics;
    auto created = detail::SimulationAccess::create(mixed_forest(), config, std::move(watched));
    EXPECT_TRUE(created.ok()) << created.status().message();
    if (!created) return nullptr;
    sim = std::move(created).value();
    return handle;
}

std::vector<double> read_output(const Simulation& sim, Output output) {
    std::vector<double> values;
    const Status read = sim.read(output, values);
    EXPECT_TRUE(read.ok()) << read.message();
    return values;
}

constexpr Output kCompared[] = {Output::chain_angles, Output::chain_rotations, Output::node_positions,
                                Output::vertex_positions};

class LodSwitchCost : public ::testing::TestWithParam<std::string> {};

// Two batched switches, the second growing some instances and shrinking others (moves up and
// down, no upload), against the same switches made one at a time and against the scene laid
// out and uploaded anew: bit for bit right after each switch and steps later.
void expect_many_switches_match(const std::string& backend, Dynamics dynamics) {
    std::unique_ptr<Simulation> moved, single, anew;
    std::string skip;
    Watched* watched = create_watched(backend, true, moved, skip, dynamics);
    if (!skip.empty()) GTEST_SKIP() << skip;
    ASSERT_TRUE(watched && create_watched(backend, true, single, skip, dynamics));
    ASSERT_TRUE(create_watched(backend, false, anew, skip, dynamics));
    const std::vector<Simulation*> others = {single.get(), anew.get()};
    auto step_all = [&](uint32_t steps) {
        for (Simulation* s : {moved.get(), single.get(), anew.get()}) ASSERT_TRUE(s->step(steps).ok());
    };
    auto switch_all = [&](std::span<const InstanceId> ids, std::span<const uint32_t> levels) {
        ASSERT_TRUE(moved->set_instance_lods(ids, levels).ok());
        ASSERT_TRUE(anew->set_instance_lods(ids, levels).ok());
        for (size_t k = 0; k < ids.size(); ++k) ASSERT_TRUE(single->set_instance_lod(ids[k], levels[k]).ok());
    };
    auto expect_same = [&](const char* when) {
        for (Simulation* other : others)
            for (Output o : kCompared)
                EXPECT_EQ(read_output(*moved, o), read_output(*other, o))
                    << when << ", output " << int(o) << (other == anew.get() ? " against the upload" : " against one at a time");
    };
    const InstanceId first_ids[] = {InstanceId(0), InstanceId(2), InstanceId(3), InstanceId(6),
                                    InstanceId(7), InstanceId(9), InstanceId(12), InstanceId(15)};
    const uint32_t first_levels[] = {3, 2, 1, 3, 2, 3, 1, 2};
    // Deep trees have fewer chains on each coarser level: instances 0 and 9 grow, the others
    // shrink, so the runs between shift up, then down.
    const InstanceId mixed_ids[] = {InstanceId(0), InstanceId(2),  InstanceId(5),  InstanceId(8),
                                    InstanceId(9), InstanceId(11), InstanceId(13), InstanceId(15)};
    const uint32_t mixed_levels[] = {0, 3, 3, 3, 0, 3, 3, 0};
    step_all(40);
    switch_all(first_ids, first_levels);
    expect_same("after the first switch");
    step_all(30);
    expect_same("steps after the first switch");
    watched->recording = true;
    switch_all(mixed_ids, mixed_levels);
    watched->recording = false;
    expect_same("after the mixed switch");
    EXPECT_EQ(detail::full_uploads_of(*moved), 0u);
    EXPECT_EQ(detail::full_uploads_of(*single), 0u);
    EXPECT_GT(detail::full_uploads_of(*anew), 0u);
    bool up = false, down = false;
    for (const auto& [id, m] : watched->moved)
        if (id == BufferId::chain_state) (m.dst > m.src ? up : down) = true;
    EXPECT_TRUE(up && down) << "the mixed switch shifts instances both ways";
    step_all(30);
    expect_same("steps after the mixed switch");
}

TEST_P(LodSwitchCost, ManySwitchesInOneCallMatchOneAtATimeAndLayingOutAnew) {
    expect_many_switches_match(GetParam(), Dynamics::paper);
}

// Under coupled a chain's force gathers its children's loads: a level's records name the
// level's children (docs/model.md 3.12), so the state after a switch decides the steps after it
// whichever way the switch was made.
TEST_P(LodSwitchCost, CoupledSwitchesInOneCallMatchOneAtATimeAndLayingOutAnew) {
    expect_many_switches_match(GetParam(), Dynamics::coupled);
}

// A switch reads nothing back. The switched instances are built in staging above the live
// chains, which they leave and return to in whole instances (a run of neighbours as one move);
// the chains a finer level unfolds are copied from a template of that level at rest, the only
// state written: once per level and half, above every live chain. A switch to coarser levels
// writes no state.
TEST_P(LodSwitchCost, ReadsNothingAndWritesOnlyTheTemplatesOfUnfoldingLevels) {
    std::unique_ptr<Simulation> sim;
    std::string skip;
    Watched* watched = create_watched(GetParam(), true, sim, skip);
    if (!skip.empty()) GTEST_SKIP() << skip;
    ASSERT_TRUE(watched);
    ASSERT_TRUE(sim->step(20).ok());
    uint32_t halves = 0;  // of every carried buffer
    for (BufferId id : detail::carried_buffers(false)) halves += detail::halves_of(id);
    auto switch_and_check = [&](std::span<const InstanceId> ids, std::span<const uint32_t> levels, const char* what) {
        std::vector<uint64_t> first_chain{0};
        for (const Instance& inst : sim->instances())
            first_chain.push_back(first_chain.back() + sim->hierarchy(inst.model).chains.size());
        std::vector<uint64_t> old_chains;
        for (InstanceId id : ids) old_chains.push_back(sim->hierarchy(sim->instances()[uint64_t(id)].model).chains.size());
        watched->reads.clear();
        watched->writes.clear();
        watched->moved.clear();
        watched->recording = true;
        ASSERT_TRUE(sim->set_instance_lods(ids, levels).ok()) << what;
        watched->recording = false;
        EXPECT_EQ(detail::full_uploads_of(*sim), 0u) << what;
        EXPECT_TRUE(watched->reads.empty()) << what;
        const uint64_t capacity = detail::scene_data_of(*sim).chain_capacity;  // grown for the staging
        // The templates: one per level that unfolds chains (new levels finer than the old).
        std::set<uint32_t> unfolding;
        uint64_t shared_chains = 0;
        for (size_t k = 0; k < ids.size(); ++k) {
            const uint32_t model = sim->instances()[uint64_t(ids[k])].model;
            const uint64_t now = sim->hierarchy(model).chains.size();
            if (now > old_chains[k]) unfolding.insert(model);
            shared_chains += std::min(now, old_chains[k]);
        }
        uint64_t template_chains = 0;
        for (uint32_t model : unfolding) template_chains += sim->hierarchy(model).chains.size();
        const uint64_t live = std::max<uint64_t>(first_chain.back(), detail::scene_data_of(*sim).total_chains);
        uint64_t written = 0;  // chain state (the wind header and instance table are rewritten too)
        for (const Watched::Range& r : watched->writes) {
            const detail::Scope scope = detail::buffer_info(r.id).scope;
            EXPECT_TRUE(scope != detail::Scope::node && scope != detail::Scope::vertex)
                << what << ": " << detail::buffer_info(r.id).name;
            if (scope != detail::Scope::chain && scope != detail::Scope::chain_halves) continue;
            EXPECT_GE(r.first % capacity, live) << what << ": " << detail::buffer_info(r.id).name;
            written += r.count;
        }
        EXPECT_EQ(written, template_chains * halves) << what;
        // The live chains are read and written in whole instances only: the switched instances'
        // old chains leave for the staging and their new chains come back from it, a run of
        // neighbours as one move, once per half of each carried buffer.
        std::vector<uint64_t> now_first{0};
        for (const Instance& inst : sim->instances())
            now_first.push_back(now_first.back() + sim->hierarchy(inst.model).chains.size());
        auto covers_whole = [&](const std::vector<uint64_t>& first, uint64_t at, uint64_t count) {
            bool starts = false, ends = false;
            uint64_t covered = 0;
            for (InstanceId i : ids) {
                const uint64_t begin = first[uint64_t(i)], end = first[uint64_t(i) + 1];
                starts = starts || begin == at;
                ends = ends || end == at + count;
                if (begin >= at && end <= at + count) covered += end - begin;
            }
            return starts && ends && covered == count;
        };
        uint64_t left = 0, came = 0, old_total = 0, new_total = 0;
        for (InstanceId i : ids) {
            old_total += first_chain[uint64_t(i) + 1] - first_chain[uint64_t(i)];
            new_total += now_first[uint64_t(i) + 1] - now_first[uint64_t(i)];
        }
        for (const auto& [id, m] : watched->moved) {
            if (detail::buffer_info(id).scope == detail::Scope::node) continue;
            const uint64_t src = m.src % capacity, dst = m.dst % capacity;
            bool from_switched = false;
            for (InstanceId i : ids)
                from_switched = from_switched || (src >= first_chain[uint64_t(i)] && src < first_chain[uint64_t(i) + 1]);
            if (src < first_chain.back() && from_switched) {
                EXPECT_TRUE(covers_whole(first_chain, src, m.count)) << what << ": [" << src << ", " << src + m.count << ")";
                left += m.count;
            }
            if (src >= live && dst < now_first.back()) {
                EXPECT_TRUE(covers_whole(now_first, dst, m.count)) << what << ": [" << dst << ", " << dst + m.count << ")";
                came += m.count;
            }
        }
        EXPECT_EQ(left, old_total * halves) << what;
        EXPECT_EQ(came, new_total * halves) << what;
        EXPECT_LT(shared_chains, std::max(old_total, new_total)) << what << ": some chains unfold or fold";
    };
    const InstanceId ids[] = {InstanceId(1), InstanceId(2), InstanceId(9)};
    const uint32_t coarser[] = {2, 3, 1};
    switch_and_check(ids, coarser, "to coarser levels");
    const uint32_t finer[] = {0, 1, 0};
    switch_and_check(ids, finer, "to finer levels");
    EXPECT_FALSE(watched->moved.empty()) << "the instances behind the switched ones shift on the device";
}

// R and O hold the pose in one half; the other is scratch that the next step's rounds write
// before they read it: the shifts move the pose half alone, every other carried buffer whole
// (the results of moving both halves: ManySwitchesInOneCallMatchOneAtATimeAndLayingOutAnew).
TEST_P(LodSwitchCost, ShiftsMoveOnlyThePoseHalfOfRotationsAndOrigins) {
    std::unique_ptr<Simulation> sim;
    std::string skip;
    Watched* watched = create_watched(GetParam(), true, sim, skip);
    if (!skip.empty()) GTEST_SKIP() << skip;
    ASSERT_TRUE(watched);
    ASSERT_TRUE(sim->step(20).ok());
    const detail::SceneData& d = detail::scene_data_of(*sim);
    ASSERT_GE(d.jump_rounds, 2u) << "the scene's rounds use both halves";
    const uint64_t live_before = d.total_chains;
    watched->recording = true;
    const InstanceId ids[] = {InstanceId(1), InstanceId(6)};
    const uint32_t levels[] = {2, 1};
    ASSERT_TRUE(sim->set_instance_lods(ids, levels).ok());
    watched->recording = false;
    const uint64_t capacity = d.chain_capacity;  // grown for the staging
    const uint64_t pose_first = uint64_t(HMSM_FINAL_HALF(d.jump_rounds)) * capacity;
    EXPECT_EQ(detail::full_uploads_of(*sim), 0u);
    // The shifts: moves within the live chains (staging lies above them, and the switched
    // instances go there and back in both halves).
    const uint64_t live = std::max(live_before, d.total_chains);
    std::map<BufferId, std::set<uint64_t>> halves;  // per buffer, the halves its shifts touch
    for (const auto& [id, m] : watched->moved) {
        if (detail::halves_of(id) != 2) continue;
        if (m.src % capacity < live && m.dst % capacity < live) halves[id].insert(m.src / capacity);
        EXPECT_EQ(m.src / capacity, m.dst / capacity) << detail::buffer_info(id).name;
    }
    for (BufferId id : {BufferId::chain_rotation, BufferId::chain_origin}) {
        ASSERT_EQ(halves[id].size(), 1u) << detail::buffer_info(id).name;
        EXPECT_EQ(*halves[id].begin() * capacity, pose_first) << detail::buffer_info(id).name;
    }
    ASSERT_TRUE(sim->step(30).ok());
    std::unique_ptr<Simulation> anew;
    ASSERT_TRUE(create_watched(GetParam(), false, anew, skip));
    ASSERT_TRUE(anew->step(20).ok());
    ASSERT_TRUE(anew->set_instance_lods(ids, levels).ok());
    ASSERT_TRUE(anew->step(30).ok());
    for (Output o : kCompared) EXPECT_EQ(read_output(*sim, o), read_output(*anew, o)) << "output " << int(o);
}

std::string param_name(const ::testing::TestParamInfo<std::string>& info) {
    std::string name = info.param;
    std::replace(name.begin(), name.end(), '-', '_');
    return name;
}

INSTANTIATE_TEST_SUITE_P(Backends, LodSwitchCost,
                         ::testing::Values("cpu64", "cpu", "cpu-parallel", "vulkan", "cuda", "cuda_emulation"), param_name);

}  // namespace
}  // namespace hmsm
