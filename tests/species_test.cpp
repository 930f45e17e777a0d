// Species presets (data/species.json), a tree file's material and leaf state (hmsm-tree version
// 2), what the coupled dynamics takes from them, and `hmsm import --species --leaf-state`.
#include "cli_fixture.h"
#include "test_trees.h"

#include <hmsm/hmsm.h>

#include <nlohmann/json.hpp>
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>

using namespace hmsm;

namespace {

TEST(Species, PresetsAreGreenWoodWithASource) {
    const auto& presets = species_presets();
    ASSERT_GE(presets.size(), 10u);
    for (const SpeciesPreset& s : presets) {
        EXPECT_GE(s.modulus, 4e9) << s.name;  // green hardwoods and softwoods: 4-14 GPa
        EXPECT_LE(s.modulus, 14e9) << s.name;
        EXPECT_GE(s.density, 400.0) << s.name;
        EXPECT_LE(s.density, 1200.0) << s.name;
        EXPECT_NE(s.citation.find("FPL-GTR-190"), std::string::npos) << s.name;
        EXPECT_TRUE(s.kind == "broadleaf" || s.kind == "conifer") << s.name;
    }
    auto maple = find_species("sugar-maple");
    ASSERT_TRUE(maple.ok());
    EXPECT_EQ(maple->modulus, 10.7e9);
    EXPECT_NEAR(maple->density, 1000.0 * 0.56 * 1.8, 1e-9);
    auto unknown = find_species("mahogany-x");
    ASSERT_FALSE(unknown.ok());
    EXPECT_NE(unknown.status().message().find("mahogany-x"), std::string::npos);
    EXPECT_NE(unknown.status().message().find("sugar-maple"), std::string::npos);  // lists the known
}

TEST(Species, TreeFileCarriesMaterialAndLeafState) {
    TreeModel tree = test::small_tree();
    EXPECT_NE(tree_to_json(tree).find("\"version\": 1"), std::string::npos);  // unchanged without
    tree.material = species_material("white-ash").value();
    tree.leaves_on = false;
    const std::string json = tree_to_json(tree);
    EXPECT_NE(json.find("\"version\": 2"), std::string::npos);
    auto back = parse_tree(json);
    ASSERT_TRUE(back.ok()) << back.status().message();
    ASSERT_TRUE(back->material && back->leaves_on);
    EXPECT_EQ(back->material->species, "white-ash");
    EXPECT_EQ(back->material->modulus, 9.9e9);
    EXPECT_EQ(back->material->density, tree.material->density);
    EXPECT_FALSE(*back->leaves_on);
    // Version 1 ignores the keys (unknown keys in version 1).
    std::string v1 = json;
    v1.replace(v1.find("\"version\": 2"), 12, "\"version\": 1");
    auto old = parse_tree(v1);
    ASSERT_TRUE(old.ok()) << old.status().message();
    EXPECT_FALSE(old->material);
    EXPECT_FALSE(old->leaves_on);
}

TEST(Species, NonPhysicalMaterialIsRefusedByName) {
    const std::string head = R"({"format": "hmsm-tree", "version": 2, )";
    const std::string nodes = R"("nodes": [{"parent": -1, "position": [0,0,0], "radius": 0.3},
                                           {"parent": 0, "position": [0,1,0], "radius": 0.2}]})";
    auto bad_modulus = parse_tree(head + R"("material": {"modulus": 9, "density": 900}, )" + nodes, "t.json");
    ASSERT_FALSE(bad_modulus.ok());
    EXPECT_EQ(bad_modulus.status().code(), ErrorCode::invalid_tree);
    EXPECT_NE(bad_modulus.status().message().find("material.modulus = 9"), std::string::npos)
        << bad_modulus.status().message();
    auto bad_density = parse_tree(head + R"("material": {"modulus": 9e9, "density": 0.9}, )" + nodes, "t.json");
    ASSERT_FALSE(bad_density.ok());
    EXPECT_NE(bad_density.status().message().find("material.density = 0.9"), std::string::npos);
    auto missing = parse_tree(head + R"("material": {"modulus": 9e9}, )" + nodes, "t.json");
    ASSERT_FALSE(missing.ok());
    EXPECT_NE(missing.status().message().find("density"), std::string::npos);
    auto bad_leaves = parse_tree(head + R"("leaves_on": 1, )" + nodes, "t.json");
    ASSERT_FALSE(bad_leaves.ok());
    EXPECT_NE(bad_leaves.status().message().find("leaves_on"), std::string::npos);
    TreeModel tree = test::small_tree();
    tree.material = TreeMaterial{"", std::nan(""), 900.0};
    Status valid = validate_tree(tree);
    ASSERT_FALSE(valid.ok());
    EXPECT_NE(valid.message().find("material.modulus"), std::string::npos);
}

