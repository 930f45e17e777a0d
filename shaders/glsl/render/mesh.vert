#version 450
// Branch mesh and leaf cards straight from the simulation's vertex buffers (vec4 position and
// normal per vertex, or in the packed vertex layout the normal octahedral-encoded in the
// position's w), and the same geometry flattened onto the ground along the sun for shadows.
#extension GL_GOOGLE_include_directive : require
#include "render_common.glsl"
#include "octahedral.glsl"  // shaders/glsl/octahedral.glsl

// The same positions as a storage buffer: a leaf vertex finds its card's centre there.
layout(set = 0, binding = 1, std430) readonly buffer Positions { vec4 positions[]; };

layout(location = 0) in vec4 in_position;
layout(location = 1) in vec4 in_normal;

layout(location = 0) out vec3 v_world;
layout(location = 1) out vec3 v_normal;
layout(location = 2) out vec2 v_card;         // leaf-card coordinates in [-1, 1]^2
layout(location = 3) flat out float v_tint;   // per-leaf (or per-instance) variation

void main() {
    vec3 p = in_position.xyz;
    bool leaf = draw.mode == MODE_LEAF || draw.mode == MODE_SHADOW_LEAF;
    v_card = vec2(0.0);
    v_tint = hash01(uint(draw.instance) * 2654435761u + 17u);
    if (leaf) {
        // Corners are written (-r,-u), (+r,-u), (+r,+u), (-r,+u) per card (src/model/mesh.cpp).
        int k = gl_VertexIndex - draw.leaf_first;
        int corner = k & 3;
        v_card = vec2((corner == 1 || corner == 2) ? 1.0 : -1.0, corner >= 2 ? 1.0 : -1.0);
        v_tint = hash01(uint(k >> 2) * 2246822519u + uint(draw.instance) * 3266489917u);
        if (frame.scale.y != 1.0) {
            // Enlarge the card about its centre (the midpoint of corners 0 and 2): leaves of
            // real size are smaller than a pixel in a small picture of a whole tree.
            int first = gl_VertexIndex - corner;
            vec3 centre = 0.5 * (positions[first].xyz + positions[first + 2].xyz);
            p = centre + (p - centre) * frame.scale.y;
        }
    }
    if (draw.mode >= MODE_SHADOW_BARK) {
        // Planar projection along the sun onto a plane slightly above the ground.
        float height = max(p.y - frame.ground.x, 0.0);
        p -= frame.sun.xyz * (height / max(frame.sun.y, 0.05));
        p.y = frame.ground.x + frame.ground.y;
    }
    v_world = p;
    v_normal = (draw.flags & FLAG_PACKED_NORMALS) != 0
                   ? oct_decode(unpackSnorm2x16(floatBitsToUint(in_position.w)))
                   : in_normal.xyz;
    gl_Position = frame.view_proj * vec4(p, 1.0);
}
