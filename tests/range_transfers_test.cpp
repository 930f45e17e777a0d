// Batched range transfers (Backend::read_ranges, write_ranges, move_elements through
// plan_move_batches): on every backend they agree element for element with the same ranges
// read, written or moved one at a time, for ranges that overlap and that are no multiple of a
// workgroup.
#include "element_moves.h"
#include "instance_moves.h"
#include "simulation_access.h"
#include "test_trees.h"

#ifdef HMSM_HAVE_CUDA
#include "agreement/cuda_emulation_backend.h"
#endif

#include <gtest/gtest.h>

#include <algorithm>
#include <cstring>
#include <numeric>
#include <random>

namespace hmsm {
namespace {

using detail::BufferId;
using detail::ElementMove;
using detail::ElementRange;

/// Applies `moves` one after another to `values` (`width` values an element), each through a
/// temporary: the contract of Backend::move_elements.
template <class T>
void move_one_by_one(std::vector<T>& values, std::span<const ElementMove> moves, uint64_t width = 1) {
    for (const ElementMove& m : moves) {
        const std::vector<T> temporary(values.begin() + std::ptrdiff_t(m.src * width),
                                       values.begin() + std::ptrdiff_t((m.src + m.count) * width));
        std::copy(temporary.begin(), temporary.end(), values.begin() + std::ptrdiff_t(m.dst * width));
    }
}

/// Random moves within [0, size): overlapping one another and themselves, some of them chains
/// (a move reading what an earlier one wrote), some empty or in place.
std::vector<ElementMove> random_moves(std::mt19937& random, uint64_t size, uint32_t count, uint64_t longest) {
    std::vector<ElementMove> moves;
    for (uint32_t k = 0; k < count; ++k) {
        const uint64_t n = random() % (std::min(longest, size) + 1);
        ElementMove m{random() % (size - n + 1), random() % (size - n + 1), n};
        if (!moves.empty() && random() % 4 == 0 && moves.back().dst + n <= size) m.src = moves.back().dst;
        if (random() % 10 == 0) m.dst = m.src;
        moves.push_back(m);
    }
    return moves;
}

// Applying each batch of the plan at once (every source gathered, then every destination
// scattered) is applying the moves one after another, whatever the moves and the scratch.
TEST(PlanMoveBatches, BatchesAppliedAtOnceEqualTheMovesOneAfterAnother) {
    std::mt19937 random(11);
    size_t batches = 0, moves_seen = 0;
    for (int trial = 0; trial < 500; ++trial) {
        const uint64_t size = 1 + random() % 200;
        const std::vector<ElementMove> moves = random_moves(random, size, 1 + random() % 12, 1 + random() % 60);
        const uint64_t scratch = 1 + random() % 80;
        std::vector<int64_t> expected(size);
        for (uint64_t e = 0; e < size; ++e) expected[e] = int64_t(e);
        std::vector<int64_t> batched = expected;
        move_one_by_one(expected, std::span<const ElementMove>(moves));
        const detail::MoveBatches plan = detail::plan_move_batches(moves, scratch);
        EXPECT_LE(plan.largest, scratch);
        size_t begin = 0;
        for (size_t end : plan.ends) {
            std::vector<int64_t> packed;
            for (size_t k = begin; k < end; ++k) {
                const ElementMove& m = plan.pieces[k];
                packed.insert(packed.end(), batched.begin() + std::ptrdiff_t(m.src),
                              batched.begin() + std::ptrdiff_t(m.src + m.count));
            }
            size_t at = 0;
            for (size_t k = begin; k < end; ++k) {
                const ElementMove& m = plan.pieces[k];
                std::copy_n(packed.begin() + std::ptrdiff_t(at), m.count, batched.begin() + std::ptrdiff_t(m.dst));
                at += m.count;
            }
            begin = end;
        }
        ASSERT_EQ(batched, expected) << "trial " << trial;
        batches += plan.ends.size();
        moves_seen += moves.size();
    }
    EXPECT_LT(batches, moves_seen) << "batches hold several moves";
}

// The shifts of a level-of-detail switch go through scratch as one batch.
TEST(PlanMoveBatches, ShiftMovesMakeOneBatch) {
    std::mt19937 random(5);
    for (int trial = 0; trial < 200; ++trial) {
        const uint32_t count = 2 + random() % 40;
        std::vector<uint64_t> old{0}, now{0};
        std::vector<uint32_t> resized;
        for (uint32_t i = 0; i < count; ++i) {
            const uint64_t size = 1 + random() % 6;
            const bool resize = random() % 3 == 0;
            if (resize) resized.push_back(i);
            old.push_back(old.back() + size);
            now.push_back(now.back() + (resize ? 1 + random() % 9 : size));
        }
        const std::vector<ElementMove> moves = detail::shift_moves(old, now, resized);
        const detail::MoveBatches plan = detail::plan_move_batches(moves, 1u << 20);
        EXPECT_LE(plan.ends.size(), 1u) << "trial " << trial;
    }
}

// The intervals a batch has written, held as sorted runs with a map past them, answer every
// overlap query as a search of all of them would: intervals added ascending, descending, in
// interleaved sequences (more than the runs held) and at random.
// Buffers moving the same elements share one plan (planning is most of a switch's host time),
// sized for the largest element among them; other lists get their own.
TEST(PlanMoveBatches, BuffersWithTheSameMovesShareOnePlan) {
    const std::vector<detail::ElementMove> a = {{0, 100, 10}, {50, 200, 5}}, a_copy = a, b = {{0, 300, 10}};
    const detail::BufferMoves moves[] = {{detail::BufferId::chain_state, a},
                                         {detail::BufferId::joint_matrix, a_copy},
                                         {detail::BufferId::chain_force, b}};
    std::vector<detail::MoveBatches> held;
    auto bytes = [](detail::BufferId id) { return id == detail::BufferId::joint_matrix ? 48u : 16u; };
    const std::vector<const detail::MoveBatches*> plans = detail::plan_buffer_moves(moves, bytes, held);
    ASSERT_EQ(plans.size(), 3u);
    EXPECT_EQ(plans[0], plans[1]) << "equal move lists, one plan";
    EXPECT_NE(plans[0], plans[2]);
    EXPECT_EQ(held.size(), 2u);
    const detail::MoveBatches alone = detail::plan_move_batches(a, detail::kMoveScratchBytes / 48);
    EXPECT_EQ(plans[0]->ends, alone.ends);
    EXPECT_EQ(plans[0]->pieces.size(), alone.pieces.size());
}

// moves_independent answers as a comparison of every pair of moves does: random moves, apart
// or overlapping, with in-place and empty ones, and a swap removal's moves in both halves of a
// ping-pong buffer (independent, though not every destination lies below every source).
TEST(MovesIndependent, AnswersAsAComparisonOfEveryPair) {
    auto brute_force = [](std::span<const ElementMove> moves) {
        auto overlap = [](uint64_t a, uint64_t n, uint64_t b, uint64_t m) { return a < b + m && b < a + n; };
        for (size_t i = 0; i < moves.size(); ++i) {
            const ElementMove& a = moves[i];
            if (a.src == a.dst || a.count == 0) continue;
            for (size_t j = 0; j < moves.size(); ++j) {
                const ElementMove& b = moves[j];
                if (b.src == b.dst || b.count == 0) continue;
                if (overlap(a.dst, a.count, b.src, b.count)) return false;
                if (i != j && overlap(a.dst, a.count, b.dst, b.count)) return false;
            }
        }
        return true;
    };
    std::mt19937 random(5);
    int independent = 0;
    for (int trial = 0; trial < 2000; ++trial) {
        const uint64_t size = 20 + random() % 400;
        const std::vector<ElementMove> moves = random_moves(random, size, 1 + random() % 6, 1 + random() % 12);
        const bool expected = brute_force(moves);
        independent += expected;
        ASSERT_EQ(detail::moves_independent(moves), expected) << "trial " << trial;
    }
    EXPECT_GT(independent, 100) << "the trials hardly ever meet independent moves";
    // Holes 0, 2, ..., 128 of 200 filled from the back, in each half of 256 elements.
    std::vector<ElementMove> swap_fill;
    for (uint64_t half = 0; half < 2; ++half)
        for (uint64_t k = 0; k < 65; ++k) swap_fill.push_back({half * 256 + 199 - k, half * 256 + 2 * k, 1});
    EXPECT_TRUE(detail::moves_independent(swap_fill));
    EXPECT_FALSE(detail::destinations_apart_from_sources(swap_fill));
    swap_fill.push_back({300, 130, 3});  // writes [130, 133), which another move reads
    EXPECT_FALSE(detail::moves_independent(swap_fill));
}

TEST(DisjointIntervals, AnswersAsASearchOfEveryInterval) {
    std::mt19937 random(3);
    for (int trial = 0; trial < 300; ++trial) {
        const int pattern = trial % 4;
        // Disjoint slots of 8 elements, each holding at most one interval, visited in the
        // pattern's order: ascending, descending, 12 interleaved ascending sequences, random.
        const uint64_t slots = 4 + random() % 120;
        std::vector<uint64_t> order(slots);
        std::iota(order.begin(), order.end(), 0);
        if (pattern == 1) std::reverse(order.begin(), order.end());
        if (pattern == 2)
            std::stable_sort(order.begin(), order.end(), [](uint64_t a, uint64_t b) { return a % 12 < b % 12; });
        if (pattern == 3) std::shuffle(order.begin(), order.end(), random);
        detail::DisjointIntervals intervals;
        std::vector<std::pair<uint64_t, uint64_t>> held;
        for (uint64_t slot : order) {
            const uint64_t first = 8 * slot + random() % 4, end = first + 1 + random() % 4;
            intervals.add(first, end);
            held.push_back({first, end});
            for (int query = 0; query < 4; ++query) {
                const uint64_t a = random() % (8 * slots + 8), b = a + 1 + random() % 20;
                const bool expected = std::any_of(held.begin(), held.end(), [&](const auto& i) {
                    return i.first < b && a < i.second;
                });
                ASSERT_EQ(intervals.overlaps(a, b), expected)
                    << "trial " << trial << " pattern " << pattern << " [" << a << ", " << b << ")";
            }
        }
        intervals.clear();
        EXPECT_FALSE(intervals.overlaps(held.front().first, held.front().second));
    }
}

/// The backend under test by name: a registered kind, "vulkan_regions" (Vulkan with
/// HMSM_VULKAN_SHADER_RANGES=0) or "cuda_emulation" (the CUDA backend's range copies on the
/// host); no_device where it is absent.
Result<std::unique_ptr<detail::Backend>> backend_named(const std::string& name) {
    if (name == "cuda_emulation") {
#ifdef HMSM_HAVE_CUDA
        return test::create_cuda_emulation_backend();
#else
        return Status{ErrorCode::no_device, "cuda emulation: this build of hmsm has no CUDA kernels"};
#endif
    }
    if (name == "vulkan_regions") {  // reads and writes of many ranges as copy regions (vulkan_backend.h)
        const char* was = std::getenv("HMSM_VULKAN_SHADER_RANGES");
        const std::string before = was ? was : "";
        ::setenv("HMSM_VULKAN_SHADER_RANGES", "0", 1);
        auto backend = detail::create_backend(BackendKind::vulkan);
        if (was) ::setenv("HMSM_VULKAN_SHADER_RANGES", before.c_str(), 1);
        else ::unsetenv("HMSM_VULKAN_SHADER_RANGES");
        return backend;
    }
    for (BackendKind kind :
         {BackendKind::cpu64, BackendKind::cpu, BackendKind::cpu_parallel, BackendKind::vulkan, BackendKind::cuda})
        if (name == to_string(kind)) return detail::create_backend(kind);
    return Status{ErrorCode::invalid_argument, "no backend " + name};
}

class RangeTransfers : public ::testing::TestWithParam<std::string> {
protected:
    /// A stepped forest (states far from zero) on the backend under test.
    void SetUp() override {
        auto backend = backend_named(GetParam());
        if (!backend) GTEST_SKIP() << backend.status().message();
        Result<Scene> scene = grid_scene(test::deep_tree(4), 24, 6.0, 3);
        ASSERT_TRUE(scene.ok()) << scene.status().message();
        auto created = detail::SimulationAccess::create(*scene, test::windy_config(), std::move(backend).value());
        ASSERT_TRUE(created.ok()) << created.status().message();
        sim_ = std::move(created).value();
        ASSERT_TRUE(sim_->step(12).ok());
        scalar_ = detail::backend_of(*sim_).kind() == BackendKind::cpu64 ? detail::Scalar::f64 : detail::Scalar::f32;
    }
    detail::Backend& backend() { return detail::backend_of(*sim_); }
    uint64_t size(BufferId id) const { return detail::scene_data_of(*sim_).element_count(id); }
    uint64_t width(BufferId id) const { return detail::shape_scalars(detail::buffer_info(id).shape); }
    /// The whole buffer, as the backend stores it.
    template <class V>
    std::vector<V> whole(BufferId id) {
        std::vector<V> values(size(id) * width(id));
        EXPECT_TRUE(backend().read(id, 0, size(id), values.data(), scalar_).ok());
        return values;
    }
    /// Random ranges within buffer `id`, some longer than a workgroup, some empty; `apart`:
    /// none overlapping another. Every other call makes more than a hundred short ones (a
    /// device backend may then copy them through a shader).
    std::vector<ElementRange> random_ranges(std::mt19937& random, BufferId id, bool apart) {
        std::vector<ElementRange> ranges;
        const uint64_t n = size(id);
        uint64_t at = 0;
        const bool many = ++calls_ % 2 == 0;
        for (int k = 0; k < (many ? 150 : 40); ++k) {
            const uint64_t longest = std::min<uint64_t>(n, many ? 3 : 300);
            const uint64_t count = random() % 5 == 0 ? 0 : random() % longest;
            if (apart) {
                at += random() % (many ? 2 : 7);
                if (at + count > n) break;
                ranges.push_back({at, count});
                at += count;
            } else {
                ranges.push_back({random() % (n - count + 1), count});
            }
        }
        if (apart) std::shuffle(ranges.begin(), ranges.end(), random);
        if (many) EXPECT_GE(ranges.size(), 64u) << "too few ranges for a shader's copy in " << n << " elements";
        return ranges;
    }
    template <class V>
    void expect_reads_agree(BufferId id);
    template <class V>
    void expect_writes_agree(BufferId id, bool apart);
    template <class V>
    void expect_moves_agree(BufferId id);