// The coupled constants take the tree's wood and leaf state: f0 ~ sqrt(E) for a rod, and a
// leaf-off tree carries less mass than the same tree in leaf.
TEST(Species, CoupledUsesTheTreesMaterial) {
    ModelOptions options;
    options.dynamics = Dynamics::coupled;
    Parameters parameters;
    TreeModel rod = test::rod(4, 10.0, 0.2);
    auto plain = build_hierarchy(rod, options, parameters);
    ASSERT_TRUE(plain.ok());
    rod.material = TreeMaterial{"", 4.0 * parameters.material.modulus, parameters.material.density};
    auto stiff = build_hierarchy(rod, options, parameters);
    ASSERT_TRUE(stiff.ok());
    EXPECT_NEAR(stiff->chains[0].dynamics.frequency[0] / plain->chains[0].dynamics.frequency[0], 2.0, 1e-9);
    // Paper ignores it.
    auto paper = build_hierarchy(rod, {}, parameters);
    auto paper_plain = build_hierarchy(test::rod(4, 10.0, 0.2), {}, parameters);
    EXPECT_EQ(paper->chains[0].stiffness, paper_plain->chains[0].stiffness);
    TreeModel leafy = test::small_tree();
    ASSERT_FALSE(leafy.leaves.empty());
    auto on = build_hierarchy(leafy, options, parameters);
    leafy.leaves_on = false;
    auto off = build_hierarchy(leafy, options, parameters);
    ASSERT_TRUE(on.ok() && off.ok());
    EXPECT_LT(off->chains[0].dynamics.subtree_mass, on->chains[0].dynamics.subtree_mass);
}

class SpeciesCli : public test::CliFixture {
protected:
    const std::string scan_ = (std::filesystem::path(HMSM_TEST_DATA) / "import" / "scan_treeqsm_v23.txt").string();
};

TEST_F(SpeciesCli, ImportWritesTheSpeciesAndLeafState) {
    ASSERT_EQ(run("import --treeqsm " + scan_ + " --out " + path("t.json") +
                  " --species douglas-fir --leaf-state off --json").exit_code,
              0)
        << last_.err;
    auto summary = nlohmann::json::parse(last_.out);
    EXPECT_EQ(summary["material"]["species"], "douglas-fir");
    EXPECT_EQ(summary["leaves_on"], false);
    auto tree = load_tree(path("t.json"));
    ASSERT_TRUE(tree.ok()) << tree.status().message();
    ASSERT_TRUE(tree->material && tree->leaves_on);
    EXPECT_EQ(tree->material->modulus, 10.8e9);
    EXPECT_FALSE(*tree->leaves_on);
    ASSERT_EQ(run("import --list-species").exit_code, 0);
    EXPECT_NE(last_.out.find("sugar-maple"), std::string::npos);
}

TEST_F(SpeciesCli, ImportRefusesUnknownSpeciesAndLeafStates) {
    expect_bad_input("import --treeqsm " + scan_ + " --out " + path("t.json") + " --species teak-x", "teak-x");
    expect_bad_input("import --treeqsm " + scan_ + " --out " + path("t.json") + " --leaf-state maybe", "maybe");
}

}  // namespace
