// Shared by the offscreen renderer's shaders (tools/render/renderer_state.h mirrors these layouts).
// Colours are linear; the colour attachment is sRGB, so the hardware encodes on store.

// The camera and scene constants: one uniform buffer for the whole render (std140).
layout(set = 0, binding = 0, std140) uniform Frame {
    mat4 view_proj;
    mat4 inv_view_proj;
    vec4 eye;     // xyz: camera position
    vec4 sun;     // xyz: unit direction towards the sun
    vec4 ground;  // x: ground height, y: shadow lift, z: fog start, w: fog end (metres)
    vec4 scale;   // x: ground checker size (metres), y: leaf-card scale about its centre
} frame;

// Per draw: what is drawn and where its leaf cards start (gl_VertexIndex includes the draw's
// vertex offset, so leaf_first is absolute).
layout(push_constant) uniform Draw {
    int mode;        // MODE_*
    int leaf_first;  // first leaf-card vertex of this instance
    int instance;    // instance index (colour variation)
    int flags;       // FLAG_*
    int chain_base;  // skinned.vert: the instance's first chain in the joint buffer
    int bind_base;   // skinned.vert: the model's first chain in the inverse-bind buffer
} draw;

#define MODE_BARK 0
#define MODE_LEAF 1
#define MODE_SHADOW_BARK 2
#define MODE_SHADOW_LEAF 3
#define FLAG_ALPHA_TO_COVERAGE 1
#define FLAG_PACKED_NORMALS 2  // VertexLayout::packed: the normal is the word in in_position.w

const vec3 kSunColour = vec3(1.00, 0.93, 0.80) * 2.4;
const vec3 kSkyZenith = vec3(0.16, 0.34, 0.70);
const vec3 kSkyHorizon = vec3(0.62, 0.74, 0.86);
const vec3 kSkyAmbient = vec3(0.30, 0.38, 0.52);
const vec3 kGroundAmbient = vec3(0.16, 0.14, 0.10);
const vec3 kGroundColour = vec3(0.23, 0.25, 0.13);
const vec3 kBarkColour = vec3(0.17, 0.11, 0.07);
const vec3 kLeafColour = vec3(0.10, 0.26, 0.045);

// A hash in [0, 1) for per-leaf and per-instance colour variation (deterministic).
float hash01(uint x) {
    x ^= x >> 16; x *= 0x7feb352du;
    x ^= x >> 15; x *= 0x846ca68bu;
    x ^= x >> 16;
    return float(x >> 8) * (1.0 / 16777216.0);
}

vec3 hemisphere_ambient(vec3 n) {
    return mix(kGroundAmbient, kSkyAmbient, 0.5 + 0.5 * n.y);
}

// Distance fog towards the horizon colour.
vec3 apply_fog(vec3 colour, float distance) {
    float f = smoothstep(frame.ground.z, frame.ground.w, distance);
    return mix(colour, kSkyHorizon, f);
}
