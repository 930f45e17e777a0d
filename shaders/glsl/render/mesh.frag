#version 450
// Bark: lit by the sun and a sky/ground hemisphere. Leaves: a leaf silhouette cut out of the
// card (alpha to coverage with MSAA), lit from both sides with some light through the blade.
// Shadows: a constant darkening, once per pixel (the stencil test guards against overlap).
#extension GL_GOOGLE_include_directive : require
#include "render_common.glsl"

layout(location = 0) in vec3 v_world;
layout(location = 1) in vec3 v_normal;
layout(location = 2) in vec2 v_card;
layout(location = 3) flat in float v_tint;

layout(location = 0) out vec4 out_colour;

// Signed distance-like value: negative inside a pointed leaf blade spanning the card.
float leaf_shape(vec2 c) {
    float t = clamp(0.5 * (c.y + 1.0), 0.0, 1.0);
    float half_width = 0.95 * pow(sin(3.14159265 * t), 0.7) * (1.0 - 0.25 * t);
    return abs(c.x) - half_width;
}

void main() {
    bool leaf = draw.mode == MODE_LEAF || draw.mode == MODE_SHADOW_LEAF;
    float coverage = 1.0;
    if (leaf) {
        float d = leaf_shape(v_card);
        float w = max(fwidth(d), 1e-4);
        coverage = clamp(0.5 - d / w, 0.0, 1.0);
        bool a2c = (draw.flags & FLAG_ALPHA_TO_COVERAGE) != 0 && draw.mode == MODE_LEAF;
        if (coverage <= (a2c ? 0.0 : 0.5)) discard;
        if (!a2c) coverage = 1.0;
    }
    if (draw.mode >= MODE_SHADOW_BARK) {
        out_colour = vec4(0.0, 0.0, 0.0, 0.5);  // blended: dst * (1 - alpha)
        return;
    }
    vec3 n = normalize(v_normal);
    if (leaf && !gl_FrontFacing) n = -n;  // two-sided lighting
    vec3 l = frame.sun.xyz;
    float diffuse = max(dot(n, l), 0.0);
    vec3 albedo;
    vec3 light;
    if (leaf) {
        albedo = kLeafColour * mix(vec3(0.75, 0.85, 0.9), vec3(1.3, 1.2, 0.8), v_tint);
        float through = max(dot(-n, l), 0.0) * 0.35;  // translucency of a thin blade
        light = kSunColour * (diffuse + through) + hemisphere_ambient(n);
    } else {
        albedo = kBarkColour * mix(0.85, 1.15, v_tint);
        light = kSunColour * diffuse + hemisphere_ambient(n);
    }
    vec3 colour = apply_fog(albedo * light, distance(v_world, frame.eye.xyz));
    out_colour = vec4(colour, coverage);
}
