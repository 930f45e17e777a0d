#version 450
// Pass 2: symplectic Euler on the two joint angles (theta_x, theta_z), clamped at max_angle,
// then the local transform T = Q Rz(theta_z) Rx(theta_x), with Ry(yaw) in front for the trunk
// (src/cpu/integrate.cpp).
#extension GL_GOOGLE_include_directive : require
#include "common.glsl"

void main() {
    uint i = thread_index();
    if (i >= pc.element_count) return;
    uint k = i / pc.model_chain_count;
    uint c = i % pc.model_chain_count;
    uint chain = state_chain(k, c);
    uint model_chain = pc.model_chain_begin + c;
    vec4 constants = chain_constants[model_chain];  // (I, K, D, A)
    float dt = pc.params.x;
    float max_angle = pc.params.y;

    vec4 s = chain_state[chain];
    vec2 angle = s.xy;
    vec2 rate = s.zw;
    vec2 force = chain_force[chain] - constants.y * angle - constants.z * rate;
    rate += dt / constants.x * force;
    angle += dt * rate;
    for (int j = 0; j < 2; ++j) {
        if (abs(angle[j]) > max_angle) {
            angle[j] = sign(angle[j]) * max_angle;
            rate[j] = 0.0;
        }
    }
    chain_state[chain] = vec4(angle, rate);

    float cx = cos(angle.x), sx = sin(angle.x);
    float cz = cos(angle.y), sz = sin(angle.y);
    mat3 rx = mat3(vec3(1, 0, 0), vec3(0, cx, sx), vec3(0, -sx, cx));  // columns
    mat3 rz = mat3(vec3(cz, sz, 0), vec3(-sz, cz, 0), vec3(0, 0, 1));
    mat3 t = as_mat3(chain_rest_rotation[model_chain]) * rz * rx;
    if (chain_parent[model_chain] < 0) {
        vec4 yaw = instance_yaw[pc.instance_begin + k];  // (cos, sin)
        mat3 ry = mat3(vec3(yaw.x, 0, -yaw.y), vec3(0, 1, 0), vec3(yaw.y, 0, yaw.x));
        t = ry * t;
    }
    chain_local[chain] = as_mat3x4(t);
}
