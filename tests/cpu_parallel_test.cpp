// cpu-parallel: the float passes of `cpu` split over a thread pool must give bitwise the
// serial results (same float math per element), in every composition and vertex layout, with
// dispatches really split (a chunk of one element) and with the default chunking on a forest
// big enough to split. Also the step plan's waits, the pool's contract, the thread-count settings and
// `automatic`'s choice. Agreement with cpu64 and run-to-run determinism are in
// agreement_test.cpp and determinism_test.cpp.
#include "simulation_access.h"
#include "test_compositions.h"
#include "test_trees.h"

#include "backend.h"
#include "cpu/step_plan.h"
#include "cpu/thread_pool.h"
#include "pass_table.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <map>
#include <mutex>
#include <tuple>
#include <string>
#include <thread>
#include <vector>

using namespace hmsm;

namespace {

constexpr Output kOutputs[] = {Output::node_positions, Output::vertex_positions, Output::vertex_normals,
                               Output::chain_rotations, Output::chain_origins, Output::chain_angles};

/// A forest of two models (one deep) in several groups, with yaws and a travelling front.
Scene mixed_forest(uint32_t copies) {
    Scene scene;
    scene.models = {test::small_tree(), test::deep_tree(5)};
    scene.model_names = {"small", "deep"};
    for (uint32_t k = 0; k < copies; ++k) {
        const double x = 8.0 * k;
        scene.instances.push_back({0, {x, 0, 0}, 0.3 * k});
        scene.instances.push_back({1, {x, 0, 9}, 1.1 - 0.2 * k});
    }
    return scene;
}

SimulationConfig windy(Composition composition, VertexLayout layout) {
    SimulationConfig config;
    config.profile_passes = false;
    config.composition = composition;
    config.vertex_layout = layout;
    config.wind.profile = WindProfile::y4;
    config.wind.strength = 12.0;
    config.wind.direction = {1.0, 0.2, 0.6};
    config.wind.frequency = 0.7;
    config.wind.front_speed = 6.0;
    return config;
}

std::unique_ptr<Simulation> create_parallel(const Scene& scene, const SimulationConfig& config,
                                            uint32_t threads, uint32_t min_chunk,
                                            detail::JumpingForm jumping_form = detail::JumpingForm::by_size) {
    auto backend = detail::create_cpu_parallel_backend(threads, min_chunk);
    EXPECT_TRUE(backend.ok()) << backend.status().message();
    if (!backend) return nullptr;
    auto sim = detail::SimulationAccess::create(scene, config, std::move(backend).value(), jumping_form);
    EXPECT_TRUE(sim.ok()) << sim.status().message();
    return sim ? std::move(sim).value() : nullptr;
}

/// Steps both simulations in the same pieces and expects every output bit for bit equal.
void expect_bitwise_equal_runs(Simulation& serial, Simulation& parallel, uint32_t steps) {
    for (uint32_t chunk : {1u, steps - 1}) {
        ASSERT_TRUE(serial.step(chunk).ok());
        ASSERT_TRUE(parallel.step(chunk).ok());
    }
    for (Output o : kOutputs) {
        std::vector<float> a, b;
        ASSERT_TRUE(serial.read(o, a).ok());
        ASSERT_TRUE(parallel.read(o, b).ok());
        ASSERT_EQ(a.size(), b.size());
        ASSERT_FALSE(a.empty());
        EXPECT_EQ(std::memcmp(a.data(), b.data(), a.size() * sizeof(float)), 0) << "output " << int(o);
    }
    // The scene really moved, so equality is not that of two rest poses.
    std::vector<double> angles;
    ASSERT_TRUE(parallel.read(Output::chain_angles, angles).ok());
    double largest = 0.0;
    for (double a : angles) largest = std::max(largest, std::abs(a));
    EXPECT_GT(largest, 1e-3);
}

uint32_t process_threads() {
    std::ifstream in("/proc/self/status");
    std::string line;
    while (std::getline(in, line))
        if (line.rfind("Threads:", 0) == 0) return uint32_t(std::stoul(line.substr(8)));
    return 0;
}

/// The process's thread count once it equals `expected`, or after a second: a joined thread can
/// stay listed in /proc for a moment after pthread_join returns (the kernel clears the thread id
/// the join waits on before it removes the task from the thread group).
uint32_t process_threads_settled(uint32_t expected) {
    uint32_t n = process_threads();
    for (int i = 0; i < 1000 && n != expected; ++i) {
        std::this_thread::sleep_for(std::chrono::milliseconds(1));
        n = process_threads();
    }
    return n;
}

}  // namespace

