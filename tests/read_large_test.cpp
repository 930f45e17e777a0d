// Simulation::read, take_read and the C API's reads of outputs large enough to be converted in
// chunks on several threads: every output, as float and as double, on every backend (one
// without a device skips), bit for bit what one serial pass over the backend's stored
// elements gives (the backend read directly in the precision it stores).
#include "simulation_access.h"
#include "test_trees.h"

#include <hmsm/hmsm.h>
#include <hmsm/hmsm_c.h>

#include <gtest/gtest.h>

#include <bit>

#include "common/octahedral.h"

using namespace hmsm;
using test::kEveryOutput;
using test::same_bits;

namespace {

/// One serial pass from the stored elements to the output's layout (include/hmsm/simulation.h).
template <class Out, class Stored>
std::vector<Out> serial_output(Output output, const std::vector<Stored>& raw, uint32_t stored, bool packed_normals) {
    const uint64_t count = raw.size() / stored;
    std::vector<Out> out;
    for (uint64_t i = 0; i < count; ++i) {
        const Stored* e = raw.data() + i * stored;
        switch (output) {
            case Output::vertex_normals:
                if (packed_normals) {
                    const auto n = detail::decode_normal_word<Out>(detail::packed_word_from_w<Stored>(e[3]));
                    out.insert(out.end(), {n.x, n.y, n.z});
                    break;
                }
                [[fallthrough]];
            case Output::node_positions:
            case Output::vertex_positions: out.insert(out.end(), {Out(e[0]), Out(e[1]), Out(e[2])}); break;
            case Output::chain_rotations:  // column-major from the rows of [R | O]
                for (int c = 0; c < 3; ++c)
                    for (int r = 0; r < 3; ++r) out.push_back(Out(e[4 * r + c]));
                break;
            case Output::chain_origins: out.insert(out.end(), {Out(e[3]), Out(e[7]), Out(e[11])}); break;
            default:
                for (uint32_t k = 0; k < stored; ++k) out.push_back(Out(e[k]));
        }
    }
    return out;
}

struct Stored {
    detail::BufferId id;
    uint64_t count;
    uint32_t scalars;
    bool packed_normals;
};

Stored stored_of(const Simulation& sim, Output output, VertexLayout layout) {
    const auto& data = detail::SimulationAccess::scene_data(sim);
    using detail::BufferId;
    switch (output) {
        case Output::node_positions: return {BufferId::node_world, data.total_nodes, 4, false};
        case Output::vertex_positions: return {BufferId::vertex_position, data.total_vertices, 4, false};
        case Output::vertex_normals:
            return layout == VertexLayout::packed ? Stored{BufferId::vertex_position, data.total_vertices, 4, true}
                                                  : Stored{BufferId::vertex_normal, data.total_vertices, 4, false};
        case Output::chain_angles: return {BufferId::chain_state, data.total_chains, 4, false};
        default: return {BufferId::joint_matrix, data.total_chains, 12, false};
    }
}

template <class Out>
std::vector<Out> expected(const Simulation& sim, Output output, VertexLayout layout) {
    const Stored s = stored_of(sim, output, layout);
    const detail::Backend& backend = detail::SimulationAccess::backend(sim);
    if (backend.kind() == BackendKind::cpu64) {
        std::vector<double> raw(s.count * s.scalars);
        EXPECT_TRUE(backend.read(s.id, 0, s.count, raw.data(), detail::Scalar::f64).ok());
        return serial_output<Out>(output, raw, s.scalars, s.packed_normals);
    }
    std::vector<float> raw(s.count * s.scalars);
    EXPECT_TRUE(backend.read(s.id, 0, s.count, raw.data(), detail::Scalar::f32).ok());
    return serial_output<Out>(output, raw, s.scalars, s.packed_normals);
}

class ReadLarge : public ::testing::TestWithParam<std::tuple<BackendKind, VertexLayout>> {};

}  // namespace

TEST_P(ReadLarge, ChunkedReadsEqualOneSerialPass) {
    const auto [backend, layout] = GetParam();
    auto tree = generate_preset("paper-1", 0);
    ASSERT_TRUE(tree.ok());
    // Enough trees that the joint matrices alone span several MiB (several chunks).
    auto probe = Simulation::create(single_tree_scene(*tree), SimulationConfig{});
    ASSERT_TRUE(probe.ok()) << probe.status().message();
    const uint64_t chains = (*probe)->chain_count();
    const uint32_t trees = uint32_t((uint64_t(5) << 19) / (48 * chains) + 1);
    auto scene = grid_scene(*tree, trees, 9.0, 3);
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
    ASSERT_TRUE(sim.step(3).ok());
    ASSERT_GT(sim.chain_count() * 48, uint64_t(2) << 20) << "too small to be read in chunks";
    for (Output output : kEveryOutput) {
        SCOPED_TRACE("output " + std::to_string(int(output)));
        const auto want = expected<float>(sim, output, layout);
        const auto want64 = expected<double>(sim, output, layout);
        std::vector<float> got;
        std::vector<double> got64;
        ASSERT_TRUE(sim.read(output, got).ok());
        ASSERT_TRUE(sim.read(output, got64).ok());
        EXPECT_TRUE(same_bits(got, want));
        EXPECT_TRUE(same_bits(got64, want64));
        got.assign(3, 7.0f);  // a vector of another size is resized, not appended to
        ASSERT_TRUE(sim.request_read(output).ok());
        ASSERT_TRUE(sim.take_read(output, got).ok());
        ASSERT_TRUE(sim.take_read(output, got64).ok());
        EXPECT_TRUE(same_bits(got, want));
        EXPECT_TRUE(same_bits(got64, want64));
    }
}

