#include <hmsm/scene.h>

#include "input_limits.h"
#include "random.h"

#include <cmath>
#include <cstdint>
#include <numbers>
#include <string>

namespace hmsm {

Scene single_tree_scene(TreeModel tree, glm::dvec3 origin, double yaw) {
    Scene scene;
    scene.models.push_back(std::move(tree));
    scene.model_names.push_back("tree");
    scene.instances.push_back({0, origin, yaw});
    return scene;
}

Result<Scene> grid_scene(TreeModel tree, uint32_t count, double spacing, uint64_t seed) {
    if (count == 0) return Status{ErrorCode::invalid_argument, "instances must be >= 1"};
    if (!std::isfinite(spacing) || spacing < 0.0)
        return Status{ErrorCode::invalid_argument, "spacing must be finite and >= 0"};
    // Refuse absurd counts before the instance list is allocated: every node lies on at least
    // one ring of >= 3 vertices, so an instance has at least 3 * nodes mesh vertices, and the
    // flattened buffers hold at most 2^32 - 1 of them.
    const uint64_t min_vertices = 3 * uint64_t(tree.nodes.size()) * uint64_t(count);
    if (count > kMaxGridInstances || min_vertices >= uint64_t(UINT32_MAX))
        return Status{ErrorCode::unsupported,
                      "scene too large: " + std::to_string(count) + " instances (at most " +
                          std::to_string(kMaxGridInstances) + ", and at most 2^32 - 1 mesh vertices; " +
                          std::to_string(tree.nodes.size()) + " nodes per instance)"};
    Scene scene;
    scene.models.push_back(std::move(tree));
    scene.model_names.push_back("tree");
    const uint32_t side = uint32_t(std::ceil(std::sqrt(double(count))));
    const double centre = 0.5 * double(side - 1) * spacing;
    detail::Random random(seed);
    for (uint32_t i = 0; i < count; ++i) {
        glm::dvec3 origin(double(i % side) * spacing - centre, 0.0, double(i / side) * spacing - centre);
        scene.instances.push_back({0, origin, random.uniform(0.0, 2.0 * std::numbers::pi)});
    }
    return scene;
}

std::optional<uint32_t> find_model(const Scene& scene, std::string_view name) {
    for (size_t m = 0; m < scene.model_names.size(); ++m)
        if (scene.model_names[m] == name) return uint32_t(m);
    for (const ModelAlias& alias : scene.model_aliases)
        if (alias.name == name) return alias.model;
    return std::nullopt;
}

std::vector<std::string> all_model_names(const Scene& scene) {
    std::vector<std::string> names = scene.model_names;
    for (const ModelAlias& alias : scene.model_aliases) names.push_back(alias.name);
    return names;
}

Status validate_scene(const Scene& scene) {
    if (scene.models.empty()) return {ErrorCode::invalid_argument, "scene has no models"};
    if (scene.model_names.size() != scene.models.size())
        return {ErrorCode::invalid_argument, "scene: model_names and models differ in length"};
    if (scene.instances.empty()) return {ErrorCode::invalid_argument, "scene has no instances"};
    HMSM_TRY(detail::check_count("scene: instances", scene.instances.size(), kMaxInstances,
                                 ErrorCode::unsupported));
    for (size_t i = 0; i < scene.instances.size(); ++i) {
        const Instance& inst = scene.instances[i];
        std::string where = "instance " + std::to_string(i) + ": ";
        if (inst.model >= scene.models.size())
            return {ErrorCode::invalid_argument, where + "model index " + std::to_string(inst.model) +
                                                     " does not exist"};
        HMSM_TRY(detail::check_coordinate(where + "origin", inst.origin));
        if (!std::isfinite(inst.yaw)) return {ErrorCode::invalid_argument, where + "yaw is not finite"};
        HMSM_TRY(detail::check_wind_scale(where + "wind_scale", inst.wind_scale));
        if (!std::isfinite(inst.wind_phase))
            return {ErrorCode::invalid_argument, where + "wind_phase is not finite"};
        const size_t levels = 1 + (inst.model < scene.lod_budgets.size() ? scene.lod_budgets[inst.model].size() : 0);
        if (inst.level >= levels)
            return {ErrorCode::invalid_argument, where + "level " + std::to_string(inst.level) +
                                                     " does not exist (model " + std::to_string(inst.model) +
                                                     " has levels 0 to " + std::to_string(levels - 1) +
                                                     ", Scene::lod_budgets)"};
    }
    if (scene.joint_budgets.size() > scene.models.size())
        return {ErrorCode::invalid_argument, "scene: " + std::to_string(scene.joint_budgets.size()) +
                                                 " joint budgets for " + std::to_string(scene.models.size()) +
                                                 " models"};
    for (size_t m = 0; m < scene.joint_budgets.size(); ++m)
        if (scene.joint_budgets[m] < 0)
            return {ErrorCode::invalid_argument,
                    "model '" + scene.model_names[m] + "': joint budget " + std::to_string(scene.joint_budgets[m]) +
                        ": must be 0 (the model whole) or at least 1 (the trunk-only level)"};
    if (scene.lod_budgets.size() > scene.models.size())
        return {ErrorCode::invalid_argument, "scene: level-of-detail budgets for " +
                                                 std::to_string(scene.lod_budgets.size()) + " models, the scene has " +
                                                 std::to_string(scene.models.size())};
    for (size_t m = 0; m < scene.lod_budgets.size(); ++m)
        for (size_t k = 0; k < scene.lod_budgets[m].size(); ++k)
            if (scene.lod_budgets[m][k] < 1)
                return {ErrorCode::invalid_argument,
                        "model '" + scene.model_names[m] + "': level " + std::to_string(k + 1) + " joint budget " +
                            std::to_string(scene.lod_budgets[m][k]) +
                            ": below the trunk-only level, the coarsest there is (1 joint)"};
    for (const ModelAlias& alias : scene.model_aliases)
        if (alias.model >= scene.models.size())
            return {ErrorCode::invalid_argument, "scene: model alias '" + detail::quote_input(alias.name) +
                                                     "' names model " + std::to_string(alias.model) +
                                                     ", which does not exist"};
    for (size_t m = 0; m < scene.models.size(); ++m) {
        Status valid = validate_tree(scene.models[m]);
        if (!valid) return {valid.code(), "model '" + scene.model_names[m] + "': " + valid.message()};
    }
    return {};
}

}  // namespace hmsm
