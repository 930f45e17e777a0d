#include "test_trees.h"

#include <gtest/gtest.h>

#include <cstdio>
#include <filesystem>
#include <fstream>

using namespace hmsm;

namespace {

std::string tree_json(const std::string& nodes, const std::string& extra = "") {
    return R"({"format": "hmsm-tree", "version": 1, "nodes": [)" + nodes + "]" + extra + "}";
}

const char* kTwoNodes = R"({"parent": -1, "position": [0,0,0], "radius": 0.3},
                           {"parent": 0, "position": [0,1,0], "radius": 0.2})";

/// Expects rejection as invalid_tree with every fragment in the message.
void expect_rejected(const std::string& json, std::initializer_list<const char*> fragments) {
    auto tree = parse_tree(json, "t.json");
    ASSERT_FALSE(tree.ok()) << json;
    EXPECT_EQ(tree.status().code(), ErrorCode::invalid_tree);
    for (const char* f : fragments)
        EXPECT_NE(tree.status().message().find(f), std::string::npos)
            << "'" << f << "' not in: " << tree.status().message();
}

}  // namespace

TEST(TreeIo, RoundTripsExactly) {
    TreeModel tree = test::small_tree();
    tree.nodes[2].position.x = 0.1 + 1e-13;  // needs 17 digits
    auto parsed = parse_tree(tree_to_json(tree));
    ASSERT_TRUE(parsed.ok()) << parsed.status().message();
    ASSERT_EQ(parsed->nodes.size(), tree.nodes.size());
    for (size_t i = 0; i < tree.nodes.size(); ++i) {
        EXPECT_EQ(parsed->nodes[i].parent, tree.nodes[i].parent);
        EXPECT_EQ(parsed->nodes[i].position, tree.nodes[i].position);
        EXPECT_EQ(parsed->nodes[i].radius, tree.nodes[i].radius);
    }
    ASSERT_EQ(parsed->leaves.size(), tree.leaves.size());
    EXPECT_EQ(parsed->leaves[2].normal, tree.leaves[2].normal);
    EXPECT_EQ(tree_to_json(*parsed), tree_to_json(tree));
}

TEST(TreeIo, IgnoresUnknownKeysAndAcceptsParentsAfterChildren) {
    auto tree = parse_tree(R"({"format": "hmsm-tree", "version": 1, "comment": "x",
        "nodes": [{"parent": 1, "position": [0,1,0], "radius": 0.2, "color": "red"},
                  {"parent": -1, "position": [0,0,0], "radius": 0.3}]})");
    ASSERT_TRUE(tree.ok()) << tree.status().message();
    EXPECT_EQ(tree->nodes[0].parent, 1);
}

