// The hmsm-schedule file (docs/model.md 4): parsing, validation against a run, application
// between steps (docs/model.md 3.9); forest instance keys and grid_scene's size checks.
#include "test_trees.h"

#include <gtest/gtest.h>

#include <limits>
#include <string>
#include <vector>

using namespace hmsm;

namespace {

std::string schedule_text(const std::string& events) {
    return R"({"format": "hmsm-schedule", "version": 1, "events": )" + events + "}";
}

Result<Schedule> parse(const std::string& events) { return parse_schedule(schedule_text(events), "s.json"); }

void expect_rejected(const std::string& events, std::vector<std::string> fragments) {
    SCOPED_TRACE(events);
    auto s = parse(events);
    Status status = s.status();
    if (s.ok()) {
        const std::vector<std::string> names = {"tree"};
        status = validate_schedule(*s, names, 1, Wind{});
    }
    ASSERT_FALSE(status.ok());
    EXPECT_EQ(status.code(), ErrorCode::invalid_argument) << status.message();
    EXPECT_EQ(status.message().find('\n'), std::string::npos) << status.message();
    for (const auto& f : fragments) EXPECT_NE(status.message().find(f), std::string::npos) << status.message();
}

const char* kSpecExample = R"([
    {"step": 240, "wind": {"profile": "turbulent", "strength": 2.5, "turbulence": 0.4, "seed": 7}},
    {"step": 300, "wind": {"direction": [0, 0, 1], "frequency": 0.3}},
    {"step": 400, "forces": [{"center": [0, 4, 0], "radius": 5, "radial": 3.0},
                             {"center": [2, 8, 1], "radius": 2, "directional": [0, 0, 5]}]},
    {"step": 420, "forces": []},
    {"step": 500, "instances": [{"instance": 2, "wind_scale": 0.3, "wind_phase": 0.5},
                                {"instance": 0, "active": false}]},
    {"step": 600, "remove": [1], "add": [{"model": "oak", "origin": [20, 0, 0], "yaw": 1.0}]}])";

}  // namespace

TEST(Schedule, ParsesTheAtmosphericProfileWithSpeedTurbulenceAndSeed) {
    auto s = parse(R"([{"step": 3, "wind": {"profile": "atmospheric", "speed": 9, "turbulence": 0.5, "seed": 11}}])");
    ASSERT_TRUE(s.ok()) << s.status().message();
    ASSERT_TRUE(s->events[0].wind.has_value());
    EXPECT_EQ(s->events[0].wind->profile, WindProfile::atmospheric);
    EXPECT_EQ(s->events[0].wind->turbulence, 0.5);
    EXPECT_EQ(s->events[0].wind->seed, 11u);
}

