// Asynchronous reads of outputs (Backend::request_read / take_read, simulation_read.cpp): each
// read slot has a host-visible buffer of its own, as large as the largest output read through
// it, and a request copies the output's regions into it with one copy command in one
// submission and returns; taking the slot waits for that submission's fence and hands out the
// mapped memory. An output then crosses the bus once, at the copy engine's speed, and the
// simulation converts it from there on its readback threads: no staging chunks, no host copy
// between them and no wait per chunk (Transfer::download).
#pragma once

#include "device.h"
#include "device_buffer.h"

#include "../backend.h"

#include <array>
#include <memory>
#include <span>

namespace hmsm::detail {
/// Test hook: outputs of more than `bytes` bytes (0: none but the device's allocation limit)
/// are read through the staging chunks instead of a read slot, as those past one allocation are.
void vulkan_set_read_slot_bytes(uint64_t bytes);
}  // namespace hmsm::detail

namespace hmsm::detail::vk {

class ReadSlots {
public:
    static Result<std::unique_ptr<ReadSlots>> create(const Device& device);
    ~ReadSlots();

    /// Whether `bytes` fit one slot's buffer on this device (maxMemoryAllocationSize, and the
    /// test hook's limit).
    bool fits(VkDeviceSize bytes) const;
    /// Copies `regions` of `src` (dstOffset: the offset in the slot) into slot `slot`'s buffer,
    /// `bytes` in all, after all earlier work on the queue, without waiting; a request the slot
    /// still holds is waited for first. Needs fits(bytes).
    Status request(uint32_t slot, VkBuffer src, std::span<const VkBufferCopy> regions, VkDeviceSize bytes);
    /// Waits for slot `slot`'s request and returns its bytes, valid until the slot's next request.
    Result<const void*> take(uint32_t slot);
    /// Queue submissions made (a test hook).
    uint64_t submissions() const { return submissions_; }

private:
    struct Slot {
        Buffer buffer;
        VkCommandBuffer command_buffer = VK_NULL_HANDLE;
        VkFence fence = VK_NULL_HANDLE;
        bool pending = false;
    };
    explicit ReadSlots(const Device& device) : device_(device) {}
    Status wait(Slot& slot);

    const Device& device_;
    VkCommandPool pool_ = VK_NULL_HANDLE;
    std::array<Slot, kReadSlots> slots_;
    uint64_t submissions_ = 0;
};

}  // namespace hmsm::detail::vk
