#version 450
// Not a pass: the device-memory roofline of `hmsm bench` (src/vulkan/copy_bandwidth.cpp). A
// grid-stride copy of 16-byte words between two storage buffers, the access pattern of the
// passes themselves (every invocation loads and stores vec4s), as cudaMemcpy's device-to-device
// copy runs on the SMs.
layout(local_size_x = 256) in;
layout(std430, set = 0, binding = 0) readonly buffer Source { uvec4 source[]; };
layout(std430, set = 0, binding = 1) writeonly buffer Target { uvec4 target[]; };
layout(push_constant) uniform Count { uint words; } pc;

void main() {
    const uint stride = gl_NumWorkGroups.x * gl_WorkGroupSize.x;
    for (uint i = gl_GlobalInvocationID.x; i < pc.words; i += stride) target[i] = source[i];
}
