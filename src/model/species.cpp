// Species presets (data/species.json, embedded at build time as species_table.h) and the
// per-tree material of the coupled dynamics (docs/model.md 3.13, 4.1).
#include <hmsm/species.h>

#include "species_table.h"  // kSpeciesJson, generated from data/species.json

#include <nlohmann/json.hpp>

namespace hmsm {

const std::vector<SpeciesPreset>& species_presets() {
    static const std::vector<SpeciesPreset> presets = [] {
        std::vector<SpeciesPreset> out;
        const auto table = nlohmann::json::parse(detail::kSpeciesJson);
        for (const auto& s : table.at("species"))
            out.push_back({s.at("name").get<std::string>(), s.at("common_name").get<std::string>(),
                           s.at("scientific_name").get<std::string>(), s.at("kind").get<std::string>(),
                           s.at("modulus_pa").get<double>(), s.at("density_kg_m3").get<double>(),
                           s.at("citation").get<std::string>()});
        return out;
    }();
    return presets;
}

Result<SpeciesPreset> find_species(std::string_view name) {
    std::string known;
    for (const SpeciesPreset& s : species_presets()) {
        if (s.name == name) return s;
        known += (known.empty() ? "" : ", ") + s.name;
    }
    std::string shown(name.substr(0, 64));
    for (char& c : shown)
        if (static_cast<unsigned char>(c) < 0x20) c = '?';
    return Status{ErrorCode::invalid_argument, "unknown species \"" + shown + "\" (known: " + known + ")"};
}

Result<TreeMaterial> species_material(std::string_view name) {
    auto preset = find_species(name);
    if (!preset) return preset.status();
    return TreeMaterial{preset->name, preset->modulus, preset->density};
}

Parameters parameters_for_tree(const TreeModel& tree, Parameters parameters) {
    if (tree.material) {
        parameters.material.modulus = tree.material->modulus;
        parameters.material.density = tree.material->density;
    }
    if (tree.leaves_on) parameters.foliage.on = *tree.leaves_on;
    return parameters;
}

}  // namespace hmsm
