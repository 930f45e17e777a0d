#include "range_copy.h"

#include "pipelines.h"
#include "vk_error.h"

#include "hmsm_spirv/copy_patterns.h"
#include "hmsm_spirv/copy_ranges.h"

#include <algorithm>
#include <cstring>

namespace hmsm::detail::vk {
namespace {

constexpr uint32_t kCopyWorkgroupSize = 256;  // local_size_x of copy_ranges.comp
constexpr uint32_t kBindings = 3;             // data, packed, ranges

struct CopyConstants {
    uint32_t first_range, range_count, packed_begin, words, gather;
};
struct PatternConstants {
    uint32_t first_entry, entry_count, first_move, words_per_element, half_words;
};
static_assert(sizeof(PatternConstants) == sizeof(CopyConstants), "one push-constant range serves both");

}  // namespace

RangeCopier::~RangeCopier() {
    const VolkDeviceTable& vk = device_.vk();
    VkDevice dev = device_.handle();
    if (pipeline_) vk.vkDestroyPipeline(dev, pipeline_, nullptr);
    if (patterns_pipeline_) vk.vkDestroyPipeline(dev, patterns_pipeline_, nullptr);
    if (layout_) vk.vkDestroyPipelineLayout(dev, layout_, nullptr);
    if (pool_) vk.vkDestroyDescriptorPool(dev, pool_, nullptr);
    for (Frame& frame : frames_)
        for (VkDescriptorPool pool : frame.pools) vk.vkDestroyDescriptorPool(dev, pool, nullptr);
    if (set_layout_) vk.vkDestroyDescriptorSetLayout(dev, set_layout_, nullptr);
}

Result<std::unique_ptr<RangeCopier>> RangeCopier::create(const Device& device) {
    std::unique_ptr<RangeCopier> c(new RangeCopier(device));
    const VolkDeviceTable& vk = device.vk();
    VkDevice dev = device.handle();
    HMSM_TRY(storage_buffer_set_layout(device, kBindings, c->set_layout_));
    VkPushConstantRange push{VK_SHADER_STAGE_COMPUTE_BIT, 0, sizeof(CopyConstants)};
    VkPipelineLayoutCreateInfo layout_info{VK_STRUCTURE_TYPE_PIPELINE_LAYOUT_CREATE_INFO};
    layout_info.setLayoutCount = 1;
    layout_info.pSetLayouts = &c->set_layout_;
    layout_info.pushConstantRangeCount = 1;
    layout_info.pPushConstantRanges = &push;
    HMSM_VK_TRY(vk.vkCreatePipelineLayout(dev, &layout_info, nullptr, &c->layout_));
    auto pipeline = compute_pipeline(device, c->layout_, hmsm_spirv_copy_ranges);
    if (!pipeline) return pipeline.status();
    c->pipeline_ = *pipeline;
    auto patterns = compute_pipeline(device, c->layout_, hmsm_spirv_copy_patterns);
    if (!patterns) return patterns.status();
    c->patterns_pipeline_ = *patterns;
    return c;
}

Status RangeCopier::prepare(uint64_t ranges, uint32_t dispatches) {
    const VolkDeviceTable& vk = device_.vk();
    VkDevice dev = device_.handle();
    dispatches = std::max<uint32_t>(dispatches, 1);
    if (dispatches > pool_sets_) {
        const uint32_t sets = std::max(dispatches, 2 * pool_sets_);
        if (pool_) vk.vkDestroyDescriptorPool(dev, pool_, nullptr);
        pool_ = VK_NULL_HANDLE;
        pool_sets_ = 0;
        VkDescriptorPoolSize size{VK_DESCRIPTOR_TYPE_STORAGE_BUFFER, kBindings * sets};
        VkDescriptorPoolCreateInfo pool_info{VK_STRUCTURE_TYPE_DESCRIPTOR_POOL_CREATE_INFO};
        pool_info.maxSets = sets;
        pool_info.poolSizeCount = 1;
        pool_info.pPoolSizes = &size;
        HMSM_VK_TRY(vk.vkCreateDescriptorPool(dev, &pool_info, nullptr, &pool_));
        pool_sets_ = sets;
    } else {
        HMSM_VK_TRY(vk.vkResetDescriptorPool(dev, pool_, 0));
    }
    const VkDeviceSize bytes = std::max<uint64_t>(ranges, 1) * sizeof(WordSpan);
    if (table_host_.size() < bytes) {
        const VkDeviceSize grown = std::max(bytes, 2 * table_host_.size());
        table_host_ = Buffer{};
        table_device_ = Buffer{};
        auto host = Buffer::create(device_, grown, VK_BUFFER_USAGE_TRANSFER_SRC_BIT, MemoryUse::staging,
                                   "range copy table (host)");
        if (!host) return host.status();
        auto on_device = Buffer::create(device_, grown,
                                        VK_BUFFER_USAGE_TRANSFER_DST_BIT | VK_BUFFER_USAGE_STORAGE_BUFFER_BIT,
                                        MemoryUse::device_local, "range copy table");
        if (!on_device) return on_device.status();
        table_host_ = std::move(host).value();
        table_device_ = std::move(on_device).value();
    }
    table_used_ = 0;
    table_prepared_ = bytes;
    return {};
}

Result<uint32_t> RangeCopier::append_rows(VkCommandBuffer cmd, const void* rows, uint64_t count) {
    const VolkDeviceTable& vk = device_.vk();
    const VkDeviceSize first = table_used_ * sizeof(WordSpan), bytes = count * sizeof(WordSpan);
    if (first + bytes > table_prepared_)
        return Status{ErrorCode::internal, "vulkan: range copy table smaller than prepared"};
    std::memcpy(static_cast<std::byte*>(table_host_.mapped()) + first, rows, bytes);
    if (table_used_ == 0) {
        // The whole prepared table in one copy ahead of the first dispatch: the host has written
        // every entry by the time the submission runs.
        const VkBufferCopy region{0, 0, table_prepared_};
        vk.vkCmdCopyBuffer(cmd, table_host_.handle(), table_device_.handle(), 1, &region);
        VkMemoryBarrier table_ready{VK_STRUCTURE_TYPE_MEMORY_BARRIER};
        table_ready.srcAccessMask = VK_ACCESS_TRANSFER_WRITE_BIT;
        table_ready.dstAccessMask = VK_ACCESS_SHADER_READ_BIT;
        vk.vkCmdPipelineBarrier(cmd, VK_PIPELINE_STAGE_TRANSFER_BIT, VK_PIPELINE_STAGE_COMPUTE_SHADER_BIT, 0, 1,
                                &table_ready, 0, nullptr, 0, nullptr);
    }
    const uint32_t at = uint32_t(table_used_);
    table_used_ += count;
    return at;
}

Result<VkDescriptorSet> RangeCopier::descriptor_set(const Buffer& data, const Buffer& packed) {
    return allocate_set(pool_, data, packed, table_device_);
}

Result<VkDescriptorSet> RangeCopier::allocate_set(VkDescriptorPool pool, const Buffer& data, const Buffer& packed,
                                                  const Buffer& table) {
    const VolkDeviceTable& vk = device_.vk();
    VkDescriptorSet set = VK_NULL_HANDLE;
    VkDescriptorSetAllocateInfo allocate{VK_STRUCTURE_TYPE_DESCRIPTOR_SET_ALLOCATE_INFO};
    allocate.descriptorPool = pool;
    allocate.descriptorSetCount = 1;
    allocate.pSetLayouts = &set_layout_;
    HMSM_VK_TRY(vk.vkAllocateDescriptorSets(device_.handle(), &allocate, &set));
    const VkDescriptorBufferInfo buffers[kBindings] = {
        {data.handle(), 0, VK_WHOLE_SIZE}, {packed.handle(), 0, VK_WHOLE_SIZE}, {table.handle(), 0, VK_WHOLE_SIZE}};
    VkWriteDescriptorSet write{VK_STRUCTURE_TYPE_WRITE_DESCRIPTOR_SET};
    write.dstSet = set;
    write.descriptorCount = kBindings;
    write.descriptorType = VK_DESCRIPTOR_TYPE_STORAGE_BUFFER;
    write.pBufferInfo = buffers;
    vk.vkUpdateDescriptorSets(device_.handle(), 1, &write, 0, nullptr);
    return set;
}

Status RangeCopier::record(VkCommandBuffer cmd, const Buffer& data, const Buffer& packed,
                           std::span<const WordSpan> ranges, bool gather) {
    if (ranges.empty()) return {};
    Result<uint32_t> first = append_rows(cmd, ranges.data(), ranges.size());
    if (!first) return first.status();
    Result<VkDescriptorSet> set = descriptor_set(data, packed);
    if (!set) return set.status();
    const uint64_t words = uint64_t(ranges.back().packed) + ranges.back().words - ranges.front().packed;
    const CopyConstants constants{*first, uint32_t(ranges.size()), ranges.front().packed, uint32_t(words),
                                  gather ? 1u : 0u};
    dispatch(cmd, pipeline_, *set, &constants, (words + kCopyWorkgroupSize - 1) / kCopyWorkgroupSize, 1);
    return {};
}

void RangeCopier::dispatch(VkCommandBuffer cmd, VkPipeline pipeline, VkDescriptorSet set, const void* constants,
                           uint64_t groups, uint32_t groups_y) {
    const VolkDeviceTable& vk = device_.vk();
    vk.vkCmdBindPipeline(cmd, VK_PIPELINE_BIND_POINT_COMPUTE, pipeline);
    vk.vkCmdBindDescriptorSets(cmd, VK_PIPELINE_BIND_POINT_COMPUTE, layout_, 0, 1, &set, 0, nullptr);
    vk.vkCmdPushConstants(cmd, layout_, VK_SHADER_STAGE_COMPUTE_BIT, 0, sizeof(CopyConstants), constants);
    const uint64_t most = std::min<uint64_t>(65535, device_.limits().max_workgroup_count[0]);
    vk.vkCmdDispatch(cmd, uint32_t(std::clamp<uint64_t>(groups, 1, most)), groups_y, 1);
    ++dispatches_;
}

Status RangeCopier::record_patterns(VkCommandBuffer cmd, const Buffer& data, std::span<const PatternRow> entries,
                                    std::span<const PatternRow> moves, uint32_t words_per_element,
                                    uint32_t half_words, uint32_t halves) {
    if (entries.empty() || moves.empty()) return {};
    Result<uint32_t> first_entry = append_rows(cmd, entries.data(), entries.size());
    if (!first_entry) return first_entry.status();
    Result<uint32_t> first_move = append_rows(cmd, moves.data(), moves.size());
    if (!first_move) return first_move.status();
    Result<VkDescriptorSet> set = descriptor_set(data, data);  // binding 1 is not read
    if (!set) return set.status();
    const PatternConstants constants{*first_entry, uint32_t(entries.size()), *first_move, words_per_element,
                                     half_words};
    dispatch(cmd, patterns_pipeline_, *set, &constants, entries.size(), halves);
    return {};
}

std::vector<WordSpan> packed_word_spans(std::span<const ElementRange> ranges, uint64_t element_bytes, bool gather,
                                   uint64_t& packed) {
    std::vector<WordSpan> spans;
    packed = 0;
    for (const ElementRange& r : ranges) {
        if (r.count == 0) continue;
        const auto words = uint32_t(r.count * element_bytes / 4), at = uint32_t(r.first * element_bytes / 4);
        spans.push_back({uint32_t(packed), words, gather ? at : 0, gather ? 0 : at});
        packed += words;
    }
    return spans;
}

// --- In an engine's command buffer ---------------------------------------------------------

Result<RangeCopier::Frame*> RangeCopier::begin_in_frame(const FrameRing& ring, uint64_t recording) {
    Frame& frame = frames_[ring.current()];
    if (frame.recording != recording) {
        // The command buffer that used this frame's sets, ring.frames() recordings ago, has
        // completed (the ring's rule), and so has every one before it.
        const VolkDeviceTable& vk = device_.vk();
        for (VkDescriptorPool pool : frame.pools) HMSM_VK_TRY(vk.vkResetDescriptorPool(device_.handle(), pool, 0));
        if (frame.pools.size() > 1) {  // keep one pool
            for (size_t k = 0; k + 1 < frame.pools.size(); ++k)
                vk.vkDestroyDescriptorPool(device_.handle(), frame.pools[k], nullptr);
            frame.pools.erase(frame.pools.begin(), frame.pools.end() - 1);
        }
        frame.pool_used = 0;
        frame.recording = recording;
        std::erase_if(outgrown_, [&](const auto& o) { return o.first + ring.frames() <= recording; });
    }
    return &frame;
}

Result<VkDescriptorSet> RangeCopier::frame_set(Frame& frame, const Buffer& data, const Buffer& packed,
                                               const Buffer& table) {
    const VolkDeviceTable& vk = device_.vk();
    constexpr uint32_t kSetsPerPool = 64;
    if (frame.pools.empty() || frame.pool_used == kSetsPerPool) {
        VkDescriptorPoolSize size{VK_DESCRIPTOR_TYPE_STORAGE_BUFFER, kBindings * kSetsPerPool};
        VkDescriptorPoolCreateInfo pool_info{VK_STRUCTURE_TYPE_DESCRIPTOR_POOL_CREATE_INFO};
        pool_info.maxSets = kSetsPerPool;
        pool_info.poolSizeCount = 1;
        pool_info.pPoolSizes = &size;
        VkDescriptorPool pool = VK_NULL_HANDLE;
        HMSM_VK_TRY(vk.vkCreateDescriptorPool(device_.handle(), &pool_info, nullptr, &pool));
        frame.pools.push_back(pool);
        frame.pool_used = 0;
    }
    Result<VkDescriptorSet> set = allocate_set(frame.pools.back(), data, packed, table);
    if (set) ++frame.pool_used;
    return set;
}

Status RangeCopier::ensure_frame_buffer(Buffer& buffer, VkDeviceSize bytes, uint64_t recording, const char* name) {
    if (buffer.handle() && buffer.size() >= bytes) return {};
    const VkDeviceSize grown = std::max<VkDeviceSize>({bytes, 2 * buffer.size(), VkDeviceSize(64) << 10});
    if (buffer.handle()) outgrown_.emplace_back(recording, std::move(buffer));
    auto made = Buffer::create(device_, grown, VK_BUFFER_USAGE_TRANSFER_DST_BIT | VK_BUFFER_USAGE_STORAGE_BUFFER_BIT,
                               MemoryUse::device_local, name);
    if (!made) return made.status();
    buffer = std::move(made).value();
    return {};
}

Status RangeCopier::stage_frame_rows(VkCommandBuffer cmd, FrameRing& ring, uint64_t recording,
                                     std::span<const std::pair<const void*, VkDeviceSize>> rows) {
    VkDeviceSize bytes = 0;
    for (const auto& [src, size] : rows) bytes += size;
    HMSM_TRY(ensure_frame_buffer(frame_table_, bytes, recording, "range copy table (frames)"));
    VkDeviceSize at = 0;
    for (const auto& [src, size] : rows) {
        if (size == 0) continue;
        Result<void*> staged = ring.stage(frame_table_.handle(), at, size);
        if (!staged) return staged.status();
        std::memcpy(*staged, src, size);
        at += size;
    }
    // The ring's copies behind earlier work on their destinations (an earlier dispatch of this
    // recording or of one before may still read the table), then visible to the dispatches,
    // which also write where copies staged before them (other writes of the frame) may have.
    ring.record_copies(cmd);
    VkMemoryBarrier ready{VK_STRUCTURE_TYPE_MEMORY_BARRIER};
    ready.srcAccessMask = VK_ACCESS_TRANSFER_WRITE_BIT;
    ready.dstAccessMask = VK_ACCESS_SHADER_READ_BIT | VK_ACCESS_SHADER_WRITE_BIT;
    device_.vk().vkCmdPipelineBarrier(cmd, VK_PIPELINE_STAGE_TRANSFER_BIT, VK_PIPELINE_STAGE_COMPUTE_SHADER_BIT, 0, 1,
                                      &ready, 0, nullptr, 0, nullptr);
    return {};
}

Status RangeCopier::record_patterns_in_frame(VkCommandBuffer cmd, FrameRing& ring, uint64_t recording,
                                             std::span<const PatternRow> entries, std::span<const PatternRow> moves,
                                             std::span<const PatternTarget> targets) {
    if (entries.empty() || moves.empty() || targets.empty()) return {};
    Result<Frame*> frame = begin_in_frame(ring, recording);
    if (!frame) return frame.status();
    const std::pair<const void*, VkDeviceSize> rows[] = {{entries.data(), entries.size_bytes()},
                                                         {moves.data(), moves.size_bytes()}};
    HMSM_TRY(stage_frame_rows(cmd, ring, recording, rows));
    for (const PatternTarget& t : targets) {  // the targets are apart: no barrier between them
        Result<VkDescriptorSet> set = frame_set(**frame, *t.data, *t.data, frame_table_);  // binding 1 unread
        if (!set) return set.status();
        const PatternConstants constants{0, uint32_t(entries.size()), uint32_t(entries.size()), t.words_per_element,
                                         t.half_words};
        dispatch(cmd, patterns_pipeline_, *set, &constants, entries.size(), t.halves);
    }
    return {};
}

Status RangeCopier::record_scatter_in_frame(VkCommandBuffer cmd, FrameRing& ring, uint64_t recording,
                                            const Buffer& data, std::span<const WordSpan> ranges, uint64_t words,
                                            const std::function<void(void*)>& fill) {
    if (ranges.empty() || words == 0) return {};
    Result<Frame*> frame = begin_in_frame(ring, recording);
    if (!frame) return frame.status();
    HMSM_TRY(ensure_frame_buffer(frame_scratch_, words * 4, recording, "range copy scratch (frames)"));
    Result<void*> values = ring.stage(frame_scratch_.handle(), 0, words * 4);
    if (!values) return values.status();
    fill(*values);
    const std::pair<const void*, VkDeviceSize> rows[] = {{ranges.data(), ranges.size_bytes()}};
    HMSM_TRY(stage_frame_rows(cmd, ring, recording, rows));  // records the values' copy too
    Result<VkDescriptorSet> set = frame_set(**frame, data, frame_scratch_, frame_table_);
    if (!set) return set.status();
    const CopyConstants constants{0, uint32_t(ranges.size()), ranges.front().packed, uint32_t(words), 0u};
    dispatch(cmd, pipeline_, *set, &constants, (words + kCopyWorkgroupSize - 1) / kCopyWorkgroupSize, 1);
    return {};
}

}  // namespace hmsm::detail::vk