TEST(Schedule, ParsesTheDocumentedExample) {
    auto s = parse(kSpecExample);
    ASSERT_TRUE(s.ok()) << s.status().message();
    ASSERT_EQ(s->events.size(), 6u);
    const ScheduleEvent& e0 = s->events[0];
    EXPECT_EQ(e0.step, 240u);
    ASSERT_TRUE(e0.wind.has_value());
    EXPECT_EQ(e0.wind->profile, WindProfile::turbulent);
    EXPECT_EQ(e0.wind->strength, 2.5);
    EXPECT_EQ(e0.wind->turbulence, 0.4);
    EXPECT_EQ(e0.wind->seed, 7u);
    EXPECT_FALSE(e0.wind->direction.has_value());
    EXPECT_FALSE(e0.wind->frequency.has_value());
    EXPECT_FALSE(e0.forces.has_value());
    const ScheduleEvent& e2 = s->events[2];
    ASSERT_TRUE(e2.forces.has_value());
    ASSERT_EQ(e2.forces->size(), 2u);
    EXPECT_EQ((*e2.forces)[0].kind, ForceField::Kind::radial);
    EXPECT_EQ((*e2.forces)[0].radial, 3.0);
    EXPECT_EQ((*e2.forces)[0].center, Vec3(0, 4, 0));
    EXPECT_EQ((*e2.forces)[1].kind, ForceField::Kind::directional);
    EXPECT_EQ((*e2.forces)[1].directional, Vec3(0, 0, 5));
    EXPECT_EQ((*e2.forces)[1].radius, 2.0);
    ASSERT_TRUE(s->events[3].forces.has_value());
    EXPECT_TRUE(s->events[3].forces->empty()) << "an empty list removes every field";
    const ScheduleEvent& e4 = s->events[4];
    ASSERT_EQ(e4.instances.size(), 2u);
    EXPECT_EQ(e4.instances[0].instance, 2u);
    EXPECT_EQ(e4.instances[0].wind_scale, 0.3);
    EXPECT_EQ(e4.instances[0].wind_phase, 0.5);
    EXPECT_FALSE(e4.instances[0].active.has_value());
    EXPECT_EQ(e4.instances[1].active, false);
    const ScheduleEvent& e5 = s->events[5];
    EXPECT_EQ(e5.remove, std::vector<uint64_t>{1});
    ASSERT_EQ(e5.add.size(), 1u);
    EXPECT_EQ(e5.add[0].model, "oak");
    EXPECT_EQ(e5.add[0].origin, Vec3(20, 0, 0));
    EXPECT_EQ(e5.add[0].yaw, 1.0);
    EXPECT_EQ(e5.add[0].wind_scale, 1.0);  // forest-instance defaults
    EXPECT_EQ(e5.add[0].wind_phase, 0.0);
    EXPECT_TRUE(e5.add[0].active);

    // Three instances of "tree" and "oak": valid; two: instance 2 does not exist at step 500.
    const std::vector<std::string> names = {"tree", "oak"};
    EXPECT_TRUE(validate_schedule(*s, names, 3, Wind{}).ok());
    Status two = validate_schedule(*s, names, 2, Wind{});
    EXPECT_FALSE(two.ok());
    EXPECT_NE(two.message().find("instance 2"), std::string::npos) << two.message();
    const std::vector<std::string> only_tree = {"tree"};
    Status no_oak = validate_schedule(*s, only_tree, 3, Wind{});
    EXPECT_FALSE(no_oak.ok());
    EXPECT_NE(no_oak.message().find("\"oak\""), std::string::npos) << no_oak.message();
}

TEST(Schedule, WindChangeReplacesOnlyTheNamedKeys) {
    Wind before;
    before.profile = WindProfile::y2;
    before.direction = Vec3(0, 0, 1);
    before.strength = 0.7;
    before.frequency = 0.25;
    before.front_speed = 3.0;
    before.turbulence = 0.5;
    before.seed = 99;
    auto s = parse(R"([{"step": 3, "wind": {"frequency": 0.4}}, {"step": 3, "wind": {"speed": 12}}])");
    ASSERT_TRUE(s.ok()) << s.status().message();
    Wind after = s->events[0].wind->applied_to(before);
    EXPECT_EQ(after.frequency, 0.4);
    EXPECT_EQ(after.profile, WindProfile::y2);
    EXPECT_EQ(after.direction, Vec3(0, 0, 1));
    EXPECT_EQ(after.strength, 0.7);
    EXPECT_EQ(after.front_speed, 3.0);
    EXPECT_EQ(after.turbulence, 0.5);
    EXPECT_EQ(after.seed, 99u);
    // A speed of 12 m/s is strength (12/6)^2 = 4.
    EXPECT_EQ(s->events[1].wind->applied_to(before).strength, 4.0);
    EXPECT_EQ(s->events[1].wind->applied_to(before).frequency, 0.25);
}

TEST(Schedule, SeedIsAnExactUnsigned64BitLiteral) {
    auto max = parse(R"([{"step": 1, "wind": {"seed": 18446744073709551615}}])");
    ASSERT_TRUE(max.ok()) << max.status().message();
    EXPECT_EQ(*max->events[0].wind->seed, UINT64_MAX);
    // 2^53 + 1 has no double: read through a double it would become 2^53.
    auto odd = parse(R"([{"step": 1, "wind": {"seed": 9007199254740993}}])");
    ASSERT_TRUE(odd.ok());
    EXPECT_EQ(*odd->events[0].wind->seed, 9007199254740993u);
    for (const char* seed : {"18446744073709551616", "-1", "7.0", "7.5", "1e3", "\"7\"", "null", "-0"})
        expect_rejected(std::string(R"([{"step": 1, "wind": {"seed": )") + seed + "}}]", {"events[0].wind.seed"});
}

