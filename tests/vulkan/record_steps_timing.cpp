// The host cost of hmsm::vulkan::record_steps as an engine pays it each frame: a device of the
// "engine" (created apart from the simulation), three command buffers with a fence each, and
// frames submitted without waiting but for the fence of the frame that last used the command
// buffer. Prints the median and 99th percentile CPU microseconds of the record_steps call alone,
// with nothing changed and with a wind change and a moved force field before every frame.
// Not a test: it asserts nothing and runs without validation (which would dominate the cost).
//
//   hmsm_vulkan_record_timing [--preset paper-1] [--trees 1] [--frames 600] [--steps 2]
//                             [--joints] [--idle] [--spin] [--sleep-us N] [--warm-us N]
//                             [--evict-kib N] [--probe] [--composition C]
//
// --joints simulates only the joint matrices (SimulationConfig::outputs = joints, so large
// forests fit a CPU driver); --idle waits for the queue to drain before each record_steps, so
// the time is hmsm's own work without device work running beside it. --spin waits for a frame's
// fence by polling it rather than blocking, so the thread never sleeps; --sleep-us N sleeps N
// microseconds before each record_steps, as a thread that blocked on a fence does: together they
// tell hmsm's own cost from the cost of running after the thread slept (cold caches, clocks).
// --warm-us N keeps the thread busy N microseconds (touching nothing of hmsm's) before each
// record_steps, as an engine's own frame work between its fence wait and the recording does;
// --evict-kib N then writes N KiB of other memory, which evicts hmsm's code and data from the
// core's caches while its clock stays up: together they tell a cold clock from cold caches.
// --probe times, every other frame and in record_steps' place, the Vulkan calls a replayed
// frame makes (a barrier, a buffer copy, one vkCmdExecuteCommands of an empty secondary) on
// buffers of the engine's: the driver's share of a cold call.
// HMSM_VULKAN_REPLAY_STEPS=0 records every step's commands into the command buffer rather than
// replaying them from secondary command buffers (src/vulkan/step_replay.h), for comparisons.
#include "simulation_access.h"
#include "vulkan/device.h"
#include "vulkan/vulkan_backend.h"

#include <hmsm/hmsm.h>
#include <hmsm/vulkan.h>

#include <algorithm>
#include <array>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <optional>
#include <string>
#include <thread>
#include <vector>

namespace {

struct Options {
    std::string preset = "paper-1";
    std::string composition = "automatic";  // path_walk: the step program of a GPU
    uint32_t trees = 1, frames = 600, steps = 2;
    bool joints = false, idle = false, spin = false, probe = false;
    uint32_t sleep_us = 0, warm_us = 0, evict_kib = 0;
};

bool parse(int argc, char** argv, Options& o) {
    for (int i = 1; i < argc; ++i) {
        const std::string arg = argv[i];
        const bool has_value = i + 1 < argc;
        if (arg == "--preset" && has_value) o.preset = argv[++i];
        else if (arg == "--trees" && has_value) o.trees = uint32_t(std::strtoul(argv[++i], nullptr, 10));
        else if (arg == "--frames" && has_value) o.frames = uint32_t(std::strtoul(argv[++i], nullptr, 10));
        else if (arg == "--steps" && has_value) o.steps = uint32_t(std::strtoul(argv[++i], nullptr, 10));
        else if (arg == "--composition" && has_value) o.composition = argv[++i];
        else if (arg == "--joints") o.joints = true;
        else if (arg == "--idle") o.idle = true;
        else if (arg == "--spin") o.spin = true;
        else if (arg == "--probe") o.probe = true;
        else if (arg == "--sleep-us" && has_value) o.sleep_us = uint32_t(std::strtoul(argv[++i], nullptr, 10));
        else if (arg == "--warm-us" && has_value) o.warm_us = uint32_t(std::strtoul(argv[++i], nullptr, 10));
        else if (arg == "--evict-kib" && has_value) o.evict_kib = uint32_t(std::strtoul(argv[++i], nullptr, 10));
        else {
            std::fprintf(stderr, "unknown or incomplete argument %s\n", arg.c_str());
            return false;
        }
    }
    return o.trees > 0 && o.frames > 0 && o.steps > 0;
}

int fail(const std::string& what) {
    std::fprintf(stderr, "error: %s\n", what.c_str());
    return 1;
}

}  // namespace

