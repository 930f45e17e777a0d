#version 450
// Not a pass: the pattern copies of the Vulkan backend (Backend::copy_patterns,
// src/vulkan/range_copy.h), as kernels/cuda/copy_ranges.cu's copy_patterns_kernel does them on
// CUDA. A workgroup per copy (a grid-stride loop beyond the grid) and per half of a ping-pong
// buffer (the y of the grid); its invocations take the words of each of the copy's moves in
// turn. No copy writes what another reads or writes, so they need no order.
layout(local_size_x = 256) in;
layout(std430, set = 0, binding = 0) buffer Data { uint data[]; };
// Entries (src, dst, first move, move count) from first_entry on, then the patterns' moves
// (src, dst, count, 0) from first_move on; in elements of words_per_element words.
layout(std430, set = 0, binding = 2) readonly buffer Table { uvec4 table[]; };
layout(push_constant) uniform Copy {
    uint first_entry;
    uint entry_count;
    uint first_move;
    uint words_per_element;
    uint half_words;  // words from one half of the buffer to the next
} pc;

void main() {
    const uint half_offset = gl_WorkGroupID.y * pc.half_words;
    for (uint e = gl_WorkGroupID.x; e < pc.entry_count; e += gl_NumWorkGroups.x) {
        const uvec4 entry = table[pc.first_entry + e];
        for (uint k = 0; k < entry.w; ++k) {
            const uvec4 m = table[pc.first_move + entry.z + k];
            const uint src = half_offset + (entry.x + m.x) * pc.words_per_element;
            const uint dst = half_offset + (entry.y + m.y) * pc.words_per_element;
            const uint words = m.z * pc.words_per_element;
            for (uint w = gl_LocalInvocationID.x; w < words; w += gl_WorkGroupSize.x) data[dst + w] = data[src + w];
        }
    }
}
