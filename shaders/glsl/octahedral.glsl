// Octahedral unit vectors (Cigolle et al. 2014): the GLSL twin of src/common/octahedral.h, same names,
// same operations in the same order. VertexLayout::packed stores a vertex normal n in the w of
// its position as uintBitsToFloat(packSnorm2x16(oct_encode(n))); a reader decodes it with
// oct_decode(unpackSnorm2x16(floatBitsToUint(position.w))). Included by common.glsl (the
// compute passes) and by the offscreen renderer's vertex shader.
#ifndef HMSM_OCTAHEDRAL_GLSL
#define HMSM_OCTAHEDRAL_GLSL

/// +1 for v >= 0 (including -0), else -1, per component.
vec2 sign_not_zero(vec2 v) { return vec2(v.x >= 0.0 ? 1.0 : -1.0, v.y >= 0.0 ? 1.0 : -1.0); }

/// The octahedral point of the non-zero vector n: projected onto |x|+|y|+|z| = 1, the lower
/// hemisphere (z < 0) folded over the diagonals.
vec2 oct_encode(vec3 n) {
    float l1 = abs(n.x) + abs(n.y) + abs(n.z);
    vec2 p = vec2(n.x / l1, n.y / l1);
    if (n.z < 0.0) p = (1.0 - abs(p.yx)) * sign_not_zero(p);
    return p;
}

/// The unit vector of an octahedral point (the inverse of oct_encode up to quantization).
vec3 oct_decode(vec2 p) {
    vec3 n = vec3(p.x, p.y, 1.0 - abs(p.x) - abs(p.y));
    float fold = n.z < 0.0 ? -n.z : 0.0;
    n.x += n.x >= 0.0 ? -fold : fold;
    n.y += n.y >= 0.0 ? -fold : fold;
    return normalize(n);
}

#endif  // HMSM_OCTAHEDRAL_GLSL
