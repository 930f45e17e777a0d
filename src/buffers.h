// The buffer table: every device buffer with its binding, element shape and scope. Backends
// allocate from it, the CPU passes index it, and the read/write test hooks name buffers by it.
#pragma once

#include "common/gpu_layout.h"

#include <array>
#include <cstdint>
#include <string_view>

namespace hmsm::detail {

/// Element shape: scalars per element as stored (a mat3x4 is 12).
enum class Shape : uint32_t { i32 = 1, i32x2 = 2, i32x4 = 4, f32x2 = 102, f32x4 = 104, mat3x4 = 112,
                              f32x24 = 124, f32x36 = 136 };

constexpr uint32_t shape_scalars(Shape s) {
    switch (s) {
        case Shape::i32: return 1;
        case Shape::i32x2: return 2;
        case Shape::i32x4: return 4;
        case Shape::f32x2: return 2;
        case Shape::f32x4: return 4;
        case Shape::mat3x4: return 12;
        case Shape::f32x24: return 24;
        case Shape::f32x36: return 36;
    }
    return 0;
}
constexpr bool shape_is_integer(Shape s) { return s == Shape::i32 || s == Shape::i32x2 || s == Shape::i32x4; }

/// What an element count is counted in.
enum class Scope : uint32_t {
    model_chain,      ///< static chains of all models
    model_chain_jump, ///< jump_rounds x static chains
    model_chain_walk, ///< HMSM_WALK_RECORD_INTS x static chains
    model_node,
    model_vertex,
    instance,
    chain,            ///< state chains of all instances
    chain_halves,     ///< 2 x state chains (ping-pong)
    node,
    vertex,
    wind,             ///< HMSM_WIND_TABLE_ELEMENTS: the wind table
};

/// X(name, binding, shape, scope)
#define HMSM_BUFFERS(X)                                                             \
    X(chain_parent, HMSM_BINDING_CHAIN_PARENT, i32, model_chain)                    \
    X(chain_jump, HMSM_BINDING_CHAIN_JUMP, i32, model_chain_jump)                   \
    X(chain_attach, HMSM_BINDING_CHAIN_ATTACH, i32, model_chain)                    \
    X(chain_rest_rotation, HMSM_BINDING_CHAIN_REST_ROTATION, mat3x4, model_chain)   \
    X(chain_constants, HMSM_BINDING_CHAIN_CONSTANTS, f32x4, model_chain)            \
    X(node_owner, HMSM_BINDING_NODE_OWNER, i32, model_node)                         \
    X(node_local, HMSM_BINDING_NODE_LOCAL, f32x4, model_node)                       \
    X(vertex_chain, HMSM_BINDING_VERTEX_CHAIN, i32x2, model_vertex)                 \
    X(vertex_rest_position, HMSM_BINDING_VERTEX_REST_POSITION, f32x4, model_vertex) \
    X(vertex_rest_normal, HMSM_BINDING_VERTEX_REST_NORMAL, f32x4, model_vertex)     \
    X(vertex_parent_position, HMSM_BINDING_VERTEX_PARENT_POSITION, f32x4, model_vertex) \
    X(vertex_parent_normal, HMSM_BINDING_VERTEX_PARENT_NORMAL, f32x4, model_vertex) \
    X(instance_origin, HMSM_BINDING_INSTANCE_ORIGIN, f32x4, instance)               \
    X(instance_yaw, HMSM_BINDING_INSTANCE_YAW, f32x4, instance)                     \
    X(chain_state, HMSM_BINDING_CHAIN_STATE, f32x4, chain)                          \
    X(chain_force, HMSM_BINDING_CHAIN_FORCE, f32x2, chain)                          \
    X(chain_local, HMSM_BINDING_CHAIN_LOCAL, mat3x4, chain)                         \
    X(chain_rotation, HMSM_BINDING_CHAIN_ROTATION, mat3x4, chain_halves)            \
    X(node_relative, HMSM_BINDING_NODE_RELATIVE, f32x4, node)                       \
    X(chain_origin, HMSM_BINDING_CHAIN_ORIGIN, f32x4, chain_halves)                 \
    X(node_world, HMSM_BINDING_NODE_WORLD, f32x4, node)                             \
    X(vertex_position, HMSM_BINDING_VERTEX_POSITION, f32x4, vertex)                 \
    X(vertex_normal, HMSM_BINDING_VERTEX_NORMAL, f32x4, vertex)                     \
    X(instance_wind, HMSM_BINDING_INSTANCE_WIND, f32x36, instance)                  \
    X(wind_table, HMSM_BINDING_WIND_TABLE, f32x4, wind)                             \
    X(joint_matrix, HMSM_BINDING_JOINT_MATRIX, mat3x4, chain)                       \
    X(chain_walk, HMSM_BINDING_CHAIN_WALK, i32, model_chain_walk)                   \
    X(chain_dynamics, HMSM_BINDING_CHAIN_DYNAMICS, f32x24, model_chain)             \
    X(chain_load, HMSM_BINDING_CHAIN_LOAD, f32x2, chain_halves)                     \
    X(instance_table, HMSM_BINDING_INSTANCE_TABLE, i32x4, instance)

enum class BufferId : uint32_t {
#define HMSM_BUFFER_ENUM(name, binding, shape, scope) name = binding,
    HMSM_BUFFERS(HMSM_BUFFER_ENUM)
#undef HMSM_BUFFER_ENUM
};
inline constexpr uint32_t kBufferCount = HMSM_BINDING_COUNT;

struct BufferInfo {
    BufferId id;
    std::string_view name;
    Shape shape;
    Scope scope;
};

inline constexpr std::array<BufferInfo, kBufferCount> kBufferTable = {{
#define HMSM_BUFFER_INFO(name, binding, shape, scope) {BufferId::name, #name, Shape::shape, Scope::scope},
    HMSM_BUFFERS(HMSM_BUFFER_INFO)
#undef HMSM_BUFFER_INFO
}};

constexpr const BufferInfo& buffer_info(BufferId id) { return kBufferTable[static_cast<uint32_t>(id)]; }

/// Halves of a chain-scope buffer: 2 for the ping-pong buffers, chain_capacity elements apart.
constexpr uint32_t halves_of(BufferId id) { return buffer_info(id).scope == Scope::chain_halves ? 2u : 1u; }

/// True for the buffers uploaded from SceneData (model and instance scope). instance_wind is
/// uploaded too and rewritten by live control; wind_table starts zeroed and is written before
/// every run.
constexpr bool is_static(BufferId id) {
    Scope s = buffer_info(id).scope;
    return s == Scope::model_chain || s == Scope::model_chain_jump || s == Scope::model_chain_walk ||
           s == Scope::model_node ||
           s == Scope::model_vertex || s == Scope::instance;
}

/// True for the buffers that hold an instance's simulated state and outputs (carried over when
/// instances are added or removed).
constexpr bool is_state(BufferId id) {
    Scope s = buffer_info(id).scope;
    return s == Scope::chain || s == Scope::chain_halves || s == Scope::node || s == Scope::vertex;
}

}  // namespace hmsm::detail
