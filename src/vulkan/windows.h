// Buffer windows: how the Vulkan backend runs scenes whose state buffers exceed
// maxStorageBufferRange (128 MiB on lavapipe, 4 GiB on most GPUs) although one descriptor can
// bind no more than that. The step program (simulation.cpp) is unchanged; the split lives here.
//
// The scene's instances are cut into segments: runs of consecutive instances whose elements,
// in every state and instance-scope buffer, lie inside one window that one descriptor can bind.
// Each segment has its own descriptor set (the static model buffers bound whole, every other
// buffer bound at the segment's window), and the recorder records a dispatch as one part per
// segment that the dispatch's instance group overlaps, with the part's *_begin constants
// rebased to the window start. Window starts are aligned down to minStorageBufferOffsetAlignment
// (in elements of every buffer of the scope), so a window may begin a few elements before the
// segment's first instance: the rebased *_begin simply stays positive.
//
// The ping-pong buffers chain_rotation and chain_origin hold two halves of total_chains elements
// (the shaders address half h at h * total_chains). A window over both halves of a segment would
// span the whole first half, so in a split scene these two buffers are stored segment-major: the
// segment's region holds half 0 then half 1, each `halves_stride` elements, and the part's
// total_chains constant is set to that stride. Shaders are unchanged. read()/write() map
// logical elements (half * total_chains + chain) to this layout. With one segment (every buffer
// within the range) the layout and the constants are exactly those of an unsplit scene.
//
// Parts of one dispatch touch disjoint elements but their windows may overlap by the alignment
// slack, so the recorder keeps separating them by barriers as it does dispatches of different
// instance groups.
#pragma once

#include "device.h"
#include "device_buffer.h"

#include "../backend.h"

#include <array>
#include <cstdint>
#include <functional>
#include <memory>
#include <span>
#include <string>
#include <unordered_map>
#include <vector>

namespace hmsm::detail {
/// Test hook: backends created afterwards use windows of at most `bytes` (0: the device's
/// maxStorageBufferRange), so the splitting path runs on small scenes, and align window starts
/// to a multiple of `alignment` bytes as well as minStorageBufferOffsetAlignment (0: that
/// alone), so a device with a small alignment exercises the slack of one with a large one.
/// The environment variable HMSM_VULKAN_WINDOW_BYTES sets the window when the hook does not.
void vulkan_set_window_bytes(uint64_t bytes, uint64_t alignment = 0);
}  // namespace hmsm::detail

namespace hmsm::detail::vk {

/// Per-scope element ranges of a segment: [begin, end) are the segment's own elements, base
/// <= begin the window start (aligned).
struct ScopeWindow {
    uint64_t base = 0, begin = 0, end = 0;
};

struct Segment {
    uint32_t instance_begin = 0, instance_end = 0;
    ScopeWindow instance, chain, node, vertex;
    /// Ping-pong region: first physical element and elements per half (the parts' total_chains).
    uint64_t halves_base = 0, halves_stride = 0;
};

/// The segments of a scene and the physical layout they imply.
class WindowPlan {
public:
    /// `window_bytes`: the most one descriptor may bind; `alignment`:
    /// minStorageBufferOffsetAlignment. Fails (unsupported) when one instance alone does not fit
    /// a window, naming the instance, the buffer and the sizes.
    static Result<WindowPlan> build(const SceneData& scene, uint64_t window_bytes, uint64_t alignment,
                                    const std::string& device_name);

    /// Whether the scene is bound in windows: not the one capacity-wide window. A plan of one
    /// segment is split too where the capacity does not fit a window but the live instances
    /// do: its ping-pong halves are as long as its chains, not the capacity.
    bool split() const { return windowed_; }
    /// Chains per ping-pong half that have a physical place: the capacity unsplit, else the
    /// live chains the segments cover.
    uint64_t mapped_chains() const { return windowed_ ? segments_.back().chain.end : total_chains_; }
    const std::vector<Segment>& segments() const { return segments_; }
    uint64_t window_bytes() const { return window_bytes_; }

    /// Elements to allocate for buffer `id` (more than the logical count for the ping-pong
    /// buffers of a split scene).
    uint64_t physical_elements(BufferId id, const SceneData& scene) const;

    /// A contiguous piece of a logical element range: `count` elements from logical `first`
    /// lie at physical element `physical`.
    struct Piece {
        uint64_t logical, physical, count;
    };
    /// The physical pieces of logical elements [first, first + count) of `id`, in order.
    std::vector<Piece> pieces(BufferId id, uint64_t first, uint64_t count) const;

    /// The (descriptor range) window of `id` in segment `s`: byte offset and size; size 0 for
    /// the static model buffers (bound whole).
    struct Range {
        uint64_t offset = 0, bytes = 0;
    };
    Range window(BufferId id, uint32_t s) const;

    /// A dispatch of the program as recorded: the whole dispatch (unsplit scene) or its part in
    /// one segment, with rebased constants; `last` marks the last part of a dispatch.
    struct Part {
        Dispatch dispatch;
        uint32_t segment = 0;
        bool last = true;
    };
    /// The parts of every dispatch of `program`, in order (a dispatch without threads keeps one
    /// part, so that every dispatch has a last part).
    std::vector<Part> expand(std::span<const Dispatch> program) const;

    /// Calls part(segment, constants) for every piece of `d` inside one segment, in instance
    /// order, with the constants rebased to the segment's windows.
    template <class Part>
    void for_each_part(const Dispatch& d, Part&& part) const {
        if (!split()) {
            part(0u, d.constants);
            return;
        }
        for_each_part_split(d, [&](uint32_t s, const gpu::PassConstants& c) { part(s, c); });
    }

private:
    void for_each_part_split(const Dispatch& d,
                             const std::function<void(uint32_t, const gpu::PassConstants&)>& part) const;
    /// Instances of the dispatch's group (from the scene's groups by instance_begin).
    uint32_t dispatch_instances(const Dispatch& d) const;

    std::vector<Segment> segments_;
    bool windowed_ = false;
    std::unordered_map<uint32_t, uint32_t> group_instances_;  // group instance_begin -> count
    uint64_t window_bytes_ = 0;
    uint64_t total_chains_ = 0;
    uint64_t physical_halves_ = 0;
};

/// One descriptor set per segment over the backend's buffers.
class WindowSets {
public:
    static Result<std::unique_ptr<WindowSets>> create(const Device& device, VkDescriptorSetLayout layout,
                                                      const WindowPlan& plan,
                                                      std::span<const Buffer, kBufferCount> buffers);
    ~WindowSets();
    VkDescriptorSet set(uint32_t segment) const { return sets_[segment]; }

private:
    explicit WindowSets(const Device& device) : device_(device) {}
    const Device& device_;
    VkDescriptorPool pool_ = VK_NULL_HANDLE;
    std::vector<VkDescriptorSet> sets_;
};

/// The window size asked for by vulkan_set_window_bytes() or HMSM_VULKAN_WINDOW_BYTES; 0: none.
uint64_t requested_window_bytes();
/// The alignment asked for by vulkan_set_window_bytes(); 0: none.
uint64_t requested_window_alignment();

/// What the recorder binds: the plan and its descriptor sets.
struct Windows {
    const WindowPlan& plan;
    const WindowSets& sets;
};

}  // namespace hmsm::detail::vk