TEST(CpuParallel, BitwiseEqualToSerialCpuInEveryCompositionAndLayout) {
    const Scene scene = mixed_forest(3);
    for (test::TestComposition composition : test::kEveryComposition) {
        for (VertexLayout layout : {VertexLayout::separate, VertexLayout::packed}) {
            SCOPED_TRACE(test::name_of(composition) + ", " + to_string(layout));
            SimulationConfig config = windy(composition.composition, layout);
            config.backend = BackendKind::cpu;
            auto serial = test::create_simulation(scene, config, composition);
            ASSERT_TRUE(serial.ok()) << serial.status().message();
            // A chunk of one element: every dispatch of more than one item is split over 3 threads.
            auto parallel = create_parallel(scene, config, 3, 1, composition.jumping_form);
            ASSERT_TRUE(parallel);
            EXPECT_EQ(parallel->backend_kind(), BackendKind::cpu_parallel);
            expect_bitwise_equal_runs(**serial, *parallel, 80);
        }
    }
}

TEST(CpuParallel, BitwiseEqualToSerialCpuWithDefaultChunksOnAForest) {
    // Enough instances that the default chunking splits every kind of dispatch, on instance
    // boundaries (at least four instances per chunk).
    auto scene = grid_scene(test::small_tree(), 120, 6.0, 5);
    ASSERT_TRUE(scene.ok());
    for (test::TestComposition composition :
         {test::TestComposition(Composition::pointer_jumping), test::kJumpingPerRound,
          test::TestComposition(Composition::level_by_level)}) {
        SCOPED_TRACE(test::name_of(composition));
        SimulationConfig config = windy(composition.composition, VertexLayout::separate);
        config.backend = BackendKind::cpu;
        auto serial = test::create_simulation(*scene, config, composition);
        ASSERT_TRUE(serial.ok());
        auto parallel = create_parallel(*scene, config, 4, detail::kCpuMinChunkElements, composition.jumping_form);
        ASSERT_TRUE(parallel);
        ASSERT_GT(uint64_t((*serial)->vertex_count()), 2ull * detail::kCpuMinChunkElements);
        expect_bitwise_equal_runs(**serial, *parallel, 60);
    }
}

TEST(CpuParallel, BitwiseEqualToSerialCpuWithEveryOtherInstancePaused) {
    // Every other instance paused splits the program into one run per active instance: the
    // plan has more dispatches than it searches conflicts for and puts a barrier between
    // dispatches instead (src/cpu/step_plan.cpp).
    auto scene = grid_scene(test::small_tree(), 240, 6.0, 5);
    ASSERT_TRUE(scene.ok());
    for (test::TestComposition composition : {test::TestComposition(Composition::pointer_jumping), test::kJumpingInDispatch}) {
        SCOPED_TRACE(test::name_of(composition));
        SimulationConfig config = windy(composition.composition, VertexLayout::separate);
        config.backend = BackendKind::cpu;
        auto serial = test::create_simulation(*scene, config, composition);
        ASSERT_TRUE(serial.ok());
        auto parallel = create_parallel(*scene, config, 3, 1, composition.jumping_form);
        ASSERT_TRUE(parallel);
        for (uint64_t i = 0; i < scene->instances.size(); i += 2) {
            ASSERT_TRUE((*serial)->set_instance_active(i, false).ok());
            ASSERT_TRUE(parallel->set_instance_active(i, false).ok());
        }
        expect_bitwise_equal_runs(**serial, *parallel, 20);
    }
}

