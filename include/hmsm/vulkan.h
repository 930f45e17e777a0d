// Engine interop for the Vulkan backend (docs/vulkan.md): run hmsm on the engine's own Vulkan
// device and queue, optionally record the steps into the engine's command buffer, and use the
// simulation's output buffers directly (vertex buffers, storage buffers) without a readback.
//
// Only available when the build has the Vulkan backend (HMSM_HAVE_VULKAN is defined by the
// hmsm target); the engine brings its own Vulkan headers.
#pragma once

#include <hmsm/simulation.h>
#include <hmsm/status.h>

#include <vulkan/vulkan_core.h>

#include <cstdint>
#include <memory>

namespace hmsm::vulkan {

/// A Vulkan context owned by the engine. hmsm never destroys these handles; they must outlive
/// every Simulation created on them. The device needs Vulkan 1.1 and no extra feature or
/// extension. `queue` must belong to `queue_family_index`, which must support compute; hmsm
/// submits to it only inside Simulation::step() and Simulation::read() (and never after
/// record_steps() for that simulation, see below), so the engine must not use the queue from
/// another thread during those calls (Vulkan's external synchronization rule).
struct ExternalContext {
    VkInstance instance = VK_NULL_HANDLE;
    VkPhysicalDevice physical_device = VK_NULL_HANDLE;
    VkDevice device = VK_NULL_HANDLE;
    VkQueue queue = VK_NULL_HANDLE;
    uint32_t queue_family_index = 0;
    /// The engine's loader entry point; null means the system Vulkan loader (libvulkan.so.1).
    PFN_vkGetInstanceProcAddr get_instance_proc_addr = nullptr;
};

/// Simulation::create() on the engine's device: `config.backend` is ignored (always Vulkan).
Result<std::unique_ptr<Simulation>> create_simulation(const Scene& scene,
                                                      const SimulationConfig& config,
                                                      const ExternalContext& context);

/// One output as a range of a device buffer: `count` elements of `stride` bytes starting at
/// `offset`. Positions are vec4 (x, y, z, 1) and normals vec4 (x, y, z, 0), float32,
/// instance-major, in the same order as Simulation::read(); in VertexLayout::packed a
/// position's w holds the normal word instead (decode it with
/// oct_decode(unpackSnorm2x16(floatBitsToUint(p.w))), docs/vulkan.md). The buffers carry the
/// usage flags STORAGE_BUFFER, VERTEX_BUFFER, TRANSFER_SRC and TRANSFER_DST. Each output is one
/// VkBuffer however large the scene, also when hmsm itself binds it in windows because it
/// exceeds maxStorageBufferRange (docs/vulkan.md); a storage-buffer binding of the engine's own
/// must keep its range within that limit.
struct BufferRange {
    VkBuffer buffer = VK_NULL_HANDLE;
    VkDeviceSize offset = 0;
    VkDeviceSize size = 0;
    uint32_t stride = 0;
    uint64_t count = 0;
};

/// The device buffers an engine can draw from. Valid until the simulation is destroyed or its
/// instances are added or removed (which reallocates them: call shared_buffers() again); their
/// contents change in every step.
struct SharedBuffers {
    BufferRange vertex_positions;  ///< branch-mesh and leaf vertices (docs/model.md 3.8)
    /// Empty (VK_NULL_HANDLE, count 0) in VertexLayout::packed: the normals are in
    /// vertex_positions' w.
    BufferRange vertex_normals;
    BufferRange node_positions;    ///< skeleton nodes in input order
    VertexLayout vertex_layout = VertexLayout::separate;  ///< the simulation's config().vertex_layout
};

/// Fails with invalid_argument when `simulation` does not run on the Vulkan backend.
Result<SharedBuffers> shared_buffers(const Simulation& simulation);

/// The device a Vulkan simulation runs on (its own or the engine's).
struct DeviceHandles {
    VkPhysicalDevice physical_device = VK_NULL_HANDLE;
    VkDevice device = VK_NULL_HANDLE;
    VkQueue queue = VK_NULL_HANDLE;
    uint32_t queue_family_index = 0;
};
Result<DeviceHandles> device_handles(const Simulation& simulation);

/// Records `count` (at most 256) steps into `command_buffer` (recording state, outside a render pass, from a
/// pool of a compute-capable queue family of the simulation's device) instead of submitting
/// them, and advances the simulation's clock as Simulation::step() would. hmsm binds its own
/// compute pipeline, descriptor set and push constants (rebind yours afterwards) and starts
/// with a compute-to-compute barrier against earlier work; before the engine consumes an
/// output it records a barrier from VK_PIPELINE_STAGE_COMPUTE_SHADER_BIT /
/// VK_ACCESS_SHADER_WRITE_BIT to its own stage (e.g. VERTEX_INPUT / VERTEX_ATTRIBUTE_READ).
/// The engine submits the command buffer; the recorded steps must complete before the next
/// Simulation::step(), read() or record_steps() of this simulation is called. Per-pass times are
/// not collected for recorded steps. Live changes made since the last step (wind, force fields,
/// instance settings) take effect in the recorded steps: record_steps uploads them, and the
/// steps' wind clock, with small transfers it submits to the queue and waits for before it
/// records. add_instances() and remove_instances() reallocate the simulation's buffers:
/// SharedBuffers and any command buffer recorded before them are invalid afterwards.
Status record_steps(Simulation& simulation, VkCommandBuffer command_buffer, uint32_t count = 1);

}  // namespace hmsm::vulkan
