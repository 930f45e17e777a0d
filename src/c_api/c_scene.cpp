// The C ABI's scenes: models and instances, assembled by the caller or read from a forest file.
#include "c_api_internal.h"
#include "c_struct.h"
#include "model/input_limits.h"

#include <optional>

using namespace hmsm;
using namespace hmsm::c_api;

extern "C" {

hmsm_status hmsm_scene_create(hmsm_scene** scene) {
    return guarded([&]() -> Status {
        if (!scene) return bad("hmsm_scene_create: scene is NULL");
        *scene = new hmsm_scene{};
        return {};
    });
}

hmsm_status hmsm_scene_load_forest(const char* path, hmsm_scene** scene) {
    return guarded([&]() -> Status {
        if (!path) return bad("hmsm_scene_load_forest: path is NULL");
        if (!scene) return bad("hmsm_scene_load_forest: scene is NULL");
        Result<Scene> loaded = load_forest(path);
        if (!loaded) return loaded.status();
        *scene = new hmsm_scene{std::move(*loaded)};
        return {};
    });
}

hmsm_status hmsm_scene_load_forest_with(const char* path, const char* const* names, size_t count,
                                        hmsm_scene** scene) {
    return guarded([&]() -> Status {
        if (!path) return bad("hmsm_scene_load_forest_with: path is NULL");
        if (!scene) return bad("hmsm_scene_load_forest_with: scene is NULL");
        if (!names && count > 0) return bad("hmsm_scene_load_forest_with: names is NULL");
        std::vector<std::string> extra;
        for (size_t i = 0; i < count; ++i) {
            if (!names[i]) return bad("hmsm_scene_load_forest_with: names[" + std::to_string(i) + "] is NULL");
            extra.emplace_back(names[i]);
        }
        Result<Scene> loaded = load_forest(path, extra);
        if (!loaded) return loaded.status();
        *scene = new hmsm_scene{std::move(*loaded)};
        return {};
    });
}

hmsm_status hmsm_scene_find_model(const hmsm_scene* scene, const char* name, uint32_t* model) {
    return guarded([&]() -> Status {
        if (!scene) return bad("hmsm_scene_find_model: scene is NULL");
        if (!name) return bad("hmsm_scene_find_model: name is NULL");
        if (!model) return bad("hmsm_scene_find_model: model is NULL");
        const std::optional<uint32_t> found = find_model(scene->scene, name);
        if (!found)
            return bad("hmsm_scene_find_model: no model is called '" + detail::quote_input(name) + "'");
        *model = *found;
        return {};
    });
}

hmsm_status hmsm_scene_add_model(hmsm_scene* scene, const hmsm_tree* tree, const char* name,
                                 uint32_t* model) {
    return guarded([&]() -> Status {
        if (!scene) return bad("hmsm_scene_add_model: scene is NULL");
        if (!tree) return bad("hmsm_scene_add_model: tree is NULL");
        if (!name) return bad("hmsm_scene_add_model: name is NULL");
        if (scene->scene.models.size() >= UINT32_MAX)
            return bad("hmsm_scene_add_model: too many models");
        const auto index = static_cast<uint32_t>(scene->scene.models.size());
        scene->scene.models.push_back(tree->model);
        scene->scene.model_names.emplace_back(name);
        if (model) *model = index;
        return {};
    });
}

hmsm_status hmsm_scene_set_joint_budget(hmsm_scene* scene, uint32_t model, int32_t max_joints) {
    return guarded([&]() -> Status {
        const std::string fn = "hmsm_scene_set_joint_budget";
        if (!scene) return bad(fn + ": scene is NULL");
        const size_t models = scene->scene.models.size();
        if (model >= models)
            return bad(fn + ": model " + std::to_string(model) + " does not exist (" + std::to_string(models) +
                       " models)");
        if (max_joints < 0)
            return bad(fn + ": max_joints " + std::to_string(max_joints) +
                       ": must be 0 (the model whole) or at least 1 (the trunk-only level)");
        scene->scene.joint_budgets.resize(models, 0);
        scene->scene.joint_budgets[model] = max_joints;
        return {};
    });
}

hmsm_status hmsm_scene_add_instance(hmsm_scene* scene, const hmsm_instance* instance) {
    return guarded([&]() -> Status {
        if (!scene) return bad("hmsm_scene_add_instance: scene is NULL");
        if (!instance) return bad("hmsm_scene_add_instance: instance is NULL");
        hmsm_instance full;
        HMSM_TRY(read_struct("hmsm_scene_add_instance: instance", instance, full));
        Instance converted;
        HMSM_TRY(to_cpp(full, converted, "hmsm_scene_add_instance: instance"));
        if (converted.model >= scene->scene.models.size())
            return bad("hmsm_scene_add_instance: instance.model " +
                       std::to_string(converted.model) +
                       " names no model (the scene has " +
                       std::to_string(scene->scene.models.size()) + ")");
        scene->scene.instances.push_back(converted);
        return {};
    });
}

hmsm_status hmsm_scene_model_count(const hmsm_scene* scene, uint32_t* count) {
    return guarded([&]() -> Status {
        if (!scene) return bad("hmsm_scene_model_count: scene is NULL");
        if (!count) return bad("hmsm_scene_model_count: count is NULL");
        *count = static_cast<uint32_t>(scene->scene.models.size());
        return {};
    });
}

hmsm_status hmsm_scene_instance_count(const hmsm_scene* scene, uint64_t* count) {
    return guarded([&]() -> Status {
        if (!scene) return bad("hmsm_scene_instance_count: scene is NULL");
        if (!count) return bad("hmsm_scene_instance_count: count is NULL");
        *count = scene->scene.instances.size();
        return {};
    });
}

void hmsm_scene_destroy(hmsm_scene* scene) { delete scene; }

}  // extern "C"
