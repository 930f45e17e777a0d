// hmsm-forest JSON v1 (docs/model.md 4): named models (files relative to the forest file, or
// "preset:NAME") and instances that refer to them. Only the models in use are loaded, each
// distinct reference once.
#include <hmsm/generator.h>
#include <hmsm/scene.h>

#include "json_util.h"
#include "input_limits.h"

#include <algorithm>
#include <filesystem>
#include <map>

namespace hmsm {

namespace {

/// The optional "joint_budgets" {name: N} (Scene::joint_budgets) and "lod_budgets"
/// {name: [N, ...]} (Scene::lod_budgets): per model name, the budgets of the level it runs on
/// and of the levels its instances may switch to. Names sharing a model must agree.
Status read_budgets(const nlohmann::json& doc, detail::JsonReader& r, const std::map<std::string, size_t>& by_name,
                    const std::vector<uint32_t>& model_of_name, Scene& scene) {
    for (const char* key : {"joint_budgets", "lod_budgets"}) {
        auto field = doc.find(key);
        if (field == doc.end()) continue;
        const bool levels = std::string_view(key) == "lod_budgets";
        if (!field->is_object())
            return r.error("", key, levels ? "expected an object of name: [joint budgets]"
                                           : "expected an object of name: joint budget");
        std::vector<char> set(scene.models.size(), 0);
        for (auto it = field->begin(); it != field->end(); ++it) {
            const std::string name = detail::quote_input(it.key());
            auto found = by_name.find(it.key());
            if (found == by_name.end()) return r.error(key, name.c_str(), "is not one of the forest's models");
            std::vector<int32_t> budgets;
            const bool list = it->is_array();
            for (const auto& b : list ? *it : nlohmann::json::array({*it})) {
                if (!b.is_number_integer() || b.get<int64_t>() < (levels ? 1 : 0) || b.get<int64_t>() > INT32_MAX)
                    return r.error(key, name.c_str(),
                                   std::string(levels ? "expected joint budgets of at least 1 (the trunk-only level)"
                                                      : "expected 0 (the model whole) or a joint budget of at least 1") +
                                       ", got " + detail::quote_input(b.dump()));
                budgets.push_back(int32_t(b.get<int64_t>()));
            }
            if (list != levels || budgets.empty())
                return r.error(key, name.c_str(), levels ? "expected a non-empty array of joint budgets"
                                                         : "expected one joint budget");
            const uint32_t m = model_of_name[found->second];
            if (m == UINT32_MAX) continue;  // a model no instance places
            if (levels) {
                scene.lod_budgets.resize(scene.models.size());
                if (set[m] && scene.lod_budgets[m] != budgets)
                    return r.error(key, name.c_str(), "names the same model as another name, with other budgets");
                scene.lod_budgets[m] = budgets;
            } else {
                scene.joint_budgets.resize(scene.models.size(), 0);
                if (set[m] && scene.joint_budgets[m] != budgets[0])
                    return r.error(key, name.c_str(), "names the same model as another name, with another budget");
                scene.joint_budgets[m] = budgets[0];
            }
            set[m] = 1;
        }
    }
    return {};
}

}  // namespace

Result<Scene> parse_forest(std::string_view text, const std::string& base_directory, std::string_view source,
                           std::span<const std::string> extra_models) {
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

    // Each name's reference, in the file's order; which names are needed is known once the
    // instances are read (docs/model.md 3.11).
    struct NamedModel {
        std::string name;
        std::string reference;
        bool needed = false;
    };
    std::vector<NamedModel> named;
    std::map<std::string, size_t> by_name;
    for (auto it = models_it->begin(); it != models_it->end(); ++it) {
        if (!it->is_string())
            return r.error("models", detail::quote_input(it.key()).c_str(), "expected a path string");
        by_name[it.key()] = named.size();
        named.push_back({it.key(), it->get<std::string>()});
    }
    for (const std::string& name : extra_models) {
        auto found = by_name.find(name);
        if (found == by_name.end())
            return Status{ErrorCode::invalid_argument,
                          detail::one_line(std::string(source) + ": model \"" + detail::quote_input(name) +
                                           "\" is asked for but is not one of the forest's models")};
        named[found->second].needed = true;
    }

    Scene scene;
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
        auto found = by_name.find(name);
        if (found == by_name.end())
            return r.error(where, "model", "\"" + detail::quote_input(name) + "\" is not one of the forest's models");
        named[found->second].needed = true;
        Instance inst;
        inst.model = uint32_t(found->second);  // a name's position until the models are built
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

    // Each distinct reference that a needed name holds is read or generated once, and what
    // building it would take is summed: at the fewest ring sides (3) that is less than any
    // simulation of the forest builds, so a forest no simulation could build is refused here.
    // A name nobody needs is only checked to name an existing file or a known preset.
    std::vector<uint32_t> model_of_name(named.size(), UINT32_MAX);
    std::map<std::string, uint32_t> built;  // reference -> scene model
    uint64_t build_bytes = 0;
    for (size_t n = 0; n < named.size(); ++n) {
        const NamedModel& entry = named[n];
        const bool preset = entry.reference.rfind("preset:", 0) == 0;
        std::filesystem::path path(entry.reference);
        if (!preset && path.is_relative()) path = std::filesystem::path(base_directory) / path;
        const std::string where = std::string(source) + ": models." + detail::quote_input(entry.name) + ": ";
        if (!entry.needed) {
            if (preset) {
                const auto& presets = preset_names();
                if (std::find(presets.begin(), presets.end(), entry.reference.substr(7)) == presets.end())
                    return Status{ErrorCode::invalid_argument,
                                  detail::one_line(where + "unknown preset '" + entry.reference.substr(7) + "'")};
            } else {
                std::error_code ec;
                const auto status = std::filesystem::status(path, ec);
                if (!std::filesystem::exists(status))
                    return Status{ErrorCode::io, detail::one_line(where + path.string() + ": no such file")};
                if (std::filesystem::is_directory(status))
                    return Status{ErrorCode::io, detail::one_line(where + path.string() + ": is a directory, expected a file")};
            }
            continue;
        }
        auto cached = built.find(entry.reference);
        if (cached != built.end()) {
            model_of_name[n] = cached->second;
            scene.model_aliases.push_back({entry.name, cached->second});
            continue;
        }
        Result<TreeModel> model = preset ? generate_preset(entry.reference.substr(7)) : load_tree(path.string());
        if (!model) return Status{model.status().code(), detail::one_line(where + model.status().message())};
        build_bytes += detail::model_build_bytes(model->nodes.size(), model->leaves.size(), 3);
        if (build_bytes > detail::size_limits().build_bytes)
            return Status{ErrorCode::unsupported,
                          std::string(source) + ": models: building its models would take more than " +
                              std::to_string(detail::size_limits().build_bytes >> 20) +
                              " MiB of host memory, the limit (docs/model.md 3.11)"};
        model_of_name[n] = uint32_t(scene.models.size());
        built.emplace(entry.reference, model_of_name[n]);
        scene.models.push_back(std::move(model).value());
        scene.model_names.push_back(entry.name);
    }
    for (Instance& inst : scene.instances) inst.model = model_of_name[inst.model];
    HMSM_TRY(read_budgets(doc, r, by_name, model_of_name, scene));
    return scene;
}

Result<Scene> load_forest(const std::string& path, std::span<const std::string> extra_models) {
    auto text = detail::read_text_file(path);
    if (!text) return text.status();
    std::string base = std::filesystem::path(path).parent_path().string();
    return parse_forest(*text, base.empty() ? "." : base, path, extra_models);
}

}  // namespace hmsm
