// Engine interop for the Vulkan backend (docs/vulkan.md): run hmsm on the engine's own Vulkan
// device and queue, optionally record the steps into the engine's command buffer, and use the
// simulation's output buffers directly (vertex buffers, storage buffers) without a readback.
//
// The engine brings its own Vulkan headers (vulkan/vulkan_core.h, for the handle types) in every
// build. In a build of hmsm without the Vulkan backend (HMSM_HAVE_VULKAN, defined by the hmsm
// target, is absent) the header still compiles and every function fails with no_device, as
// hmsm/cuda.h does without CUDA.
#pragma once

#include <hmsm/export.h>

#include <hmsm/simulation.h>
#include <hmsm/status.h>

#include <vulkan/vulkan_core.h>

#include <cstdint>
#include <memory>

namespace hmsm::vulkan {

/// A Vulkan context owned by the engine. hmsm never destroys these handles; they must outlive
/// every Simulation created on them. The device needs Vulkan 1.1 and no extra feature or
/// extension. `queue` must belong to `queue_family_index`, which must support compute; hmsm
/// may submit to it inside Simulation::create(), step(), read() and its other reads,
/// add_instances(), remove_instances(), swap_remove_instances(), reset_instances(),
/// reserve_instances() and the level calls (set_instance_lod(s), request_instance_lods(),
/// update_lod()), never inside record_steps(), so the engine must not use the queue from
/// another thread during those calls (Vulkan's external synchronization rule). With step(),
/// instance changes within the capacity are held back and submitted with the next step() or
/// before the next read (docs/vulkan.md, "Instance changes between blocking steps").
struct ExternalContext {
    VkInstance instance = VK_NULL_HANDLE;
    VkPhysicalDevice physical_device = VK_NULL_HANDLE;
    VkDevice device = VK_NULL_HANDLE;
    VkQueue queue = VK_NULL_HANDLE;
    uint32_t queue_family_index = 0;
    /// The engine's loader entry point; null means the system Vulkan loader (libvulkan.so.1).
    PFN_vkGetInstanceProcAddr get_instance_proc_addr = nullptr;
    /// Command buffers recorded by record_steps() that may be pending execution at once (1 to
    /// 16): the slots of the ring that carries each frame's live changes to the device. See
    /// record_steps() for the rule it sets.
    uint32_t frames_in_flight = 3;
};

/// One output as a range of a device buffer: `count` elements of `stride` bytes starting at
/// `offset`. Positions are vec4 (x, y, z, 1) and normals vec4 (x, y, z, 0), float32,
/// instance-major, in the same order as Simulation::read() in the packed layout
/// (SimulationConfig::instance_layout; in the placed layout an instance's elements begin at
/// Simulation::instance_placement, and the range holds free slots too); in VertexLayout::packed a
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

/// The device buffers an engine can draw from. Valid until the simulation is destroyed or added
/// instances outgrow its capacity (which reallocates them: call shared_buffers() again); their
/// contents change in every step and move when instances are added or removed. Outputs the simulation does not produce
/// (SimulationConfig::outputs) are empty ranges.
struct SharedBuffers {
    BufferRange vertex_positions;  ///< branch-mesh and leaf vertices (docs/model.md 3.8)
    /// Empty (VK_NULL_HANDLE, count 0) in VertexLayout::packed: the normals are in
    /// vertex_positions' w.
    BufferRange vertex_normals;
    BufferRange node_positions;    ///< skeleton nodes in input order
    VertexLayout vertex_layout = VertexLayout::separate;  ///< the simulation's config().vertex_layout
    /// Joint matrices M_c = [R_c | O_c], one per chain (chain_count() in all, instance-major,
    /// chains in chain order; in the placed layout from each instance's placement on), stride 48: three vec4 rows (R row i, O_i), i.e. a GLSL
    /// `mat3x4` whose columns are the rows (p' = vec4(p, 1) * M) or an HLSL row-major float3x4
    /// (p' = mul(M, float4(p, 1))). Written by root_positions, so present for every
    /// SimulationConfig::outputs; bind it as a storage buffer (bone palette, docs/skinning.md).
    BufferRange joint_matrices;
};

/// The device a Vulkan simulation runs on (its own or the engine's).
struct DeviceHandles {
    VkPhysicalDevice physical_device = VK_NULL_HANDLE;
    VkDevice device = VK_NULL_HANDLE;
    VkQueue queue = VK_NULL_HANDLE;
    uint32_t queue_family_index = 0;
};

/// A Vulkan instance and device created by hmsm, shared by several simulations: N forests on
/// one Context cost one VkInstance, one VkDevice and one set of driver threads instead of N
/// (some drivers also refuse new instances after a few dozen in one process). The device is
/// chosen as for BackendKind::vulkan (HMSM_VULKAN_DEVICE included). Simulations created on a
/// Context hold a reference to its device, so the Context may be released before them. hmsm
/// serializes its own submissions to the shared queue: simulations on one Context may step on
/// different threads (each simulation still from one thread at a time).
class Context;

#ifdef HMSM_HAVE_VULKAN

HMSM_API Result<std::shared_ptr<Context>> create_context();

/// Simulation::create() on the device of `context`: `config.backend` is ignored (always
/// Vulkan); `frames_in_flight` as ExternalContext::frames_in_flight.
HMSM_API Result<std::unique_ptr<Simulation>> create_simulation(const Scene& scene,
                                                               const SimulationConfig& config,
                                                               const std::shared_ptr<Context>& context,
                                                               uint32_t frames_in_flight = 3);

/// Simulation::create() on the engine's device: `config.backend` is ignored (always Vulkan).
HMSM_API Result<std::unique_ptr<Simulation>> create_simulation(const Scene& scene,
                                                               const SimulationConfig& config,
                                                               const ExternalContext& context);

/// Fails with invalid_argument when `simulation` does not run on the Vulkan backend.
HMSM_API Result<SharedBuffers> shared_buffers(const Simulation& simulation);

HMSM_API Result<DeviceHandles> device_handles(const Simulation& simulation);

/// Records `count` (at most 256) steps into `command_buffer` (a primary command buffer in the
/// recording state, outside a render pass, from a pool of the simulation's queue family:
/// ExternalContext::queue_family_index, or DeviceHandles::queue_family_index on hmsm's own
/// device) instead of submitting them, and advances the simulation's clock as
/// Simulation::step() would. hmsm neither submits nor waits here. The steps' commands are
/// recorded once into secondary command buffers of hmsm's own and executed with
/// vkCmdExecuteCommands, recorded again only when the step program changes (instances added or
/// removed, levels switched, fades ended); vkCmdExecuteCommands is why the pool's queue family
/// must be the simulation's and the command buffer must be outside a render pass (the
/// secondaries inherit none). HMSM_VULKAN_REPLAY_STEPS=0, set before the simulation is
/// created, records the commands into `command_buffer` itself instead (any compute-capable
/// queue family of the device then). Live changes made since the last step (wind, force fields,
/// instance settings) take effect in the recorded steps: record_steps writes them, with the
/// steps' wind clock, into a host-visible ring slot of this frame and records copies from it
/// into the simulation's device buffers ahead of the steps.
///
/// Frames in flight (docs/vulkan.md): with F = ExternalContext::frames_in_flight (3 unless set;
/// the create_simulation argument on a Context; 3 on hmsm's own device), the command buffer of the n-th call must have
/// completed execution before the (n + F)-th call is made (e.g. wait for the fence of frame
/// n before recording frame n + F, as a swap chain with F frames in flight does). Submit the
/// command buffers in the order they were recorded, to one queue or with semaphores ordering
/// them. All recorded steps must have completed before Simulation::step(), read(),
/// reset_instances() or the simulation's destruction. add_instances() and remove_instances()
/// within the capacity (reserve_instances) after a first record_steps neither submit nor wait:
/// the change is recorded at the start of the next record_steps; so are level switches
/// (set_instance_lod(s), update_lod(), request_instance_lods(): these read no state then, and a
/// coarsening fades even for an instance at rest); growth past the capacity submits, waits and
/// reallocates (docs/vulkan.md, "Streaming instances").
///
/// hmsm binds its own compute pipeline, descriptor set and push constants (rebind yours
/// afterwards) and starts with a barrier against earlier compute and transfer work; before the
/// engine consumes an output it records a barrier from VK_PIPELINE_STAGE_COMPUTE_SHADER_BIT /
/// VK_ACCESS_SHADER_WRITE_BIT to its own stage (e.g. VERTEX_INPUT / VERTEX_ATTRIBUTE_READ), and
/// before the next recording overwrites outputs the engine's draws still read, a barrier from
/// its stage to COMPUTE_SHADER. Per-pass times are not collected for recorded steps.
/// add_instances() and remove_instances() move state within the simulation's buffers; growing
/// past the capacity reallocates them: SharedBuffers and any command buffer recorded before
/// that are invalid afterwards.
HMSM_API Status record_steps(Simulation& simulation, VkCommandBuffer command_buffer,
                             uint32_t count = 1);

#else

inline Result<std::shared_ptr<Context>> create_context() {
    return Status{ErrorCode::no_device, "vulkan: this build of hmsm has no Vulkan backend"};
}
inline Result<std::unique_ptr<Simulation>> create_simulation(const Scene&, const SimulationConfig&,
                                                             const std::shared_ptr<Context>&, uint32_t = 3) {
    return Status{ErrorCode::no_device, "vulkan: this build of hmsm has no Vulkan backend"};
}
inline Result<std::unique_ptr<Simulation>> create_simulation(const Scene&, const SimulationConfig&,
                                                             const ExternalContext&) {
    return Status{ErrorCode::no_device, "vulkan: this build of hmsm has no Vulkan backend"};
}
inline Result<SharedBuffers> shared_buffers(const Simulation&) {
    return Status{ErrorCode::no_device, "vulkan: this build of hmsm has no Vulkan backend"};
}
inline Result<DeviceHandles> device_handles(const Simulation&) {
    return Status{ErrorCode::no_device, "vulkan: this build of hmsm has no Vulkan backend"};
}
inline Status record_steps(Simulation&, VkCommandBuffer, uint32_t = 1) {
    return {ErrorCode::no_device, "vulkan: this build of hmsm has no Vulkan backend"};
}

#endif

}  // namespace hmsm::vulkan
