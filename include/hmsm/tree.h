// The tree skeleton (docs/model.md 3.1) and its file formats (docs/model.md 4).
#pragma once

#include <hmsm/export.h>

#include <hmsm/status.h>

#include <hmsm/types.h>

#include <cstdint>
#include <string>
#include <string_view>
#include <vector>

namespace hmsm {

/// One skeleton node: rest position (m), radius (m) and parent index (-1 for the root).
struct TreeNode {
    int32_t parent = -1;
    Vec3 position{0.0};
    double radius = 0.0;
};

/// A leaf card attached to a node; it moves rigidly with the chain that owns the node.
struct TreeLeaf {
    int32_t node = 0;
    Vec3 offset{0.0};
    Vec3 normal{0.0, 0.0, 1.0};
    Vec3 up{0.0, 1.0, 0.0};
    Vec2 size{0.1, 0.1};
};

/// A validated skeleton: nodes in input order (ids are indices) plus optional leaves.
struct TreeModel {
    std::vector<TreeNode> nodes;
    std::vector<TreeLeaf> leaves;
};

/// Checks every rule of docs/model.md 3.1 plus the leaf fields; the message names node or leaf.
HMSM_API Status validate_tree(const TreeModel& tree);

/// Parses hmsm-tree JSON v1 and validates it. `source` names the input in error messages.
HMSM_API Result<TreeModel> parse_tree(std::string_view json, std::string_view source = "tree");
/// Reads and parses a tree file.
HMSM_API Result<TreeModel> load_tree(const std::string& path);
/// Serializes to hmsm-tree JSON v1 (round-trips exactly: numbers are written with 17 digits).
HMSM_API std::string tree_to_json(const TreeModel& tree);
/// Writes a tree file; on failure no file is left behind.
HMSM_API Status save_tree(const TreeModel& tree, const std::string& path);

/// Rest-pose height of a tree: max minus min node y (the conformance error scale, docs/model.md 7).
HMSM_API double tree_height(const TreeModel& tree);

}  // namespace hmsm
