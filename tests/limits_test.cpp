// The input limits (docs/model.md 3.11) through the C++ API and the loaders: numbers beyond the
// float range are refused where they enter with a message naming the value and the limit; sizes
// are refused from their counts before anything proportional is built.
#include "test_trees.h"

#include "model/input_limits.h"
#include "step_program.h"

#include <gtest/gtest.h>

#include <chrono>
#include <cmath>
#include <filesystem>
#include <fstream>

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

namespace hmsm {
namespace {

namespace fs = std::filesystem;

SimulationConfig cpu_config() {
    SimulationConfig config;
    config.backend = BackendKind::cpu;
    config.wind.profile = WindProfile::constant;
    return config;
}

std::unique_ptr<Simulation> small_simulation() {
    auto sim = Simulation::create(single_tree_scene(test::small_tree()), cpu_config());
    EXPECT_TRUE(sim.ok()) << sim.status().message();
    return sim.ok() ? std::move(sim).value() : nullptr;
}

void expect_refused(const Status& status, std::initializer_list<const char*> fragments) {
    EXPECT_FALSE(status.ok());
    EXPECT_TRUE(is_input_error(status.code())) << status.message();
    for (const char* f : fragments) EXPECT_NE(status.message().find(f), std::string::npos) << status.message();
}

// A force field strength or centre beyond float range made every chain NaN for good.
TEST(Limits, ForceFieldsBeyondFloatRangeAreRefused) {
    auto sim = small_simulation();
    ASSERT_TRUE(sim);
    ForceField radial;
    radial.kind = ForceField::Kind::radial;
    radial.radius = 3.0;
    radial.radial = 3.5e38;
    expect_refused(sim->set_force_fields({&radial, 1}), {"force field 0", "radial", "3.5e+38", "1e+30"});
    ForceField directional;
    directional.directional = Vec3(0.0, 0.0, -4e38);
    expect_refused(sim->set_force_fields({&directional, 1}), {"directional", "1e+30"});
    ForceField far;
    far.center = Vec3(1e308, 0.0, 0.0);
    expect_refused(sim->set_force_fields({&far, 1}), {"center", "1e+09"});
    ForceField huge;
    huge.radius = 1e308;
    expect_refused(sim->set_force_fields({&huge, 1}), {"radius", "1e+308"});
    EXPECT_TRUE(sim->force_fields().empty());
    // The largest accepted field still leaves every chain finite (outside it: no contribution).
    ForceField strong;
    strong.kind = ForceField::Kind::radial;
    strong.center = Vec3(1e9, 0.0, 0.0);
    strong.radius = 1.0;
    strong.radial = 1e-3 * detail::kMaxForce;
    ASSERT_TRUE(sim->set_force_fields({&strong, 1}).ok());
    ASSERT_TRUE(sim->step(10).ok());
    std::vector<double> angles;
    ASSERT_TRUE(sim->read(Output::chain_angles, angles).ok());
    EXPECT_TRUE(test::all_finite(angles));
}

// wind_scale beyond float range, and the product strength x scale x area.
TEST(Limits, WindScaleAndItsProductWithTheStrengthAreBounded) {
    auto sim = small_simulation();
    ASSERT_TRUE(sim);
    expect_refused(sim->set_instance_wind_scale(0, 1e28), {"wind scale", "1e+28", "1e+06"});
    Wind wind = sim->wind();
    wind.strength = 1e26;
    ASSERT_TRUE(sim->set_wind(wind).ok());
    expect_refused(sim->set_instance_wind_scale(0, 1e6), {"wind force", "1e+30"});
    EXPECT_EQ(sim->instances()[0].wind_scale, 1.0);
    Instance added;
    added.wind_scale = 1e5;
    expect_refused(sim->add_instances({&added, 1}), {"added instance 0", "wind force"});
    Scene scene = single_tree_scene(test::small_tree());
    scene.instances[0].wind_scale = 1e28;
    expect_refused(Simulation::create(scene, cpu_config()).status(), {"wind_scale", "1e+28"});
    scene.instances[0].wind_scale = 1e6;
    SimulationConfig strong = cpu_config();
    strong.wind.strength = 1e28;
    expect_refused(Simulation::create(scene, strong).status(), {"wind force"});
}

// set_wind bounds the forces by the largest instance load it keeps between instance changes:
// a raised wind scale, an added instance and a removal each change that bound.
TEST(Limits, SetWindSeesEveryInstanceChange) {
    auto sim = small_simulation();
    ASSERT_TRUE(sim);
    Wind wind = sim->wind();
    wind.strength = 1e20;
    ASSERT_TRUE(sim->set_wind(wind).ok());
    ASSERT_TRUE(sim->set_instance_wind_scale(0, 1e5).ok());
    wind.strength = 1e26;  // fine for a scale of 1, too strong for 1e5
    expect_refused(sim->set_wind(wind), {"instance 0", "wind force", "1e+30"});
    ASSERT_TRUE(sim->set_instance_wind_scale(0, 1.0).ok());
    ASSERT_TRUE(sim->set_wind(wind).ok());  // the lowered scale is seen too
    wind.strength = 1e20;
    ASSERT_TRUE(sim->set_wind(wind).ok());
    Instance added;
    added.wind_scale = 1e5;
    ASSERT_TRUE(sim->add_instances({&added, 1}).ok());
    wind.strength = 1e26;
    expect_refused(sim->set_wind(wind), {"instance 1", "wind force"});
    EXPECT_EQ(sim->wind().strength, 1e20);
    const uint64_t strong = 1;
    ASSERT_TRUE(sim->remove_instances({&strong, 1}).ok());
    EXPECT_TRUE(sim->set_wind(wind).ok());
}

// Origins and radii of 1e300 ran with inf and NaN outputs.
TEST(Limits, OriginsAndRadiiBeyondTheRangeAreRefused) {
    Scene scene = single_tree_scene(test::small_tree(), Vec3(1e300, 0.0, 0.0));
    expect_refused(Simulation::create(scene, cpu_config()).status(), {"origin", "1e+300", "1e+09"});
    expect_refused(validate_tree(test::make_tree({{-1, 0, 0, 0, 1e300}, {0, 0, 1, 0, 0.1}})), {"radius", "1e+300"});
    expect_refused(validate_tree(test::make_tree({{-1, 0, 0, 0, 0.1}, {0, 0, 1e300, 0, 0.1}})), {"position"});
    auto sim = small_simulation();
    ASSERT_TRUE(sim);
    Instance far;
    far.origin = Vec3(0.0, 0.0, -1e300);
    expect_refused(sim->add_instances({&far, 1}), {"origin"});
    EXPECT_EQ(sim->instance_count(), 1u);
    auto forest = parse_forest(R"({"format": "hmsm-forest", "version": 1, "models": {"p": "preset:paper-5"},
        "instances": [{"model": "p", "origin": [1e300, 0, 0]}]})", ".", "f.json");
    expect_refused(forest.status(), {"instances[0].origin", "1e+300"});
}

// A wind frequency of 1e308 was accepted by set_wind and refused only at step().
TEST(Limits, WindFrequencyIsCheckedAgainstTheClockWhereItEnters) {
    auto sim = small_simulation();
    ASSERT_TRUE(sim);
    Wind wind = sim->wind();
    wind.frequency = 1e308;
    expect_refused(sim->set_wind(wind), {"wind frequency", "1e+308", "1e+06"});
    EXPECT_NE(sim->wind().frequency, 1e308);
    ASSERT_TRUE(sim->step(1).ok());
}

// A tree of millions of nodes was built (24 GB) before anything sized it.
TEST(Limits, TreesAreSizedFromTheirCountsBeforeTheBuild) {
    detail::SizeLimits small = detail::kDefaultSizeLimits;
    small.tree_nodes = 8;
    detail::ScopedSizeLimits scoped(small);
    std::string text = R"({"format": "hmsm-tree", "version": 1, "nodes": [{"parent": -1, "position": [0,0,0], "radius": 0.1})";
    for (int i = 1; i < 9; ++i)
        text += R"(, {"parent": )" + std::to_string(i - 1) + R"(, "position": [0,)" + std::to_string(i) + R"(,0], "radius": 0.1})";
    text += "]}";
    auto tree = parse_tree(text, "big.json");
    ASSERT_FALSE(tree.ok());
    EXPECT_EQ(tree.status().code(), ErrorCode::invalid_tree);
    EXPECT_NE(tree.status().message().find("9 is more than the limit of 8"), std::string::npos) << tree.status().message();
    // The memory a build takes: a lowered budget refuses the scene before building.
    small.tree_nodes = detail::kDefaultSizeLimits.tree_nodes;
    small.build_bytes = 1 << 20;
    detail::ScopedSizeLimits budget(small);
    auto sim = Simulation::create(single_tree_scene(test::rod(2000, 0.1, 0.2)), cpu_config());
    ASSERT_FALSE(sim.ok());
    EXPECT_EQ(sim.status().code(), ErrorCode::unsupported);
    EXPECT_NE(sim.status().message().find("MiB"), std::string::npos) << sim.status().message();
}

// 2,000 names of one preset were each generated and built (about 6 MB each): out of memory.
// Names that share a reference share one model; names nobody uses are not built.
TEST(Limits, ForestBuildsEachUsedReferenceOnce) {
    auto forest_of = [](int names, const std::string& instances) {
        std::string text = R"({"format": "hmsm-forest", "version": 1, "models": {)";
        for (int i = 0; i < names; ++i) text += (i ? ", " : "") + ("\"m" + std::to_string(i) + "\": \"preset:paper-5\"");
        return text + R"(, "other": "preset:paper-4"}, "instances": )" + instances + "}";
    };
    const auto start = std::chrono::steady_clock::now();
    auto scene = parse_forest(forest_of(2000, R"([{"model": "m7"}, {"model": "m9"}, {"model": "m7"}])"), ".", "f.json");
    ASSERT_TRUE(scene.ok()) << scene.status().message();
    EXPECT_LT(std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count(), 5.0);
    ASSERT_EQ(scene->models.size(), 1u);  // m7 and m9 name one preset; m0.. and "other" are unused
    EXPECT_EQ(scene->model_names, std::vector<std::string>{"m7"});
    ASSERT_EQ(scene->model_aliases.size(), 1u);
    EXPECT_EQ(scene->model_aliases[0].name, "m9");
    for (const Instance& inst : scene->instances) EXPECT_EQ(inst.model, 0u);
    EXPECT_EQ(find_model(*scene, "m9"), std::optional<uint32_t>(0));
    EXPECT_EQ(find_model(*scene, "m8"), std::nullopt);
    EXPECT_TRUE(validate_scene(*scene).ok());
    auto sim = Simulation::create(*scene, {});
    ASSERT_TRUE(sim.ok()) << sim.status().message();
    EXPECT_EQ((*sim)->scene().models.size(), 1u);

    // An extra name builds its model for later add_instances; an unknown one is refused.
    const std::vector<std::string> extra{"other", "m3"};
    auto with_extra = parse_forest(forest_of(20, R"([{"model": "m7"}])"), ".", "f.json", extra);
    ASSERT_TRUE(with_extra.ok()) << with_extra.status().message();
    ASSERT_EQ(with_extra->models.size(), 2u);
    EXPECT_EQ(find_model(*with_extra, "m3"), find_model(*with_extra, "m7"));
    EXPECT_NE(find_model(*with_extra, "other"), find_model(*with_extra, "m7"));
    const std::vector<std::string> unknown{"birch"};
    expect_refused(parse_forest(forest_of(20, R"([{"model": "m7"}])"), ".", "f.json", unknown).status(),
                   {"birch", "f.json"});

    // The build estimate counts the built models only.
    detail::SizeLimits tight = detail::kDefaultSizeLimits;
    tight.build_bytes = detail::model_build_bytes(generate_preset("paper-5")->nodes.size(),
                                                  generate_preset("paper-5")->leaves.size(), 3) + 1;
    {
        detail::ScopedSizeLimits scoped(tight);
        EXPECT_TRUE(parse_forest(forest_of(200, R"([{"model": "m1"}, {"model": "m2"}])"), ".", "f.json").ok());
        auto both = parse_forest(forest_of(200, R"([{"model": "m1"}, {"model": "other"}])"), ".", "f.json");
        ASSERT_FALSE(both.ok());
        EXPECT_EQ(both.status().code(), ErrorCode::unsupported);
        EXPECT_NE(both.status().message().find("MiB"), std::string::npos) << both.status().message();
    }
    detail::SizeLimits small = detail::kDefaultSizeLimits;
    small.forest_models = 10;
    detail::ScopedSizeLimits scoped(small);
    expect_refused(parse_forest(forest_of(20, R"([{"model": "m1"}])"), ".", "f.json").status(), {"models", "21", "10"});
}

// Importers: a 2 GB sparse file and a character device were read (4.2 GB, or until memory ran out).
TEST(Limits, ImportersAreSizedBeforeReading) {
    const fs::path dir = fs::temp_directory_path() / "hmsm_limits_import";
    fs::create_directories(dir);
    const std::string sparse = (dir / "sparse.txt").string();
    const int fd = ::open(sparse.c_str(), O_CREAT | O_TRUNC | O_WRONLY, 0644);
    ASSERT_GE(fd, 0);
    ASSERT_EQ(::ftruncate(fd, off_t(2) << 30), 0);
    ::close(fd);
    const auto start = std::chrono::steady_clock::now();
    for (auto imported : {import_treeqsm(sparse), import_simpleforest(sparse)}) {
        ASSERT_FALSE(imported.ok());
        EXPECT_EQ(imported.status().code(), ErrorCode::io);
        EXPECT_NE(imported.status().message().find("256 MiB"), std::string::npos) << imported.status().message();
    }
    EXPECT_LT(std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count(), 2.0);
    for (auto imported : {import_treeqsm("/dev/urandom"), import_simpleforest("/dev/zero")}) {
        ASSERT_FALSE(imported.ok());
        EXPECT_NE(imported.status().message().find("not a regular file"), std::string::npos)
            << imported.status().message();
    }
    fs::remove_all(dir);
    // Rows are counted before they are split.
    detail::SizeLimits small = detail::kDefaultSizeLimits;
    small.tree_nodes = 4;
    detail::ScopedSizeLimits scoped(small);
    auto rows = parse_treeqsm("1 1 0 0 0 0 0 1 0 0\n1\n1\n1\n1\n1\n1\n", "rows.txt");
    ASSERT_FALSE(rows.ok());
    EXPECT_NE(rows.status().message().find("more than the limit"), std::string::npos) << rows.status().message();
}

// A schedule of 10^7 events took 5.9 GB.
TEST(Limits, SchedulesAreSizedFromTheirCounts) {
    detail::SizeLimits small = detail::kDefaultSizeLimits;
    small.schedule_events = 10;
    detail::ScopedSizeLimits scoped(small);
    std::string text = R"({"format": "hmsm-schedule", "version": 1, "events": [)";
    for (int i = 1; i <= 11; ++i) text += (i > 1 ? ", " : "") + ("{\"step\": " + std::to_string(i) + "}");
    text += "]}";
    auto schedule = parse_schedule(text, "s.json");
    ASSERT_FALSE(schedule.ok());
    EXPECT_NE(schedule.status().message().find("11 is more than the limit of 10"), std::string::npos)
        << schedule.status().message();
    auto removals = parse_schedule(R"({"format": "hmsm-schedule", "version": 1, "events": [
        {"step": 1, "remove": [0, 1, 2, 3, 4, 5, 6, 7, 8, 9]}]})", "s.json");
    EXPECT_FALSE(removals.ok());
}

