// Properties the tree, forest and schedule parsers must have for ANY input, shared by the
// libFuzzer targets (fuzz_tree.cpp, fuzz_forest.cpp) and the corpus replay in the normal test
// suite (fuzz_replay_test.cpp). Each check returns "" or a description of the violation.
//
// For any byte string the parser returns (it must not crash, hang, leak or hit undefined
// behaviour: the sanitizers check that) either
//   - an error of an input class (invalid_tree, invalid_argument or io) with a non-empty message
//     on one line (the CLI prints it as its single stderr line), or
//   - a tree that validates and survives tree_to_json -> parse_tree bit for bit, resp. a scene
//     whose instances all name a model and whose numbers are finite.
#pragma once

#include <hmsm/scene.h>
#include <hmsm/schedule.h>
#include <hmsm/tree.h>

#include <cmath>
#include <cstdint>
#include <cstring>
#include <string>
#include <string_view>

namespace hmsm::fuzz {

inline std::string check_error(const Status& status) {
    if (status.ok()) return "an error Status without a code";
    if (!is_input_error(status.code()))
        return std::string("bad input reported as ") + to_string(status.code()) + ": " + status.message();
    if (status.message().empty()) return "empty error message";
    for (char c : status.message())
        if (c == '\n' || c == '\r') return "error message spans lines: " + status.message();
    return "";
}

inline bool same_bits(double a, double b) { return std::memcmp(&a, &b, sizeof a) == 0; }

inline std::string check_tree(const uint8_t* data, size_t size) {
    std::string_view text(reinterpret_cast<const char*>(data), size);
    Result<TreeModel> tree = parse_tree(text, "fuzz.json");
    if (!tree.ok()) return check_error(tree.status());
    Status valid = validate_tree(*tree);
    if (!valid.ok()) return "parse_tree accepted a tree validate_tree rejects: " + valid.message();
    // Round trip: what we write reads back to the same bits (17 significant digits).
    std::string json = tree_to_json(*tree);
    Result<TreeModel> again = parse_tree(json, "round-trip");
    if (!again.ok()) return "tree_to_json output does not parse: " + again.status().message();
    const TreeModel& a = *tree;
    const TreeModel& b = *again;
    if (a.nodes.size() != b.nodes.size() || a.leaves.size() != b.leaves.size())
        return "round trip changed the counts";
    for (size_t i = 0; i < a.nodes.size(); ++i) {
        bool same = a.nodes[i].parent == b.nodes[i].parent && same_bits(a.nodes[i].radius, b.nodes[i].radius);
        for (int k = 0; k < 3; ++k) same = same && same_bits(a.nodes[i].position[k], b.nodes[i].position[k]);
        if (!same) return "round trip changed node " + std::to_string(i);
    }
    for (size_t j = 0; j < a.leaves.size(); ++j) {
        const TreeLeaf& x = a.leaves[j];
        const TreeLeaf& y = b.leaves[j];
        bool same = x.node == y.node && same_bits(x.size.x, y.size.x) && same_bits(x.size.y, y.size.y);
        for (int k = 0; k < 3; ++k)
            same = same && same_bits(x.offset[k], y.offset[k]) && same_bits(x.normal[k], y.normal[k]) &&
                   same_bits(x.up[k], y.up[k]);
        if (!same) return "round trip changed leaf " + std::to_string(j);
    }
    if (a.material.has_value() != b.material.has_value() || a.leaves_on != b.leaves_on)
        return "round trip changed the material or leaf state's presence";
    if (a.material && (a.material->species != b.material->species ||
                       !same_bits(a.material->modulus, b.material->modulus) ||
                       !same_bits(a.material->density, b.material->density)))
        return "round trip changed the material";
    return "";
}

/// `models_dir` is where relative model paths resolve (a folder with a few valid trees).
inline std::string check_forest(const uint8_t* data, size_t size, const std::string& models_dir) {
    std::string_view text(reinterpret_cast<const char*>(data), size);
    Result<Scene> scene = parse_forest(text, models_dir, "fuzz-forest.json");
    if (!scene.ok()) return check_error(scene.status());
    const Scene& s = *scene;
    if (s.models.empty() || s.instances.empty()) return "accepted a forest without models or instances";
    if (s.model_names.size() != s.models.size()) return "model names and models differ in length";
    Status valid = validate_scene(s);
    if (!valid.ok()) return "parse_forest accepted a scene validate_scene rejects: " + valid.message();
    return "";
}

/// A schedule either fails to parse with a one-line input error, or parses into events in
/// non-decreasing step order (>= 1) with at most 16 valid force fields each, and then either
/// validates against a run of models "tree" and "oak" with 3 instances or fails with a one-line
/// input error.
inline std::string check_schedule(const uint8_t* data, size_t size) {
    std::string_view text(reinterpret_cast<const char*>(data), size);
    Result<Schedule> schedule = parse_schedule(text, "fuzz-schedule.json");
    if (!schedule.ok()) return check_error(schedule.status());
    uint64_t previous = 1;
    for (const ScheduleEvent& e : schedule->events) {
        if (e.step < previous) return "accepted a step < 1 or out of order: " + std::to_string(e.step);
        previous = e.step;
        if (e.wind && e.wind->speed && e.wind->strength) return "accepted both speed and strength";
        if (e.forces) {
            if (e.forces->size() > kMaxForceFields) return "accepted more than 16 force fields";
            for (const ForceField& f : *e.forces)
                if (!(f.radius > 0.0) || !std::isfinite(f.radius) || !std::isfinite(f.radial) ||
                    !std::isfinite(f.center.x + f.center.y + f.center.z) ||
                    !std::isfinite(f.directional.x + f.directional.y + f.directional.z))
                    return "accepted a force field with a bad number";
        }
    }
    const std::string names[] = {"tree", "oak"};
    Status valid = validate_schedule(*schedule, names, 3, Wind{});
    if (!valid.ok()) return check_error(valid);
    return "";
}

}  // namespace hmsm::fuzz