TEST(Schedule, RejectsWhatTheFormatForbids) {
    const std::string force = R"({"center": [0, 1, 0], "radius": 1, "radial": 1})";
    std::string seventeen = "[";
    for (int k = 0; k < 17; ++k) seventeen += (k ? ", " : "") + force;
    seventeen += "]";
    expect_rejected(R"([{"step": 1, "wind": {"strength": 1, "speed": 6}}])", {"not both"});
    expect_rejected(R"([{"step": 1, "wind": {"strenght": 1}}])", {"events[0].wind", "unknown key", "strenght"});
    expect_rejected(R"([{"step": 1, "gusts": []}])", {"events[0]", "unknown key", "gusts"});
    expect_rejected(R"([{"step": 1, "forces": [{"center": [0, 1, 0], "radius": 1, "radial": 1, "colour": 1}]}])",
                    {"events[0].forces[0]", "colour"});
    expect_rejected(R"([{"step": 1, "instances": [{"instance": 0, "scale": 1}]}])", {"events[0].instances[0]", "scale"});
    expect_rejected(R"([{"step": 1, "add": [{"model": "tree", "yaw": 1, "height": 3}]}])", {"events[0].add[0]", "height"});
    expect_rejected(R"([{"step": 1, "forces": )" + seventeen + "}]", {"17 force fields", "at most 16"});
    expect_rejected(R"([{"step": 1, "forces": [{"center": [0, 1, 0], "radius": 1, "radial": 1, "directional": [1, 0, 0]}]}])",
                    {"exactly one"});
    expect_rejected(R"([{"step": 1, "forces": [{"center": [0, 1, 0], "radius": 1}]}])", {"exactly one"});
    expect_rejected(R"([{"step": 1, "forces": [{"center": [0, 1, 0], "radius": 0, "radial": 1}]}])", {"radius", "> 0"});
    expect_rejected(R"([{"step": 1, "forces": [{"center": [0, 1, 0], "radius": -2, "radial": 1}]}])", {"radius", "> 0"});
    expect_rejected(R"([{"step": 1, "forces": [{"radius": 2, "radial": 1}]}])", {"center", "missing"});
    expect_rejected(R"([{"step": 1, "wind": {"strength": 1e999}}])", {"1e999"});
    expect_rejected(R"([{"step": 1, "wind": {"strength": "NaN"}}])", {"strength", "number"});
    expect_rejected(R"([{"step": 0}])", {"events[0].step", "steps start at 1"});
    expect_rejected(R"([{"step": -2}])", {"events[0].step", "steps start at 1"});
    expect_rejected(R"([{"step": 2.5}])", {"events[0].step", "integer"});
    expect_rejected(R"([{"wind": {}}])", {"events[0].step", "missing"});
    expect_rejected(R"([{"step": 5}, {"step": 5}, {"step": 4}])", {"events[2].step", "non-decreasing"});
    expect_rejected(R"([{"step": 1, "instances": [{"instance": 1, "active": false}]}])", {"instance 1", "does not exist"});
    expect_rejected(R"([{"step": 1, "instances": [{"instance": 0}, {"instance": 0}]}])", {"instance 0", "twice"});
    expect_rejected(R"([{"step": 1, "instances": [{"instance": 0, "wind_scale": -0.1}]}])", {"wind_scale", ">= 0"});
    expect_rejected(R"([{"step": 1, "instances": [{"instance": 0, "active": 1}]}])", {"active", "true or false"});
    expect_rejected(R"([{"step": 1, "remove": [0, 0]}])", {"remove", "twice"});
    expect_rejected(R"([{"step": 1, "add": [{"model": "birch"}]}])", {"add[0]", "birch"});
    expect_rejected(R"([{"step": 1, "wind": {"turbulence": 2.01}}])", {"turbulence", "[0, 2]"});
    expect_rejected(R"([{"step": 1, "wind": {"front_speed": 0.001}}])", {"front_speed", "0.01"});
    expect_rejected(R"([{"step": 1, "wind": {"direction": [0, 0, 0]}}])", {"direction", "non-zero"});
    expect_rejected(R"([{"step": 1, "wind": {"speed": -3}}])", {"speed", ">= 0"});
    expect_rejected(R"([], "note": 1)", {"unknown key", "note"});
    for (const char* text : {"", "[]", R"({"format": "hmsm-schedule", "version": 2, "events": []})",
                             R"({"format": "hmsm-forest", "version": 1, "events": []})",
                             R"({"format": "hmsm-schedule", "version": 1})",
                             R"({"format": "hmsm-schedule", "version": 1, "events": {}})", "{\"format\": "}) {
        auto s = parse_schedule(text, "s.json");
        EXPECT_FALSE(s.ok()) << text;
        EXPECT_EQ(s.status().code(), ErrorCode::invalid_argument) << text;
    }
}

