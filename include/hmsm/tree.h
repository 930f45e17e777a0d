// The tree skeleton (docs/model.md 3.1) and its file formats (docs/model.md 4).
#pragma once

#include <hmsm/export.h>

#include <hmsm/status.h>

#include <hmsm/types.h>

#include <cstdint>
#include <optional>
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

/// The wood a tree is made of, for the coupled dynamics (docs/model.md 3.13, 4.1).
struct TreeMaterial {
    std::string species;   ///< a species preset's name or empty (include/hmsm/species.h)
    double modulus = 0.0;  ///< E (Pa)
    double density = 0.0;  ///< green density (kg/m^3)
};

/// A validated skeleton: nodes in input order (ids are indices) plus optional leaves, and
/// optionally its wood and leaf state (hmsm-tree version 2); without them the simulation's
/// Parameters decide (hmsm::parameters_for_tree).
struct TreeModel {
    std::vector<TreeNode> nodes;
    std::vector<TreeLeaf> leaves;
    std::optional<TreeMaterial> material;
    std::optional<bool> leaves_on;  ///< leaf-on (true) or leaf-off (false) under coupled
};

/// Checks every rule of docs/model.md 3.1 plus the leaf fields; the message names node or leaf.
HMSM_API Status validate_tree(const TreeModel& tree);

/// Parses hmsm-tree JSON (version 1, or 2 with material and leaf state) and validates it. `source` names the input in error messages.
HMSM_API Result<TreeModel> parse_tree(std::string_view json, std::string_view source = "tree");
/// Reads and parses a tree file.
HMSM_API Result<TreeModel> load_tree(const std::string& path);
/// Serializes to hmsm-tree JSON, version 1, or 2 where the tree carries a material or a leaf
/// state (round-trips exactly: numbers are written with 17 digits).
HMSM_API std::string tree_to_json(const TreeModel& tree);
/// Writes a tree file; on failure no file is left behind.
HMSM_API Status save_tree(const TreeModel& tree, const std::string& path);

/// Rest-pose height of a tree: max minus min node y (the conformance error scale, docs/model.md 7).
HMSM_API double tree_height(const TreeModel& tree);

}  // namespace hmsm
