// Device memory for the backend: DEVICE_LOCAL working buffers, and a Transfer that moves data
// between host and device through a HOST_VISIBLE staging buffer in bounded chunks (one-shot
// command buffers, each waited for). Lavapipe has a single memory type that is both; real GPUs
// do not, and a shader over host-visible memory runs an order of magnitude slower there.
#pragma once

#include "device.h"

#include <functional>
#include <memory>
#include <span>

namespace hmsm::detail::vk {

enum class MemoryUse { device_local, staging };

/// A buffer with its own allocation; movable, destroyed with the object.
class Buffer {
public:
    Buffer() = default;
    Buffer(Buffer&& other) noexcept { *this = std::move(other); }
    Buffer& operator=(Buffer&& other) noexcept;
    ~Buffer() { reset(); }

    /// `name` appears in error messages (e.g. "vertex_position").
    static Result<Buffer> create(const Device& device, VkDeviceSize size, VkBufferUsageFlags usage,
                                 MemoryUse use, const std::string& name);

    VkBuffer handle() const { return buffer_; }
    VkDeviceSize size() const { return size_; }
    /// Host pointer of a staging buffer (persistently mapped); null for device-local buffers.
    void* mapped() const { return mapped_; }

private:
    void reset();
    const Device* device_ = nullptr;
    VkBuffer buffer_ = VK_NULL_HANDLE;
    VkDeviceMemory memory_ = VK_NULL_HANDLE;
    VkDeviceSize size_ = 0;
    void* mapped_ = nullptr;
};

/// Host <-> device copies. Each call records, submits and waits; every submission starts with
/// a barrier against all earlier shader and transfer writes, so callers need no barriers.
class Transfer {
public:
    static Result<std::unique_ptr<Transfer>> create(const Device& device);
    ~Transfer();

    /// Fills [offset, offset + bytes) of `dst`: `fill(staging, first_byte, chunk_bytes)` writes
    /// the chunk of source bytes [first_byte, first_byte + chunk_bytes) into `staging`.
    Status upload(const Buffer& dst, VkDeviceSize offset, VkDeviceSize bytes,
                  const std::function<void(void*, VkDeviceSize, VkDeviceSize)>& fill);
    /// The inverse: `consume(staging, first_byte, chunk_bytes)` receives each chunk.
    Status download(const Buffer& src, VkDeviceSize offset, VkDeviceSize bytes,
                    const std::function<void(const void*, VkDeviceSize, VkDeviceSize)>& consume);
    /// download() of many regions of `src` ([offset, offset + bytes) each, which may overlap):
    /// `consume` receives their bytes back to back, packed, one submission per staging-full.
    Status download_ranges(const Buffer& src, std::span<const VkBufferCopy> regions,
                           const std::function<void(const void*, VkDeviceSize, VkDeviceSize)>& consume);
    /// upload() into many regions of `dst` (disjoint): `fill` writes their bytes back to back.
    Status upload_ranges(const Buffer& dst, std::span<const VkBufferCopy> regions,
                         const std::function<void(void*, VkDeviceSize, VkDeviceSize)>& fill);
    /// Regions of one buffer for download_parts/upload_parts (srcOffset: the offset in the
    /// buffer, size: the bytes; dstOffset unused).
    struct BufferRegions {
        const Buffer* buffer = nullptr;
        std::span<const VkBufferCopy> regions;
    };
    /// The most bytes download_parts/upload_parts carry in one call.
    static VkDeviceSize most_staged_bytes();
    /// download_ranges of several buffers in one submission (one copy command each):
    /// `consume(part, bytes)` receives part k's regions back to back.
    Status download_parts(std::span<const BufferRegions> parts,
                          const std::function<void(size_t, const void*)>& consume);
    /// The inverse: `fill(part, bytes)` writes part k's regions back to back (disjoint regions).
    Status upload_parts(std::span<const BufferRegions> parts, const std::function<void(size_t, void*)>& fill);
    /// Records `commands` into a one-shot command buffer, submits it and waits.
    Status submit(const std::function<void(VkCommandBuffer)>& commands);
    /// upload() of at most most_staged_bytes() whose copy is followed, in the same submission,
    /// by `then(cmd)` (after a barrier that makes the copy visible to compute shaders): one
    /// submission and one wait where upload() and a later submit() take two. The first error of
    /// `then` is returned.
    Status upload_then(const Buffer& dst, VkDeviceSize offset, VkDeviceSize bytes,
                       const std::function<void(void*, VkDeviceSize, VkDeviceSize)>& fill,
                       const std::function<Status(VkCommandBuffer)>& then);
    /// Submissions made so far (a test hook).
    uint64_t submissions() const { return submissions_; }

private:
    explicit Transfer(const Device& device) : device_(device) {}
    Status ensure_staging(VkDeviceSize bytes);

    const Device& device_;
    VkCommandPool pool_ = VK_NULL_HANDLE;
    VkCommandBuffer command_buffer_ = VK_NULL_HANDLE;
    VkFence fence_ = VK_NULL_HANDLE;
    Buffer staging_;
    uint64_t submissions_ = 0;
};

/// A global memory barrier making all earlier compute and transfer writes visible to `dst_stage`
/// with `dst_access`, and ordering earlier reads before it (write-after-read).
void barrier_after_all_writes(const Device& device, VkCommandBuffer cmd, VkPipelineStageFlags dst_stage,
                              VkAccessFlags dst_access);

}  // namespace hmsm::detail::vk
