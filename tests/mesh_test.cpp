#include "test_trees.h"

#include <glm/geometric.hpp>
#include <glm/matrix.hpp>
#include <gtest/gtest.h>

using namespace hmsm;

TEST(Mesh, VertexCountMatchesTheFormula) {
    TreeModel tree = test::small_tree();
    for (int sides : {3, 5, 8, 11}) {
        ModelOptions options;
        options.ring_sides = sides;
        for (int cut : {0, 2}) {
            options.max_chain_segments = cut;
            auto h = build_hierarchy(tree, options);
            ASSERT_TRUE(h.ok());
            MeshTemplate mesh = build_mesh(tree, *h, options);
            uint64_t expected = 4 * tree.leaves.size();
            for (const Chain& c : h->chains) {
                expected += (c.members.size() + 1) * sides;
                bool has_children = false;
                for (const TreeNode& n : tree.nodes) has_children |= n.parent == c.members.back();
                expected += has_children ? 0 : 1;
            }
            EXPECT_EQ(mesh.vertices.size(), expected) << sides << " sides, cut " << cut;
            EXPECT_EQ(mesh_vertex_count(tree, *h, options), expected);
            EXPECT_EQ(mesh.leaf_count, tree.leaves.size());
            for (uint32_t i : mesh.indices) EXPECT_LT(i, mesh.vertices.size());
        }
    }
}

TEST(Mesh, RingsSitOnTheBranchSurfaceAndFaceOutward) {
    TreeModel tree = test::small_tree();
    auto h = build_hierarchy(tree, {});
    ASSERT_TRUE(h.ok());
    MeshTemplate mesh = build_mesh(tree, *h, {});
    size_t v = 0;
    for (size_t c = 0; c < h->chains.size(); ++c) {
        const Chain& chain = h->chains[c];
        std::vector<int32_t> path{chain.attach_node};
        path.insert(path.end(), chain.members.begin(), chain.members.end());
        for (size_t j = 0; j < path.size(); ++j) {
            double radius = j == 0 ? tree.nodes[path[1]].radius : tree.nodes[path[j]].radius;
            for (int k = 0; k < 8; ++k, ++v) {
                const MeshVertex& mv = mesh.vertices[v];
                EXPECT_EQ(mv.chain, int32_t(c));
                EXPECT_EQ(mv.fix_chain, (j == 0 && c > 0) ? chain.parent : -1);
                glm::dvec3 world = tree.nodes[chain.attach_node].position + chain.frame * mv.position;
                glm::dvec3 offset = world - tree.nodes[path[j]].position;
                EXPECT_NEAR(glm::length(offset), radius, 1e-9);
                EXPECT_NEAR(glm::dot(glm::normalize(offset), chain.frame * mv.normal), 1.0, 1e-9);
                if (mv.fix_chain >= 0) {  // same rest vertex seen from the parent chain
                    const Chain& parent = h->chains[mv.fix_chain];
                    glm::dvec3 p = tree.nodes[parent.attach_node].position + parent.frame * mv.parent_position;
                    EXPECT_NEAR(glm::length(p - world), 0.0, 1e-9);
                }
            }
        }
        if (h->continuation[chain.members.back()] < 0) ++v;  // tip
    }
    EXPECT_EQ(v + 4 * tree.leaves.size(), mesh.vertices.size());
}

TEST(Mesh, TrianglesFaceOutward) {
    TreeModel tree = test::rod(3, 3.0, 0.2);
    auto h = build_hierarchy(tree, {});
    ASSERT_TRUE(h.ok());
    MeshTemplate mesh = build_mesh(tree, *h, {});
    for (size_t t = 0; t < mesh.indices.size(); t += 3) {
        glm::dvec3 a = mesh.vertices[mesh.indices[t]].position;
        glm::dvec3 b = mesh.vertices[mesh.indices[t + 1]].position;
        glm::dvec3 c = mesh.vertices[mesh.indices[t + 2]].position;
        glm::dvec3 n = glm::cross(b - a, c - a);
        glm::dvec3 centre = (a + b + c) / 3.0;
        glm::dvec3 outward(centre.x, 0.0, centre.z);  // the rod's axis is the local y axis
        if (glm::length(outward) < 1e-6) outward = {0, 1, 0};
        EXPECT_GT(glm::dot(n, outward), 0.0) << "triangle " << t / 3;
    }
}

TEST(Mesh, LeafCardsFollowTheSpec) {
    TreeModel tree = test::small_tree();
    auto h = build_hierarchy(tree, {});
    ASSERT_TRUE(h.ok());
    MeshTemplate mesh = build_mesh(tree, *h, {});
    size_t first = mesh.vertices.size() - 4 * tree.leaves.size();
    for (size_t j = 0; j < tree.leaves.size(); ++j) {
        const TreeLeaf& leaf = tree.leaves[j];
        glm::dvec3 n = glm::normalize(leaf.normal);
        glm::dvec3 er = glm::normalize(glm::cross(leaf.up, n));
        glm::dvec3 eu = glm::cross(n, er);
        glm::dvec3 c = tree.nodes[leaf.node].position + leaf.offset;
        glm::dvec3 expected[4] = {c - 0.5 * leaf.size.x * er - 0.5 * leaf.size.y * eu,
                                  c + 0.5 * leaf.size.x * er - 0.5 * leaf.size.y * eu,
                                  c + 0.5 * leaf.size.x * er + 0.5 * leaf.size.y * eu,
                                  c - 0.5 * leaf.size.x * er + 0.5 * leaf.size.y * eu};
        for (int k = 0; k < 4; ++k) {
            const MeshVertex& v = mesh.vertices[first + 4 * j + k];
            EXPECT_EQ(v.chain, h->node_owner[leaf.node]);
            const Chain& chain = h->chains[v.chain];
            glm::dvec3 world = tree.nodes[chain.attach_node].position + chain.frame * v.position;
            EXPECT_NEAR(glm::length(world - expected[k]), 0.0, 1e-12);
            EXPECT_NEAR(glm::length(chain.frame * v.normal - n), 0.0, 1e-12);
        }
    }
}
