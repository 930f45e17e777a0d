#version 450
// A full-screen triangle: the sky and the infinite ground plane, ray traced per pixel.
#extension GL_GOOGLE_include_directive : require
#include "render_common.glsl"

layout(location = 0) out vec3 v_far;   // world position on the far plane

void main() {
    vec2 ndc = vec2(float((gl_VertexIndex << 1) & 2), float(gl_VertexIndex & 2)) * 2.0 - 1.0;
    vec4 far = frame.inv_view_proj * vec4(ndc, 1.0, 1.0);
    v_far = far.xyz / far.w;
    gl_Position = vec4(ndc, 0.0, 1.0);
}