TEST(Schedule, InstanceIndicesFollowRemovesAndAdds) {
    const std::vector<std::string> names = {"tree"};
    // Two instances; an add makes index 2 valid; removing two makes 1 the last valid index.
    auto ok = parse(R"([{"step": 2, "add": [{"model": "tree"}]},
                        {"step": 2, "instances": [{"instance": 2, "active": false}]},
                        {"step": 3, "remove": [0, 2]},
                        {"step": 3, "instances": [{"instance": 0, "wind_scale": 0.5}]},
                        {"step": 4, "remove": [0], "add": [{"model": "tree"}, {"model": "tree"}]},
                        {"step": 5, "instances": [{"instance": 1}]}])");
    ASSERT_TRUE(ok.ok()) << ok.status().message();
    EXPECT_TRUE(validate_schedule(*ok, names, 2, Wind{}).ok());
    // Remove indices are those before the event: after removing 0 of two, index 1 is gone.
    auto gone = parse(R"([{"step": 3, "remove": [0]}, {"step": 3, "instances": [{"instance": 1}]}])");
    ASSERT_TRUE(gone.ok());
    Status s = validate_schedule(*gone, names, 2, Wind{});
    EXPECT_FALSE(s.ok());
    EXPECT_NE(s.message().find("events[1]"), std::string::npos) << s.message();
    // An event that leaves no instance is refused (a simulation keeps at least one); removing
    // the only instance while adding one in the same event is fine.
    auto empty = parse(R"([{"step": 3, "remove": [0]}])");
    ASSERT_TRUE(empty.ok());
    s = validate_schedule(*empty, names, 1, Wind{});
    EXPECT_FALSE(s.ok());
    EXPECT_NE(s.message().find("removes every instance"), std::string::npos) << s.message();
    auto swap = parse(R"([{"step": 3, "remove": [0], "add": [{"model": "tree"}]}])");
    ASSERT_TRUE(swap.ok());
    EXPECT_TRUE(validate_schedule(*swap, names, 1, Wind{}).ok());
    // Within one event, instances use the indices before the event (applied before remove).
    auto same_event = parse(R"([{"step": 3, "instances": [{"instance": 1, "active": false}], "remove": [1]}])");
    ASSERT_TRUE(same_event.ok());
    EXPECT_TRUE(validate_schedule(*same_event, names, 2, Wind{}).ok());
    // Events past the run's end are still validated.
    auto late = parse(R"([{"step": 1000000, "instances": [{"instance": 7}]}])");
    ASSERT_TRUE(late.ok());
    EXPECT_FALSE(validate_schedule(*late, names, 2, Wind{}).ok());
}

