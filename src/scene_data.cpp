#include "scene_data.h"

#include "model/articulated_constants.h"
#include "model/coupled_constants.h"

#include <algorithm>
#include <cmath>
#include <numeric>

namespace hmsm::detail {

uint32_t jump_rounds_for_depth(int32_t max_depth) {
    uint32_t rounds = 0;
    while ((int64_t(1) << rounds) < int64_t(max_depth) + 1) ++rounds;
    return std::max(rounds, 1u);
}

namespace {

glm::dvec4 point(const glm::dvec3& p) { return {p, 0.0}; }

/// A chain's record of the coupled dynamics (gpu_layout.h HMSM_CHAIN_DYNAMICS_VEC4S), with the
/// quotients the passes would otherwise take every step folded in double; `q` is the chain's
/// rest rotation Q_c.
void append_coupled_record(std::vector<double>& out, const ChainDynamics& k, const Mat3& q, double dt) {
    for (int a = 0; a < 2; ++a) {
        const auto phi = oscillator_transition(k.inertia[a], k.stiffness[a], k.damping[a], dt);
        out.insert(out.end(), phi.begin(), phi.end());
    }
    const glm::dvec3 moment = kReferencePressure * k.wind_moment;
    // The motion drag per unit rate over the wind's aerodynamic damping per sqrt(|w|), one
    // ratio for both axes (their drag-weighted mean).
    const double aero_sum = k.aero_damping[0] + k.aero_damping[1];
    const double motion_ratio = aero_sum > 0.0 ? (k.motion_drag[0] + k.motion_drag[1]) / aero_sum : 0.0;
    const double rest[16] = {k.inertia[0] / dt, k.inertia[1] / dt, 1.0 / k.stiffness[0], 1.0 / k.stiffness[1],
                             k.aero_damping[0] * dt / k.inertia[0], k.aero_damping[1] * dt / k.inertia[1],
                             double(k.first_child), double(k.child_count),
                             moment.x, moment.y, moment.z, motion_ratio,
                             q[0][0], q[2][0], q[0][2], q[2][2]};  // glm: q[column][row]
    out.insert(out.end(), std::begin(rest), std::end(rest));
}

}  // namespace

gpu::PassConstants group_constants(const SceneData& d, const InstanceGroup& g, uint32_t final_half) {
    const ModelRange& m = d.models[g.model];
    gpu::PassConstants pc{};
    pc.instance_begin = g.instance_begin;
    pc.chain_begin = g.chain_begin;
    pc.node_begin = g.node_begin;
    pc.vertex_begin = g.vertex_begin;
    pc.model_chain_begin = m.chain_begin;
    pc.model_node_begin = m.node_begin;
    pc.model_vertex_begin = m.vertex_begin;
    pc.model_chain_count = m.chain_count;
    pc.model_node_count = m.node_count;
    pc.model_vertex_count = m.vertex_count;
    pc.kind = HMSM_DISPATCH_PER_ELEMENT;
    pc.profile = uint32_t(d.profile);
    pc.total_chains = uint32_t(d.chain_capacity);  // the stride between ping-pong halves
    pc.total_model_chains = d.total_model_chains();
    pc.src_half = final_half;
    pc.dst_half = final_half;
    pc.dynamics = d.articulated() ? HMSM_PASS_DYNAMICS_ARTICULATED
                  : d.coupled()   ? HMSM_PASS_DYNAMICS_COUPLED
                                  : HMSM_PASS_DYNAMICS_PAPER;
    pc.params = {float(d.dt), float(d.max_angle), float(d.fix_weight), g.covers_paused ? 1.0f : 0.0f};
    pc.instance_list = g.listed ? 1u : 0u;
    return pc;
}

InstanceGroup group_slice(const SceneData& d, const InstanceGroup& group, uint32_t first, uint32_t count) {
    const ModelRange& m = d.models[group.model];
    const uint32_t k = first - group.instance_begin;
    InstanceGroup slice = group;
    slice.instance_begin = first;
    slice.instance_count = count;
    slice.chain_begin += k * m.chain_count;
    slice.node_begin += k * m.node_count;
    slice.vertex_begin += k * m.vertex_count;
    slice.covers_paused = false;
    return slice;
}

std::vector<InstanceGroup> slices_covering(const SceneData& d, std::span<const uint32_t> indices) {
    std::vector<InstanceGroup> out;
    const InstanceGroup* g = nullptr;  // the group of the last index covered
    for (const uint32_t i : indices) {
        if (!g || i >= g->instance_begin + g->instance_count) {
            auto after = std::upper_bound(d.groups.begin(), d.groups.end(), i,
                                          [](uint32_t at, const InstanceGroup& group) { return at < group.instance_begin; });
            if (after == d.groups.begin()) continue;
            const InstanceGroup& found = *(after - 1);
            if (i >= found.instance_begin + found.instance_count) continue;  // in no group
            g = &found;
        }
        if (!out.empty() && i != g->instance_begin && out.back().instance_begin + out.back().instance_count == i)
            ++out.back().instance_count;  // i - 1 is in the same group and in this slice
        else
            out.push_back(group_slice(d, *g, i, 1));
    }
    return out;
}

/// The walk records of every model chain (gpu_layout.h HMSM_WALK_RECORD_INTS): depth, the
/// ancestors going up, the attach nodes of the chain and of its ancestors.
void fill_walk_records(SceneData& d) {
    d.chain_walk.assign(size_t(HMSM_WALK_RECORD_INTS) * d.total_model_chains(), -1);
    for (const ModelRange& range : d.models) {
        for (uint32_t c = 0; c < range.chain_count; ++c) {
            int32_t* record = &d.chain_walk[size_t(HMSM_WALK_RECORD_INTS) * (range.chain_begin + c)];
            int32_t depth = 0;
            for (int32_t x = int32_t(c); x >= 0; x = d.chain_parent[range.chain_begin + x], ++depth) {
                if (depth >= 1 && depth <= int32_t(HMSM_WALK_PATH_CAPACITY)) record[depth] = x;
                if (depth < int32_t(HMSM_WALK_ATTACH_CAPACITY) && d.chain_parent[range.chain_begin + x] >= 0)
                    record[HMSM_WALK_ATTACH(uint32_t(depth))] = d.chain_attach[range.chain_begin + x];
            }
            record[0] = depth - 1;
        }
    }
}

void lay_out_groups(SceneData& d, std::span<const Instance> instances, uint64_t max_group_elements) {
    d.groups.clear();
    d.total_chains = d.total_nodes = d.total_vertices = 0;
    for (size_t i = 0; i < instances.size(); ++i) {
        const ModelRange& range = d.models[instances[i].model];
        uint64_t per_instance = std::max({range.chain_count, range.node_count, range.vertex_count});
        InstanceGroup* group = d.groups.empty() ? nullptr : &d.groups.back();
        if (!group || group->model != instances[i].model ||
            uint64_t(group->instance_count + 1) * per_instance > max_group_elements) {
            InstanceGroup g;
            g.model = instances[i].model;
            g.instance_begin = uint32_t(i);
            g.chain_begin = uint32_t(d.total_chains);
            g.node_begin = uint32_t(d.total_nodes);
            g.vertex_begin = uint32_t(d.total_vertices);
            d.groups.push_back(g);
            group = &d.groups.back();
        }
        ++group->instance_count;
        d.total_chains += range.chain_count;
        d.total_nodes += range.node_count;
        d.total_vertices += range.vertex_count;
    }
}

void relay_groups(SceneData& d, std::span<const Instance> instances, std::span<const uint32_t> changed) {
    // The groups before the first change stay as they are; those from it on are laid anew.
    const uint32_t count = uint32_t(instances.size());
    const uint32_t first = std::min(changed.empty() ? count : changed.front(), count);
    auto from = std::upper_bound(d.groups.begin(), d.groups.end(), first,
                                 [](uint32_t at, const InstanceGroup& g) { return at < g.instance_begin; });
    if (from != d.groups.begin()) --from;
    const std::vector<InstanceGroup> old(from, d.groups.end());
    d.groups.erase(from, d.groups.end());
    if (!old.empty()) {
        d.total_chains = old.front().chain_begin;
        d.total_nodes = old.front().node_begin;
        d.total_vertices = old.front().vertex_begin;
    } else {
        d.total_chains = d.total_nodes = d.total_vertices = 0;
    }
    // Appends instances [begin, begin + count) of `model` as lay_out_groups would: onto the last
    // group while it runs the same model and stays within the largest dispatch.
    auto emit = [&](uint32_t model, uint32_t begin, uint32_t count) {
        const ModelRange& range = d.models[model];
        const uint64_t per_instance = std::max<uint64_t>({range.chain_count, range.node_count, range.vertex_count, 1});
        const uint32_t most = uint32_t(std::max<uint64_t>(1, std::min<uint64_t>(kMaxInstances, kMaxGroupElements / per_instance)));
        while (count > 0) {
            InstanceGroup* group = d.groups.empty() ? nullptr : &d.groups.back();
            if (!group || group->model != model || group->instance_count >= most) {
                InstanceGroup g;
                g.model = model;
                g.instance_begin = begin;
                g.chain_begin = uint32_t(d.total_chains);
                g.node_begin = uint32_t(d.total_nodes);
                g.vertex_begin = uint32_t(d.total_vertices);
                d.groups.push_back(g);
                group = &d.groups.back();
            }
            const uint32_t take = std::min(count, most - group->instance_count);
            group->instance_count += take;
            d.total_chains += uint64_t(take) * range.chain_count;
            d.total_nodes += uint64_t(take) * range.node_count;
            d.total_vertices += uint64_t(take) * range.vertex_count;
            begin += take;
            count -= take;
        }
    };
    size_t next = 0;  // the next changed instance
    for (const InstanceGroup& g : old) {
        uint32_t begin = g.instance_begin;
        const uint32_t end = std::min(g.instance_begin + g.instance_count, count);
        while (begin < end) {
            if (next < changed.size() && changed[next] < end) {
                const uint32_t i = changed[next++];
                if (i > begin) emit(g.model, begin, i - begin);
                emit(instances[i].model, i, 1);
                begin = i + 1;
            } else {
                emit(g.model, begin, end - begin);
                begin = end;
            }
        }
    }
    for (; next < changed.size(); ++next) emit(instances[changed[next]].model, changed[next], 1);
}

void lay_out_instances(SceneData& d, std::span<const Instance> instances, uint64_t max_group_elements) {
    lay_out_groups(d, instances, max_group_elements);
    d.instance_origin.clear();
    d.instance_yaw.clear();
    d.instance_origin.reserve(instances.size());
    d.instance_yaw.reserve(instances.size());
    for (const Instance& inst : instances) {
        d.instance_origin.push_back({inst.origin, 0.0});
        d.instance_yaw.push_back({std::cos(inst.yaw), std::sin(inst.yaw), 0.0, 0.0});
    }
    d.instance_wind.assign(size_t(HMSM_INSTANCE_WIND_VEC4S) * 4 * d.instance_origin.size(), 0.0);
}

std::vector<int32_t> stepped_nodes(const Hierarchy& h, Outputs outputs) {
    std::vector<int32_t> nodes;
    if (outputs != Outputs::joints) {
        nodes.resize(h.node_owner.size());
        std::iota(nodes.begin(), nodes.end(), 0);
        return nodes;
    }
    nodes.reserve(h.chains.size());
    for (const Chain& chain : h.chains) nodes.push_back(chain.attach_node);
    std::sort(nodes.begin(), nodes.end());
    nodes.erase(std::unique(nodes.begin(), nodes.end()), nodes.end());
    return nodes;
}

SceneData flatten_scene(std::span<const Instance> instances, const std::vector<Hierarchy>& hierarchies,
                        const std::vector<MeshTemplate>& meshes, const Parameters& parameters,
                        const ModelOptions& options, const Wind& wind, Outputs outputs,
                        uint64_t max_group_elements) {
    SceneData d;
    d.outputs = outputs;
    int32_t max_depth = 0;
    for (const Hierarchy& h : hierarchies) max_depth = std::max(max_depth, h.max_depth);
    d.jump_rounds = jump_rounds_for_depth(max_depth);

    // Model-scope arrays.
    for (size_t m = 0; m < hierarchies.size(); ++m) {
        const Hierarchy& h = hierarchies[m];
        const MeshTemplate& mesh = meshes[m];
        ModelRange range;
        range.chain_begin = uint32_t(d.chain_parent.size());
        range.chain_count = uint32_t(h.chains.size());
        // The model's nodes are its stepped nodes, each chain attached to its node's place among them.
        const std::vector<int32_t> kept = stepped_nodes(h, outputs);
        std::vector<int32_t> kept_at(h.node_owner.size(), -1);
        for (size_t k = 0; k < kept.size(); ++k) kept_at[size_t(kept[k])] = int32_t(k);
        range.node_begin = uint32_t(d.node_owner.size());
        range.node_count = uint32_t(kept.size());
        range.vertex_begin = uint32_t(d.vertex_chain.size());
        range.vertex_count = uint32_t(mesh.vertices.size());
        for (int32_t depth = 0, c = 0; depth <= h.max_depth + 1; ++depth) {
            while (c < int32_t(h.chains.size()) && h.chains[c].depth < depth) ++c;
            range.level_begin.push_back(uint32_t(c));
        }
        for (const Chain& chain : h.chains) {
            d.chain_parent.push_back(chain.parent);
            d.chain_attach.push_back(kept_at[size_t(chain.attach_node)]);
            d.chain_rest_rotation.push_back(chain.rest_rotation);
            d.chain_constants.push_back({chain.inertia, chain.stiffness, chain.damping, chain.wind_area});
            if (options.dynamics == Dynamics::coupled)
                append_coupled_record(d.chain_dynamics, chain.dynamics, chain.rest_rotation, parameters.dt);
        }
        for (int32_t n : kept) {
            d.node_owner.push_back(h.node_owner[size_t(n)]);
            d.node_local.push_back(point(h.node_local[size_t(n)]));
        }
        for (const MeshVertex& v : mesh.vertices) {
            d.vertex_chain.push_back({v.chain, v.fix_chain});
            d.vertex_rest_position.push_back(point(v.position));
            d.vertex_rest_normal.push_back(point(v.normal));
            d.vertex_parent_position.push_back(point(v.parent_position));
            d.vertex_parent_normal.push_back(point(v.parent_normal));
        }
        if (options.dynamics == Dynamics::coupled && options.exchange == Exchange::articulated)
            append_articulated_records(h, parameters.dt, d.chain_articulated);
        d.models.push_back(std::move(range));
    }

    // Jump table: round r holds each chain's 2^r-th ancestor (model-local), or -1.
    const uint32_t total = d.total_model_chains();
    d.chain_jump.assign(size_t(d.jump_rounds) * total, -1);
    for (const ModelRange& range : d.models) {
        for (uint32_t c = 0; c < range.chain_count; ++c)
            d.chain_jump[range.chain_begin + c] = d.chain_parent[range.chain_begin + c];
        for (uint32_t r = 1; r < d.jump_rounds; ++r) {
            for (uint32_t c = 0; c < range.chain_count; ++c) {
                int32_t half = d.chain_jump[size_t(r - 1) * total + range.chain_begin + c];
                d.chain_jump[size_t(r) * total + range.chain_begin + c] =
                    half < 0 ? -1 : d.chain_jump[size_t(r - 1) * total + range.chain_begin + half];
            }
        }
    }

    fill_walk_records(d);

    lay_out_instances(d, instances, max_group_elements);
    d.fit_capacity();

    d.dt = parameters.dt;
    d.max_angle = parameters.max_angle;
    d.fix_weight = options.fix_weight;
    d.profile = wind.profile;
    d.dynamics = options.dynamics;
    d.exchange = options.exchange;
    return d;
}

}  // namespace hmsm::detail
