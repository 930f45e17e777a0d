// hmsm-forest JSON v1 (docs/model.md 4): named models (files relative to the forest file, or
// "preset:NAME") and instances that refer to them. Each distinct reference is loaded once.
#include <hmsm/generator.h>
#include <hmsm/scene.h>

#include "json_util.h"
#include "input_limits.h"

#include <filesystem>
#include <map>

namespace hmsm {

Result<Scene> parse_forest(std::string_view text, const std::string& base_directory,
                           std::string_view source) {
    auto parsed = detail::parse_json(text, source);
    if (!parsed) return parsed.status();
    const auto& doc = *parsed;
    detail::JsonReader r(source, ErrorCode::invalid_tree);
    HMSM_TRY(r.expect_object(doc, ""));
    HMSM_TRY(r.expect_format(doc, "hmsm-forest"));
    auto models_it = doc.find("models");
    if (models_it == doc.end()) return r.error("", "models", "missing");
    if (!models_it->is_object() || models_it->empty())
        return r.error("", "models", "expected a non-empty object of name: path");

    HMSM_TRY(detail::check_count(std::string(source) + ": models", models_it->size(), detail::size_limits().forest_models,
                                 ErrorCode::invalid_tree));

    // Every named model is loaded (a schedule may add instances of any), each distinct
    // reference (file or preset) read or generated once. What building them would take is
    // summed before a model is copied under another name: at the fewest ring sides (3) it is
    // less than any simulation of the forest builds, so a forest no simulation could build is
    // refused here (docs/model.md 3.11).
    Scene scene;
    std::map<std::string, uint32_t> index;    // model name -> scene model
    std::map<std::string, TreeModel> loaded;  // reference -> model, loaded once
    uint64_t build_bytes = 0;
    for (auto it = models_it->begin(); it != models_it->end(); ++it) {
        const std::string name = it.key();
        if (!it->is_string()) return r.error("models", detail::quote_input(name).c_str(), "expected a path string");
        const std::string ref = it->get<std::string>();
        auto cached = loaded.find(ref);
        if (cached == loaded.end()) {
            Result<TreeModel> model = Status{};
            if (ref.rfind("preset:", 0) == 0) {
                model = generate_preset(ref.substr(7));
            } else {
                std::filesystem::path path(ref);
                if (path.is_relative()) path = std::filesystem::path(base_directory) / path;
                model = load_tree(path.string());
            }
            if (!model)
                return Status{model.status().code(),
                              detail::one_line(std::string(source) + ": models." + detail::quote_input(name) + ": " +
                                               model.status().message())};
            cached = loaded.emplace(ref, std::move(model).value()).first;
        }
        build_bytes += detail::model_build_bytes(cached->second.nodes.size(), cached->second.leaves.size(), 3);
        if (build_bytes > detail::size_limits().build_bytes)
            return Status{ErrorCode::unsupported,
                          std::string(source) + ": models: building its models would take more than " +
                              std::to_string(detail::size_limits().build_bytes >> 20) +
                              " MiB of host memory, the limit (docs/model.md 3.11)"};
        index[name] = uint32_t(scene.models.size());
        scene.models.push_back(cached->second);
        scene.model_names.push_back(name);
    }

    const nlohmann::json* instances = nullptr;
    HMSM_TRY(r.array_field(doc, "", "instances", instances));
    if (instances->empty()) return r.error("", "instances", "must list at least one instance");
    HMSM_TRY(detail::check_count(std::string(source) + ": instances", instances->size(), kMaxInstances,
                                 ErrorCode::unsupported));
    for (size_t i = 0; i < instances->size(); ++i) {
        const auto& item = (*instances)[i];
        std::string where = "instances[" + std::to_string(i) + "]";
        HMSM_TRY(r.expect_object(item, where));
        std::string name;
        HMSM_TRY(r.string_field(item, where, "model", name));
        auto found = index.find(name);
        if (found == index.end())
            return r.error(where, "model", "\"" + detail::quote_input(name) + "\" is not one of the forest's models");
        Instance inst;
        inst.model = found->second;
        if (item.contains("origin")) {
            HMSM_TRY(r.vec3_field(item, where, "origin", inst.origin));
            if (Status range = detail::check_coordinate("origin", inst.origin); !range)
                return r.error(where, "origin", range.message());
        }
        if (item.contains("yaw")) HMSM_TRY(r.number_field(item, where, "yaw", inst.yaw));
        if (item.contains("wind_scale")) {
            HMSM_TRY(r.number_field(item, where, "wind_scale", inst.wind_scale));
            if (Status range = detail::check_wind_scale("wind_scale", inst.wind_scale); !range)
                return r.error(where, "wind_scale", range.message());
        }
        if (item.contains("wind_phase")) HMSM_TRY(r.number_field(item, where, "wind_phase", inst.wind_phase));
        if (item.contains("active")) {
            if (!item["active"].is_boolean())
                return r.error(where, "active", "expected true or false, got " + detail::quote_input(item["active"].dump()));
            inst.active = item["active"].get<bool>();
        }
        scene.instances.push_back(inst);
    }
    return scene;
}

Result<Scene> load_forest(const std::string& path) {
    auto text = detail::read_text_file(path);
    if (!text) return text.status();
    std::string base = std::filesystem::path(path).parent_path().string();
    return parse_forest(*text, base.empty() ? "." : base, path);
}

}  // namespace hmsm
