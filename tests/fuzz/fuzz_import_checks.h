// Properties the cylinder-model importers (hmsm/import.h) must have for ANY input, shared by the
// libFuzzer targets fuzz_treeqsm and fuzz_simpleforest and the corpus replay in import_test.cpp.
// For any byte string the parser returns either an input-class error with a one-line message
// (fuzz_checks.h's check_error), or a tree that validates, has its root at x = z = 0 and its
// lowest node at y = 0, and no segment shorter than the merge distance.
#pragma once

#include "fuzz_checks.h"

#include <hmsm/import.h>

#include <glm/geometric.hpp>

#include <algorithm>

namespace hmsm::fuzz {

inline std::string check_imported(const Result<ImportedTree>& imported) {
    if (!imported.ok()) return check_error(imported.status());
    const TreeModel& tree = imported->tree;
    Status valid = validate_tree(tree);
    if (!valid.ok()) return "the importer returned an invalid tree: " + valid.message();
    if (tree.nodes[0].parent != -1 || tree.nodes[0].position.x != 0.0 || tree.nodes[0].position.z != 0.0)
        return "node 0 is not the root at x = z = 0";
    double lowest = tree.nodes[0].position.y;
    for (const TreeNode& node : tree.nodes) {
        lowest = std::min(lowest, node.position.y);
        if (node.parent >= 0 &&
            glm::length(node.position - tree.nodes[size_t(node.parent)].position) < 0.5 * kImportMergeDistance)
            return "a segment shorter than the merge distance survived";
    }
    if (lowest != 0.0) return "the lowest node is not at y = 0";
    if (imported->summary.cylinders == 0) return "a tree from no cylinders";
    return "";
}

inline std::string check_treeqsm(const uint8_t* data, size_t size) {
    return check_imported(parse_treeqsm(std::string_view(reinterpret_cast<const char*>(data), size), "fuzz.txt"));
}

inline std::string check_simpleforest(const uint8_t* data, size_t size) {
    return check_imported(parse_simpleforest(std::string_view(reinterpret_cast<const char*>(data), size), "fuzz.csv"));
}

}  // namespace hmsm::fuzz