TEST(Schedule, ValidatesTheWindAfterEveryChange) {
    const std::vector<std::string> names = {"tree"};
    Schedule s;
    ScheduleEvent e;
    e.step = 2;
    e.wind.emplace().strength = std::numeric_limits<double>::quiet_NaN();
    s.events.push_back(e);
    Status nan = validate_schedule(s, names, 1, Wind{});
    EXPECT_FALSE(nan.ok());
    EXPECT_NE(nan.message().find("strength"), std::string::npos) << nan.message();
    s.events[0].wind = WindChange{};
    s.events[0].wind->turbulence = 5.0;
    EXPECT_FALSE(validate_schedule(s, names, 1, Wind{}).ok());
    s.events[0].wind = WindChange{};
    s.events[0].forces = std::vector<ForceField>(17);
    EXPECT_FALSE(validate_schedule(s, names, 1, Wind{}).ok());
    s.events[0].forces = std::vector<ForceField>(1);
    (*s.events[0].forces)[0].radius = -1.0;
    EXPECT_FALSE(validate_schedule(s, names, 1, Wind{}).ok());
    (*s.events[0].forces)[0].radius = 1.0;
    EXPECT_TRUE(validate_schedule(s, names, 1, Wind{}).ok());
    s.events.push_back(s.events[0]);
    s.events[1].step = 1;  // out of order
    EXPECT_FALSE(validate_schedule(s, names, 1, Wind{}).ok());
    // An invalid initial wind direction makes a change of strength alone invalid.
    Wind zero;
    zero.direction = Vec3(0.0);
    auto strength = parse(R"([{"step": 1, "wind": {"strength": 2}}])");
    ASSERT_TRUE(strength.ok());
    EXPECT_FALSE(validate_schedule(*strength, names, 1, zero).ok());
}

TEST(Schedule, NextStepBatchesTheStepsBetweenEvents) {
    auto s = parse(R"([{"step": 3}, {"step": 3}, {"step": 10}])");
    ASSERT_TRUE(s.ok());
    EXPECT_EQ(next_schedule_step(*s, 0), 3u);
    EXPECT_EQ(next_schedule_step(*s, 3), 10u);
    EXPECT_FALSE(next_schedule_step(*s, 10).has_value());
}

// Needs the live-control calls of Simulation (set_wind, set_force_fields, set_instance_*,
// add_instances, remove_instances).
TEST(Schedule, AppliesEventsInOrderWindForcesInstancesRemoveAdd) {
    Scene scene = single_tree_scene(test::small_tree());
    scene.instances.push_back({0, Vec3(5, 0, 0), 0.3});
    scene.instances.push_back({0, Vec3(10, 0, 0), 0.6});
    SimulationConfig config;
    config.backend = BackendKind::cpu64;
    auto created = Simulation::create(scene, config);
    ASSERT_TRUE(created.ok()) << created.status().message();
    Simulation& sim = **created;
    auto s = parse(R"([{"step": 2, "wind": {"speed": 12, "direction": [0, 0, 1]},
                        "forces": [{"center": [0, 1, 0], "radius": 3, "radial": 2}],
                        "instances": [{"instance": 2, "wind_scale": 0.25, "active": false}],
                        "remove": [0], "add": [{"model": "tree", "origin": [20, 0, 0], "wind_phase": 0.5}]},
                       {"step": 5, "forces": []}])");
    ASSERT_TRUE(s.ok()) << s.status().message();
    ASSERT_TRUE(validate_schedule(*s, scene.model_names, 3, config.wind).ok());
    ASSERT_TRUE(sim.step(1).ok());
    ASSERT_TRUE(apply_schedule_events(*s, 2, sim).ok());
    EXPECT_EQ(sim.wind().strength, 4.0);
    EXPECT_EQ(sim.wind().direction, Vec3(0, 0, 1));
    EXPECT_EQ(sim.wind().profile, config.wind.profile);
    ASSERT_EQ(sim.force_fields().size(), 1u);
    EXPECT_EQ(sim.force_fields()[0].radial, 2.0);
    // Instance 2 was changed before instance 0 was removed: it is now index 1.
    ASSERT_EQ(sim.instances().size(), 3u);
    EXPECT_EQ(sim.instances()[0].origin, Vec3(5, 0, 0));
    EXPECT_EQ(sim.instances()[1].origin, Vec3(10, 0, 0));
    EXPECT_EQ(sim.instances()[1].wind_scale, 0.25);
    EXPECT_FALSE(sim.instances()[1].active);
    EXPECT_EQ(sim.instances()[2].origin, Vec3(20, 0, 0));
    EXPECT_EQ(sim.instances()[2].wind_phase, 0.5);
    // Events of other steps are not applied.
    ASSERT_TRUE(apply_schedule_events(*s, 4, sim).ok());
    EXPECT_EQ(sim.force_fields().size(), 1u);
    ASSERT_TRUE(apply_schedule_events(*s, 5, sim).ok());
    EXPECT_TRUE(sim.force_fields().empty());
}

