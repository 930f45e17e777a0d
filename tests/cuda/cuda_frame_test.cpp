// The CUDA frame paths on a device: steps enqueued on an engine stream (hmsm::cuda::
// enqueue_steps) against blocking steps, bit for bit, with live changes uploaded from the
// pinned ring between them; and the one-copy readback (read, request_read / take_read) against
// the chunked path and each other. Every test skips with the reason when there is no device.
#include "simulation_access.h"
#include "cuda_test_support.h"
#include "test_trees.h"

#include <hmsm/cuda.h>

#include <cuda_runtime_api.h>

#include <cstring>

namespace hmsm::cuda_test {
namespace {

using test::kEveryOutput;

std::unique_ptr<Simulation> create_or_fail(const Scene& scene, const SimulationConfig& config) {
    auto sim = Simulation::create(scene, config);
    EXPECT_TRUE(sim.ok()) << sim.status().message();
    return sim.ok() ? std::move(sim).value() : nullptr;
}

/// Every output of both simulations, float and double, equal bit for bit.
void expect_same_outputs(const Simulation& a, const Simulation& b) {
    for (Output o : kEveryOutput) {
        std::vector<float> fa, fb;
        ASSERT_TRUE(a.read(o, fa).ok());
        ASSERT_TRUE(b.read(o, fb).ok());
        ASSERT_EQ(fa.size(), fb.size()) << int(o);
        ASSERT_FALSE(fa.empty()) << int(o);
        EXPECT_EQ(std::memcmp(fa.data(), fb.data(), fa.size() * sizeof(float)), 0) << "output " << int(o);
    }
}

/// Frame k's live change, the same on both simulations: wind strength, a force field that
/// moves, an instance paused and resumed, and every seventh frame one instance streamed out
/// and back in.
Status change_for_frame(Simulation& s, uint32_t k) {
    Wind wind = s.wind();
    wind.strength = 8.0 + double(k % 5);
    HMSM_TRY(s.set_wind(wind));
    ForceField field;
    field.radius = 6.0;
    field.directional = {0.0, 0.0, 4.0};
    field.center = {0.7 * k, 2.0, 0.0};
    HMSM_TRY(s.set_force_fields({&field, 1}));
    HMSM_TRY(s.set_instance_active(1, k % 4 != 3));
    if (k % 7 == 6) {
        const Instance moved = s.instances()[0];
        const uint64_t first = 0;
        HMSM_TRY(s.remove_instances({&first, 1}));
        HMSM_TRY(s.add_instances({&moved, 1}));
    }
    return {};
}

}  // namespace

TEST(CudaFrame, EnqueuedStepsEqualBlockingStepsBitForBit) {
    HMSM_SKIP_WITHOUT_CUDA();
    for (Composition composition : {Composition::path_walk, Composition::pointer_jumping}) {
        SCOPED_TRACE(to_string(composition));
        const Scene scene = forest_scene(21);
        const SimulationConfig config = test_config(BackendKind::cuda, composition, false);
        auto blocking = create_or_fail(scene, config);
        auto enqueued = create_or_fail(scene, config);
        ASSERT_TRUE(blocking && enqueued);
        cudaStream_t stream = nullptr;
        ASSERT_EQ(cudaStreamCreateWithFlags(&stream, cudaStreamNonBlocking), cudaSuccess);
        // 40 frames, never waiting on the host between them: every upload of a live change
        // goes through the ring of pinned slots while earlier steps may still run.
        for (uint32_t k = 0; k < 40; ++k) {
            ASSERT_TRUE(change_for_frame(*blocking, k).ok());
            ASSERT_TRUE(change_for_frame(*enqueued, k).ok());
            ASSERT_TRUE(blocking->step(k % 3 == 0 ? 2 : 1).ok());
            ASSERT_TRUE(cuda::enqueue_steps(*enqueued, stream, k % 3 == 0 ? 2 : 1).ok());
        }
        EXPECT_EQ(enqueued->steps_done(), blocking->steps_done());
        // The outputs are ready for work enqueued on the stream after the steps: a copy there
        // (no host wait before it) sees the last step.
        auto device = cuda::device_outputs(*enqueued);
        ASSERT_TRUE(device.ok());
        std::vector<float> on_stream(device->chain_count * 12);
        ASSERT_EQ(cudaMemcpyAsync(on_stream.data(), device->joint_matrices, on_stream.size() * sizeof(float),
                                  cudaMemcpyDeviceToHost, stream),
                  cudaSuccess);
        ASSERT_EQ(cudaStreamSynchronize(stream), cudaSuccess);
        std::vector<float> joints;
        ASSERT_TRUE(blocking->read(Output::joint_matrices, joints).ok());
        ASSERT_EQ(joints.size(), on_stream.size());
        EXPECT_EQ(std::memcmp(joints.data(), on_stream.data(), joints.size() * sizeof(float)), 0);
        // read() waits for the enqueued work by itself.
        ASSERT_TRUE(cuda::enqueue_steps(*enqueued, stream, 3).ok());
        ASSERT_TRUE(blocking->step(3).ok());
        expect_same_outputs(*blocking, *enqueued);
        ASSERT_TRUE(cuda::set_stream(*enqueued, nullptr).ok());
        EXPECT_EQ(cudaStreamDestroy(stream), cudaSuccess);
    }
}

TEST(CudaFrame, RequestedReadsEqualReadsTakenAtTheRequest) {
    HMSM_SKIP_WITHOUT_CUDA();
    const Scene scene = forest_scene(22);
    auto sim = create_or_fail(scene, test_config(BackendKind::cuda, Composition::path_walk, false));
    ASSERT_TRUE(sim);
    cudaStream_t stream = nullptr;
    ASSERT_EQ(cudaStreamCreateWithFlags(&stream, cudaStreamNonBlocking), cudaSuccess);
    std::vector<float> values;
    EXPECT_EQ(sim->take_read(Output::joint_matrices, values).code(), ErrorCode::invalid_argument);
    for (uint32_t frame = 0; frame < 6; ++frame) {
        ASSERT_TRUE(cuda::enqueue_steps(*sim, stream, 1 + frame).ok());
        // The request is enqueued behind the steps; the blocking read waits for them.
        for (Output o : kEveryOutput) ASSERT_TRUE(sim->request_read(o).ok());
        std::vector<std::vector<float>> expected(std::size(kEveryOutput));
        std::vector<std::vector<double>> expected64(std::size(kEveryOutput));
        for (size_t i = 0; i < std::size(kEveryOutput); ++i) {
            ASSERT_TRUE(sim->read(kEveryOutput[i], expected[i]).ok());
            ASSERT_TRUE(sim->read(kEveryOutput[i], expected64[i]).ok());
        }
        // Later frames run before the take: the values stay those of the request.
        ASSERT_TRUE(cuda::enqueue_steps(*sim, stream, 2).ok());
        if (frame == 3) {  // instances streamed: the request keeps the old instance list
            const uint64_t first = 0;
            ASSERT_TRUE(sim->remove_instances({&first, 1}).ok());
        }
        for (size_t i = 0; i < std::size(kEveryOutput); ++i) {
            std::vector<float> taken;
            std::vector<double> taken64;
            ASSERT_TRUE(sim->take_read(kEveryOutput[i], taken).ok());
            ASSERT_TRUE(sim->take_read(kEveryOutput[i], taken64).ok());
            ASSERT_EQ(taken.size(), expected[i].size());
            EXPECT_EQ(std::memcmp(taken.data(), expected[i].data(), taken.size() * sizeof(float)), 0)
                << "frame " << frame << " output " << int(kEveryOutput[i]);
            EXPECT_EQ(taken64, expected64[i]) << "frame " << frame << " output " << int(kEveryOutput[i]);
        }
    }
    ASSERT_TRUE(cuda::set_stream(*sim, nullptr).ok());
    EXPECT_EQ(cudaStreamDestroy(stream), cudaSuccess);
}

TEST(CudaFrame, OneCopyReadsMatchTheChunkedPathAndGrowTheirSlots) {
    HMSM_SKIP_WITHOUT_CUDA();
    // A forest large enough that vertex_positions passes the 8 MiB chunk of the staging path,
    // then grown by added instances (the pinned slots grow with it).
    auto tree = generate_preset("paper-1");
    ASSERT_TRUE(tree.ok());
    auto scene = grid_scene(*tree, 60, 20.0, 3);
    ASSERT_TRUE(scene.ok());
    SimulationConfig config = test_config(BackendKind::cuda, Composition::path_walk, false);
    auto sim = create_or_fail(*scene, config);
    ASSERT_TRUE(sim);
    ASSERT_TRUE(sim->step(10).ok());
    for (int round = 0; round < 2; ++round) {
        for (Output o : {Output::vertex_positions, Output::joint_matrices, Output::node_positions}) {
            std::vector<float> fast;
            ASSERT_TRUE(sim->read(o, fast).ok());
            // The chunked path: the backend's own read of the stored elements.
            auto& backend = detail::SimulationAccess::backend(*sim);
            const detail::BufferId id = o == Output::vertex_positions ? detail::BufferId::vertex_position
                                        : o == Output::joint_matrices ? detail::BufferId::joint_matrix
                                                                      : detail::BufferId::node_world;
            const uint64_t count = o == Output::vertex_positions ? sim->vertex_count()
                                   : o == Output::joint_matrices ? sim->chain_count()
                                                                 : sim->node_count();
            const uint32_t stored = detail::shape_scalars(detail::buffer_info(id).shape);
            std::vector<float> chunked(count * stored);
            ASSERT_TRUE(backend.read(id, 0, count, chunked.data(), detail::Scalar::f32).ok());
            const uint32_t wanted = output_components(o);
            ASSERT_EQ(fast.size(), count * wanted);
            for (uint64_t e = 0; e < count; ++e)
                for (uint32_t c = 0; c < wanted && wanted == stored; ++c)
                    ASSERT_EQ(fast[e * wanted + c], chunked[e * stored + c]) << int(o) << " " << e;
            if (wanted == 3)
                for (uint64_t e = 0; e < count; ++e)
                    for (uint32_t c = 0; c < 3; ++c) ASSERT_EQ(fast[3 * e + c], chunked[4 * e + c]) << int(o) << " " << e;
        }
        std::vector<Instance> more(40, sim->instances()[0]);
        ASSERT_TRUE(sim->add_instances(more).ok());
        ASSERT_TRUE(sim->step(3).ok());
    }
}

// A coarsening request fades in pass 2 on the device, with no host round trip per step: the
// fades run inside enqueued steps, and enqueue_steps switches the fades that are over before its
// steps, exactly as step() does with the same requests on a plain simulation.
TEST(CudaFrame, EnqueuedStepsFadeAsStepDoes) {
    HMSM_SKIP_WITHOUT_CUDA();
    auto tree = generate_preset("paper-5");
    ASSERT_TRUE(tree.ok()) << tree.status().message();
    Scene scene = *grid_scene(*tree, 5, 12.0, 4);
    scene.lod_budgets = {{16, 1}};
    SimulationConfig config;
    config.backend = BackendKind::cuda;
    config.wind.strength = 6.0;
    auto enqueued = create_or_fail(scene, config);
    auto reference = create_or_fail(scene, config);
    ASSERT_TRUE(enqueued && reference);
    LodBands bands;
    bands.edges = {100.0};
    bands.fade_steps = 4;  // two frames of two steps
    ASSERT_TRUE(enqueued->set_lod_bands(bands).ok());
    ASSERT_TRUE(reference->set_lod_bands(bands).ok());
    cudaStream_t stream = nullptr;
    ASSERT_EQ(cudaStreamCreateWithFlags(&stream, cudaStreamNonBlocking), cudaSuccess);
    for (uint32_t k = 0; k < 6; ++k) {
        if (k == 2) {
            const InstanceId ids[] = {InstanceId(1), InstanceId(4)};
            const uint32_t levels[] = {2, 1};
            for (Simulation* s : {enqueued.get(), reference.get()}) {
                auto requested = s->request_instance_lods(ids, levels);
                ASSERT_TRUE(requested.ok()) << requested.status().message();
                ASSERT_EQ(s->fading_instance_count(), 2u) << "the trees sway: their switches fade";
            }
        }
        ASSERT_TRUE(cuda::enqueue_steps(*enqueued, stream, 2).ok());
        EXPECT_EQ(enqueued->fading_instance_count(), k == 2 || k == 3 ? 2u : 0u) << "frame " << k;
        ASSERT_TRUE(reference->step(2).ok());
    }
    ASSERT_EQ(cudaStreamSynchronize(stream), cudaSuccess);
    EXPECT_EQ(*enqueued->instance_lod(InstanceId(1)), 2u);
    EXPECT_EQ(*enqueued->instance_lod(InstanceId(4)), 1u);
    for (size_t i = 0; i < enqueued->instance_count(); ++i)
        EXPECT_EQ(enqueued->instances()[i].model, reference->instances()[i].model);
    expect_same_outputs(*reference, *enqueued);
    ASSERT_TRUE(cuda::set_stream(*enqueued, nullptr).ok());
    EXPECT_EQ(cudaStreamDestroy(stream), cudaSuccess);
}

}  // namespace hmsm::cuda_test
