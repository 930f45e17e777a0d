// Cylinder-model imports (hmsm/import.h, docs/model.md 4): conventions, round trips through the
// three formats, tiny cylinders, leaves, and the bad-file catalog (each error names its line).
#include "fuzz/fuzz_import_checks.h"
#include "test_trees.h"

#include <hmsm/import.h>

#include <glm/geometric.hpp>
#include <gtest/gtest.h>

#include <cstdio>
#include <filesystem>
#include <fstream>
#include <map>
#include <sstream>

using namespace hmsm;
namespace fs = std::filesystem;

namespace {

const fs::path kData = HMSM_TEST_DATA;

std::string read(const fs::path& path) {
    std::ifstream in(path, std::ios::binary);
    std::stringstream s;
    s << in.rdbuf();
    return s.str();
}

/// hmsm (y up) to scan coordinates (z up): the inverse of the import's (x, y, z) -> (x, z, -y).
glm::dvec3 to_z_up(const glm::dvec3& p) { return {p.x, -p.z, p.y}; }

enum class Layout { treeqsm_text, treeqsm_v23, simpleforest };

/// One cylinder per segment (parent node -> node), radius of the node, rows in node order
/// (node i > 0 is row i), moved by `offset` in scan coordinates, `digits` decimals.
std::string as_cylinders(const TreeModel& tree, Layout layout, glm::dvec3 offset, int digits) {
    std::string out;
    if (layout == Layout::treeqsm_text)
        out = "radius (m)\tlength (m)\tstart_point\t\t\taxis_direction\t\t\tparent\textension\tbranch\t"
              "branch_order\tposition_in_branch\tmad\tSurfCov\tadded\tUnmodRadius (m)\n";
    if (layout == Layout::simpleforest) out = "ID,parentID,startX,startY,startZ,endX,endY,endZ,radius,branchOrder\n";
    char cell[64];
    auto num = [&](double v) {
        std::snprintf(cell, sizeof cell, "%.*f", digits, v);
        return std::string(cell);
    };
    for (size_t i = 0; i < tree.nodes.size(); ++i) {
        const TreeNode& node = tree.nodes[i];
        if (node.parent < 0) continue;
        const glm::dvec3 s = to_z_up(tree.nodes[size_t(node.parent)].position) + offset;
        const glm::dvec3 e = to_z_up(node.position) + offset;
        const double length = glm::length(e - s);
        // Not unit length, as in real exports.
        const glm::dvec3 axis = 1.0004 * (e - s) / length;
        const int64_t parent_row = tree.nodes[size_t(node.parent)].parent < 0 ? 0 : node.parent;
        std::vector<std::string> row;
        if (layout == Layout::simpleforest) {
            row = {std::to_string(i), std::to_string(parent_row == 0 ? -1 : parent_row), num(s.x), num(s.y),
                   num(s.z),          num(e.x),  num(e.y), num(e.z), num(node.radius), "0"};
        } else {
            row = {num(node.radius), num(length), num(s.x), num(s.y), num(s.z), num(axis.x), num(axis.y), num(axis.z),
                   std::to_string(parent_row), "0"};
            if (layout == Layout::treeqsm_text)
                for (const char* extra : {"1", "0", "1", "0.001", "0.9", "0", "0.1"}) row.push_back(extra);
            else
                for (const char* extra : {"0", "0.1", "1", "0", "1"}) row.push_back(extra);
        }
        for (size_t k = 0; k < row.size(); ++k)
            out += row[k] + (k + 1 < row.size() ? (layout == Layout::simpleforest ? "," : "\t") : "\n");
    }
    return out;
}

/// Every node of `original` has an imported node within `tolerance` (after the same move of the
/// root to x = z = 0 and the lowest node to y = 0), and the counts agree.
void expect_same_nodes(const TreeModel& original, const TreeModel& imported, double tolerance) {
    ASSERT_EQ(imported.nodes.size(), original.nodes.size());
    double min_y = original.nodes[0].position.y;
    int64_t root = 0;
    for (size_t i = 0; i < original.nodes.size(); ++i) {
        min_y = std::min(min_y, original.nodes[i].position.y);
        if (original.nodes[i].parent < 0) root = int64_t(i);
    }
    const glm::dvec3 shift(original.nodes[size_t(root)].position.x, min_y, original.nodes[size_t(root)].position.z);
    double worst = 0;
    for (const TreeNode& node : original.nodes) {
        double best = 1e30;
        const TreeNode* match = nullptr;
        for (const TreeNode& other : imported.nodes) {
            const double d = glm::length(other.position - (node.position - shift));
            if (d < best) best = d, match = &other;
        }
        worst = std::max(worst, best);
        // Radii live on cylinders: every node but the root (which takes its cylinder's) keeps its own.
        if (node.parent >= 0) EXPECT_NEAR(match->radius, node.radius, 1e-4);
    }
    EXPECT_LT(worst, tolerance);
}

TEST(Import, RoundTripKeepsEveryNodeWithinOneMillimetre) {
    // A preset as a scanned tree: thousands of cylinders, side branches at nodes, four decimals.
    auto preset = generate_preset("paper-5");
    ASSERT_TRUE(preset.ok()) << preset.status().message();
    TreeModel tree = *preset;
    tree.leaves.clear();
    const glm::dvec3 offset(512.25, -33.5, 101.0);  // scan coordinates are rarely near 0
    for (Layout layout : {Layout::treeqsm_text, Layout::treeqsm_v23, Layout::simpleforest}) {
        SCOPED_TRACE(int(layout));
        const std::string text = as_cylinders(tree, layout, offset, 4);
        auto imported = layout == Layout::simpleforest ? parse_simpleforest(text) : parse_treeqsm(text);
        ASSERT_TRUE(imported.ok()) << imported.status().message();
        EXPECT_EQ(imported->summary.cylinders, tree.nodes.size() - 1);
        EXPECT_EQ(imported->summary.merged_nodes, 0u);
        expect_same_nodes(tree, imported->tree, 1e-3);
        EXPECT_NEAR(imported->summary.height, tree_height(tree), 1e-3);
        EXPECT_EQ(imported->summary.format, layout == Layout::treeqsm_text   ? CylinderFormat::treeqsm_text
                                            : layout == Layout::treeqsm_v23 ? CylinderFormat::treeqsm_v23
                                                                            : CylinderFormat::simpleforest);
        // The same hierarchy shape as the original: chains per depth agree.
        auto a = build_hierarchy(tree, {});
        auto b = build_hierarchy(imported->tree, {});
        ASSERT_TRUE(a.ok() && b.ok());
        EXPECT_EQ(a->chains_per_depth, b->chains_per_depth);
    }
}

TEST(Import, ZUpBaseOffsetPartWayBranchAndRadii) {
    // Trunk of two cylinders from (10, 20, 5) straight up (z), axis not unit length; a branch whose
    // start lies on the first cylinder's surface 0.8 m up; a second root-level cylinder
    // continuing from the trunk top.
    const std::string table =
        "Radius\tLength\tStart\t\t\tAxis\t\t\tParent\tExtension\tBranch\tBranchOrder\tPositionInBranch\tMad\tSurfCov\tAdded\tUnmodRadius\n"
        "0.3\t2.0\t10\t20\t5\t0\t0\t2\t0\t2\t1\t0\t1\t0\t1\t0\t0.3\n"
        "0.2\t3.0\t10\t20\t7\t0\t0\t0.5\t1\t0\t1\t0\t2\t0\t1\t0\t0.2\n"
        "0.05\t1.0\t10.25\t20\t5.8\t3\t0\t4\t1\t0\t2\t1\t1\t0\t1\t0\t0.05\n";
    auto imported = parse_treeqsm(table);
    ASSERT_TRUE(imported.ok()) << imported.status().message();
    const TreeModel& tree = imported->tree;
    // root, split at 0.8 m on cylinder 1, end of 1, end of 2, end of 3 (its start on the surface
    // 0.25 m < 0.3 m from the axis is the split point).
    ASSERT_EQ(tree.nodes.size(), 5u);
    EXPECT_EQ(tree.nodes[0].parent, -1);
    EXPECT_EQ(tree.nodes[0].position, glm::dvec3(0.0));
    EXPECT_DOUBLE_EQ(tree.nodes[0].radius, 0.3);
    EXPECT_DOUBLE_EQ(imported->summary.base_radius, 0.3);
    EXPECT_NEAR(imported->summary.height, 5.0, 1e-12);
    auto find = [&](glm::dvec3 p) {
        for (size_t i = 0; i < tree.nodes.size(); ++i)
            if (glm::length(tree.nodes[i].position - p) < 1e-9) return int64_t(i);
        return int64_t(-1);
    };
    const int64_t split = find({0, 0.8, 0}), top1 = find({0, 2, 0}), top2 = find({0, 5, 0});
    // The branch: axis (3, 0, 4) normalized, 1 m from (0.25, 0, 0.8) z-up -> (0.85, 1.6, -0) y-up.
    const int64_t tip = find({0.25 + 0.6, 0.8 + 0.8, 0});
    ASSERT_GE(split, 0);
    ASSERT_GE(top1, 0);
    ASSERT_GE(top2, 0);
    ASSERT_GE(tip, 0);
    EXPECT_EQ(tree.nodes[split].parent, 0);
    EXPECT_EQ(tree.nodes[top1].parent, split);
    EXPECT_EQ(tree.nodes[top2].parent, top1);
    EXPECT_EQ(tree.nodes[tip].parent, split);
    EXPECT_DOUBLE_EQ(tree.nodes[split].radius, 0.3);
    EXPECT_DOUBLE_EQ(tree.nodes[top2].radius, 0.2);
    EXPECT_DOUBLE_EQ(tree.nodes[tip].radius, 0.05);
}

TEST(Import, ZUpMapsYToMinusZ) {
    // A cylinder leaning towards +y (scan) leans towards -z in hmsm.
    auto imported = parse_treeqsm("0.1 1 0 0 0 0 0.6 0.8 0 0 0 0.1 1 0 1\n");
    ASSERT_TRUE(imported.ok()) << imported.status().message();
    EXPECT_NEAR(glm::length(imported->tree.nodes[1].position - glm::dvec3(0, 0.8, -0.6)), 0.0, 1e-12);
}

TEST(Import, FarStartKeepsAConnectingSegment) {
    // A branch whose start is 1 m from its parent's axis (a gap in the scan) keeps its start.
    auto imported = parse_simpleforest(
        "ID,parentID,startX,startY,startZ,endX,endY,endZ,radius\n"
        "5,-1,0,0,0,0,0,4,0.2\n"
        "9,5,1,0,2,2,0,3,0.05\n");
    ASSERT_TRUE(imported.ok()) << imported.status().message();
    ASSERT_EQ(imported->tree.nodes.size(), 5u);  // root, split at 2 m, top, branch start, branch end
    EXPECT_NEAR(glm::length(imported->tree.nodes[3].position - glm::dvec3(1, 2, 0)), 0.0, 1e-12);
    EXPECT_EQ(imported->tree.nodes[3].parent, 1);
    EXPECT_EQ(imported->tree.nodes[4].parent, 3);
}

TEST(Import, TinyCylindersAreMergedNotRejected) {
    // Twig cylinders of 4 micrometres and of 2 mm: the first merges into its parent node, the
    // second is kept; no segment is shorter than the merge distance.
    auto imported = parse_treeqsm(
        "0.1 1 0 0 0 0 0 1 0 2 0 0.1 1 0 1\n"
        "0.01 0.000004 0 0 1 0 0 1 1 3 0 0.01 1 1 1\n"
        "0.003 0.002 0 0 1 0 1 1 2 0 0 0.003 1 2 1\n");
    ASSERT_TRUE(imported.ok()) << imported.status().message();
    EXPECT_EQ(imported->summary.merged_nodes, 1u);
    EXPECT_EQ(imported->tree.nodes.size(), 3u);
    EXPECT_EQ(fuzz::check_imported(imported), "");
}

TEST(Import, HeaderOverV23ColumnsAndQuotedCsvFields) {
    auto v23 = parse_treeqsm(
        "Radius Length Start_X Start_Y Start_Z Axis_X Axis_Y Axis_Z Parent Extension Added UnmodRadius Branch BranchOrder PositionInBranch\n"
        "0.1 1 0 0 0 0 0 1 0 2 0 0.1 1 0 1\n"
        "0.05 1 0 0 1 0 0 1 1 0 0 0.05 1 0 2\n");
    ASSERT_TRUE(v23.ok()) << v23.status().message();
    EXPECT_EQ(v23->summary.format, CylinderFormat::treeqsm_v23);
    EXPECT_EQ(v23->tree.nodes.size(), 3u);
    auto quoted = parse_simpleforest(
        "\"ID\", \"parentID\", \"startX\", \"startY\", \"startZ\", \"endX\", \"endY\", \"endZ\", \"radius\"\n"
        "\"1\", \"-1\", 0, 0, 0, 0, 0, 2, 0.2\n");
    ASSERT_TRUE(quoted.ok()) << quoted.status().message();
    EXPECT_EQ(quoted->tree.nodes.size(), 2u);
}

TEST(Import, SeveralParentlessCylindersHangFromTheFirst) {
    auto imported = parse_treeqsm(
        "0.1 1 0 0 0 0 0 1 0 0 0 0.1 1 0 1\n"
        "0.05 1 0 0 1 1 0 0 0 0 0 0.05 2 0 1\n");
    ASSERT_TRUE(imported.ok()) << imported.status().message();
    EXPECT_EQ(imported->tree.nodes.size(), 3u);
    EXPECT_EQ(imported->tree.nodes[2].parent, 1);
}

TEST(Import, ExampleScansAgreeAcrossFormats) {
    auto text = import_treeqsm((kData / "import" / "scan_treeqsm.txt").string());
    auto v23 = import_treeqsm((kData / "import" / "scan_treeqsm_v23.txt").string());
    auto sf = import_simpleforest((kData / "import" / "scan_simpleforest.csv").string());
    ASSERT_TRUE(text.ok()) << text.status().message();
    ASSERT_TRUE(v23.ok()) << v23.status().message();
    ASSERT_TRUE(sf.ok()) << sf.status().message();
    EXPECT_EQ(text->summary.format, CylinderFormat::treeqsm_text);
    EXPECT_EQ(v23->summary.format, CylinderFormat::treeqsm_v23);
    for (const auto* t : {&*text, &*v23, &*sf}) {
        EXPECT_EQ(fuzz::check_imported(*t), "");
        EXPECT_EQ(t->summary.cylinders, 230u);
        EXPECT_NEAR(t->summary.height, 16.116, 2e-3);
        EXPECT_DOUBLE_EQ(t->summary.base_radius, 0.24);
        auto h = build_hierarchy(t->tree, {});
        ASSERT_TRUE(h.ok());
        // The trunk is one chain through all 28 stem cylinders, not cut at its side branches.
        EXPECT_GT(h->chains[0].length, 15.0);
        EXPECT_EQ(h->max_depth, 2);
    }
    // Content detection picks the format.
    auto detected = parse_cylinders(read(kData / "import" / "scan_simpleforest.csv"));
    ASSERT_TRUE(detected.ok());
    EXPECT_EQ(detected->summary.format, CylinderFormat::simpleforest);
}

TEST(Import, LeavesOnTheThinnestBranchesAreDeterministic) {
    auto imported = import_treeqsm((kData / "import" / "scan_treeqsm.txt").string());
    ASSERT_TRUE(imported.ok());
    TreeModel a = imported->tree, b = imported->tree, c = imported->tree;
    ASSERT_TRUE(scatter_leaves(a, 400, 7).ok());
    ASSERT_TRUE(scatter_leaves(b, 400, 7).ok());
    ASSERT_TRUE(scatter_leaves(c, 400, 8).ok());
    ASSERT_EQ(a.leaves.size(), 400u);
    EXPECT_EQ(tree_to_json(a), tree_to_json(b));
    EXPECT_NE(tree_to_json(a), tree_to_json(c));
    EXPECT_TRUE(validate_tree(a).ok());
    double thinnest = 1e30;
    for (const TreeNode& n : a.nodes) thinnest = std::min(thinnest, n.radius);
    for (const TreeLeaf& leaf : a.leaves) {
        EXPECT_NE(leaf.node, 0);
        EXPECT_LE(a.nodes[size_t(leaf.node)].radius, 0.25 * a.nodes[0].radius) << leaf.node;
    }
    EXPECT_EQ(scatter_leaves(a, 1, 1, -0.1).code(), ErrorCode::invalid_argument);
}

struct BadCase {
    const char* file;
    const char* fragment;  // names the line (or the whole file) and the problem
};

TEST(Import, BadFilesAreRejectedNamingTheLine) {
    const BadCase treeqsm[] = {
        {"empty.txt", "empty file"},
        {"blank_lines.txt", "empty file"},
        {"header_only.txt", "no cylinder rows"},
        {"wrong_header.txt", "line 1: not a TreeQSM header"},
        {"missing_column.txt", "line 3: expected 17 numbers"},
        {"not_a_number.txt", "line 3: column 1 '0.1S' is not a finite number"},
        {"nan.txt", "line 4: column 1 'nan'"},
        {"zero_length.txt", "line 3: length must be > 0"},
        {"negative_radius.txt", "line 4: radius must be > 0"},
        {"zero_axis.txt", "line 3: axis direction is zero"},
        {"parent_out_of_range.txt", "line 4: parent '9' is not a row number"},
        {"parent_fraction.txt", "line 4: parent '1.5'"},
        {"self_parent.txt", "line 3: cylinder is its own parent"},
        {"cycle.txt", "line 3: cylinder is in a cycle"},
        {"no_root.txt", "line 2: no cylinder without a parent"},
        {"v23_wrong_count.txt", "line 2: expected 15 numbers"},
    };
    const BadCase simpleforest[] = {
        {"empty.csv", "empty file"},
        {"header_only.csv", "no cylinder rows"},
        {"missing_parentid.csv", "line 1: not a SimpleForest header: no column 'parentid'"},
        {"missing_field.csv", "line 3: expected 10 columns"},
        {"not_a_number.csv", "line 4: column 'endX' value 'zero'"},
        {"equal_points.csv", "line 3: length must be > 0"},
        {"zero_radius.csv", "line 3: radius must be > 0"},
        {"unknown_parent.csv", "line 4: parentID 7"},
        {"duplicate_id.csv", "line 4: ID 2 repeats"},
        {"cycle.csv", "line 3: cylinder is in a cycle"},
    };
    size_t files = 0;
    for (bool sf : {false, true}) {
        const fs::path dir = kData / "bad" / (sf ? "simpleforests" : "treeqsms");
        for (const BadCase& c : sf ? std::vector<BadCase>(std::begin(simpleforest), std::end(simpleforest))
                                   : std::vector<BadCase>(std::begin(treeqsm), std::end(treeqsm))) {
            SCOPED_TRACE(c.file);
            const std::string path = (dir / c.file).string();
            auto imported = sf ? import_simpleforest(path) : import_treeqsm(path);
            ASSERT_FALSE(imported.ok());
            EXPECT_EQ(imported.status().code(), ErrorCode::invalid_tree);
            EXPECT_NE(imported.status().message().find(c.fragment), std::string::npos) << imported.status().message();
            EXPECT_NE(imported.status().message().find(path), std::string::npos) << imported.status().message();
            ++files;
        }
        // Every file in the catalog folder is listed above.
        EXPECT_EQ(size_t(std::distance(fs::directory_iterator(dir), fs::directory_iterator())),
                  sf ? std::size(simpleforest) : std::size(treeqsm));
    }
    EXPECT_EQ(files, std::size(treeqsm) + std::size(simpleforest));
    EXPECT_EQ(import_treeqsm((kData / "no_such_file.txt").string()).status().code(), ErrorCode::io);
}

TEST(Import, FuzzCorporaKeepTheImportProperties) {
    size_t files = 0;
    for (const char* target : {"treeqsm", "simpleforest"})
        for (const fs::path& dir : {fs::path(HMSM_FUZZ_DIR) / "corpus" / target, fs::path(HMSM_FUZZ_DIR) / "regressions" / target,
                                    kData / "bad" / (std::string(target) + "s")}) {
            if (!fs::is_directory(dir)) continue;
            for (const auto& entry : fs::directory_iterator(dir)) {
                const std::string bytes = read(entry.path());
                const auto* data = reinterpret_cast<const uint8_t*>(bytes.data());
                const std::string failure = std::string(target) == "treeqsm" ? fuzz::check_treeqsm(data, bytes.size())
                                                                             : fuzz::check_simpleforest(data, bytes.size());
                EXPECT_EQ(failure, "") << entry.path();
                ++files;
            }
        }
    EXPECT_GE(files, 30u);
}

}  // namespace