// A 100 MB "format" string made a 100 MB error line.
TEST(Limits, MessagesQuoteAtMostEightyCharactersOfAValue) {
    const std::string huge(1 << 20, 'x');
    auto tree = parse_tree(R"({"format": ")" + huge + R"(", "version": 1, "nodes": []})", "t.json");
    ASSERT_FALSE(tree.ok());
    EXPECT_LT(tree.status().message().size(), 300u) << tree.status().message().substr(0, 400);
    EXPECT_NE(tree.status().message().find("1048576 bytes"), std::string::npos);
    auto forest = parse_forest(R"({"format": "hmsm-forest", "version": 1, "models": {"p": "preset:paper-5"},
        "instances": [{"model": ")" + huge + R"("}]})", ".", "f.json");
    ASSERT_FALSE(forest.ok());
    EXPECT_LT(forest.status().message().size(), 300u);
    auto schedule = parse_schedule(R"({"format": "hmsm-schedule", "version": 1, "events": [{"step": 1, ")" + huge +
                                       R"(": 1}]})", "s.json");
    ASSERT_FALSE(schedule.ok());
    EXPECT_LT(schedule.status().message().size(), 300u);
    EXPECT_EQ(detail::quote_input("a\nb"), "a\\nb");
}

// The grid allowed 2^24 instances, built 3.1 GB, and create refused >= 2^24.
TEST(Limits, OneInstanceLimitForGridCreateAndAdd) {
    EXPECT_EQ(kMaxGridInstances, kMaxInstances);
    auto grid = grid_scene(test::small_tree(), kMaxInstances + 1, 1.0, 1);
    ASSERT_FALSE(grid.ok());
    EXPECT_EQ(grid.status().code(), ErrorCode::unsupported);
    EXPECT_NE(grid.status().message().find(std::to_string(kMaxInstances)), std::string::npos)
        << grid.status().message();
    EXPECT_TRUE(grid_scene(test::small_tree(), 4, 1.0, 1).ok());
}

// `automatic` picked the walk on every GPU whatever the depth: O(depth^2) per step.
TEST(Limits, AutomaticKeepsThePathWalkOnlyUpToTheBreakEvenDepth) {
    EXPECT_EQ(detail::automatic_composition(true, 3), Composition::path_walk);
    EXPECT_EQ(detail::automatic_composition(true, detail::kPathWalkMaxDepth), Composition::path_walk);
    EXPECT_EQ(detail::automatic_composition(true, detail::kPathWalkMaxDepth + 1), Composition::pointer_jumping);
    EXPECT_EQ(detail::automatic_composition(true, 20000), Composition::pointer_jumping);
    EXPECT_EQ(detail::automatic_composition(false, 3), Composition::pointer_jumping);
}

}  // namespace
}  // namespace hmsm
