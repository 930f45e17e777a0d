// The Vulkan tests' engine: an instance, device and frames in flight created as an engine
// creates them, not by hmsm (examples/common/engine_vulkan.h, shared with
// examples/engine_loop), behind an interface free of Vulkan prototypes so that test sources
// compiled against hmsm's private entry points can use it.
#pragma once

#include <hmsm/simulation.h>
#include <hmsm/vulkan.h>

#include <cstdint>
#include <memory>
#include <string>

namespace engine {
class Device;
class Frames;
}  // namespace engine

namespace hmsm::test {

class EngineDevice {
public:
    /// A compute device of the engine's own, validated (with synchronization validation) when
    /// the layer is installed: its messages join take_validation_messages(), so VulkanTest
    /// fails on them. Null with `skip` set when there is no device; other errors fail the test.
    static std::unique_ptr<EngineDevice> create(std::string& skip);
    ~EngineDevice();

    /// The hmsm/vulkan.h context of this device (frames_in_flight 3).
    vulkan::ExternalContext context() const;
    const engine::Device& device() const { return *device_; }
    uint64_t min_storage_buffer_offset_alignment() const;

private:
    explicit EngineDevice(std::unique_ptr<engine::Device> device);
    std::unique_ptr<engine::Device> device_;
};

/// The engine's `frames` command buffers, each with a fence that starts signalled. Failures are
/// reported as test failures.
class EngineFrames {
public:
    EngineFrames(const EngineDevice& device, uint32_t frames);
    ~EngineFrames();
    /// Waits for the fence of the frame that last used command buffer `frame % frames` (the
    /// ring rule), then begins it.
    VkCommandBuffer begin(uint64_t frame);
    /// Ends and submits the frame's command buffer with its fence; does not wait.
    void submit(uint64_t frame);
    void wait_all();

private:
    std::unique_ptr<engine::Frames> frames_;
};

/// Adds a validation message reported by the engine's device (vulkan_test_support.cpp).
void add_validation_message(const std::string& message);

/// As an engine would: records `steps` steps of `simulation` (created on `device`) into a
/// command buffer of its own pool with hmsm::vulkan::record_steps, submits it and waits for it.
/// Failures are reported as test failures (check HasFatalFailure()).
void record_steps_on_engine_queue(const EngineDevice& device, Simulation& simulation, uint32_t steps);

}  // namespace hmsm::test
