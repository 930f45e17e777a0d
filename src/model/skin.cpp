// Skin data of docs/model.md 3.10 from the mesh template: bind positions and normals, joints
// and weights, inverse bind matrices.
#include <hmsm/skin.h>

#include <glm/geometric.hpp>
#include <glm/matrix.hpp>

namespace hmsm {
namespace {

/// [m | t] row by row.
std::array<double, 12> rows(const glm::dmat3& m, const glm::dvec3& t) {
    std::array<double, 12> out{};
    for (int i = 0; i < 3; ++i) {
        for (int j = 0; j < 3; ++j) out[4 * i + j] = m[j][i];  // glm: m[column][row]
        out[4 * i + 3] = t[i];
    }
    return out;
}

}  // namespace

SkinTemplate build_skin(const TreeModel& tree, const Hierarchy& h, const MeshTemplate& mesh,
                        const ModelOptions& options) {
    SkinTemplate skin;
    const glm::dvec3 root(tree.nodes[h.chains[0].attach_node].position);
    std::vector<glm::dvec3> attach(h.chains.size());  // p̄_attach(c)
    for (size_t c = 0; c < h.chains.size(); ++c) {
        const glm::dmat3 frame(h.chains[c].frame);
        attach[c] = glm::dvec3(tree.nodes[h.chains[c].attach_node].position) - root;
        skin.bind.push_back(rows(frame, attach[c]));
        skin.inverse_bind.push_back(rows(glm::transpose(frame), -(glm::transpose(frame) * attach[c])));
        skin.parents.push_back(h.chains[c].parent);
        skin.source_chains.push_back(int32_t(c));
    }
    const double beta = options.fix_weight;
    skin.vertices.reserve(mesh.vertices.size());
    for (const MeshVertex& v : mesh.vertices) {
        const glm::dmat3 frame(h.chains[v.chain].frame);
        SkinVertex s;
        s.position = attach[v.chain] + frame * glm::dvec3(v.position);
        s.normal = glm::normalize(frame * glm::dvec3(v.normal));
        s.joints = {v.chain, -1};
        s.weights = {1.0, 0.0};
        if (v.fix_chain >= 0 && beta > 0.0) {
            if (beta >= 1.0) s.joints = {v.fix_chain, -1};
            else {
                s.joints = {v.chain, v.fix_chain};
                s.weights = {1.0 - beta, beta};
            }
        }
        skin.vertices.push_back(s);
    }
    return skin;
}

SkinTemplate build_skin(const TreeModel& tree, const Hierarchy& h, const MeshTemplate& mesh,
                        const ModelOptions& options, const DetailLevel& level) {
    const SkinTemplate full = build_skin(tree, h, mesh, options);
    SkinTemplate skin;
    for (size_t c = 0; c < level.source_chain.size(); ++c) {
        const size_t source = size_t(level.source_chain[c]);
        skin.inverse_bind.push_back(full.inverse_bind[source]);
        skin.bind.push_back(full.bind[source]);
        skin.parents.push_back(level.hierarchy.chains[c].parent);
        skin.source_chains.push_back(int32_t(source));
    }
    skin.vertices = full.vertices;
    for (SkinVertex& v : skin.vertices) {
        for (int32_t& joint : v.joints)
            if (joint >= 0) joint = level.chain_of[size_t(joint)];
        if (v.joints[1] >= 0 && v.joints[1] == v.joints[0]) {  // both joints fold into one chain
            v.joints = {v.joints[0], -1};
            v.weights = {1.0, 0.0};
        }
    }
    return skin;
}

}  // namespace hmsm