TEST(TreeIo, RejectsEveryViolationWithTheItemNamed) {
    expect_rejected("", {"empty"});
    expect_rejected("{\"format\": \"hmsm-tree\", \"version\": 1, \"nodes\": [", {"not valid JSON"});
    expect_rejected("[1, 2]", {"object"});
    expect_rejected(R"({"format": "hmsm-forest", "version": 1, "nodes": []})", {"format", "hmsm-tree"});
    expect_rejected(R"({"version": 1, "nodes": []})", {"format", "missing"});
    expect_rejected(R"({"format": "hmsm-tree", "version": 3, "nodes": []})", {"version", "1 to 2"});
    expect_rejected(R"({"format": "hmsm-tree", "version": 1})", {"nodes", "missing"});
    expect_rejected(tree_json(R"({"parent": -1, "position": [0,0,0], "radius": 0.3})"), {"at least two"});
    expect_rejected(tree_json(R"({"parent": -1, "position": [0,0,0], "radius": 0.3},
                                 {"parent": -1, "position": [0,1,0], "radius": 0.2})"),
                    {"node 1", "second root"});
    expect_rejected(tree_json(R"({"parent": 1, "position": [0,0,0], "radius": 0.3},
                                 {"parent": 0, "position": [0,1,0], "radius": 0.2})"),
                    {"no root"});
    expect_rejected(tree_json(R"({"parent": -1, "position": [0,0,0], "radius": 0.3},
                                 {"parent": 2, "position": [0,1,0], "radius": 0.2},
                                 {"parent": 1, "position": [0,2,0], "radius": 0.2})"),
                    {"cycle"});
    expect_rejected(tree_json(R"({"parent": -1, "position": [0,0,0], "radius": 0.3},
                                 {"parent": 1, "position": [0,1,0], "radius": 0.2})"),
                    {"node 1", "own parent"});
    expect_rejected(tree_json(R"({"parent": -1, "position": [0,0,0], "radius": 0.3},
                                 {"parent": 7, "position": [0,1,0], "radius": 0.2})"),
                    {"node 1", "parent 7"});
    expect_rejected(tree_json(R"({"parent": -1, "position": [0,0,0], "radius": 0.3},
                                 {"parent": 0.5, "position": [0,1,0], "radius": 0.2})"),
                    {"nodes[1].parent", "integer"});
    expect_rejected(tree_json(R"({"parent": -1, "position": [0,0,0], "radius": 0.3},
                                 {"parent": 0, "position": [0,1,0], "radius": 0})"),
                    {"node 1", "radius"});
    expect_rejected(tree_json(R"({"parent": -1, "position": [0,0,0], "radius": -0.3},
                                 {"parent": 0, "position": [0,1,0], "radius": 0.2})"),
                    {"node 0", "radius"});
    expect_rejected(tree_json(R"({"parent": -1, "position": [0,0,0], "radius": 0.3},
                                 {"parent": 0, "position": [0,0,0.0000001], "radius": 0.2})"),
                    {"node 1", "zero-length"});
    expect_rejected(tree_json(R"({"parent": -1, "position": [0,0,0], "radius": 0.3},
                                 {"parent": 0, "position": [0,1e999,0], "radius": 0.2})"),
                    {"1e999"});
    expect_rejected(tree_json(R"({"parent": -1, "position": [0,0], "radius": 0.3},
                                 {"parent": 0, "position": [0,1,0], "radius": 0.2})"),
                    {"nodes[0].position", "3 numbers"});
    expect_rejected(tree_json(R"({"parent": -1, "position": [0,0,0]},
                                 {"parent": 0, "position": [0,1,0], "radius": 0.2})"),
                    {"nodes[0].radius", "missing"});
    expect_rejected(tree_json(R"({"parent": -1, "position": [0,0,0], "radius": "big"},
                                 {"parent": 0, "position": [0,1,0], "radius": 0.2})"),
                    {"nodes[0].radius", "number"});
    expect_rejected(tree_json(kTwoNodes, R"(, "leaves": [{"node": 5, "offset": [0,0,0],
        "normal": [0,0,1], "up": [0,1,0], "size": [0.1, 0.1]}])"),
                    {"leaf 0", "node 5"});
    expect_rejected(tree_json(kTwoNodes, R"(, "leaves": [{"node": 1, "offset": [0,0,0],
        "normal": [0,1,0], "up": [0,1,0], "size": [0.1, 0.1]}])"),
                    {"leaf 0", "parallel"});
    expect_rejected(tree_json(kTwoNodes, R"(, "leaves": [{"node": 1, "offset": [0,0,0],
        "normal": [0,0,1], "up": [0,1,0], "size": [0.1, -0.1]}])"),
                    {"leaf 0", "size"});
    expect_rejected(tree_json(kTwoNodes, R"(, "leaves": [{"node": 1}])"), {"leaves[0].offset", "missing"});
    expect_rejected(std::string(200, '[') + std::string(200, ']'), {"nested"});
}

TEST(TreeIo, FilesSaveAndLoadAndMissingFilesAreNamed) {
    auto dir = std::filesystem::temp_directory_path() / "hmsm_tree_io_test";
    std::filesystem::create_directories(dir);
    std::string path = (dir / "tree.json").string();
    ASSERT_TRUE(save_tree(test::small_tree(), path).ok());
    auto loaded = load_tree(path);
    ASSERT_TRUE(loaded.ok()) << loaded.status().message();
    EXPECT_EQ(loaded->nodes.size(), test::small_tree().nodes.size());
    auto missing = load_tree((dir / "missing.json").string());
    EXPECT_EQ(missing.status().code(), ErrorCode::io);
    EXPECT_NE(missing.status().message().find("missing.json"), std::string::npos);
    // An invalid tree is not written at all.
    TreeModel bad = test::small_tree();
    bad.nodes[4].radius = 0;
    std::string bad_path = (dir / "bad.json").string();
    EXPECT_FALSE(save_tree(bad, bad_path).ok());
    EXPECT_FALSE(std::filesystem::exists(bad_path));
    std::filesystem::remove_all(dir);
}