int main(int argc, char** argv) {
    using namespace hmsm;
    Options o;
    if (!parse(argc, argv, o)) return fail("usage: see the comment at the top of record_steps_timing.cpp");
    auto engine = detail::vk::Device::create();
    if (!engine) return fail(engine.status().message());
    const detail::vk::Device& device = **engine;
    const VolkDeviceTable& vk = device.vk();
    vulkan::ExternalContext context;
    context.instance = device.instance();
    context.physical_device = device.physical_device();
    context.device = device.handle();
    context.queue = device.queue();
    context.queue_family_index = device.queue_family();

    auto tree = generate_preset(o.preset);
    if (!tree) return fail(tree.status().message());
    auto scene = grid_scene(*tree, o.trees, 6.0, 1);
    if (!scene) return fail(scene.status().message());
    SimulationConfig config;
    config.wind.strength = 8.0;
    if (o.joints) config.outputs = Outputs::joints;
    const std::optional<Composition> composition = parse_composition(o.composition);
    if (!composition) return fail("unknown composition " + o.composition);
    config.composition = *composition;
    auto created = vulkan::create_simulation(*scene, config, context);
    if (!created) return fail(created.status().message());
    Simulation& sim = **created;

    constexpr uint32_t kFrames = 3;
    VkCommandPoolCreateInfo pool_info{VK_STRUCTURE_TYPE_COMMAND_POOL_CREATE_INFO};
    pool_info.flags = VK_COMMAND_POOL_CREATE_RESET_COMMAND_BUFFER_BIT;
    pool_info.queueFamilyIndex = device.queue_family();
    VkCommandPool pool = VK_NULL_HANDLE;
    if (vk.vkCreateCommandPool(device.handle(), &pool_info, nullptr, &pool) != VK_SUCCESS)
        return fail("vkCreateCommandPool");
    std::array<VkCommandBuffer, kFrames> commands{};
    VkCommandBufferAllocateInfo allocate{VK_STRUCTURE_TYPE_COMMAND_BUFFER_ALLOCATE_INFO};
    allocate.commandPool = pool;
    allocate.level = VK_COMMAND_BUFFER_LEVEL_PRIMARY;
    allocate.commandBufferCount = kFrames;
    if (vk.vkAllocateCommandBuffers(device.handle(), &allocate, commands.data()) != VK_SUCCESS)
        return fail("vkAllocateCommandBuffers");
    std::array<VkFence, kFrames> fences{};
    VkFenceCreateInfo fence_info{VK_STRUCTURE_TYPE_FENCE_CREATE_INFO};
    fence_info.flags = VK_FENCE_CREATE_SIGNALED_BIT;
    for (VkFence& f : fences)
        if (vk.vkCreateFence(device.handle(), &fence_info, nullptr, &f) != VK_SUCCESS) return fail("vkCreateFence");

    std::printf("device %s, %s x %u%s, record_steps(sim, cmd, %u), %u frames, %u in flight%s%s, sleep %u us, "
                "busy %u us, %u KiB evicted\n",
                device.name().c_str(), o.preset.c_str(), o.trees, o.joints ? " (joints only)" : "", o.steps,
                o.frames, kFrames, o.idle ? ", queue idle before each call" : "",
                o.spin ? ", fences polled" : "", o.sleep_us, o.warm_us, o.evict_kib);
    std::vector<uint64_t> other(size_t(o.evict_kib) * 1024 / sizeof(uint64_t));
    // The probe's buffers and empty secondary (--probe).
    auto probe_src = detail::vk::Buffer::create(device, 256, VK_BUFFER_USAGE_TRANSFER_SRC_BIT,
                                                detail::vk::MemoryUse::staging, "probe source");
    auto probe_dst = detail::vk::Buffer::create(device, 256, VK_BUFFER_USAGE_TRANSFER_DST_BIT,
                                                detail::vk::MemoryUse::device_local, "probe destination");
    if (!probe_src || !probe_dst) return fail("probe buffers");
    VkCommandBuffer empty_secondary = VK_NULL_HANDLE;
    {
        VkCommandBufferAllocateInfo info{VK_STRUCTURE_TYPE_COMMAND_BUFFER_ALLOCATE_INFO};
        info.commandPool = pool;
        info.level = VK_COMMAND_BUFFER_LEVEL_SECONDARY;
        info.commandBufferCount = 1;
        if (vk.vkAllocateCommandBuffers(device.handle(), &info, &empty_secondary) != VK_SUCCESS)
            return fail("vkAllocateCommandBuffers (secondary)");
        VkCommandBufferInheritanceInfo inheritance{VK_STRUCTURE_TYPE_COMMAND_BUFFER_INHERITANCE_INFO};
        VkCommandBufferBeginInfo begin{VK_STRUCTURE_TYPE_COMMAND_BUFFER_BEGIN_INFO};
        begin.pInheritanceInfo = &inheritance;
        vk.vkBeginCommandBuffer(empty_secondary, &begin);
        vk.vkEndCommandBuffer(empty_secondary);
    }
    auto record_probe = [&](VkCommandBuffer cmd) {
        VkMemoryBarrier barrier{VK_STRUCTURE_TYPE_MEMORY_BARRIER};
        barrier.srcAccessMask = VK_ACCESS_SHADER_WRITE_BIT | VK_ACCESS_TRANSFER_WRITE_BIT;
        barrier.dstAccessMask = VK_ACCESS_TRANSFER_WRITE_BIT;
        vk.vkCmdPipelineBarrier(cmd, VK_PIPELINE_STAGE_COMPUTE_SHADER_BIT | VK_PIPELINE_STAGE_TRANSFER_BIT,
                                VK_PIPELINE_STAGE_TRANSFER_BIT, 0, 1, &barrier, 0, nullptr, 0, nullptr);
        const VkBufferCopy region{0, 0, 256};
        vk.vkCmdCopyBuffer(cmd, probe_src->handle(), probe_dst->handle(), 1, &region);
        vk.vkCmdExecuteCommands(cmd, 1, &empty_secondary);
    };
    std::vector<double> probe_micros;
    const auto& backend = dynamic_cast<const detail::vk::VulkanBackend&>(detail::backend_of(sim));
    uint64_t frame = 0;
    for (const bool live : {false, true}) {
        std::vector<double> micros, change_micros;
        for (uint32_t i = 0; i < o.frames; ++i, ++frame) {
            const uint32_t k = uint32_t(frame % kFrames);
            if (o.spin)
                while (vk.vkGetFenceStatus(device.handle(), fences[k]) == VK_NOT_READY) {
                }
            else
                vk.vkWaitForFences(device.handle(), 1, &fences[k], VK_TRUE, UINT64_MAX);
            vk.vkResetFences(device.handle(), 1, &fences[k]);
            if (o.idle) vk.vkQueueWaitIdle(device.queue());
            if (o.sleep_us) std::this_thread::sleep_for(std::chrono::microseconds(o.sleep_us));
            if (o.warm_us) {
                const auto until = std::chrono::steady_clock::now() + std::chrono::microseconds(o.warm_us);
                while (std::chrono::steady_clock::now() < until) {
                }
            }
            for (size_t w = 0; w < other.size(); w += 8) other[w] += frame;  // a line each
            vk.vkResetCommandBuffer(commands[k], 0);
            VkCommandBufferBeginInfo begin{VK_STRUCTURE_TYPE_COMMAND_BUFFER_BEGIN_INFO};
            begin.flags = VK_COMMAND_BUFFER_USAGE_ONE_TIME_SUBMIT_BIT;
            vk.vkBeginCommandBuffer(commands[k], &begin);
            if (live) {
                const auto start = std::chrono::steady_clock::now();
                Wind wind = sim.wind();
                wind.strength = 8.0 + 2.0 * double(i % 7) / 7.0;  // a gust
                if (Status s = sim.set_wind(wind); !s) return fail(s.message());
                ForceField field;
                field.kind = ForceField::Kind::radial;
                field.center = {0.1 * double(i % 50), 2.0, 0.0};  // a moving helicopter
                field.radius = 5.0;
                field.radial = 10.0;
                if (Status s = sim.set_force_fields({&field, 1}); !s) return fail(s.message());
                change_micros.push_back(
                    std::chrono::duration<double, std::micro>(std::chrono::steady_clock::now() - start).count());
            }
            const bool probing = o.probe && frame % 2 == 1;
            const auto start = std::chrono::steady_clock::now();
            if (probing) {
                record_probe(commands[k]);
                probe_micros.push_back(
                    std::chrono::duration<double, std::micro>(std::chrono::steady_clock::now() - start).count());
            }
            const Status recorded = vulkan::record_steps(sim, commands[k], o.steps);
            if (!probing)
                micros.push_back(
                    std::chrono::duration<double, std::micro>(std::chrono::steady_clock::now() - start).count());
            if (!recorded) return fail(recorded.message());
            vk.vkEndCommandBuffer(commands[k]);
            VkSubmitInfo submit{VK_STRUCTURE_TYPE_SUBMIT_INFO};
            submit.commandBufferCount = 1;
            submit.pCommandBuffers = &commands[k];
            if (vk.vkQueueSubmit(device.queue(), 1, &submit, fences[k]) != VK_SUCCESS) return fail("vkQueueSubmit");
        }
        auto quantile = [](std::vector<double> v, double q) {
            if (v.empty()) return 0.0;
            std::sort(v.begin(), v.end());
            return v[std::min(v.size() - 1, size_t(q * double(v.size())))];
        };
        std::printf("%-34s record_steps median %8.1f us  p99 %8.1f us", live ? "wind change + moved force field:" : "nothing changed:",
                    quantile(micros, 0.5), quantile(micros, 0.99));
        if (live) std::printf("   (set_wind + set_force_fields median %.1f us)", quantile(change_micros, 0.5));
        std::printf("\n");
    }
    if (o.probe) {
        std::sort(probe_micros.begin(), probe_micros.end());
        std::printf("probe (barrier, copy, execute of an empty secondary) median %8.1f us\n",
                    probe_micros[probe_micros.size() / 2]);
    }
    // Replayed (step_replay.h): one secondary per frame in flight, recorded in the first frames.
    std::printf("secondaries recorded %llu, replayed %llu times (HMSM_VULKAN_REPLAY_STEPS=0: none)\n",
                (unsigned long long)backend.step_secondaries_recorded(), (unsigned long long)backend.step_replays());
    vk.vkQueueWaitIdle(device.queue());
    std::vector<float> joints;
    if (Status s = sim.read(Output::joint_matrices, joints); !s) return fail(s.message());
    for (VkFence f : fences) vk.vkDestroyFence(device.handle(), f, nullptr);
    vk.vkDestroyCommandPool(device.handle(), pool, nullptr);
    created->reset();  // before the engine's device
    return 0;
}