namespace {

std::vector<float> c_read_f32(hmsm_simulation* sim, int32_t output, bool take) {
    size_t count = 0;
    if (take) EXPECT_EQ(hmsm_simulation_request_read(sim, output), HMSM_OK) << hmsm_status_message();
    auto read = [&](float* values, size_t capacity) {
        return take ? hmsm_simulation_take_read_f32(sim, output, values, capacity, &count)
                    : hmsm_simulation_read_f32(sim, output, values, capacity, &count);
    };
    EXPECT_EQ(read(nullptr, 0), HMSM_OK) << hmsm_status_message();
    std::vector<float> values(count);
    EXPECT_EQ(read(values.data(), count), HMSM_OK) << hmsm_status_message();
    return values;
}

}  // namespace

// The C API's reads of a large forest: joint matrices agree with the rotations and origins
// picked out of them, the double reads with the float ones, and take_read with read.
TEST(ReadLargeC, JointMatricesAgreeWithTheirParts) {
    for (int32_t backend : {HMSM_BACKEND_CPU_PARALLEL, HMSM_BACKEND_VULKAN}) {
        SCOPED_TRACE("backend " + std::to_string(backend));
        hmsm_tree* tree = nullptr;
        hmsm_scene* scene = nullptr;
        ASSERT_EQ(hmsm_tree_preset("paper-1", 0, &tree), HMSM_OK);
        ASSERT_EQ(hmsm_scene_create(&scene), HMSM_OK);
        ASSERT_EQ(hmsm_scene_add_model(scene, tree, "paper-1", nullptr), HMSM_OK);
        hmsm_instance instance;
        ASSERT_EQ(HMSM_INIT(hmsm_instance_init, &instance), HMSM_OK);
        for (int i = 0; i < 24; ++i) {
            instance.origin[0] = 9.0 * (i % 12);
            instance.origin[2] = 9.0 * (i / 12);
            instance.yaw = 0.1 * i;
            ASSERT_EQ(hmsm_scene_add_instance(scene, &instance), HMSM_OK);
        }
        hmsm_config config;
        ASSERT_EQ(HMSM_INIT(hmsm_config_init, &config), HMSM_OK);
        config.backend = backend;
        config.wind.strength = 12.0;
        hmsm_simulation* sim = nullptr;
        const hmsm_status created = hmsm_simulation_create(scene, &config, &sim);
        hmsm_scene_destroy(scene);
        hmsm_tree_destroy(tree);
        if (created == HMSM_NO_DEVICE || created == HMSM_UNSUPPORTED) continue;  // no Vulkan device here
        ASSERT_EQ(created, HMSM_OK) << hmsm_status_message();
        ASSERT_EQ(hmsm_simulation_step(sim, 3), HMSM_OK) << hmsm_status_message();
        const auto joints = c_read_f32(sim, HMSM_OUTPUT_JOINT_MATRICES, false);
        const auto rotations = c_read_f32(sim, HMSM_OUTPUT_CHAIN_ROTATIONS, false);
        const auto origins = c_read_f32(sim, HMSM_OUTPUT_CHAIN_ORIGINS, false);
        const uint64_t chains = joints.size() / 12;
        ASSERT_GT(chains * 48, uint64_t(2) << 20) << "too small to be read in chunks";
        ASSERT_EQ(rotations.size(), chains * 9);
        ASSERT_EQ(origins.size(), chains * 3);
        uint64_t differing = 0;
        for (uint64_t i = 0; i < chains; ++i)
            for (int r = 0; r < 3; ++r) {
                differing += std::bit_cast<uint32_t>(origins[3 * i + r]) !=
                             std::bit_cast<uint32_t>(joints[12 * i + 4 * r + 3]);
                for (int c = 0; c < 3; ++c)
                    differing += std::bit_cast<uint32_t>(rotations[9 * i + 3 * c + r]) !=
                                 std::bit_cast<uint32_t>(joints[12 * i + 4 * r + c]);
            }
        EXPECT_EQ(differing, 0u);
        size_t count = 0;
        std::vector<double> joints64(joints.size());
        ASSERT_EQ(hmsm_simulation_read_f64(sim, HMSM_OUTPUT_JOINT_MATRICES, joints64.data(), joints64.size(), &count),
                  HMSM_OK);
        uint64_t widened_differing = 0;
        for (size_t i = 0; i < joints.size(); ++i) widened_differing += joints64[i] != double(joints[i]);
        EXPECT_EQ(widened_differing, 0u);
        EXPECT_TRUE(same_bits(c_read_f32(sim, HMSM_OUTPUT_JOINT_MATRICES, true), joints));
        EXPECT_TRUE(same_bits(c_read_f32(sim, HMSM_OUTPUT_CHAIN_ROTATIONS, true), rotations));
        hmsm_simulation_destroy(sim);
    }
}

INSTANTIATE_TEST_SUITE_P(Backends, ReadLarge,
                         ::testing::Combine(::testing::Values(BackendKind::cpu, BackendKind::cpu64,
                                                              BackendKind::cpu_parallel, BackendKind::vulkan,
                                                              BackendKind::cuda),
                                            ::testing::Values(VertexLayout::separate, VertexLayout::packed)),
                         [](const auto& info) {
                             std::string name = to_string(std::get<0>(info.param));
                             for (char& c : name)
                                 if (c == '-') c = '_';
                             return name + "_" + to_string(std::get<1>(info.param));
                         });
