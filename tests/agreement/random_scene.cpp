#include "random_scene.h"

#include <glm/geometric.hpp>
#include <glm/mat3x3.hpp>

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>

namespace hmsm::test {
namespace {

double uniform(std::mt19937& rng, double lo, double hi) {
    return std::uniform_real_distribution<double>(lo, hi)(rng);
}
uint32_t pick(std::mt19937& rng, uint32_t lo, uint32_t hi) {  // [lo, hi]
    return std::uniform_int_distribution<uint32_t>(lo, hi)(rng);
}

glm::dmat3 random_rotation(std::mt19937& rng) {
    glm::dvec3 axis = glm::normalize(glm::dvec3(uniform(rng, -1, 1), uniform(rng, -1, 1),
                                                uniform(rng, -1, 1)) + glm::dvec3(1e-3));
    double angle = uniform(rng, -3.0, 3.0), c = std::cos(angle), s = std::sin(angle);
    glm::dmat3 k(0.0);
    k[1][0] = axis.z; k[2][0] = -axis.y; k[0][1] = -axis.z;
    k[2][1] = axis.x; k[0][2] = axis.y; k[1][2] = -axis.x;
    return glm::dmat3(1.0) + s * k + (1 - c) * k * k;
}

glm::dvec4 random_point(std::mt19937& rng, double extent) {
    return {uniform(rng, -extent, extent), uniform(rng, -extent, extent), uniform(rng, -extent, extent), 0.0};
}

}  // namespace

detail::SceneData random_scene_data(std::mt19937& rng, const std::vector<ModelShape>& models,
                                    const std::vector<uint32_t>& instance_models,
                                    uint32_t max_group_instances) {
    detail::SceneData d;
    int32_t max_depth = 0;
    for (const ModelShape& shape : models) {
        detail::ModelRange range;
        range.chain_begin = uint32_t(d.chain_parent.size());
        range.chain_count = shape.chains;
        range.node_begin = uint32_t(d.node_owner.size());
        range.node_count = shape.nodes;
        range.vertex_begin = uint32_t(d.vertex_chain.size());
        range.vertex_count = shape.vertices;
        // Chains in depth order: a chain's parent is at most one level above its predecessor.
        std::vector<int32_t> parent(shape.chains, -1), depth(shape.chains, 0);
        for (uint32_t c = 1; c < shape.chains; ++c) {
            uint32_t lo = 0;
            while (depth[lo] < depth[c - 1] - 1) ++lo;
            parent[c] = int32_t(pick(rng, lo, c - 1));
            depth[c] = depth[parent[c]] + 1;
        }
        max_depth = std::max(max_depth, depth.back());
        for (int32_t level = 0, c = 0; level <= depth.back() + 1; ++level) {
            while (c < int32_t(shape.chains) && depth[c] < level) ++c;
            range.level_begin.push_back(uint32_t(c));
        }
        // Every chain owns at least one node; the rest are spread at random.
        std::vector<int32_t> owner(shape.nodes);
        for (uint32_t n = 0; n < shape.nodes; ++n)
            owner[n] = n < shape.chains ? int32_t(n) : int32_t(pick(rng, 0, shape.chains - 1));
        for (uint32_t c = 0; c < shape.chains; ++c) {
            d.chain_parent.push_back(parent[c]);
            int32_t attach = 0;  // the trunk's attach node is the root, owned by chain 0
            if (parent[c] >= 0) {
                std::vector<int32_t> candidates;
                for (uint32_t n = 0; n < shape.nodes; ++n)
                    if (owner[n] == parent[c]) candidates.push_back(int32_t(n));
                attach = candidates[pick(rng, 0, uint32_t(candidates.size() - 1))];
            }
            d.chain_attach.push_back(attach);
            d.chain_rest_rotation.push_back(random_rotation(rng));
            d.chain_constants.push_back({uniform(rng, 1, 5), uniform(rng, 10, 100),
                                         uniform(rng, 0, 2), uniform(rng, 0.1, 1)});
        }
        for (uint32_t n = 0; n < shape.nodes; ++n) {
            d.node_owner.push_back(owner[n]);
            d.node_local.push_back(random_point(rng, 3.0));
        }
        for (uint32_t v = 0; v < shape.vertices; ++v) {
            int32_t chain = int32_t(pick(rng, 0, shape.chains - 1));
            int32_t fix = parent[chain] >= 0 && pick(rng, 0, 2) == 0 ? parent[chain] : -1;
            d.vertex_chain.push_back({chain, fix});
            d.vertex_rest_position.push_back(random_point(rng, 1.0));
            d.vertex_rest_normal.push_back(glm::dvec4(glm::normalize(glm::dvec3(random_point(rng, 1.0)) + 1e-3), 0.0));
            d.vertex_parent_position.push_back(random_point(rng, 1.0));
            d.vertex_parent_normal.push_back(glm::dvec4(glm::normalize(glm::dvec3(random_point(rng, 1.0)) + 1e-3), 0.0));
        }
        d.models.push_back(std::move(range));
    }

    d.jump_rounds = detail::jump_rounds_for_depth(max_depth);
    const uint32_t total = d.total_model_chains();
    d.chain_jump.assign(size_t(d.jump_rounds) * total, -1);
    for (const detail::ModelRange& range : d.models) {
        for (uint32_t c = 0; c < range.chain_count; ++c)
            d.chain_jump[range.chain_begin + c] = d.chain_parent[range.chain_begin + c];
        for (uint32_t r = 1; r < d.jump_rounds; ++r)
            for (uint32_t c = 0; c < range.chain_count; ++c) {
                int32_t half = d.chain_jump[size_t(r - 1) * total + range.chain_begin + c];
                d.chain_jump[size_t(r) * total + range.chain_begin + c] =
                    half < 0 ? -1 : d.chain_jump[size_t(r - 1) * total + range.chain_begin + half];
            }
    }
    detail::fill_walk_records(d);

    for (uint32_t i = 0; i < instance_models.size(); ++i) {
        const detail::ModelRange& range = d.models[instance_models[i]];
        d.instance_origin.push_back({uniform(rng, -20, 20), uniform(rng, -1, 1), uniform(rng, -20, 20),
                                     uniform(rng, 0, 2)});
        double yaw = uniform(rng, -3, 3);
        d.instance_yaw.push_back({std::cos(yaw), std::sin(yaw), 0, 0});
        // instance_wind: (lambda, phi mod 2, 0, 0), then 32 reduced mode phases in [0, 1).
        d.instance_wind.push_back(uniform(rng, 0, 2));
        d.instance_wind.push_back(uniform(rng, 0, 2));
        d.instance_wind.push_back(0.0);
        d.instance_wind.push_back(0.0);
        for (int k = 0; k < 32; ++k) d.instance_wind.push_back(uniform(rng, 0, 1));
        detail::InstanceGroup* group = d.groups.empty() ? nullptr : &d.groups.back();
        if (!group || group->model != instance_models[i] || group->instance_count == max_group_instances) {
            d.groups.push_back({instance_models[i], i, 0, uint32_t(d.total_chains),
                                uint32_t(d.total_nodes), uint32_t(d.total_vertices)});
            group = &d.groups.back();
        }
        ++group->instance_count;
        d.total_chains += range.chain_count;
        d.total_nodes += range.node_count;
        d.total_vertices += range.vertex_count;
    }
    d.fit_capacity();
    d.dt = 1.0 / 120.0;
    d.max_angle = 0.8;
    d.fix_weight = 0.4;
    d.profile = uniform(rng, 0, 1) < 0.5 ? WindProfile::y1 : WindProfile::turbulent;
    return d;
}

const char* name_of(PassForm form) {
    switch (form) {
    case PassForm::jump_per_round: return "pointer_jumping_per_round";
    case PassForm::jump_in_dispatch: return "pointer_jumping_in_dispatch";
    case PassForm::level_by_level: return "level_by_level";
    case PassForm::path_walk: return "path_walk";
    }
    return "unknown";
}

std::vector<std::vector<detail::Dispatch>> pass_variants(const detail::SceneData& d, Pass pass, PassForm form,
                                                         std::mt19937& rng) {
    std::vector<std::vector<detail::Dispatch>> variants;
    const bool hierarchical = pass == Pass::compose || pass == Pass::root_positions;
    if (form == PassForm::path_walk) {
        // One dispatch per group running the pass and its walk partner; the walk both ways: from
        // the records and by following chain_parent up.
        for (uint32_t from_records : {0u, 1u}) {
            if (from_records && pass != Pass::compose) continue;
            std::vector<detail::Dispatch> list;
            uint32_t half = pick(rng, 0, 1);
            for (const auto& g : d.groups) {
                detail::Dispatch dispatch{pass, detail::group_constants(d, g, half)};
                const auto& m = d.models[g.model];
                dispatch.constants.element_count =
                    g.instance_count * (pass == Pass::node_relative ? m.node_count : m.chain_count);
                dispatch.constants.kind = pass == Pass::wind_force      ? HMSM_DISPATCH_WIND_PAIR
                                          : pass == Pass::node_relative ? HMSM_DISPATCH_NODE_PAIR
                                          : from_records                ? HMSM_DISPATCH_POSE_WALK_FROM_RECORDS
                                                                        : HMSM_DISPATCH_POSE_WALK;
                list.push_back(dispatch);
            }
            variants.push_back(list);
        }
        return variants;
    }
    if (!hierarchical) {
        std::vector<detail::Dispatch> list;
        uint32_t half = pick(rng, 0, 1);
        for (const auto& g : d.groups) {
            detail::Dispatch dispatch{pass, detail::group_constants(d, g, 0)};
            const auto& m = d.models[g.model];
            uint32_t per_instance = pass == Pass::node_relative || pass == Pass::node_world ? m.node_count
                                    : pass == Pass::contour                              ? m.vertex_count
                                                                                         : m.chain_count;
            dispatch.constants.element_count = g.instance_count * per_instance;
            if (pass == Pass::contour)
                dispatch.constants.kind = d.packed_vertices() ? HMSM_DISPATCH_CONTOUR_PACKED : HMSM_DISPATCH_CONTOUR_SEPARATE;
            dispatch.constants.src_half = dispatch.constants.dst_half = half;
            list.push_back(dispatch);
        }
        variants.push_back(list);
        return variants;
    }
    if (form == PassForm::jump_in_dispatch) {
        std::vector<detail::Dispatch> list;  // every round in one dispatch per group
        for (const auto& g : d.groups) {
            detail::Dispatch dispatch{pass, detail::group_constants(d, g, 0)};
            dispatch.constants.element_count = g.instance_count * d.models[g.model].chain_count;
            dispatch.constants.kind = HMSM_DISPATCH_JUMP_ROUNDS_IN_DISPATCH;
            dispatch.constants.round = d.jump_rounds;
            list.push_back(dispatch);
        }
        variants.push_back(list);
        return variants;
    }
    if (form != PassForm::level_by_level) {  // one dispatch list per round
        for (uint32_t r = 0; r < d.jump_rounds; ++r) {
            std::vector<detail::Dispatch> list;
            uint32_t src = pick(rng, 0, 1);
            for (const auto& g : d.groups) {
                detail::Dispatch dispatch{pass, detail::group_constants(d, g, 0)};
                dispatch.constants.element_count = g.instance_count * d.models[g.model].chain_count;
                dispatch.constants.kind = HMSM_DISPATCH_JUMP_ROUND;
                dispatch.constants.round = r;
                dispatch.constants.src_half = src;
                dispatch.constants.dst_half = 1 - src;
                list.push_back(dispatch);
            }
            variants.push_back(list);
        }
        return variants;
    }
    size_t levels = 0;
    for (const auto& m : d.models) levels = std::max(levels, m.level_begin.size() - 1);
    for (size_t level = 0; level < levels; ++level) {
        std::vector<detail::Dispatch> list;
        uint32_t half = pick(rng, 0, 1);
        for (const auto& g : d.groups) {
            const auto& m = d.models[g.model];
            if (level + 1 >= m.level_begin.size()) continue;
            uint32_t count = m.level_begin[level + 1] - m.level_begin[level];
            if (count == 0) continue;
            detail::Dispatch dispatch{pass, detail::group_constants(d, g, 0)};
            dispatch.constants.kind = HMSM_DISPATCH_LEVEL;
            dispatch.constants.level_begin = m.level_begin[level];
            dispatch.constants.level_count = count;
            dispatch.constants.element_count = g.instance_count * count;
            dispatch.constants.src_half = dispatch.constants.dst_half = half;
            list.push_back(dispatch);
        }
        if (!list.empty()) variants.push_back(list);
    }
    return variants;
}

uint32_t uniform_wind_slot(std::mt19937& rng) {
    return uint32_t(std::floor(uniform(rng, 0.0, double(HMSM_WIND_STEP_SLOTS) - 1e-9)));
}

void randomize_state(const detail::SceneData& d, detail::Backend& a, detail::Backend& b,
                     std::mt19937& rng) {
    using detail::BufferId;
    auto fill = [&](BufferId id, auto make_element) {
        uint64_t count = d.element_count(id);
        uint32_t scalars = detail::shape_scalars(detail::buffer_info(id).shape);
        std::vector<double> values(count * scalars);
        for (uint64_t i = 0; i < count; ++i) make_element(&values[i * scalars]);
        ASSERT_TRUE(a.write(id, 0, count, values.data(), detail::Scalar::f64).ok());
        ASSERT_TRUE(b.write(id, 0, count, values.data(), detail::Scalar::f64).ok());
    };
    auto rotation = [&](double* m) {
        glm::dmat3 r = random_rotation(rng);
        for (int col = 0; col < 3; ++col) {
            for (int row = 0; row < 3; ++row) m[4 * col + row] = r[col][row];
            m[4 * col + 3] = 0.0;
        }
    };
    auto point = [&](double* v) {
        glm::dvec4 p = random_point(rng, 5.0);
        for (int k = 0; k < 4; ++k) v[k] = p[k];
    };
    fill(BufferId::chain_state, [&](double* v) {
        v[0] = uniform(rng, -0.7, 0.7); v[1] = uniform(rng, -0.7, 0.7);
        v[2] = uniform(rng, -2, 2); v[3] = uniform(rng, -2, 2);
    });
    fill(BufferId::chain_force, [&](double* v) { v[0] = uniform(rng, -50, 50); v[1] = uniform(rng, -50, 50); });
    fill(BufferId::chain_local, rotation);
    fill(BufferId::chain_rotation, rotation);
    fill(BufferId::node_relative, point);
    fill(BufferId::chain_origin, point);
    fill(BufferId::node_world, point);
    fill(BufferId::vertex_position, point);
    fill(BufferId::vertex_normal, point);
    // A joint matrix [R | O] by rows: the pose the contour pass and a path walk step read.
    fill(BufferId::joint_matrix, [&](double* m) {
        glm::dmat3 r = random_rotation(rng);
        glm::dvec4 o = random_point(rng, 5.0);
        for (int row = 0; row < 3; ++row) {
            for (int col = 0; col < 3; ++col) m[4 * row + col] = r[col][row];
            m[4 * row + 3] = o[row];
        }
    });
    // The wind table (gpu_layout.h): amplitudes, wind vector with three force fields of both
    // kinds, and every step slot with tau mod 2 and mode phases in [0, 1).
    std::vector<double> table(4 * HMSM_WIND_TABLE_ELEMENTS, 0.0);
    for (int k = 0; k < 32; ++k) table[4 * HMSM_WIND_AMPLITUDES + k] = uniform(rng, 0, 0.2);
    double* vector = &table[4 * HMSM_WIND_VECTOR];
    vector[0] = uniform(rng, -4, 4); vector[1] = uniform(rng, -1, 1); vector[2] = uniform(rng, -4, 4); vector[3] = 3;
    for (int k = 0; k < 3; ++k) {  // the atmospheric profile's cross-wind vectors s e_y, s e_z
        table[4 * HMSM_WIND_LATERAL + k] = uniform(rng, -3, 3);
        table[4 * HMSM_WIND_VERTICAL + k] = uniform(rng, -3, 3);
    }
    for (int f = 0; f < 3; ++f) {
        double* sphere = &table[4 * (HMSM_WIND_FIELDS + 2 * f)];
        for (int k = 0; k < 3; ++k) sphere[k] = uniform(rng, -5, 5);
        sphere[3] = uniform(rng, 3, 9);
        for (int k = 0; k < 3; ++k) sphere[4 + k] = uniform(rng, -6, 6);
        sphere[7] = f % 2;
    }
    for (int slot = 0; slot < HMSM_WIND_STEP_SLOTS; ++slot) {
        double* step = &table[4 * (HMSM_WIND_STEPS + HMSM_WIND_STEP_VEC4S * slot)];
        step[0] = uniform(rng, 0, 2);
        for (int k = 0; k < 32; ++k) step[4 + k] = uniform(rng, 0, 1);
    }
    ASSERT_TRUE(a.write(BufferId::wind_table, 0, HMSM_WIND_TABLE_ELEMENTS, table.data(), detail::Scalar::f64).ok());
    ASSERT_TRUE(b.write(BufferId::wind_table, 0, HMSM_WIND_TABLE_ELEMENTS, table.data(), detail::Scalar::f64).ok());
}

}  // namespace hmsm::test
