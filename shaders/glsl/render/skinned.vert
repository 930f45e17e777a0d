#version 450
// `hmsm render --draw skinned`: each model's bind-pose mesh, skinned here from the joint
// matrices with shaders/glsl/skinning.glsl; otherwise as mesh.vert (leaf cards enlarged about
// their centres, planar shadows). No vertex attributes: gl_VertexIndex (the draw's vertex
// offset is the model's first bind vertex) indexes the bind mesh.
#extension GL_GOOGLE_include_directive : require
#include "render_common.glsl"

struct SkinVertex {
    vec4 position;  // xyz: bind position, w: weight of joints.x
    vec4 normal;    // xyz: bind normal, w: weight of joints.y
    ivec4 joints;   // model chain ids (y = -1: one joint)
};
layout(set = 0, binding = 2, std430) readonly buffer SkinVertices { SkinVertex skin[]; };
// Per model chain [B^T | -B^T p_attach] and per instance chain [R | O], three rows each.
layout(set = 0, binding = 3, std430) readonly buffer InverseBinds { mat3x4 inverse_binds[]; };
layout(set = 0, binding = 4, std430) readonly buffer Joints { mat3x4 hmsm_joints[]; };

#define HMSM_JOINT(i) hmsm_joints[i]
#define HMSM_INVERSE_BIND(i) inverse_binds[uint(draw.bind_base) + (i)]
#include "skinning.glsl"  // shaders/glsl/skinning.glsl

layout(location = 0) out vec3 v_world;
layout(location = 1) out vec3 v_normal;
layout(location = 2) out vec2 v_card;         // leaf-card coordinates in [-1, 1]^2
layout(location = 3) flat out float v_tint;   // per-leaf (or per-instance) variation

vec3 skinned(int index, out vec3 normal) {
    SkinVertex v = skin[index];
    return hmsm_skin(v.position.xyz, v.normal.xyz, v.joints.xy, vec2(v.position.w, v.normal.w),
                     uint(draw.chain_base), normal);
}

void main() {
    vec3 n;
    vec3 p = skinned(gl_VertexIndex, n);
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
            // Enlarge the card about its centre, the midpoint of its skinned corners 0 and 2.
            int first = gl_VertexIndex - corner;
            vec3 unused;
            vec3 centre = 0.5 * (skinned(first, unused) + skinned(first + 2, unused));
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
    v_normal = n;
    gl_Position = frame.view_proj * vec4(p, 1.0);
}
