// The CUDA kernel bodies run serially on the host (emulate_NAME of kernels/cuda/launchers.h)
// over host images of the device buffers, against the double-precision CPU reference. Needs no
// GPU, so CI checks the kernels' arithmetic and indexing on every machine; the tests in
// cuda_device_test.cpp check the same on the device.
#include "simulation_access.h"
#include "cuda_test_support.h"
#include "test_compositions.h"

#include "device_words.h"
#include "live_wind.h"
#include "cuda/launch_dispatch.h"
#include "step_program.h"
#include "common/octahedral.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdlib>
#include <limits>
#include <string>

namespace hmsm::cuda_test {
namespace {

using detail::BufferId;
using detail::cuda::BufferPointers;

/// Every buffer of the table in host memory, laid out as on the device.
struct HostImage {
    std::array<std::vector<std::byte>, detail::kBufferCount> bytes;
    std::vector<std::byte> next_state;  // BufferPointers::chain_state_next
    BufferPointers pointers;
};

/// Host image of a cpu64 simulation's buffers: static data converted like an upload, state
/// as the reference holds it now (converted to float).
HostImage image_of(const Simulation& reference) {
    HostImage image;
    const detail::SceneData& scene = hmsm::detail::scene_data_of(reference);
    for (const detail::BufferInfo& info : detail::kBufferTable) {
        const uint64_t count = scene.element_count(info.id);
        auto& bytes = image.bytes[uint32_t(info.id)];
        // instance_wind is written by the simulation (live_wind.h), so it is read back like state.
        if (detail::is_static(info.id) && info.id != BufferId::instance_wind) {
            bytes = detail::device_image(scene, info.id);
        } else {
            std::vector<double> values(count * detail::shape_scalars(info.shape));
            EXPECT_TRUE(hmsm::detail::backend_of(reference).read(info.id, 0, count, values.data(), detail::Scalar::f64).ok());
            bytes.resize(count * detail::device_element_bytes(info.id));
            detail::scalars_to_words(info.shape, values.data(), values.size(), bytes.data(),
                                           detail::Scalar::f64);
        }
        bytes.resize(std::max<size_t>(bytes.size(), 16));
    }
#define HMSM_TEST_BIND(name, binding, shape, scope) \
    image.pointers.name = reinterpret_cast<detail::cuda::DeviceType_##shape*>(image.bytes[binding].data());
    HMSM_BUFFERS(HMSM_TEST_BIND)
#undef HMSM_TEST_BIND
    image.next_state.assign(image.bytes[uint32_t(BufferId::chain_state)].size(), std::byte{0});
    image.pointers.chain_state_next = reinterpret_cast<float4*>(image.next_state.data());
    return image;
}

/// xyz of every float4 of an output buffer of the image.
std::vector<double> xyz_of(const HostImage& image, BufferId id) {
    const auto* words = reinterpret_cast<const float*>(image.bytes[uint32_t(id)].data());
    const size_t count = image.bytes[uint32_t(id)].size() / 16;
    std::vector<double> out;
    for (size_t i = 0; i < count; ++i)
        for (int k = 0; k < 3; ++k) out.push_back(words[4 * i + k]);
    return out;
}

void poison(HostImage& image, BufferId id) {
    auto* words = reinterpret_cast<float*>(image.bytes[uint32_t(id)].data());
    const size_t n = image.bytes[uint32_t(id)].size() / 4;
    for (size_t i = 0; i < n; ++i) words[i] = std::numeric_limits<float>::quiet_NaN();
}

class CudaEmulation : public ::testing::TestWithParam<test::TestComposition> {};

/// Runs `steps` steps of `sim`'s step program through the kernel bodies on the host, after the
/// first `done` steps, with the wind clock of each step as Simulation::step computes it (tau =
/// f t, or U t for the atmospheric profile, reduced on the host into wind-table slot 0) and the
/// fades' clock (gpu_layout.h HMSM_FADE_*).
void emulate_steps(const Simulation& sim, HostImage& image, uint32_t steps, uint64_t done = 0) {
    const double dt = sim.config().parameters.dt;
    const Wind& wind = sim.wind();
    const detail::WindModes modes = detail::wind_modes(wind);
    auto* table = reinterpret_cast<float*>(image.bytes[uint32_t(BufferId::wind_table)].data());
    double slot[detail::kWindStepScalars];
    for (uint32_t k = 0; k < steps; ++k) {
        detail::fill_wind_step(wind, modes, (wind_clock_rate(wind) * dt) * double(done + k), slot);
        slot[2] = double((done + k + 1) & HMSM_FADE_END_MASK);
        for (uint32_t i = 0; i < detail::kWindStepScalars; ++i) table[4 * HMSM_WIND_STEPS + i] = float(slot[i]);
        for (const detail::Dispatch& d : hmsm::detail::step_program_of(sim)) detail::cuda::emulate_dispatch(d, image.pointers, 0);
    }
}

/// The step program of `composition` through the kernel bodies, against cpu64, 240 steps.
void expect_kernel_bodies_follow_cpu64(test::TestComposition composition) {
    const Scene scene = forest_scene(11);
    auto reference =
        test::create_simulation(scene, test_config(BackendKind::cpu64, composition.composition, false), composition);
    ASSERT_TRUE(reference.ok()) << reference.status().message();
    Simulation& sim = **reference;
    HostImage image = image_of(sim);
    for (BufferId id : {BufferId::node_world, BufferId::vertex_position, BufferId::vertex_normal})
        poison(image, id);
    // A path-walk step's pose is its joint matrix, which the next step reads: there the R and O
    // halves, which no path-walk kernel reads, are poisoned instead.
    if (composition.composition == Composition::path_walk) {
        poison(image, BufferId::chain_rotation);
        poison(image, BufferId::chain_origin);
    } else {
        poison(image, BufferId::joint_matrix);
    }

    const uint32_t steps = 240;
    emulate_steps(sim, image, steps);
    ASSERT_TRUE(sim.step(steps).ok());

    const double height = scene_height(scene);
    struct Check {
        Output output;
        BufferId buffer;
        double scale;
    };
    for (Check check : {Check{Output::node_positions, BufferId::node_world, height},
                        Check{Output::vertex_positions, BufferId::vertex_position, height},
                        Check{Output::vertex_normals, BufferId::vertex_normal, 1.0}}) {
        std::vector<double> expected;
        ASSERT_TRUE(sim.read(check.output, expected).ok());
        const double error = max_abs_difference(xyz_of(image, check.buffer), expected) / check.scale;
        EXPECT_LE(error, 1e-4) << "output " << int(check.output);
    }
    // Joint matrices: the 12 floats per chain as stored are Output::joint_matrices (rows of
    // [R | O]), written by the root_positions kernel in this composition.
    std::vector<double> joints;
    ASSERT_TRUE(sim.read(Output::joint_matrices, joints).ok());
    const auto& joint_bytes = image.bytes[uint32_t(BufferId::joint_matrix)];
    ASSERT_GE(joint_bytes.size(), joints.size() * sizeof(float));
    const auto* joint_words = reinterpret_cast<const float*>(joint_bytes.data());
    const std::vector<double> emulated(joint_words, joint_words + joints.size());
    EXPECT_LE(max_abs_difference(emulated, joints) / std::max(1.0, height), 1e-4);
    // The wind must have moved the trees, or the comparison above proves little.
    std::vector<double> rest, now;
    auto at_rest =
        test::create_simulation(scene, test_config(BackendKind::cpu64, composition.composition, false), composition);
    ASSERT_TRUE(at_rest.ok());
    ASSERT_TRUE((*at_rest)->read(Output::node_positions, rest).ok());
    ASSERT_TRUE(sim.read(Output::node_positions, now).ok());
    EXPECT_GT(max_abs_difference(rest, now) / height, 1e-3);
}

TEST_P(CudaEmulation, KernelBodiesFollowCpu64OverManySteps) { expect_kernel_bodies_follow_cpu64(GetParam()); }

// A paused instance between active ones of the same group: every kernel of the composition skips
// its elements (the dispatch covers it), so it stays frozen bit for bit while the others follow
// cpu64.
TEST_P(CudaEmulation, PausedInstanceInsideADispatchIsSkipped) {
    Scene scene = forest_scene(11);
    for (Instance& instance : scene.instances) instance.model = 0;  // one group of five
    scene.instances[2].active = false;
    auto reference = test::create_simulation(
        scene, test_config(BackendKind::cpu64, GetParam().composition, false), GetParam());
    ASSERT_TRUE(reference.ok()) << reference.status().message();
    Simulation& sim = **reference;
    ASSERT_TRUE(sim.step(0).ok());  // writes the paused flag
    const std::vector<detail::Dispatch>& program = hmsm::detail::step_program_of(sim);
    ASSERT_TRUE(std::any_of(program.begin(), program.end(),
                            [](const detail::Dispatch& d) { return d.constants.instance_begin == 0 &&
                                                                   d.constants.element_count > 2 * d.constants.model_chain_count; }));
    HostImage image = image_of(sim);
    const HostImage before = image_of(sim);
    const uint32_t steps = 120;
    emulate_steps(sim, image, steps);
    ASSERT_TRUE(sim.step(steps).ok());
    std::vector<double> expected;
    ASSERT_TRUE(sim.read(Output::node_positions, expected).ok());
    EXPECT_LE(max_abs_difference(xyz_of(image, BufferId::node_world), expected) / scene_height(scene), 1e-4);
    const size_t node_bytes = 16 * size_t(sim.node_count() / 5);
    for (BufferId id : {BufferId::node_world, BufferId::chain_state}) {
        const size_t per = id == BufferId::node_world ? node_bytes : 16 * sim.hierarchy(0).chains.size();
        const auto& a = image.bytes[uint32_t(id)];
        const auto& b = before.bytes[uint32_t(id)];
        EXPECT_TRUE(std::equal(a.begin() + 2 * per, a.begin() + 3 * per, b.begin() + 2 * per)) << "paused instance moved";
        EXPECT_FALSE(std::equal(a.begin() + 3 * per, a.begin() + 4 * per, b.begin() + 3 * per)) << "active instance frozen";
    }
}

// A fade to the trunk-only level through the kernel bodies: the integrate kernels scale the
// folded chains' state by the fade's factor each step, as cpu64 does, and leave them exactly at
// rest after the fade's steps while the trunk moves on.
TEST_P(CudaEmulation, FadeRelaxesTheFoldedChainsAsCpu64Does) {
    Scene scene = forest_scene(11);
    scene.lod_budgets.assign(scene.models.size(), {8, 1});
    auto reference = test::create_simulation(
        scene, test_config(BackendKind::cpu64, GetParam().composition, false), GetParam());
    ASSERT_TRUE(reference.ok()) << reference.status().message();
    Simulation& sim = **reference;
    LodBands bands;
    bands.edges = {100.0};
    bands.fade_steps = 24;
    ASSERT_TRUE(sim.set_lod_bands(bands).ok());
    ASSERT_TRUE(sim.step(60).ok());
    const InstanceId first{0};
    const uint32_t trunk_only = 2;
    ASSERT_TRUE(sim.request_instance_lods({&first, 1}, {&trunk_only, 1}).ok());
    ASSERT_EQ(sim.fading_instance_count(), 1u);
    ASSERT_TRUE(sim.step(0).ok());  // writes the fade word
    HostImage image = image_of(sim);
    emulate_steps(sim, image, bands.fade_steps, sim.steps_done());
    ASSERT_TRUE(sim.step(bands.fade_steps).ok());
    std::vector<double> expected;
    ASSERT_TRUE(sim.read(Output::node_positions, expected).ok());
    EXPECT_LE(max_abs_difference(xyz_of(image, BufferId::node_world), expected) / scene_height(scene), 1e-4);
    const auto* state = reinterpret_cast<const float*>(image.bytes[uint32_t(BufferId::chain_state)].data());
    const size_t chains = sim.hierarchy(sim.instances()[0].model).chains.size();
    ASSERT_GT(chains, 1u);
    EXPECT_TRUE(state[0] != 0.0f || state[1] != 0.0f) << "the trunk moves on";
    for (size_t k = 4; k < 4 * chains; ++k) ASSERT_EQ(state[k], 0.0f) << "folded chain " << k / 4 << " not at rest";
}

class CudaEmulationWind : public ::testing::TestWithParam<WindProfile> {};

TEST_P(CudaEmulationWind, ProfileFrontAndForceFieldsFollowCpu64) {
    // The wind_force kernel with the turbulent or atmospheric profile, a front (unused by the
    // atmospheric one), per-instance wind scale and phase, and force fields of both kinds
    // (docs/model.md 3.5, 3.9).
    Scene scene = forest_scene(7);
    scene.instances[1].wind_scale = 0.4;
    scene.instances[2].wind_phase = 0.8;
    SimulationConfig config = test_config(BackendKind::cpu64, Composition::pointer_jumping, false);
    config.wind.profile = GetParam();
    config.wind.turbulence = 0.9;
    config.wind.seed = 99;
    config.wind.front_speed = 3.0;
    auto reference = Simulation::create(scene, config);
    ASSERT_TRUE(reference.ok()) << reference.status().message();
    Simulation& sim = **reference;
    ForceField fields[2];
    fields[0].center = {0, 3, 0};
    fields[0].radius = 20.0;
    fields[0].directional = {0, 0, 6};
    fields[1].kind = ForceField::Kind::radial;
    fields[1].center = {5, 2, 5};
    fields[1].radius = 15.0;
    fields[1].radial = 8.0;
    ASSERT_TRUE(sim.set_force_fields(fields).ok());
    ASSERT_TRUE(sim.step(0).ok());  // uploads the pending wind table
    HostImage image = image_of(sim);
    const uint32_t steps = 200;
    emulate_steps(sim, image, steps);
    ASSERT_TRUE(sim.step(steps).ok());
    std::vector<double> expected, rest;
    ASSERT_TRUE(sim.read(Output::node_positions, expected).ok());
    const double height = scene_height(scene);
    EXPECT_LE(max_abs_difference(xyz_of(image, BufferId::node_world), expected) / height, 1e-4);
    auto at_rest = Simulation::create(scene, config);
    ASSERT_TRUE(at_rest.ok());
    ASSERT_TRUE((*at_rest)->read(Output::node_positions, rest).ok());
    EXPECT_GT(max_abs_difference(rest, expected) / height, 1e-3);
}

TEST(CudaEmulationPacked, ContourWritesThePositionAndTheNormalWordOnly) {
    const Scene scene = forest_scene(15);
    SimulationConfig config = test_config(BackendKind::cpu64, Composition::pointer_jumping, false);
    config.vertex_layout = VertexLayout::packed;
    auto reference = Simulation::create(scene, config);
    ASSERT_TRUE(reference.ok()) << reference.status().message();
    Simulation& sim = **reference;
    ASSERT_EQ(hmsm::detail::scene_data_of(sim).element_count(BufferId::vertex_normal), 0u);
    HostImage image = image_of(sim);
    for (BufferId id : {BufferId::node_world, BufferId::vertex_position, BufferId::vertex_normal})
        poison(image, id);

    const uint32_t steps = 120;
    emulate_steps(sim, image, steps);
    ASSERT_TRUE(sim.step(steps).ok());

    std::vector<double> positions, normals;
    ASSERT_TRUE(sim.read(Output::vertex_positions, positions).ok());
    ASSERT_TRUE(sim.read(Output::vertex_normals, normals).ok());
    EXPECT_LE(max_abs_difference(xyz_of(image, BufferId::vertex_position), positions) / scene_height(scene), 1e-4);
    // Each w is the octahedral word of the vertex normal (src/common/octahedral.h).
    const auto* words = reinterpret_cast<const float*>(image.bytes[uint32_t(BufferId::vertex_position)].data());
    std::vector<double> decoded;
    for (uint64_t v = 0; v < sim.vertex_count(); ++v) {
        const auto n = detail::decode_normal_word<double>(detail::bits_from_float(words[4 * v + 3]));
        decoded.insert(decoded.end(), {n.x, n.y, n.z});
    }
    EXPECT_LE(max_abs_difference(decoded, normals), 1e-3);
    // The placeholder behind the empty vertex_normal buffer is never written.
    for (float w : xyz_of(image, BufferId::vertex_normal)) EXPECT_TRUE(std::isnan(w));
}

/// Wind-table slots 0 and 1 of `image` with the wind clock of steps k and k + 1 (0-based, as
/// emulate_steps).
void write_step_slots(const Simulation& sim, HostImage& image, uint32_t k) {
    const Wind& wind = sim.wind();
    const detail::WindModes modes = detail::wind_modes(wind);
    auto* table = reinterpret_cast<float*>(image.bytes[uint32_t(BufferId::wind_table)].data());
    double slot[detail::kWindStepScalars];
    for (uint32_t s = 0; s < 2; ++s) {
        detail::fill_wind_step(wind, modes, (wind_clock_rate(wind) * sim.config().parameters.dt) * double(k + s), slot);
        for (uint32_t i = 0; i < detail::kWindStepScalars; ++i)
            table[4 * (HMSM_WIND_STEPS + s * HMSM_WIND_STEP_VEC4S) + i] = float(slot[i]);
    }
}

bool same_buffer(const HostImage& a, const HostImage& b, BufferId id) {
    return a.bytes[uint32_t(id)] == b.bytes[uint32_t(id)];
}

// The walk that integrates ahead (gpu_layout.h HMSM_DISPATCH_WALK_AHEAD), as the CUDA backend runs it:
// the first step whole, then each step without its wind_force dispatches, taking the angles the
// step before wrote to chain_state_next. Its joint matrices and angles equal the plain path
// walk's bit for bit, with the turbulent profile (whose value the top poses hoist per instance)
// and force fields, and with the atmospheric one (whose wind vector the walk ahead evaluates
// itself); after a live change (the wind vector) a step must run whole again: one
// that takes the stale angles departs from the plain walk.
class CudaEmulationWalkAhead : public ::testing::TestWithParam<WindProfile> {};

TEST_P(CudaEmulationWalkAhead, EqualsThePathWalkBitForBit) {
    const Scene scene = forest_scene(11);
    SimulationConfig config = test_config(BackendKind::cpu64, Composition::path_walk, false);
    config.wind.profile = GetParam();
    config.wind.turbulence = 0.9;
    auto reference = Simulation::create(scene, config);
    ASSERT_TRUE(reference.ok()) << reference.status().message();
    Simulation& sim = **reference;
    ForceField field;
    field.center = {0, 3, 0};
    field.radius = 20.0;
    field.directional = {0, 0, 6};
    ASSERT_TRUE(sim.set_force_fields({&field, 1}).ok());
    ASSERT_TRUE(sim.step(0).ok());  // uploads the pending wind table
    const detail::SceneData& data = hmsm::detail::scene_data_of(sim);
    using detail::Dispatch;
    const auto plain = detail::build_program(data, data.groups, Composition::path_walk, false, Pass::wind_force, ~0u);
    const auto ahead =
        detail::build_program(data, data.groups, Composition::path_walk, false, Pass::wind_force, ~0u, true);
    ASSERT_EQ(std::count_if(ahead.begin(), ahead.end(), detail::is_walk_ahead), data.groups.size());
    ASSERT_EQ(std::count_if(ahead.begin(), ahead.end(), detail::is_top_poses_walk), data.groups.size());
    // Some model's top poses reach below depth 1 (step_program.h walk_top_depth): walks start
    // from stored poses at more than one depth.
    ASSERT_TRUE(std::any_of(data.models.begin(), data.models.end(),
                            [](const detail::ModelRange& m) { return detail::walk_top_depth(m.level_begin) > 1; }));
    std::vector<Dispatch> without_wind;
    for (const Dispatch& d : ahead)
        if (d.pass != Pass::wind_force) without_wind.push_back(d);

    HostImage walked = image_of(sim), walked_ahead = image_of(sim), stale = image_of(sim);
    auto run = [](const std::vector<Dispatch>& program, HostImage& image) {
        for (const Dispatch& d : program) detail::cuda::emulate_dispatch(d, image.pointers, 0);
    };
    auto take_next_state = [](HostImage& image) {
        std::swap(image.bytes[uint32_t(BufferId::chain_state)], image.next_state);
        image.pointers.chain_state = reinterpret_cast<float4*>(image.bytes[uint32_t(BufferId::chain_state)].data());
        image.pointers.chain_state_next = reinterpret_cast<float4*>(image.next_state.data());
    };
    const uint32_t steps = 60, change = 40;
    for (uint32_t k = 0; k < steps; ++k) {
        if (k == change) {
            for (HostImage* image : {&walked, &walked_ahead, &stale}) {
                auto* vector = reinterpret_cast<float*>(image->bytes[uint32_t(BufferId::wind_table)].data()) +
                               4 * HMSM_WIND_VECTOR;
                vector[0] += 3.0f;
            }
        }
        for (HostImage* image : {&walked, &walked_ahead, &stale}) write_step_slots(sim, *image, k);
        run(plain, walked);
        if (k == 0 || k == change) {
            run(ahead, walked_ahead);
        } else {
            take_next_state(walked_ahead);
            run(without_wind, walked_ahead);
        }
        if (k > 0) take_next_state(stale);
        run(k == 0 ? ahead : without_wind, stale);
        ASSERT_TRUE(same_buffer(walked, walked_ahead, BufferId::joint_matrix)) << "step " << k;
        ASSERT_TRUE(same_buffer(walked, walked_ahead, BufferId::chain_state)) << "step " << k;
        if (k < change) ASSERT_TRUE(same_buffer(walked, stale, BufferId::joint_matrix)) << "step " << k;
    }
    EXPECT_FALSE(same_buffer(walked, stale, BufferId::joint_matrix));
}

INSTANTIATE_TEST_SUITE_P(Compositions, CudaEmulation,
                         ::testing::Values(test::kJumpingPerRound, test::kJumpingInDispatch,
                                           test::TestComposition(Composition::level_by_level),
                                           test::TestComposition(Composition::path_walk)),
                         [](const auto& info) { return test::name_of(info.param); });

std::string profile_name(const ::testing::TestParamInfo<WindProfile>& info) { return to_string(info.param); }

INSTANTIATE_TEST_SUITE_P(Profiles, CudaEmulationWind,
                         ::testing::Values(WindProfile::turbulent, WindProfile::atmospheric), profile_name);
INSTANTIATE_TEST_SUITE_P(Profiles, CudaEmulationWalkAhead,
                         ::testing::Values(WindProfile::turbulent, WindProfile::atmospheric), profile_name);

}  // namespace
}  // namespace hmsm::cuda_test
