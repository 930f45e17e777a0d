#version 450
// Not a pass: the range copies of the Vulkan backend's moves (src/vulkan/range_copy.h), as
// kernels/cuda/copy_ranges.cu does them on CUDA. One invocation per 32-bit word of the packed
// side, a grid-stride loop beyond the grid: gather copies words of many ranges of `data` into
// `packed` back to back, scatter the reverse. A copy command of many regions costs microseconds
// per region on some drivers; this costs the words.
layout(local_size_x = 256) in;
layout(std430, set = 0, binding = 0) buffer Data { uint data[]; };
layout(std430, set = 0, binding = 1) buffer Packed { uint packed[]; };
// Per range (packed, words, source, target), in words: packed words [packed, packed + words)
// are data words [source, ...) when gathered and go to [target, ...) when scattered; `packed`
// ascends over the dispatch's ranges.
layout(std430, set = 0, binding = 2) readonly buffer Ranges { uvec4 ranges[]; };
layout(push_constant) uniform Copy {
    uint first_range;   // the dispatch's first entry of `ranges`
    uint range_count;
    uint packed_begin;  // the first packed word of the dispatch
    uint words;         // packed words of the dispatch
    uint gather;        // 1: data to packed, 0: packed to data
} pc;

void main() {
    const uint stride = gl_NumWorkGroups.x * gl_WorkGroupSize.x;
    for (uint i = gl_GlobalInvocationID.x; i < pc.words; i += stride) {
        const uint t = pc.packed_begin + i;
        uint low = 0, high = pc.range_count;  // the last range whose packed <= t
        while (high - low > 1) {
            const uint middle = low + (high - low) / 2;
            if (ranges[pc.first_range + middle].x <= t) low = middle;
            else high = middle;
        }
        const uvec4 r = ranges[pc.first_range + low];
        if (pc.gather != 0) packed[t] = data[r.z + (t - r.x)];
        else data[r.w + (t - r.x)] = packed[t];
    }
}
