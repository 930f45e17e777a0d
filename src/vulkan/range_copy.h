// The range copies of the Vulkan backend's batched moves (move_buffers, move_elements outside an
// engine's recording: level-of-detail switches, fades, swap removals): a compute dispatch of
// shaders/glsl/copy_ranges.comp gathers many ranges of a buffer into a packed device scratch or
// scatters them back, as the CUDA backend's copy_ranges kernel does. A copy command with a region
// per range costs about 2-5 microseconds per region on an H100 (measured: docs/vulkan.md).
// The same copier runs copy_patterns.comp (Backend::copy_patterns: a level switch's kept chains
// by pattern, a workgroup per copy), and reads and writes of many ranges (a gather into the
// scratch and one download, or one upload into it and a scatter; HMSM_VULKAN_SHADER_RANGES=0
// keeps a copy region per range).
//
// Use within one submission that is waited for before the next: prepare() sizes the range table
// and the descriptor sets for the dispatches to come and forgets those of the submission before;
// record() then appends one dispatch (the first also copies the whole table to the device). Not
// for an engine's command buffer, which may still be pending when the next call prepares (those
// keep copy commands, deferred_changes.cpp).
#pragma once

#include "device_buffer.h"

#include <cstdint>
#include <memory>
#include <span>

namespace hmsm::detail::vk {

/// One range, in 32-bit words: packed words [packed, packed + words) are `data` words
/// [source, source + words) when gathered and go to [target, target + words) when scattered.
struct WordSpan {
    uint32_t packed = 0, words = 0, source = 0, target = 0;
};
/// One row of a pattern copy's table (shaders/glsl/copy_patterns.comp), in elements: an entry
/// (src, dst, first move, move count) or a move (src, dst, count, 0). As large as a WordSpan,
/// so that both kinds share the table.
struct PatternRow {
    uint32_t x = 0, y = 0, z = 0, w = 0;
};
static_assert(sizeof(PatternRow) == sizeof(WordSpan));

class RangeCopier {
public:
    static Result<std::unique_ptr<RangeCopier>> create(const Device& device);
    ~RangeCopier();

    /// Makes room for `dispatches` record() calls with `ranges` entries in all, and forgets the
    /// earlier ones (their submission has finished).
    Status prepare(uint64_t ranges, uint32_t dispatches);
    /// Records a dispatch copying every word of `ranges` (packed ascending, back to back from
    /// ranges[0].packed) between `data` and `packed`: gather (data to packed) or scatter. The
    /// caller orders it with barriers (compute stage, shader read and write access).
    Status record(VkCommandBuffer cmd, const Buffer& data, const Buffer& packed, std::span<const WordSpan> ranges,
                  bool gather);

    /// Records a dispatch of copy_patterns.comp over `data`: `entries` copies, their moves
    /// `moves` (PatternRow), each in `halves` halves `half_words` words apart, elements of
    /// `words_per_element` words. prepare() counts the entries and moves as ranges.
    Status record_patterns(VkCommandBuffer cmd, const Buffer& data, std::span<const PatternRow> entries,
                           std::span<const PatternRow> moves, uint32_t words_per_element, uint32_t half_words,
                           uint32_t halves);

    /// Dispatches recorded so far (a test hook).
    uint64_t dispatches() const { return dispatches_; }

private:
    explicit RangeCopier(const Device& device) : device_(device) {}
    /// Appends `rows` to the table (the first append of a prepare() also records the table's
    /// copy to the device); returns the index of their first row.
    Result<uint32_t> append_rows(VkCommandBuffer cmd, const void* rows, uint64_t count);
    /// A descriptor set of `data`, `packed` and the table.
    Result<VkDescriptorSet> descriptor_set(const Buffer& data, const Buffer& packed);

    const Device& device_;
    VkDescriptorSetLayout set_layout_ = VK_NULL_HANDLE;
    VkPipelineLayout layout_ = VK_NULL_HANDLE;
    VkPipeline pipeline_ = VK_NULL_HANDLE;
    VkPipeline patterns_pipeline_ = VK_NULL_HANDLE;  // copy_patterns.comp, the same layout
    VkDescriptorPool pool_ = VK_NULL_HANDLE;
    uint32_t pool_sets_ = 0;
    Buffer table_host_;    // the WordSpans of the dispatches since prepare(), written by the host
    Buffer table_device_;  // their copy the dispatches read (device-local: each word bisects it)
    uint64_t table_used_ = 0;          // entries recorded since prepare()
    VkDeviceSize table_prepared_ = 0;  // bytes prepare() made room for
    uint64_t dispatches_ = 0;
};

}  // namespace hmsm::detail::vk