TEST(CpuParallel, StepPlanWaitsOnlyWhereAChunkReadsAnotherThreadsWrites) {
    using detail::cpu::StepPlan;
    SimulationConfig config = windy(Composition::pointer_jumping, VertexLayout::separate);
    config.backend = BackendKind::cpu;
    Scene tree;
    tree.models = {test::deep_tree(5)};
    tree.model_names = {"deep"};
    tree.instances = {{0, {0, 0, 0}, 0.0}};
    auto single = test::create_simulation(tree, config, test::kJumpingPerRound);
    ASSERT_TRUE(single.ok()) << single.status().message();
    const auto& program = detail::step_program_of(**single);
    const StepPlan plan(program, 4, 1);
    EXPECT_TRUE(plan.matches(program));
    ASSERT_EQ(plan.threads(), 4u);
    uint32_t hierarchical_waits = 0;
    for (uint32_t t = 0; t < plan.threads(); ++t) {
        for (const StepPlan::Task& task : plan.tasks(t)) {
            const Pass pass = program[task.dispatch].pass;
            // integrate reads the forces wind_force wrote for the same chains on this thread.
            if (pass == Pass::integrate) EXPECT_TRUE(plan.waits(task).empty()) << "thread " << t;
            if (detail::is_hierarchical(pass)) hierarchical_waits += uint32_t(plan.waits(task).size());
            for (const StepPlan::Wait& w : plan.waits(task)) {
                EXPECT_NE(w.thread, t);
                EXPECT_LE(w.done, int32_t(plan.tasks(w.thread).size()));
                EXPECT_GT(w.done, -int32_t(plan.tasks(w.thread).size()));
            }
        }
    }
    // Rounds read ancestors anywhere in the tree: each waits for the round before on others.
    EXPECT_GT(hierarchical_waits, 0u);

    // A forest split on instance boundaries: no thread ever waits for another.
    auto scene = grid_scene(test::small_tree(), 120, 6.0, 5);
    ASSERT_TRUE(scene.ok());
    config.composition = Composition::pointer_jumping;
    auto forest = Simulation::create(*scene, config);
    ASSERT_TRUE(forest.ok());
    const StepPlan split(detail::step_program_of(**forest), 4, detail::kCpuMinChunkElements);
    ASSERT_EQ(split.threads(), 4u);
    for (uint32_t t = 0; t < split.threads(); ++t)
        for (const StepPlan::Task& task : split.tasks(t)) EXPECT_TRUE(split.waits(task).empty());
    EXPECT_FALSE(split.matches(program));
}

TEST(CpuParallel, ThreadPoolCoversEveryItemOnceInContiguousRanges) {
    detail::cpu::ThreadPool pool(4);
    for (uint32_t count : {0u, 1u, 3u, 4u, 5u, 97u, 1000u, 4099u}) {
        for (uint32_t min_chunk : {1u, 2u, 50u, 5000u}) {
            SCOPED_TRACE("count " + std::to_string(count) + ", min_chunk " + std::to_string(min_chunk));
            std::vector<std::atomic<uint32_t>> hits(count);
            std::atomic<uint32_t> calls{0};
            pool.parallel_for(count, min_chunk, [&](uint32_t begin, uint32_t end) {
                EXPECT_LT(begin, end);
                EXPECT_LE(end, count);
                for (uint32_t i = begin; i < end; ++i) hits[i].fetch_add(1);
                calls.fetch_add(1);
            });
            for (uint32_t i = 0; i < count; ++i) ASSERT_EQ(hits[i].load(), 1u) << "item " << i;
            const uint32_t expected = count == 0 ? 0 : pool.range_count(count, min_chunk);
            EXPECT_EQ(calls.load(), expected);
            EXPECT_LE(expected, 4u);
            if (count >= 4 * min_chunk) EXPECT_EQ(expected, 4u);
        }
    }
    // Many short jobs back to back, each seeing the writes of the one before: the count
    // alternates, so the ranges shift and an item moves between threads from job to job.
    std::vector<uint32_t> values(64, 0);
    for (uint32_t job = 0; job < 2000; ++job)
        pool.parallel_for(64 - job % 2, 1, [&](uint32_t begin, uint32_t end) {
            for (uint32_t i = begin; i < end; ++i) ++values[i];
        });
    for (uint32_t i = 0; i < 63; ++i) EXPECT_EQ(values[i], 2000u) << i;
    EXPECT_EQ(values[63], 1000u);
}

TEST(CpuParallel, ThreadPoolSharesAJobAmongTheThreadsThatCome) {
    detail::cpu::ThreadPool pool(4);
    for (uint32_t count : {0u, 1u, 2u, 7u, 1000u}) {
        std::vector<std::atomic<uint32_t>> hits(count);
        pool.for_each(count, [&](uint32_t k) { hits[k].fetch_add(1); });
        for (uint32_t k = 0; k < count; ++k) ASSERT_EQ(hits[k].load(), 1u) << count << " " << k;
    }
    // share(): the caller is thread 0 and always comes; each worker comes at most once, with
    // its own index; the caller's body alone may finish the work (here it claims every item).
    for (uint32_t job = 0; job < 200; ++job) {
        std::vector<std::atomic<uint32_t>> calls(4);
        std::atomic<uint32_t> next{0}, items{0};
        pool.share(3, [&](uint32_t thread) {
            ASSERT_LT(thread, 4u);
            calls[thread].fetch_add(1);
            while (next.fetch_add(1) < 64) items.fetch_add(1);
        });
        EXPECT_EQ(calls[0].load(), 1u);
        for (uint32_t t = 1; t < 4; ++t) EXPECT_LE(calls[t].load(), 1u);
        EXPECT_EQ(items.load(), 64u);
    }
}

