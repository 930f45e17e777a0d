#version 450
// The engine's skinning vertex shader: linear-blend skinning of the bind pose from hmsm's
// joint matrices (docs/skinning.md), read straight from the simulation's device buffer.
// Joint matrix c is [R_c | O_c] as three vec4 rows; a GLSL mat3x4 read from it has the rows as
// its columns, so M (p, 1) is vec4(p, 1.0) * M.
layout(set = 0, binding = 0, std430) readonly buffer Joints { mat3x4 joints[]; };
layout(set = 0, binding = 1, std430) readonly buffer InverseBinds { mat3x4 inverse_binds[]; };
// The skinned positions, written out so the engine can check them against the CPU.
layout(set = 0, binding = 2, std430) writeonly buffer Skinned { vec4 skinned[]; };

layout(push_constant) uniform Camera { mat4 view_proj; } camera;

layout(location = 0) in vec3 bind_position;
layout(location = 1) in ivec2 joint_ids;
layout(location = 2) in vec2 weights;

void main() {
    vec3 p = vec3(0.0);
    for (int j = 0; j < 2; ++j) {
        if (joint_ids[j] < 0 || weights[j] == 0.0) continue;
        vec3 local = vec4(bind_position, 1.0) * inverse_binds[joint_ids[j]];
        p += weights[j] * (vec4(local, 1.0) * joints[joint_ids[j]]);
    }
    skinned[gl_VertexIndex] = vec4(p, 1.0);
    gl_Position = camera.view_proj * vec4(p, 1.0);
}
