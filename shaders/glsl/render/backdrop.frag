#version 450
// Sky gradient above the horizon; below it the ground plane y = ground height, with a faint
// checker (filtered against aliasing), sunlight and fog. Writes the ground's depth so the tree
// and the shadows depth-test against it.
#extension GL_GOOGLE_include_directive : require
#include "render_common.glsl"

layout(location = 0) in vec3 v_far;
layout(location = 0) out vec4 out_colour;

void main() {
    vec3 eye = frame.eye.xyz;
    vec3 dir = normalize(v_far - eye);
    float t = dir.y < -1e-5 ? (frame.ground.x - eye.y) / dir.y : -1.0;
    if (t <= 0.0) {
        float up = clamp(dir.y, 0.0, 1.0);
        vec3 sky = mix(kSkyHorizon, kSkyZenith, pow(up, 0.6));
        float glow = pow(max(dot(dir, frame.sun.xyz), 0.0), 64.0);
        out_colour = vec4(sky + vec3(1.0, 0.9, 0.7) * glow * 0.6, 1.0);
        gl_FragDepth = 1.0;
        return;
    }
    vec3 hit = eye + t * dir;
    float s = frame.scale.x;
    float c = sin(3.14159265 * hit.x / s) * sin(3.14159265 * hit.z / s);
    float w = max(fwidth(c), 1e-4);
    float checker = mix(0.5, smoothstep(-w, w, c), clamp(1.0 - 4.0 * w, 0.0, 1.0));
    vec3 albedo = kGroundColour * mix(0.93, 1.07, checker);
    vec3 n = vec3(0.0, 1.0, 0.0);
    vec3 colour = albedo * (kSunColour * max(frame.sun.y, 0.0) + hemisphere_ambient(n));
    out_colour = vec4(apply_fog(colour, t), 1.0);
    vec4 clip = frame.view_proj * vec4(hit, 1.0);
    gl_FragDepth = clamp(clip.z / clip.w, 0.0, 1.0);
}