namespace {

/// Runs `steps` steps of `plan` on `pool` and checks that every chunk ran once per step and
/// started only after every chunk it waits for had finished.
void expect_plan_runs_in_order(const detail::cpu::StepPlan& const_plan, detail::cpu::ThreadPool& pool,
                               uint32_t steps) {
    using detail::cpu::StepPlan;
    auto& plan = const_cast<StepPlan&>(const_plan);
    // Sequence t's task j of step s has the key (s, t, j); its start and finish on one clock.
    std::map<std::tuple<size_t, uint32_t, size_t>, std::pair<uint64_t, uint64_t>> times;
    std::mutex mutex;
    std::atomic<uint64_t> clock{0};
    plan.run(pool, steps, [&](uint32_t dispatch, size_t step, detail::cpu::Range items) {
        const uint64_t start = clock.fetch_add(1);
        std::this_thread::yield();
        const uint64_t finish = clock.fetch_add(1);
        std::lock_guard lock(mutex);
        for (uint32_t t = 0; t < plan.threads(); ++t) {
            const auto tasks = plan.tasks(t);
            for (size_t j = 0; j < tasks.size(); ++j)
                if (tasks[j].dispatch == dispatch && tasks[j].items.begin == items.begin &&
                    tasks[j].items.end == items.end) {
                    EXPECT_TRUE(times.emplace(std::tuple{step, t, j}, std::pair{start, finish}).second);
                    return;
                }
        }
        ADD_FAILURE() << "a chunk that is in no sequence ran";
    });
    for (uint32_t t = 0; t < plan.threads(); ++t) {
        const auto tasks = plan.tasks(t);
        for (size_t s = 0; s < steps; ++s) {
            for (size_t j = 0; j < tasks.size(); ++j) {
                auto self = times.find(std::tuple{s, t, j});
                ASSERT_NE(self, times.end()) << "step " << s << " sequence " << t << " task " << j;
                if (j > 0) {
                    const auto before = times.find(std::tuple{s, t, j - 1});
                    ASSERT_NE(before, times.end());
                    EXPECT_GT(self->second.first, before->second.second);
                }
                for (const StepPlan::Wait& w : plan.waits(tasks[j])) {
                    const size_t n = plan.tasks(w.thread).size();
                    const int64_t target = int64_t(s * n) + w.done;  // tasks of w.thread finished
                    if (target <= 0) continue;
                    const size_t last = size_t(target - 1);
                    auto waited = times.find(std::tuple{last / n, w.thread, last % n});
                    ASSERT_NE(waited, times.end());
                    EXPECT_GT(self->second.first, waited->second.second)
                        << "step " << s << " sequence " << t << " task " << j;
                }
            }
        }
    }
}

}  // namespace

TEST(CpuParallel, StepPlanRunsOnAnyNumberOfThreadsInWaitOrder) {
    SimulationConfig config = windy(Composition::pointer_jumping, VertexLayout::separate);
    config.backend = BackendKind::cpu;
    Scene tree;
    tree.models = {test::deep_tree(5)};
    tree.model_names = {"deep"};
    tree.instances = {{0, {0, 0, 0}, 0.0}};
    auto single = test::create_simulation(tree, config, test::kJumpingPerRound);
    ASSERT_TRUE(single.ok()) << single.status().message();
    const detail::cpu::StepPlan plan(detail::step_program_of(**single), 4, 1);
    ASSERT_EQ(plan.threads(), 4u);
    // One thread: the caller claims every sequence and interleaves them (no worker to wait for).
    detail::cpu::ThreadPool alone(1);
    expect_plan_runs_in_order(plan, alone, 3);
    for (uint32_t threads : {2u, 4u, 9u}) {
        SCOPED_TRACE(std::to_string(threads) + " threads");
        detail::cpu::ThreadPool pool(threads);
        for (int repeat = 0; repeat < 20; ++repeat) expect_plan_runs_in_order(plan, pool, 3);
    }
}

