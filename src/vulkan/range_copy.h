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
// record() then appends one dispatch (the first also copies the whole table to the device).
// In an engine's command buffer (record_steps), which may still be pending when the next call
// records, the *_in_frame calls stage the table rows (and a scatter's values) in the frame's ring
// slot (frame_ring.h), copied into device buffers of the copier's own ahead of the dispatch, and
// take descriptor sets from pools of that frame, reset when the ring comes round to it again.
#pragma once

#include "device_buffer.h"
#include "frame_ring.h"

#include "../backend.h"

#include <array>
#include <cstdint>
#include <functional>
#include <memory>
#include <span>
#include <vector>

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

/// The word spans of the range copy for `ranges` of a buffer of `element_bytes` elements,
/// packed back to back in the scratch from word 0: each range read from its place (`gather`)
/// or written to it (scatter). `packed` receives the words packed.
std::vector<WordSpan> packed_word_spans(std::span<const ElementRange> ranges, uint64_t element_bytes, bool gather,
                                         uint64_t& packed);

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

    /// The target of a pattern copy in a frame: the buffer, its elements' words, the words
    /// between its halves and its halves (as record_patterns takes them).
    struct PatternTarget {
        const Buffer* data = nullptr;
        uint32_t words_per_element = 0, half_words = 0, halves = 1;
    };
    /// record_patterns into an engine's command buffer, once per target, the rows staged in
    /// `ring`'s current slot. `recording` numbers the engine's recordings: the first call of a
    /// recording resets the frame's descriptor pools (the command buffer that used them, `ring`'s
    /// frames recordings ago, has completed). The caller orders the dispatches' writes before
    /// the work after them.
    Status record_patterns_in_frame(VkCommandBuffer cmd, FrameRing& ring, uint64_t recording,
                                    std::span<const PatternRow> entries, std::span<const PatternRow> moves,
                                    std::span<const PatternTarget> targets);
    /// A scatter into an engine's command buffer: `fill` writes the packed words (`words` in
    /// all, as the ranges pack them from 0) into the ring slot, whence they are copied into a
    /// device scratch of the copier's own and scattered to `ranges` of `data`.
    Status record_scatter_in_frame(VkCommandBuffer cmd, FrameRing& ring, uint64_t recording, const Buffer& data,
                                   std::span<const WordSpan> ranges, uint64_t words,
                                   const std::function<void(void*)>& fill);

    /// Dispatches recorded so far (a test hook).
    uint64_t dispatches() const { return dispatches_; }

private:
    explicit RangeCopier(const Device& device) : device_(device) {}
    /// Appends `rows` to the table (the first append of a prepare() also records the table's
    /// copy to the device); returns the index of their first row.
    Result<uint32_t> append_rows(VkCommandBuffer cmd, const void* rows, uint64_t count);
    /// A descriptor set of `data`, `packed` and the table.
    Result<VkDescriptorSet> descriptor_set(const Buffer& data, const Buffer& packed);
    /// A descriptor set of `data`, `packed` and `table` from `pool`.
    Result<VkDescriptorSet> allocate_set(VkDescriptorPool pool, const Buffer& data, const Buffer& packed,
                                         const Buffer& table);
    /// Binds `pipeline` and `set`, pushes `constants` (CopyConstants or PatternConstants, of one
    /// size) and dispatches `groups` workgroups (clamped to the device's limit) by `groups_y`.
    void dispatch(VkCommandBuffer cmd, VkPipeline pipeline, VkDescriptorSet set, const void* constants,
                  uint64_t groups, uint32_t groups_y);

    /// What the *_in_frame calls use of ring frame `ring.current()`: its pools reset for
    /// `recording`, the outgrown device buffers freed whose last recording has completed.
    struct Frame {
        std::vector<VkDescriptorPool> pools;  // sets of the frame's dispatches; the last has room
        uint32_t pool_used = 0;               // sets taken from pools.back()
        uint64_t recording = 0;
    };
    Result<Frame*> begin_in_frame(const FrameRing& ring, uint64_t recording);
    Result<VkDescriptorSet> frame_set(Frame& frame, const Buffer& data, const Buffer& packed, const Buffer& table);
    /// Makes `buffer` (device-local, storage and transfer destination) hold at least `bytes`;
    /// an outgrown one lives until `recording`'s command buffer has completed.
    Status ensure_frame_buffer(Buffer& buffer, VkDeviceSize bytes, uint64_t recording, const char* name);
    /// Stages `bytes` bytes of rows into the frame table and records the ring's copies, then a
    /// barrier that makes them visible to the dispatches.
    Status stage_frame_rows(VkCommandBuffer cmd, FrameRing& ring, uint64_t recording,
                            std::span<const std::pair<const void*, VkDeviceSize>> rows);

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
    std::array<Frame, kMaxFramesInFlight> frames_;
    Buffer frame_table_, frame_scratch_;  // the *_in_frame calls' table rows and scattered words
    std::vector<std::pair<uint64_t, Buffer>> outgrown_;  // (last recording using it, buffer)
};

}  // namespace hmsm::detail::vk
