// hmsm-tree JSON v1 (docs/model.md 4) and the skeleton rules of docs/model.md 3.1.
#include <hmsm/tree.h>

#include "json_util.h"
#include "input_limits.h"

#include <glm/geometric.hpp>

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <sstream>

namespace hmsm {

namespace {

Status tree_error(std::string message) { return {ErrorCode::invalid_tree, std::move(message)}; }

/// A limit's status as a tree error (the class every tree check reports).
Status size_checked(const Status& status) {
    return status ? status : tree_error(status.message());
}

bool finite3(const glm::dvec3& v) {
    return std::isfinite(v.x) && std::isfinite(v.y) && std::isfinite(v.z);
}

}  // namespace

Status validate_tree(const TreeModel& tree) {
    const auto& nodes = tree.nodes;
    const int64_t n = int64_t(nodes.size());
    if (n < 2) return tree_error("a tree needs at least two nodes, got " + std::to_string(n));
    HMSM_TRY(size_checked(detail::check_count("tree: nodes", uint64_t(n), detail::size_limits().tree_nodes)));
    HMSM_TRY(size_checked(
        detail::check_count("tree: leaves", tree.leaves.size(), detail::size_limits().tree_leaves)));
    int64_t root = -1;
    for (int64_t i = 0; i < n; ++i) {
        const TreeNode& node = nodes[i];
        std::string where = "node " + std::to_string(i) + ": ";
        if (!finite3(node.position)) return tree_error(where + "position is not finite");
        HMSM_TRY(size_checked(detail::check_coordinate(where + "position", node.position)));
        if (!std::isfinite(node.radius) || node.radius <= 0.0)
            return tree_error(where + "radius must be finite and > 0");
        HMSM_TRY(size_checked(detail::check_radius(where + "radius", node.radius)));
        if (node.parent == -1) {
            if (root >= 0)
                return tree_error(where + "second root (node " + std::to_string(root) +
                                  " is already the root; exactly one node has parent -1)");
            root = i;
            continue;
        }
        if (node.parent < 0 || node.parent >= n)
            return tree_error(where + "parent " + std::to_string(node.parent) +
                              " is not a node index (0.." + std::to_string(n - 1) + ") or -1");
        if (node.parent == i) return tree_error(where + "is its own parent");
        double length = glm::length(node.position - nodes[node.parent].position);
        if (!(length >= 1e-6))
            return tree_error(where + "zero-length segment to parent " +
                              std::to_string(node.parent) + " (shorter than 1e-6 m)");
    }
    if (root < 0) return tree_error("no root: exactly one node must have parent -1");
    // Every node must reach the root: walk up with a visit mark (O(n) overall).
    std::vector<int8_t> state(n, 0);  // 0 unknown, 1 on the current path, 2 reaches the root
    state[root] = 2;
    std::vector<int64_t> path;
    for (int64_t i = 0; i < n; ++i) {
        int64_t k = i;
        path.clear();
        while (state[k] == 0) {
            state[k] = 1;
            path.push_back(k);
            k = nodes[k].parent;
        }
        if (state[k] == 1)
            return tree_error("node " + std::to_string(k) + ": parent links form a cycle");
        for (int64_t p : path) state[p] = 2;
    }
    for (size_t j = 0; j < tree.leaves.size(); ++j) {
        const TreeLeaf& leaf = tree.leaves[j];
        std::string where = "leaf " + std::to_string(j) + ": ";
        if (leaf.node < 0 || leaf.node >= n)
            return tree_error(where + "node " + std::to_string(leaf.node) + " does not exist");
        if (!finite3(leaf.offset) || !finite3(leaf.normal) || !finite3(leaf.up) ||
            !std::isfinite(leaf.size.x) || !std::isfinite(leaf.size.y))
            return tree_error(where + "a number is not finite");
        if (!(leaf.size.x > 0.0 && leaf.size.y > 0.0))
            return tree_error(where + "size must be > 0 in both dimensions");
        if (!(glm::length(leaf.normal) > 1e-9)) return tree_error(where + "normal is zero");
        if (!(glm::length(glm::cross(leaf.up, leaf.normal)) > 1e-9 * glm::length(leaf.normal)))
            return tree_error(where + "up is zero or parallel to normal");
    }
    if (tree.material)
        HMSM_TRY(size_checked(detail::check_tree_material("material.", tree.material->species, tree.material->modulus,
                                                          tree.material->density)));
    return {};
}

double tree_height(const TreeModel& tree) {
    if (tree.nodes.empty()) return 0.0;
    double lo = tree.nodes[0].position.y, hi = lo;
    for (const auto& node : tree.nodes) {
        lo = std::min(lo, node.position.y);
        hi = std::max(hi, node.position.y);
    }
    return hi - lo;
}

Result<TreeModel> parse_tree(std::string_view text, std::string_view source) {
    using detail::JsonReader;
    auto parsed = detail::parse_json(text, source);
    if (!parsed) return parsed.status();
    JsonReader r(source, ErrorCode::invalid_tree);
    const auto& doc = *parsed;
    TreeModel tree;
    HMSM_TRY(r.expect_object(doc, ""));
    int version = 1;
    HMSM_TRY(r.expect_format(doc, "hmsm-tree", 2, &version));
    const nlohmann::json* nodes = nullptr;
    HMSM_TRY(r.array_field(doc, "", "nodes", nodes));
    // Sized from the counts before the node and leaf lists are allocated.
    if (Status counted = detail::check_count("tree: nodes", nodes->size(), detail::size_limits().tree_nodes); !counted)
        return Status{ErrorCode::invalid_tree, std::string(source) + ": " + counted.message()};
    tree.nodes.resize(nodes->size());
    for (size_t i = 0; i < nodes->size(); ++i) {
        const auto& item = (*nodes)[i];
        std::string where = "nodes[" + std::to_string(i) + "]";
        HMSM_TRY(r.expect_object(item, where));
        HMSM_TRY(r.int_field(item, where, "parent", tree.nodes[i].parent));
        HMSM_TRY(r.vec3_field(item, where, "position", tree.nodes[i].position));
        HMSM_TRY(r.number_field(item, where, "radius", tree.nodes[i].radius));
    }
    if (doc.contains("leaves")) {
        const nlohmann::json* leaves = nullptr;
        HMSM_TRY(r.array_field(doc, "", "leaves", leaves));
        if (Status counted = detail::check_count("tree: leaves", leaves->size(), detail::size_limits().tree_leaves);
            !counted)
            return Status{ErrorCode::invalid_tree, std::string(source) + ": " + counted.message()};
        tree.leaves.resize(leaves->size());
        for (size_t j = 0; j < leaves->size(); ++j) {
            const auto& item = (*leaves)[j];
            std::string where = "leaves[" + std::to_string(j) + "]";
            TreeLeaf& leaf = tree.leaves[j];
            HMSM_TRY(r.expect_object(item, where));
            HMSM_TRY(r.int_field(item, where, "node", leaf.node));
            HMSM_TRY(r.vec3_field(item, where, "offset", leaf.offset));
            HMSM_TRY(r.vec3_field(item, where, "normal", leaf.normal));
            HMSM_TRY(r.vec3_field(item, where, "up", leaf.up));
            HMSM_TRY(r.vec2_field(item, where, "size", leaf.size));
        }
    }
    // Version 2: the wood and the leaf state (docs/model.md 4.1); version 1 ignores them as
    // unknown keys.
    if (version >= 2 && doc.contains("material")) {
        const auto& m = doc["material"];
        HMSM_TRY(r.expect_object(m, "material"));
        TreeMaterial material;
        if (m.contains("species")) HMSM_TRY(r.string_field(m, "material", "species", material.species));
        HMSM_TRY(r.number_field(m, "material", "modulus", material.modulus));
        HMSM_TRY(r.number_field(m, "material", "density", material.density));
        tree.material = material;
    }
    if (version >= 2 && doc.contains("leaves_on")) {
        if (!doc["leaves_on"].is_boolean())
            return Status{ErrorCode::invalid_tree, std::string(source) + ": leaves_on: expected true or false, got " +
                                                       detail::quote_input(doc["leaves_on"].dump())};
        tree.leaves_on = doc["leaves_on"].get<bool>();
    }
    Status valid = validate_tree(tree);
    if (!valid) return Status{valid.code(), std::string(source) + ": " + valid.message()};
    return tree;
}

Result<TreeModel> load_tree(const std::string& path) {
    auto text = detail::read_text_file(path);
    if (!text) return text.status();
    return parse_tree(*text, path);
}

std::string tree_to_json(const TreeModel& tree) {
    std::ostringstream out;
    auto num = [](double v) {
        if (v == 0.0 && std::signbit(v)) return std::string("-0.0");  // "-0" would read back as +0
        char buf[40];
        std::snprintf(buf, sizeof buf, "%.17g", v);
        return std::string(buf);
    };
    auto vec = [&](const auto& v, int n) {
        std::string s = "[";
        for (int k = 0; k < n; ++k) s += (k ? "," : "") + num(v[k]);
        return s + "]";
    };
    const bool version2 = tree.material || tree.leaves_on;
    out << "{\"format\": \"hmsm-tree\", \"version\": " << (version2 ? 2 : 1) << ",\n";
    if (tree.material)
        out << "\"material\": {\"species\": " << nlohmann::json(tree.material->species).dump(-1, ' ', false, nlohmann::json::error_handler_t::replace)
            << ", \"modulus\": " << num(tree.material->modulus) << ", \"density\": " << num(tree.material->density)
            << "},\n";
    if (tree.leaves_on) out << "\"leaves_on\": " << (*tree.leaves_on ? "true" : "false") << ",\n";
    out << "\"nodes\": [\n";
    for (size_t i = 0; i < tree.nodes.size(); ++i) {
        const auto& n = tree.nodes[i];
        out << "{\"parent\": " << n.parent << ", \"position\": " << vec(n.position, 3)
            << ", \"radius\": " << num(n.radius) << "}" << (i + 1 < tree.nodes.size() ? ",\n" : "\n");
    }
    out << "]";
    if (!tree.leaves.empty()) {
        out << ",\n\"leaves\": [\n";
        for (size_t j = 0; j < tree.leaves.size(); ++j) {
            const auto& l = tree.leaves[j];
            out << "{\"node\": " << l.node << ", \"offset\": " << vec(l.offset, 3)
                << ", \"normal\": " << vec(l.normal, 3) << ", \"up\": " << vec(l.up, 3)
                << ", \"size\": " << vec(l.size, 2) << "}"
                << (j + 1 < tree.leaves.size() ? ",\n" : "\n");
        }
        out << "]";
    }
    out << "}\n";
    return out.str();
}

Status save_tree(const TreeModel& tree, const std::string& path) {
    HMSM_TRY(validate_tree(tree));
    return detail::write_text_file_atomically(path, tree_to_json(tree));
}

}  // namespace hmsm
