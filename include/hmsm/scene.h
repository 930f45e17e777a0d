// Instances of one or many tree models (docs/model.md 3.6) and the forest file (docs/model.md 4).
#pragma once

#include <hmsm/export.h>

#include <hmsm/tree.h>

#include <cstdint>
#include <optional>
#include <span>
#include <string>
#include <string_view>
#include <vector>

namespace hmsm {

/// A placed copy of a model: rotated by Ry(yaw) about its origin, then moved to origin.
struct Instance {
    uint32_t model = 0;
    Vec3 origin{0.0};
    double yaw = 0.0;          ///< radians, about +y
    double wind_scale = 1.0;   ///< lambda >= 0: shelter (< 1), exposed forest edge (> 1)
    double wind_phase = 0.0;   ///< p, added to the profile's argument (profile units)
    bool active = true;        ///< an inactive instance is frozen (docs/model.md 3.9)
    /// Level of detail (Scene::lod_budgets; 0: the model as created): the level it starts on
    /// in Scene::instances and Simulation::add_instances, so that a tree streamed in far away
    /// never runs its finer levels; in Simulation::instances(), the level it runs on.
    uint32_t level = 0;
};

/// A further name of a scene model: forest keys that name one file or preset share its model.
struct ModelAlias {
    std::string name;
    uint32_t model = 0;
};

struct Scene {
    std::vector<TreeModel> models;
    std::vector<std::string> model_names;  ///< same length as models: each model's first name
    std::vector<ModelAlias> model_aliases; ///< more names, each of a model in `models`
    std::vector<Instance> instances;
    /// Per model (models past its end: 0): 0 runs the model whole; N >= 1 runs, in its place,
    /// its finest level of detail with at most N chains (docs/model.md 3.12), whose kept chains
    /// move as the model's and whose folded branches move rigidly with them.
    std::vector<int32_t> joint_budgets;
    /// Per model (models past its end: none): the joint budgets (each >= 1) of the levels of
    /// detail its instances may switch to while the simulation runs (Simulation::set_instance_lod,
    /// docs/driving.md). Level 0 is the model as joint_budgets runs it; level k >= 1 is the
    /// finest level with at most lod_budgets[m][k - 1] chains. Empty: the model has level 0 only.
    std::vector<std::vector<int32_t>> lod_budgets;
};

/// The model called `name`: among model_names first, then model_aliases.
HMSM_API std::optional<uint32_t> find_model(const Scene& scene, std::string_view name);
/// Every name of the scene's models: model_names, then the aliases' names.
HMSM_API std::vector<std::string> all_model_names(const Scene& scene);

/// One instance of `tree` (at the origin with yaw 0 by default).
HMSM_API Scene single_tree_scene(TreeModel tree, Vec3 origin = Vec3(0.0), double yaw = 0.0);

/// Most instances a simulation holds (2^24 - 1): Simulation::create, add_instances, a forest
/// file and grid_scene refuse more (docs/model.md 3.11).
inline constexpr uint32_t kMaxInstances = (uint32_t(1) << 24) - 1;
/// Most instances grid_scene places: kMaxInstances.
inline constexpr uint32_t kMaxGridInstances = kMaxInstances;

/// `count` instances of `tree` on a square grid `spacing` apart, centred on the origin, with
/// yaws drawn deterministically from `seed`. Counts above kMaxGridInstances, or with more than
/// 2^32 - 2 mesh vertices for certain (3 per node per instance at least), are refused as
/// `unsupported` ("scene too large", as Simulation::create) before anything is allocated.
HMSM_API Result<Scene> grid_scene(TreeModel tree, uint32_t count, double spacing, uint64_t seed);

/// Reads an hmsm-forest JSON v1 file; model paths are relative to the file, "preset:NAME"
/// generates a preset. Only the models that an instance places or `extra_models` names are
/// loaded and built, each distinct file or preset once: names sharing one become one scene
/// model (model_names holds its first needed name, model_aliases the others). A model nobody
/// needs is checked to be a string naming an existing file or a known preset, never read
/// (docs/model.md 3.11). A name in `extra_models` that the forest does not define is an error.
HMSM_API Result<Scene> load_forest(const std::string& path, std::span<const std::string> extra_models = {});
HMSM_API Result<Scene> parse_forest(std::string_view json, const std::string& base_directory,
                                    std::string_view source = "forest",
                                    std::span<const std::string> extra_models = {});

/// Checks that every instance names a model and every number is finite.
HMSM_API Status validate_scene(const Scene& scene);

}  // namespace hmsm
