// Compiled with the Vulkan loader's prototypes (the engine calls the loader directly), unlike
// the rest of the suite, which reaches Vulkan through hmsm's private entry points.
#undef VK_NO_PROTOTYPES
#include "../../examples/common/engine_vulkan.h"

#include "engine_device.h"

#include <gtest/gtest.h>

namespace hmsm::test {

EngineDevice::EngineDevice(std::unique_ptr<engine::Device> device) : device_(std::move(device)) {}
EngineDevice::~EngineDevice() = default;

std::unique_ptr<EngineDevice> EngineDevice::create(std::string& skip) {
    engine::DeviceOptions options;
    options.graphics = false;
    options.on_validation_message = [](const char* message) { add_validation_message(message); };
    try {
        return std::unique_ptr<EngineDevice>(new EngineDevice(std::make_unique<engine::Device>(options)));
    } catch (const engine::NoDevice& e) {
        skip = e.what();
    } catch (const std::exception& e) {
        ADD_FAILURE() << "engine device: " << e.what();
    }
    return nullptr;
}

vulkan::ExternalContext EngineDevice::context() const {
    vulkan::ExternalContext context;
    context.instance = device_->instance();
    context.physical_device = device_->physical_device();
    context.device = device_->handle();
    context.queue = device_->queue();
    context.queue_family_index = device_->queue_family();
    context.get_instance_proc_addr = vkGetInstanceProcAddr;
    return context;
}

uint64_t EngineDevice::min_storage_buffer_offset_alignment() const {
    VkPhysicalDeviceProperties properties;
    vkGetPhysicalDeviceProperties(device_->physical_device(), &properties);
    return properties.limits.minStorageBufferOffsetAlignment;
}

EngineFrames::EngineFrames(const EngineDevice& device, uint32_t frames) {
    try {
        frames_ = std::make_unique<engine::Frames>(device.device(), frames);
    } catch (const std::exception& e) {
        ADD_FAILURE() << "engine frames: " << e.what();
    }
}
EngineFrames::~EngineFrames() = default;

VkCommandBuffer EngineFrames::begin(uint64_t frame) {
    try {
        if (frames_) return frames_->begin(frame);
    } catch (const std::exception& e) {
        ADD_FAILURE() << "frame " << frame << ": " << e.what();
    }
    return VK_NULL_HANDLE;
}

void EngineFrames::submit(uint64_t frame) {
    try {
        if (frames_) frames_->submit(frame);
    } catch (const std::exception& e) {
        ADD_FAILURE() << "frame " << frame << ": " << e.what();
    }
}

void EngineFrames::wait_all() {
    try {
        if (frames_) frames_->wait_all();
    } catch (const std::exception& e) {
        ADD_FAILURE() << "waiting for the frames: " << e.what();
    }
}

void record_steps_on_engine_queue(const EngineDevice& device, Simulation& simulation, uint32_t steps) {
    EngineFrames frames(device, 1);
    VkCommandBuffer cmd = frames.begin(0);
    ASSERT_NE(cmd, VK_NULL_HANDLE);
    const Status recorded = vulkan::record_steps(simulation, cmd, steps);
    EXPECT_TRUE(recorded.ok()) << recorded.message();
    frames.submit(0);
    frames.wait_all();
}

}  // namespace hmsm::test