TEST(CpuParallel, StartsNoThreadUntilADispatchIsSplit) {
    const uint32_t before = process_threads();
    if (before == 0) GTEST_SKIP() << "no /proc/self/status on this system";
    SimulationConfig config = windy(Composition::pointer_jumping, VertexLayout::separate);
    config.backend = BackendKind::cpu;
    auto serial = Simulation::create(mixed_forest(1), config);
    ASSERT_TRUE(serial.ok());
    ASSERT_TRUE((*serial)->step(5).ok());
    EXPECT_EQ(process_threads(), before) << "the serial backend started threads";
    // cpu-parallel on a scene far below one chunk runs every dispatch on the caller.
    auto small = create_parallel(mixed_forest(1), config, 4, detail::kCpuMinChunkElements);
    ASSERT_TRUE(small && small->step(5).ok());
    EXPECT_EQ(process_threads(), before);
    auto split = create_parallel(mixed_forest(1), config, 4, 1);
    ASSERT_TRUE(split && split->step(1).ok());
    EXPECT_EQ(process_threads(), before + 3);
    split.reset();
    EXPECT_EQ(process_threads_settled(before), before) << "the pool's threads outlive the simulation";
}

TEST(CpuParallel, ThreadCountFromConfigEnvironmentOrHardware) {
    SimulationConfig config = windy(Composition::pointer_jumping, VertexLayout::separate);
    config.backend = BackendKind::cpu_parallel;
    const Scene scene = mixed_forest(1);
    ::unsetenv("HMSM_CPU_THREADS");
    config.cpu_threads = 3;
    auto three = Simulation::create(scene, config);
    ASSERT_TRUE(three.ok());
    EXPECT_EQ((*three)->device_name(), "host CPU (3 threads, float)");

    ::setenv("HMSM_CPU_THREADS", "2", 1);
    config.cpu_threads = 0;
    auto from_env = Simulation::create(scene, config);
    ASSERT_TRUE(from_env.ok());
    EXPECT_EQ((*from_env)->device_name(), "host CPU (2 threads, float)");
    config.cpu_threads = 5;  // the config wins over the environment
    auto config_wins = Simulation::create(scene, config);
    ASSERT_TRUE(config_wins.ok());
    EXPECT_EQ((*config_wins)->device_name(), "host CPU (5 threads, float)");

    for (const char* bad : {"0", "-1", "two", "4x", "100000"}) {
        ::setenv("HMSM_CPU_THREADS", bad, 1);
        config.cpu_threads = 0;
        auto rejected = Simulation::create(scene, config);
        ASSERT_FALSE(rejected.ok()) << bad;
        EXPECT_EQ(rejected.status().code(), ErrorCode::invalid_argument);
        EXPECT_NE(rejected.status().message().find("HMSM_CPU_THREADS='" + std::string(bad) + "'"),
                  std::string::npos)
            << rejected.status().message();
    }
    ::unsetenv("HMSM_CPU_THREADS");
    config.cpu_threads = detail::kMaxCpuThreads + 1;
    auto too_many = Simulation::create(scene, config);
    ASSERT_FALSE(too_many.ok());
    EXPECT_EQ(too_many.status().code(), ErrorCode::invalid_argument);
    EXPECT_NE(too_many.status().message().find("cpu_threads 1025"), std::string::npos);

    config.cpu_threads = 0;
    auto hardware = Simulation::create(scene, config);
    ASSERT_TRUE(hardware.ok());
    const uint32_t host = std::max(1u, std::thread::hardware_concurrency());
    EXPECT_EQ((*hardware)->device_name(), "host CPU (" + std::to_string(host) + " threads, float)");
}

TEST(CpuParallel, AutomaticPicksItWithoutAGpuAndMoreThanOneThread) {
    ::unsetenv("HMSM_CPU_THREADS");
    SimulationConfig config = windy(Composition::pointer_jumping, VertexLayout::separate);
    config.backend = BackendKind::automatic;
    config.cpu_threads = 2;
    auto two = Simulation::create(mixed_forest(1), config);
    ASSERT_TRUE(two.ok()) << two.status().message();
    const BackendKind picked = (*two)->backend_kind();
    if (picked == BackendKind::cuda || picked == BackendKind::vulkan)
        GTEST_SKIP() << "auto picked the GPU backend " << to_string(picked) << " (" << (*two)->device_name() << ")";
    EXPECT_EQ(picked, BackendKind::cpu_parallel);
    config.cpu_threads = 1;
    auto one = Simulation::create(mixed_forest(1), config);
    ASSERT_TRUE(one.ok());
    EXPECT_EQ((*one)->backend_kind(), BackendKind::cpu);
}

TEST(CpuParallel, NameRoundTripsAndIsCompiledIn) {
    EXPECT_STREQ(to_string(BackendKind::cpu_parallel), "cpu-parallel");
    EXPECT_EQ(parse_backend_kind("cpu-parallel"), BackendKind::cpu_parallel);
    const auto compiled = compiled_backends();
    EXPECT_NE(std::find(compiled.begin(), compiled.end(), BackendKind::cpu_parallel), compiled.end());
}
