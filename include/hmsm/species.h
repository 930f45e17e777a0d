// Wood species presets of the coupled dynamics (docs/model.md 3.13, data/species.json, embedded
// in the library) and the material a tree file carries (docs/model.md 4.1).
#pragma once

#include <hmsm/export.h>

#include <hmsm/options.h>
#include <hmsm/status.h>
#include <hmsm/tree.h>

#include <string>
#include <string_view>
#include <vector>

namespace hmsm {

/// One species: green (unseasoned) modulus and density with their source.
struct SpeciesPreset {
    std::string name;             ///< the key, e.g. "sugar-maple"
    std::string common_name, scientific_name;
    std::string kind;             ///< "broadleaf" or "conifer"
    double modulus = 0.0;         ///< E (Pa)
    double density = 0.0;         ///< green density (kg/m^3)
    std::string citation;
};

/// Every preset, in the table's order.
HMSM_API const std::vector<SpeciesPreset>& species_presets();
/// The preset called `name`; invalid_argument naming it and the known names otherwise.
HMSM_API Result<SpeciesPreset> find_species(std::string_view name);
/// The tree's material for `species`: its modulus and density, named after it.
HMSM_API Result<TreeMaterial> species_material(std::string_view name);

/// The parameters a model is simulated with under coupled: `parameters` with the tree's own
/// material (modulus, density) and leaf state in place of Parameters::material and foliage.on
/// where the tree carries them. To override a tree's material, change or clear
/// TreeModel::material and TreeModel::leaves_on.
HMSM_API Parameters parameters_for_tree(const TreeModel& tree, Parameters parameters);

}  // namespace hmsm