TEST(Forest, LoadsModelsAndInstancesRelativeToTheFile) {
    auto dir = std::filesystem::temp_directory_path() / "hmsm_forest_test";
    std::filesystem::create_directories(dir / "trees");
    ASSERT_TRUE(save_tree(test::small_tree(), (dir / "trees" / "small.json").string()).ok());
    ASSERT_TRUE(save_tree(test::rod(), (dir / "rod.json").string()).ok());
    std::ofstream(dir / "forest.json") << R"({"format": "hmsm-forest", "version": 1,
        "models": {"small": "trees/small.json", "rod": "rod.json"},
        "instances": [{"model": "rod", "origin": [1,0,2], "yaw": 0.3},
                      {"model": "small", "origin": [5,0,0]}]})";
    auto scene = load_forest((dir / "forest.json").string());
    ASSERT_TRUE(scene.ok()) << scene.status().message();
    ASSERT_EQ(scene->models.size(), 2u);
    ASSERT_EQ(scene->instances.size(), 2u);
    EXPECT_EQ(scene->model_names[scene->instances[0].model], "rod");
    EXPECT_EQ(scene->instances[0].origin, glm::dvec3(1, 0, 2));
    EXPECT_EQ(scene->instances[0].yaw, 0.3);
    EXPECT_EQ(scene->instances[1].yaw, 0.0);

    std::ofstream(dir / "bad.json") << R"({"format": "hmsm-forest", "version": 1,
        "models": {"rod": "rod.json"}, "instances": [{"model": "oak", "origin": [0,0,0]}]})";
    auto bad = load_forest((dir / "bad.json").string());
    ASSERT_FALSE(bad.ok());
    EXPECT_NE(bad.status().message().find("instances[0].model"), std::string::npos);
    EXPECT_NE(bad.status().message().find("oak"), std::string::npos);

    std::ofstream(dir / "missing_model.json") << R"({"format": "hmsm-forest", "version": 1,
        "models": {"rod": "nope.json"}, "instances": [{"model": "rod", "origin": [0,0,0]}]})";
    auto missing = load_forest((dir / "missing_model.json").string());
    ASSERT_FALSE(missing.ok());
    EXPECT_NE(missing.status().message().find("models.rod"), std::string::npos);
    std::filesystem::remove_all(dir);
}

// A model nobody places and no caller asks for is not read: a broken or huge file behind it
// does not stop the forest, a missing file or an unknown preset still does.
TEST(Forest, UnusedModelsAreCheckedButNotRead) {
    auto dir = std::filesystem::temp_directory_path() / "hmsm_forest_unused_test";
    std::filesystem::create_directories(dir);
    ASSERT_TRUE(save_tree(test::rod(), (dir / "rod.json").string()).ok());
    std::ofstream(dir / "broken.json") << "{ this is not a tree";
    {
        std::ofstream huge(dir / "huge.json");
        huge.seekp((std::streamoff(1) << 30) - 1);  // sparse: past the input size limit
        huge.put('x');
    }
    std::ofstream(dir / "forest.json") << R"({"format": "hmsm-forest", "version": 1,
        "models": {"rod": "rod.json", "broken": "broken.json", "huge": "huge.json", "p": "preset:paper-5"},
        "instances": [{"model": "rod"}]})";
    auto scene = load_forest((dir / "forest.json").string());
    ASSERT_TRUE(scene.ok()) << scene.status().message();
    EXPECT_EQ(scene->models.size(), 1u);
    EXPECT_EQ(scene->model_names, std::vector<std::string>{"rod"});
    EXPECT_FALSE(find_model(*scene, "broken").has_value());

    const std::vector<std::string> wants_broken{"broken"};
    auto asked = load_forest((dir / "forest.json").string(), wants_broken);
    ASSERT_FALSE(asked.ok());
    EXPECT_NE(asked.status().message().find("models.broken"), std::string::npos) << asked.status().message();
    const std::vector<std::string> wants_huge{"huge"};
    auto huge = load_forest((dir / "forest.json").string(), wants_huge);
    ASSERT_FALSE(huge.ok());
    EXPECT_NE(huge.status().message().find("models.huge"), std::string::npos) << huge.status().message();

    std::ofstream(dir / "missing.json") << R"({"format": "hmsm-forest", "version": 1,
        "models": {"rod": "rod.json", "gone": "nope.json"}, "instances": [{"model": "rod"}]})";
    auto missing = load_forest((dir / "missing.json").string());
    ASSERT_FALSE(missing.ok());
    EXPECT_EQ(missing.status().code(), ErrorCode::io);
    EXPECT_NE(missing.status().message().find("models.gone"), std::string::npos) << missing.status().message();
    std::ofstream(dir / "preset.json") << R"({"format": "hmsm-forest", "version": 1,
        "models": {"rod": "rod.json", "p": "preset:paper-9"}, "instances": [{"model": "rod"}]})";
    auto preset = load_forest((dir / "preset.json").string());
    ASSERT_FALSE(preset.ok());
    EXPECT_NE(preset.status().message().find("paper-9"), std::string::npos) << preset.status().message();
    std::filesystem::remove_all(dir);
}
