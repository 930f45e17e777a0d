// hmsm/vulkan.h: the engine-facing side of the Vulkan backend.
#include <hmsm/vulkan.h>

#include "vulkan_backend.h"
#include "../simulation_access.h"

namespace hmsm::vulkan {

/// The device hmsm created for the simulations of a Context (hmsm/vulkan.h).
class Context {
public:
    explicit Context(std::shared_ptr<detail::vk::Device> device) : device_(std::move(device)) {}
    const std::shared_ptr<detail::vk::Device>& device() const { return device_; }

private:
    std::shared_ptr<detail::vk::Device> device_;
};

namespace {

using detail::BufferId;
using detail::vk::VulkanBackend;

Result<VulkanBackend*> vulkan_backend_of(const Simulation& simulation) {
    auto* backend = dynamic_cast<VulkanBackend*>(&detail::SimulationAccess::backend(simulation));
    if (!backend)
        return Status{ErrorCode::invalid_argument,
                      std::string("vulkan: the simulation runs on the ") +
                          to_string(simulation.backend_kind()) + " backend, not on Vulkan"};
    return backend;
}

/// An empty range (no buffer) for a buffer without elements, such as vertex_normal in the packed
/// vertex layout: its VkBuffer is a 16-byte placeholder an engine must not draw from.
BufferRange range_of(const VulkanBackend& backend, BufferId id) {
    if (backend.element_count(id) == 0) return {};
    const detail::vk::Buffer& buffer = backend.buffer(id);
    const uint32_t stride = detail::shape_scalars(detail::buffer_info(id).shape) * 4;
    return {buffer.handle(), 0, VkDeviceSize(backend.element_count(id)) * stride, stride,
            backend.element_count(id)};
}

}  // namespace

Result<std::shared_ptr<Context>> create_context() {
    auto device = detail::vk::Device::create();
    if (!device) return device.status();
    return std::make_shared<Context>(std::move(device).value());
}

Result<std::unique_ptr<Simulation>> create_simulation(const Scene& scene, const SimulationConfig& config,
                                                      const std::shared_ptr<Context>& context,
                                                      uint32_t frames_in_flight) {
    if (!context) return Status{ErrorCode::invalid_argument, "vulkan: create_simulation needs a Context"};
    auto backend = detail::vk::VulkanBackend::create(context->device(), frames_in_flight);
    if (!backend) return backend.status();
    return detail::SimulationAccess::create(scene, config, std::move(backend).value());
}

Result<std::unique_ptr<Simulation>> create_simulation(const Scene& scene,
                                                      const SimulationConfig& config,
                                                      const ExternalContext& context) {
    auto device = detail::vk::Device::adopt(context);
    if (!device) return device.status();
    auto backend = detail::vk::VulkanBackend::create(std::move(device).value(), context.frames_in_flight);
    if (!backend) return backend.status();
    return detail::SimulationAccess::create(scene, config, std::move(backend).value());
}

Result<SharedBuffers> shared_buffers(const Simulation& simulation) {
    auto backend = vulkan_backend_of(simulation);
    if (!backend) return backend.status();
    const VulkanBackend& b = *backend.value();
    return SharedBuffers{range_of(b, BufferId::vertex_position), range_of(b, BufferId::vertex_normal),
                         range_of(b, BufferId::node_world), simulation.config().vertex_layout,
                         range_of(b, BufferId::joint_matrix)};
}

Result<DeviceHandles> device_handles(const Simulation& simulation) {
    auto backend = vulkan_backend_of(simulation);
    if (!backend) return backend.status();
    const detail::vk::Device& device = backend.value()->device();
    return DeviceHandles{device.physical_device(), device.handle(), device.queue(),
                         device.queue_family()};
}

Status record_steps(Simulation& simulation, VkCommandBuffer command_buffer, uint32_t count) {
    auto backend = vulkan_backend_of(simulation);
    if (!backend) return backend.status();
    // A recording stays within one wind table of steps (hmsm/vulkan.h).
    if (count > HMSM_WIND_STEP_SLOTS)
        return {ErrorCode::invalid_argument, "vulkan: record_steps records at most " +
                                                 std::to_string(HMSM_WIND_STEP_SLOTS) + " steps at once (asked for " +
                                                 std::to_string(count) + ")"};
    if (!command_buffer)
        return {ErrorCode::invalid_argument, "vulkan: record_steps needs a command buffer"};
    // Simulation::step() uploads the live changes and the steps' wind clock, runs the program
    // through the backend and advances the clock; while recording, the backend stages the
    // uploads in the frame's ring slot and records copies and steps instead of submitting.
    VulkanBackend& vulkan = *backend.value();
    // Fades run inside the recorded steps (pass 2); the fades that are over switch here, before
    // the recording, as a switch made between frames.
    if (Status folded = detail::SimulationAccess::impl(simulation).fold_ready_fades(); !folded.ok())
        return folded;
    // Instance changes held back since the last recording come first (docs/vulkan.md).
    Status status = vulkan.begin_recording(command_buffer);
    if (status.ok()) status = simulation.step(count);
    Status ended = vulkan.end_recording();
    return status.ok() ? ended : status;
}

}  // namespace hmsm::vulkan
