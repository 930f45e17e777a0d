// Real trees from laser scans: cylinder models (TreeQSM, SimpleForest) turned into hmsm skeletons
// (docs/model.md 4, "Imports"; docs/real-trees.md).
//
// Units: metres, as in the cylinder files. Conventions:
// - Cylinder data is z-up; a point (x, y, z) becomes (x, z, -y) (y-up, right-handed), then the
//   tree is moved so that its root sits at x = z = 0 and its lowest node at y = 0.
// - Axis vectors are normalized; a cylinder's end is start + length * unit(axis) (TreeQSM) or
//   the given end point (SimpleForest).
// - Parents: TreeQSM rows are 1-based, 0 = no parent; SimpleForest names rows by `ID` with
//   `parentID` -1 for none. A cylinder's start is attached to its parent cylinder at the
//   projection of the start onto the parent's axis: at the parent's end (the usual extension), at
//   its start (projections within min(parent radius, half its length) of an end snap to that
//   end), or at a node inserted part-way along it (a side branch). When the child's start
//   lies farther from that point than the parent's radius, the start keeps its own node (a
//   connecting segment); otherwise it is the attach point (the stub inside the parent's wood is
//   dropped, the branch keeps its end).
// - Radii are kept per node: the root and every node on or at the end of a cylinder carry that
//   cylinder's radius, so the trunk base radius is the first trunk cylinder's.
// - Nodes that would lie closer than kImportMergeDistance to their parent node are merged into
//   it, so tiny twig cylinders never make a zero-length segment (docs/model.md 3.1).
// - More than one cylinder without a parent: the first is the root cylinder, the others attach
//   to it as if it were their parent.
// Errors (ErrorCode::invalid_tree, the message names the row, 1-based as in the file, counting
// the header): an empty file, a wrong or missing header, a row with the wrong number of columns
// or a field that is not a finite number, a radius or length <= 0, a zero axis, a parent that is
// not a row, a cycle of parents, no cylinder without a parent.
#pragma once

#include <hmsm/export.h>
#include <hmsm/status.h>
#include <hmsm/tree.h>

#include <cstdint>
#include <string>
#include <string_view>

namespace hmsm {

/// Nodes closer than this to their parent node are merged into it (m); well above the 1e-6 m
/// segment limit so that rounding never brings a segment below it.
inline constexpr double kImportMergeDistance = 1e-5;

/// The cylinder-model formats hmsm reads.
enum class CylinderFormat {
    treeqsm_text,  ///< TreeQSM text export: one header line, 17 numbers a row
    treeqsm_v23,   ///< TreeQSM v2.3 text: no header, 15 numbers a row
    simpleforest,  ///< SimpleForest CSV: header with ID, parentID, start/end points, radius
};
HMSM_API const char* to_string(CylinderFormat format);

/// What an import read, for the CLI's summary line.
struct ImportSummary {
    CylinderFormat format = CylinderFormat::treeqsm_text;
    size_t cylinders = 0;
    size_t merged_nodes = 0;  ///< cylinder ends merged into their parent node (tiny cylinders)
    double height = 0.0;      ///< max minus min node y (m)
    double base_radius = 0.0; ///< radius of the root cylinder (m)
};

struct ImportedTree {
    TreeModel tree;  ///< valid (validate_tree passes), no leaves
    ImportSummary summary;
};

/// TreeQSM cylinder table, either variant: a first line that is not numbers is a header (it
/// must name radius, length and parent, in any spelling and case); the first data row's count,
/// 17 (text export) or 15 (v2.3), is then required of every row.
HMSM_API Result<ImportedTree> parse_treeqsm(std::string_view text, std::string_view source = "treeqsm");
HMSM_API Result<ImportedTree> import_treeqsm(const std::string& path);

/// SimpleForest QSM CSV.
HMSM_API Result<ImportedTree> parse_simpleforest(std::string_view text, std::string_view source = "simpleforest");
HMSM_API Result<ImportedTree> import_simpleforest(const std::string& path);

/// Either format, detected by content: a header naming `parentID` is SimpleForest, another
/// header line is the TreeQSM text export, none is TreeQSM v2.3.
HMSM_API Result<ImportedTree> parse_cylinders(std::string_view text, std::string_view source = "cylinders");

/// Adds `count` leaf cards, deterministic for `seed`, to the thinnest branches: the tips
/// (nodes without children) and nodes no thicker than twice the thinnest tip or than the
/// thinnest quarter of the nodes, each site equally likely. A card sits anywhere along the
/// segment ending at its node, `width` x `height` metres (scaled 0.75-1.25), stands off the twig
/// along its own up axis and faces the sky with some scatter. The tree must be valid.
HMSM_API Status scatter_leaves(TreeModel& tree, uint64_t count, uint64_t seed, double width = 0.08,
                      double height = 0.12);

}  // namespace hmsm
