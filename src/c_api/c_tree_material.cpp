// The C ABI of a tree's wood and leaf state for the coupled dynamics (include/hmsm/species.h,
// docs/model.md 3.13 and 4.1): species presets, a material by species or by value, leaf-on or
// leaf-off. They set TreeModel::material and TreeModel::leaves_on, which a model added to a
// scene afterwards carries (hmsm_scene_add_model copies the tree).
#include "c_api_internal.h"

#include "model/input_limits.h"

#include <hmsm/species.h>

using namespace hmsm;
using namespace hmsm::c_api;

extern "C" {

hmsm_status hmsm_species_count(uint64_t* count) {
    return guarded([&]() -> Status {
        if (!count) return bad("hmsm_species_count: count is NULL");
        *count = species_presets().size();
        return {};
    });
}

hmsm_status hmsm_species_name(uint64_t index, const char** name) {
    return guarded([&]() -> Status {
        if (!name) return bad("hmsm_species_name: name is NULL");
        const std::vector<SpeciesPreset>& presets = species_presets();
        if (index >= presets.size())
            return bad("hmsm_species_name: index " + std::to_string(index) + " does not exist (" +
                       std::to_string(presets.size()) + " species)");
        *name = presets[index].name.c_str();
        return {};
    });
}

hmsm_status hmsm_tree_set_species(hmsm_tree* tree, const char* name) {
    return guarded([&]() -> Status {
        if (!tree) return bad("hmsm_tree_set_species: tree is NULL");
        if (!name) return bad("hmsm_tree_set_species: name is NULL");
        Result<TreeMaterial> material = species_material(name);
        if (!material) return {material.status().code(), "hmsm_tree_set_species: " + material.status().message()};
        tree->model.material = *material;
        return {};
    });
}

hmsm_status hmsm_tree_set_material(hmsm_tree* tree, double modulus, double density) {
    return guarded([&]() -> Status {
        if (!tree) return bad("hmsm_tree_set_material: tree is NULL");
        HMSM_TRY(detail::check_tree_material("hmsm_tree_set_material: ", {}, modulus, density));
        tree->model.material = TreeMaterial{{}, modulus, density};
        return {};
    });
}

hmsm_status hmsm_tree_clear_material(hmsm_tree* tree) {
    return guarded([&]() -> Status {
        if (!tree) return bad("hmsm_tree_clear_material: tree is NULL");
        tree->model.material.reset();
        return {};
    });
}

hmsm_status hmsm_tree_material(const hmsm_tree* tree, int32_t* has_material, double* modulus, double* density) {
    return guarded([&]() -> Status {
        if (!tree) return bad("hmsm_tree_material: tree is NULL");
        if (!has_material || !modulus || !density)
            return bad("hmsm_tree_material: has_material, modulus and density must not be NULL");
        *has_material = tree->model.material ? 1 : 0;
        *modulus = tree->model.material ? tree->model.material->modulus : 0.0;
        *density = tree->model.material ? tree->model.material->density : 0.0;
        return {};
    });
}

hmsm_status hmsm_tree_set_leaf_state(hmsm_tree* tree, int32_t state) {
    return guarded([&]() -> Status {
        if (!tree) return bad("hmsm_tree_set_leaf_state: tree is NULL");
        switch (state) {
        case HMSM_LEAF_STATE_FROM_PARAMETERS: tree->model.leaves_on.reset(); return {};
        case HMSM_LEAF_STATE_ON: tree->model.leaves_on = true; return {};
        case HMSM_LEAF_STATE_OFF: tree->model.leaves_on = false; return {};
        default:
            return bad("hmsm_tree_set_leaf_state: state " + std::to_string(state) +
                       " is not an HMSM_LEAF_STATE_* value (0, 1 or 2)");
        }
    });
}

hmsm_status hmsm_tree_leaf_state(const hmsm_tree* tree, int32_t* state) {
    return guarded([&]() -> Status {
        if (!tree) return bad("hmsm_tree_leaf_state: tree is NULL");
        if (!state) return bad("hmsm_tree_leaf_state: state is NULL");
        *state = !tree->model.leaves_on ? HMSM_LEAF_STATE_FROM_PARAMETERS
                                         : (*tree->model.leaves_on ? HMSM_LEAF_STATE_ON : HMSM_LEAF_STATE_OFF);
        return {};
    });
}

}  // extern "C"
