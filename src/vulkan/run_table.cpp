#include "run_table.h"

#include "vk_error.h"

#include <algorithm>
#include <array>
#include <atomic>
#include <cstdlib>
#include <cstring>
#include <string>

namespace hmsm::detail {
namespace {
// 0: the environment decides, 1: on, 2: off.
std::atomic<int> g_batch_runs{0};
std::atomic<uint64_t> g_batch_workgroups{0};
}  // namespace

void vulkan_set_batch_runs(std::optional<bool> enabled, uint64_t max_workgroups) {
    g_batch_runs = enabled ? (*enabled ? 1 : 2) : 0;
    g_batch_workgroups = max_workgroups;
}

namespace vk {

std::optional<bool> requested_batch_runs() {
    if (int hook = g_batch_runs.load()) return hook == 1;
    const char* env = std::getenv("HMSM_VULKAN_BATCH_RUNS");
    if (env && std::string(env) == "0") return false;
    if (env && std::string(env) == "1") return true;
    return std::nullopt;
}

uint64_t requested_batch_workgroups() { return g_batch_workgroups.load(); }

namespace {
constexpr VkDeviceSize kEntryBytes = sizeof(gpu::PassConstants);
constexpr VkDeviceSize kWorkgroupBytes = sizeof(uint32_t);
}  // namespace

Result<std::unique_ptr<RunTable>> RunTable::create(const Device& device, VkDescriptorSetLayout layout,
                                                   uint32_t entries) {
    std::unique_ptr<RunTable> table(new RunTable(device, layout));
    auto storage = table->create_storage(std::max<uint32_t>(entries, 1));
    if (!storage) return storage.status();
    table->current_ = std::move(storage).value();
    return table;
}

RunTable::~RunTable() {
    destroy(current_);
    release_replaced();
}

Result<RunTable::Storage> RunTable::create_storage(uint32_t entries) const {
    const VkDeviceSize alignment = std::max<VkDeviceSize>(device_.limits().min_storage_buffer_offset_alignment, 16);
    Storage s;
    s.capacity = entries;
    s.workgroups_offset = (entries * kEntryBytes + alignment - 1) / alignment * alignment;
    auto buffer = Buffer::create(device_, s.workgroups_offset + entries * kWorkgroupBytes,
                                 VK_BUFFER_USAGE_STORAGE_BUFFER_BIT | VK_BUFFER_USAGE_TRANSFER_DST_BIT,
                                 MemoryUse::device_local, "run table");
    if (!buffer) return buffer.status();
    s.buffer = std::move(buffer).value();
    const VolkDeviceTable& vk = device_.vk();
    VkDescriptorPoolSize size{VK_DESCRIPTOR_TYPE_STORAGE_BUFFER, 2};
    VkDescriptorPoolCreateInfo pool_info{VK_STRUCTURE_TYPE_DESCRIPTOR_POOL_CREATE_INFO};
    pool_info.maxSets = 1;
    pool_info.poolSizeCount = 1;
    pool_info.pPoolSizes = &size;
    HMSM_VK_TRY(vk.vkCreateDescriptorPool(device_.handle(), &pool_info, nullptr, &s.pool));
    VkDescriptorSetAllocateInfo allocate{VK_STRUCTURE_TYPE_DESCRIPTOR_SET_ALLOCATE_INFO};
    allocate.descriptorPool = s.pool;
    allocate.descriptorSetCount = 1;
    allocate.pSetLayouts = &layout_;
    if (VkResult r = vk.vkAllocateDescriptorSets(device_.handle(), &allocate, &s.set); r != VK_SUCCESS) {
        vk.vkDestroyDescriptorPool(device_.handle(), s.pool, nullptr);
        return failure(r, "vkAllocateDescriptorSets(run table)", __FILE__, __LINE__);
    }
    const std::array<VkDescriptorBufferInfo, 2> infos{{
        {s.buffer.handle(), 0, entries * kEntryBytes},
        {s.buffer.handle(), s.workgroups_offset, entries * kWorkgroupBytes},
    }};
    std::array<VkWriteDescriptorSet, 2> writes{};
    for (uint32_t b = 0; b < 2; ++b) {
        writes[b].sType = VK_STRUCTURE_TYPE_WRITE_DESCRIPTOR_SET;
        writes[b].dstSet = s.set;
        writes[b].dstBinding = b == 0 ? HMSM_RUN_TABLE_CONSTANTS : HMSM_RUN_TABLE_WORKGROUPS;
        writes[b].descriptorCount = 1;
        writes[b].descriptorType = VK_DESCRIPTOR_TYPE_STORAGE_BUFFER;
        writes[b].pBufferInfo = &infos[b];
    }
    vk.vkUpdateDescriptorSets(device_.handle(), uint32_t(writes.size()), writes.data(), 0, nullptr);
    return s;
}

void RunTable::destroy(Storage& storage) const {
    if (storage.pool) device_.vk().vkDestroyDescriptorPool(device_.handle(), storage.pool, nullptr);
    storage.pool = VK_NULL_HANDLE;
    storage.set = VK_NULL_HANDLE;
    storage.buffer = Buffer();
}

void RunTable::release_replaced() {
    for (Storage& s : replaced_) destroy(s);
    replaced_.clear();
}

void RunTable::next_recording(uint32_t frames) {
    ++recordings_;
    if (replaced_.empty()) return;
    // The recording that replaced a buffer has completed once `frames` recordings have begun
    // after it (the ring rule).
    std::vector<Storage> kept;
    for (Storage& s : replaced_) {
        if (s.replaced_at + frames > recordings_) kept.push_back(std::move(s));
        else destroy(s);
    }
    replaced_ = std::move(kept);
}

Status RunTable::reserve(uint32_t entries) {
    if (entries <= current_.capacity) return {};
    auto grown = create_storage(std::max(entries, 2 * current_.capacity));
    if (!grown) return grown.status();
    current_.replaced_at = recordings_;
    replaced_.push_back(std::move(current_));
    current_ = std::move(grown).value();
    return {};
}

Status RunTable::upload(Transfer& transfer, std::span<const gpu::PassConstants> constants,
                        std::span<const uint32_t> first_workgroups) {
    if (constants.empty()) return {};
    HMSM_TRY(reserve(uint32_t(constants.size())));
    HMSM_TRY(transfer.upload(current_.buffer, 0, constants.size_bytes(),
                             [&](void* staging, VkDeviceSize first, VkDeviceSize bytes) {
                                 std::memcpy(staging, reinterpret_cast<const std::byte*>(constants.data()) + first,
                                             bytes);
                             }));
    return transfer.upload(current_.buffer, current_.workgroups_offset, first_workgroups.size_bytes(),
                           [&](void* staging, VkDeviceSize first, VkDeviceSize bytes) {
                               std::memcpy(staging,
                                           reinterpret_cast<const std::byte*>(first_workgroups.data()) + first,
                                           bytes);
                           });
}

Status RunTable::stage(FrameRing& ring, std::span<const gpu::PassConstants> constants,
                       std::span<const uint32_t> first_workgroups) {
    if (constants.empty()) return {};
    HMSM_TRY(reserve(uint32_t(constants.size())));
    auto staged = ring.stage(current_.buffer.handle(), 0, constants.size_bytes());
    if (!staged) return staged.status();
    std::memcpy(*staged, constants.data(), constants.size_bytes());
    staged = ring.stage(current_.buffer.handle(), current_.workgroups_offset, first_workgroups.size_bytes());
    if (!staged) return staged.status();
    std::memcpy(*staged, first_workgroups.data(), first_workgroups.size_bytes());
    return {};
}

}  // namespace vk
}  // namespace hmsm::detail
