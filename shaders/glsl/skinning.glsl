// Linear-blend skinning from hmsm's joint matrices (docs/skinning.md; docs/model.md 3.10).
// Include it in a vertex shader after declaring the palette, e.g.
//
//   layout(set = 0, binding = 0, std430) readonly buffer Joints { mat3x4 hmsm_joints[]; };
//   #define HMSM_JOINT(i) hmsm_joints[i]
//   #include "skinning.glsl"
//
// The palette is hmsm's joint-matrix buffer as it is (hmsm::vulkan::SharedBuffers::
// joint_matrices, hmsm::cuda::DeviceOutputs::joint_matrices, or Output::joint_matrices
// uploaded): per chain M_c = [R_c | O_c] as three vec4 rows (R row i, O_i), instance-major,
// chains in chain order, 48 bytes each. A GLSL mat3x4 read from it has the rows as its
// columns, so M (p, 1) is `vec4(p, 1.0) * m` and R n is `vec4(n, 0.0) * m`.
//
// Per vertex (hmsm::SkinTemplate): the bind position and normal (rest pose of an instance at
// the origin with yaw 0), up to two joints of the vertex's model and their weights. Per model
// chain: the inverse bind matrix [B_c^T | -B_c^T p̄_attach(c)], laid out like a joint matrix
// (an engine may instead store each vertex in its joints' local frames and skip it; this
// snippet keeps the bind pose and applies the inverse bind matrix, as glTF does).
#ifndef HMSM_SKINNING_GLSL
#define HMSM_SKINNING_GLSL

#ifndef HMSM_JOINT
#error "define HMSM_JOINT(i) to read joint matrix i (a mat3x4 of rows) before including skinning.glsl"
#endif
#ifndef HMSM_INVERSE_BIND
#error "define HMSM_INVERSE_BIND(i) to read the inverse bind matrix of model chain i (a mat3x4 of rows)"
#endif

/// M (p, 1) for a joint matrix stored as rows.
vec3 hmsm_transform_point(mat3x4 rows, vec3 p) { return vec4(p, 1.0) * rows; }
/// R n for the rotation part.
vec3 hmsm_transform_vector(mat3x4 rows, vec3 n) { return vec4(n, 0.0) * rows; }

/// Skins one vertex: `joints` are model chain ids (a second joint < 0 or a zero weight is
/// skipped), `chain_base` the instance's first chain in the palette (instance-major:
/// the sum of the chain counts of the instances before it). Returns the world position; the
/// world normal (unit) goes to `normal_out`.
vec3 hmsm_skin(vec3 bind_position, vec3 bind_normal, ivec2 joints, vec2 weights, uint chain_base,
               out vec3 normal_out) {
    vec3 p = vec3(0.0), n = vec3(0.0);
    for (int j = 0; j < 2; ++j) {
        if (joints[j] < 0 || weights[j] == 0.0) continue;
        mat3x4 inverse_bind = HMSM_INVERSE_BIND(uint(joints[j]));
        mat3x4 joint = HMSM_JOINT(chain_base + uint(joints[j]));
        p += weights[j] * hmsm_transform_point(joint, hmsm_transform_point(inverse_bind, bind_position));
        n += weights[j] * hmsm_transform_vector(joint, hmsm_transform_vector(inverse_bind, bind_normal));
    }
    normal_out = normalize(n);
    return p;
}

#endif  // HMSM_SKINNING_GLSL