TEST(Forest, InstanceWindScalePhaseAndActive) {
    auto scene = parse_forest(R"({"format": "hmsm-forest", "version": 1, "models": {"p": "preset:paper-5"},
        "instances": [{"model": "p"},
                      {"model": "p", "origin": [4, 0, 1], "yaw": 0.5, "wind_scale": 0.6, "wind_phase": 0.25, "active": false}]})",
                              ".", "f.json");
    ASSERT_TRUE(scene.ok()) << scene.status().message();
    ASSERT_EQ(scene->instances.size(), 2u);
    const Instance& a = scene->instances[0];
    EXPECT_EQ(a.origin, Vec3(0.0));  // the defaults of docs/model.md 4
    EXPECT_EQ(a.yaw, 0.0);
    EXPECT_EQ(a.wind_scale, 1.0);
    EXPECT_EQ(a.wind_phase, 0.0);
    EXPECT_TRUE(a.active);
    const Instance& b = scene->instances[1];
    EXPECT_EQ(b.origin, Vec3(4, 0, 1));
    EXPECT_EQ(b.yaw, 0.5);
    EXPECT_EQ(b.wind_scale, 0.6);
    EXPECT_EQ(b.wind_phase, 0.25);
    EXPECT_FALSE(b.active);
    for (const char* bad : {R"("wind_scale": -1)", R"("wind_scale": "1")", R"("wind_phase": "x")", R"("active": 1)"}) {
        auto rejected = parse_forest(std::string(R"({"format": "hmsm-forest", "version": 1, "models": {"p": "preset:paper-5"},
            "instances": [{"model": "p", )") + bad + "}]}", ".", "f.json");
        EXPECT_FALSE(rejected.ok()) << bad;
        EXPECT_TRUE(is_input_error(rejected.status().code())) << bad;
        EXPECT_NE(rejected.status().message().find("instances[0]"), std::string::npos) << rejected.status().message();
    }
    Scene direct = single_tree_scene(test::small_tree());
    direct.instances[0].wind_scale = -0.5;
    EXPECT_FALSE(validate_scene(direct).ok());
    direct.instances[0].wind_scale = 0.0;
    direct.instances[0].wind_phase = std::numeric_limits<double>::infinity();
    EXPECT_FALSE(validate_scene(direct).ok());
}

TEST(GridScene, RefusesAbsurdCountsBeforeAllocating) {
    for (uint32_t count : {kMaxGridInstances + 1, uint32_t(4000000000u)}) {
        auto scene = grid_scene(test::small_tree(), count, 10.0, 1);
        ASSERT_FALSE(scene.ok()) << count;
        EXPECT_EQ(scene.status().code(), ErrorCode::unsupported);  // a limit, as in Simulation::create
        EXPECT_NE(scene.status().message().find("scene too large"), std::string::npos);
        EXPECT_NE(scene.status().message().find(std::to_string(count)), std::string::npos) << scene.status().message();
    }
    // 3 vertices per node per instance at least: 1,000 nodes x 2^21 instances is past 2^32.
    auto big = grid_scene(test::rod(999, 50.0, 0.5), uint32_t(1) << 21, 1.0, 1);
    ASSERT_FALSE(big.ok());
    EXPECT_NE(big.status().message().find("mesh vertices"), std::string::npos) << big.status().message();
    EXPECT_TRUE(grid_scene(test::small_tree(), 9, 10.0, 1).ok());
}