    std::unique_ptr<Simulation> sim_;
    detail::Scalar scalar_ = detail::Scalar::f32;
    uint32_t calls_ = 0;
};

template <class V>
void RangeTransfers::expect_reads_agree(BufferId id) {
    std::mt19937 random(uint32_t(id) + 3);
    for (int trial = 0; trial < 4; ++trial) {
        const std::vector<ElementRange> ranges = random_ranges(random, id, false);
        std::vector<V> expected, batched;
        for (const ElementRange& r : ranges) {
            std::vector<V> one(r.count * width(id));
            ASSERT_TRUE(backend().read(id, r.first, r.count, one.data(), scalar_).ok());
            expected.insert(expected.end(), one.begin(), one.end());
        }
        batched.assign(expected.size(), V(-7));
        ASSERT_TRUE(backend().read_ranges(id, ranges, batched.data(), scalar_).ok());
        ASSERT_EQ(batched, expected) << detail::buffer_info(id).name << " trial " << trial;
    }
}

template <class V>
void RangeTransfers::expect_writes_agree(BufferId id, bool apart) {
    std::mt19937 random(uint32_t(id) + 17);
    for (int trial = 0; trial < 4; ++trial) {
        const std::vector<ElementRange> ranges = random_ranges(random, id, apart);
        const std::vector<V> before = whole<V>(id);
        std::vector<V> values;
        for (const ElementRange& r : ranges)
            for (uint64_t s = 0; s < r.count * width(id); ++s) values.push_back(V(int(random() % 20001) - 10000) / V(64));
        // One range at a time (a later range's values stay where ranges overlap), then from the
        // same start all at once.
        const V* at = values.data();
        for (const ElementRange& r : ranges) {
            ASSERT_TRUE(backend().write(id, r.first, r.count, at, scalar_).ok());
            at += r.count * width(id);
        }
        const std::vector<V> expected = whole<V>(id);
        ASSERT_NE(expected, before);
        ASSERT_TRUE(backend().write(id, 0, size(id), before.data(), scalar_).ok());
        ASSERT_EQ(whole<V>(id), before);
        ASSERT_TRUE(backend().write_ranges(id, ranges, values.data(), scalar_).ok());
        ASSERT_EQ(whole<V>(id), expected) << detail::buffer_info(id).name << " trial " << trial;
    }
}

template <class V>
void RangeTransfers::expect_moves_agree(BufferId id) {
    std::mt19937 random(uint32_t(id) + 29);
    for (int trial = 0; trial < 4; ++trial) {
        const std::vector<ElementMove> moves = random_moves(random, size(id), 30, 300);
        std::vector<V> expected = whole<V>(id);
        move_one_by_one(expected, std::span<const ElementMove>(moves), width(id));
        ASSERT_TRUE(backend().move_elements(id, moves).ok());
        ASSERT_EQ(whole<V>(id), expected) << detail::buffer_info(id).name << " trial " << trial;
    }
}

template <class F>
void for_scalar(detail::Scalar scalar, F&& f) {
    if (scalar == detail::Scalar::f64) f(0.0);
    else f(0.0f);
}

TEST_P(RangeTransfers, ReadRangesAgreeWithOneRangeReads) {
    for_scalar(scalar_, [&](auto zero) {
        for (BufferId id : {BufferId::chain_state, BufferId::chain_local, BufferId::chain_force, BufferId::chain_origin,
                            BufferId::chain_parent})
            expect_reads_agree<decltype(zero)>(id);
    });
}

TEST_P(RangeTransfers, WriteRangesAgreeWithOneRangeWrites) {
    for_scalar(scalar_, [&](auto zero) {
        for (BufferId id : {BufferId::chain_state, BufferId::chain_local, BufferId::chain_force})
            for (bool apart : {true, false}) expect_writes_agree<decltype(zero)>(id, apart);
    });
}

TEST_P(RangeTransfers, MovesAgreeWithMovesOneAfterAnother) {
    for_scalar(scalar_, [&](auto zero) {
        for (BufferId id : {BufferId::chain_state, BufferId::chain_local, BufferId::vertex_position})
            expect_moves_agree<decltype(zero)>(id);
    });
}

// read_buffers, write_buffers and move_buffers over several buffers (halves and shapes mixed)
// agree with the calls buffer by buffer.
TEST_P(RangeTransfers, CallsOverSeveralBuffersAgreeWithCallsBufferByBuffer) {
    for_scalar(scalar_, [&](auto zero) {
        using V = decltype(zero);
        std::mt19937 random(41);
        const BufferId ids[] = {BufferId::chain_state, BufferId::chain_local, BufferId::chain_origin};
        std::vector<std::vector<ElementRange>> ranges;
        std::vector<std::vector<V>> expected, batched;
        std::vector<detail::BufferRangesRead> reads;
        for (BufferId id : ids) {
            ranges.push_back(random_ranges(random, id, true));
            uint64_t elements = 0;
            for (const ElementRange& r : ranges.back()) elements += r.count;
            expected.emplace_back(elements * width(id));
            ASSERT_TRUE(backend().read_ranges(id, ranges.back(), expected.back().data(), scalar_).ok());
            batched.emplace_back(elements * width(id), V(-7));
        }
        for (size_t k = 0; k < std::size(ids); ++k) reads.push_back({ids[k], ranges[k], batched[k].data()});
        ASSERT_TRUE(backend().read_buffers(reads, scalar_).ok());
        EXPECT_EQ(batched, expected);

        // Written back shifted by one buffer's values: each buffer's ranges take new values.
        std::vector<std::vector<V>> before, values;
        std::vector<detail::BufferRangesWrite> writes;
        for (size_t k = 0; k < std::size(ids); ++k) {
            before.push_back(whole<V>(ids[k]));
            values.push_back(expected[k]);
            for (V& v : values.back()) v = v * V(0.5) + V(1);
            writes.push_back({ids[k], ranges[k], values.back().data()});
        }
        ASSERT_TRUE(backend().write_buffers(writes, scalar_).ok());
        std::vector<std::vector<V>> written;
        for (size_t k = 0; k < std::size(ids); ++k) {
            written.push_back(whole<V>(ids[k]));
            ASSERT_TRUE(backend().write(ids[k], 0, size(ids[k]), before[k].data(), scalar_).ok());
            ASSERT_TRUE(backend().write_ranges(ids[k], ranges[k], values[k].data(), scalar_).ok());
            EXPECT_EQ(written.back(), whole<V>(ids[k])) << detail::buffer_info(ids[k]).name;
        }

        std::vector<std::vector<ElementMove>> moves;
        std::vector<detail::BufferMoves> all_moves;
        std::vector<std::vector<V>> moved;
        for (BufferId id : ids) moves.push_back(random_moves(random, size(id), 20, 200));
        for (size_t k = 0; k < std::size(ids); ++k) {
            moved.push_back(whole<V>(ids[k]));
            move_one_by_one(moved.back(), std::span<const ElementMove>(moves[k]), width(ids[k]));
            all_moves.push_back({ids[k], moves[k]});
        }
        ASSERT_TRUE(backend().move_buffers(all_moves).ok());
        for (size_t k = 0; k < std::size(ids); ++k)
            EXPECT_EQ(whole<V>(ids[k]), moved[k]) << detail::buffer_info(ids[k]).name;
    });
}

// copy_patterns (a level switch's kept chains in the placed layout) agrees with its copies
// expanded into moves and applied one by one, in every carried buffer and both halves of the
// ping-pong ones, for patterns of moves of odd lengths; a copy past a buffer's end and a pattern
// that does not exist are refused.
TEST_P(RangeTransfers, PatternCopiesAgreeWithTheirMovesOneByOne) {
    for_scalar(scalar_, [&](auto zero) {
        using V = decltype(zero);
        std::mt19937 random(53);
        const uint64_t capacity = detail::scene_data_of(*sim_).chain_capacity;
        constexpr uint64_t kSlot = 20;  // every pattern reaches less than a slot from src and from dst
        ASSERT_GE(capacity, 4 * kSlot);
        // Three patterns: moves into disjoint pieces of a slot, from anywhere in a slot.
        std::vector<std::vector<ElementMove>> pattern_moves(3);
        for (std::vector<ElementMove>& moves : pattern_moves) {
            for (uint64_t at = random() % 3; at < kSlot;) {
                const uint64_t count = 1 + random() % 7, end = std::min(kSlot, at + count);
                moves.push_back({random() % (kSlot - (end - at) + 1), at, end - at});
                at = end + random() % 3;
            }
        }
        std::vector<detail::MovePattern> patterns;
        for (const std::vector<ElementMove>& moves : pattern_moves) patterns.push_back({moves});
        // Sources below capacity / 2, destinations in slots above it.
        std::vector<detail::PatternCopy> copies;
        const uint64_t sources = capacity / 2 - kSlot;
        for (uint64_t dst = capacity / 2; dst + kSlot <= capacity; dst += kSlot)
            copies.push_back({random() % (sources + 1), dst, uint32_t(random() % patterns.size())});
        const std::vector<BufferId> ids = detail::carried_buffers(false);
        std::vector<std::vector<V>> expected;
        for (BufferId id : ids) {
            expected.push_back(whole<V>(id));
            for (uint64_t h = 0; h < detail::halves_of(id); ++h)
                for (const detail::PatternCopy& c : copies)
                    for (const ElementMove& m : pattern_moves[c.pattern])
                        std::copy_n(expected.back().begin() + std::ptrdiff_t((h * capacity + c.src + m.src) * width(id)),
                                    m.count * width(id),
                                    expected.back().begin() + std::ptrdiff_t((h * capacity + c.dst + m.dst) * width(id)));
        }
        ASSERT_TRUE(backend().copy_patterns(ids, capacity, patterns, copies).ok());
        for (size_t b = 0; b < ids.size(); ++b)
            EXPECT_EQ(whole<V>(ids[b]), expected[b]) << detail::buffer_info(ids[b]).name;

        const detail::PatternCopy past_the_end{0, capacity - 1, 0}, no_pattern{0, capacity / 2, 3};
        const Status past = backend().copy_patterns(ids, capacity, patterns, {&past_the_end, 1});
        EXPECT_FALSE(past.ok());
        EXPECT_NE(past.message().find("chain_state"), std::string::npos) << past.message();
        const Status missing = backend().copy_patterns(ids, capacity, patterns, {&no_pattern, 1});
        EXPECT_EQ(missing.code(), ErrorCode::internal);
        EXPECT_NE(missing.message().find("pattern 3 of 3"), std::string::npos) << missing.message();
    });
}

std::string param_name(const ::testing::TestParamInfo<std::string>& info) {
    std::string name = info.param;
    std::replace(name.begin(), name.end(), '-', '_');
    return name;
}

INSTANTIATE_TEST_SUITE_P(Backends, RangeTransfers,
                         ::testing::Values("cpu64", "cpu", "cpu-parallel", "vulkan", "vulkan_regions", "cuda",
                                           "cuda_emulation"),
                         param_name);

}  // namespace
}  // namespace hmsm
