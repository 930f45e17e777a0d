#include "cli_common.h"

#include <charconv>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <limits>

#include <sys/stat.h>
#include <unistd.h>

#include "model/json_util.h"

namespace hmsm::cli {

int fail(const Status& status) {
    // One line, whatever the message quotes (a file name with a newline, say).
    std::string line = status.message();
    for (char& c : line)
        if (c == '\n' || c == '\r') c = ' ';
    std::fprintf(stderr, "hmsm: error: %s\n", line.c_str());
    return is_input_error(status.code()) ? kExitBadInput : kExitInternal;
}

int fail_input(const std::string& message) {
    return fail(Status{ErrorCode::invalid_argument, message});
}

std::string join_choices(const std::vector<std::string>& names) {
    std::string text;
    for (size_t i = 0; i < names.size(); ++i) {
        if (i > 0) text += i + 1 == names.size() ? " or " : ", ";
        text += names[i];
    }
    return text;
}

std::string spelled(std::string_view name, Spelling spelling) {
    std::string text(name);
    if (spelling == Spelling::hyphens) std::replace(text.begin(), text.end(), '_', '-');
    return text;
}

Result<BackendKind> parse_backend(const std::string& name, const std::string& flag, bool allow_auto) {
    if (allow_auto) return parse_choice(kBackendKindNames, name, flag, Spelling::as_is);
    return parse_choice(kBackendKindNames, name, flag, Spelling::as_is, {BackendKind::automatic});
}

std::string backend_choices(std::optional<BackendKind> marked, bool allow_auto) {
    if (allow_auto) return choices(kBackendKindNames, Spelling::as_is, marked);
    return choices(kBackendKindNames, Spelling::as_is, marked, {BackendKind::automatic});
}

void add_source_flags(CLI::App& app, SourceFlags& f, bool with_forest_and_instances) {
    auto* tree = app.add_option("--tree", f.tree, "hmsm-tree JSON file");
    auto* preset = app.add_option("--preset", f.preset, "built-in tree: paper-1 ... paper-5");
    tree->excludes(preset);
    if (!with_forest_and_instances) return;
    auto* forest = app.add_option("--forest", f.forest, "hmsm-forest JSON file");
    forest->excludes(tree)->excludes(preset);
    auto* instances =
        add_integer_option(app, "--instances", f.instances, "N instances of the tree on a square grid");
    instances->excludes(forest);
    app.add_option("--spacing", f.spacing, "grid spacing in metres (default 25)");
    add_integer_option(app, "--seed", f.seed, "seed of the grid's random yaws (default 1)");
    app.add_option("--origin", f.origin, "single instance origin X,Y,Z");
    app.add_option("--yaw", f.yaw, "single instance yaw in radians");
}

Result<glm::dvec3> parse_vec3(const std::string& text, const char* flag) {
    glm::dvec3 v(0.0);
    const char* p = text.data();
    const char* end = text.data() + text.size();
    for (int k = 0; k < 3; ++k) {
        auto [next, ec] = std::from_chars(p, end, v[k]);
        if (ec != std::errc() || !std::isfinite(v[k]))
            return Status{ErrorCode::invalid_argument,
                          std::string(flag) + " '" + detail::quote_input(text) + "': expected three finite numbers X,Y,Z"};
        p = next;
        if (k < 2) {
            if (p == end || *p != ',')
                return Status{ErrorCode::invalid_argument,
                              std::string(flag) + " '" + detail::quote_input(text) + "': expected X,Y,Z"};
            ++p;
        }
    }
    if (p != end)
        return Status{ErrorCode::invalid_argument,
                      std::string(flag) + " '" + detail::quote_input(text) + "': unexpected text after X,Y,Z"};
    return v;
}

namespace {

Result<Scene> load_scene_as_given(const SourceFlags& f, CLI::App& app, const ModelOptions* options,
                                  std::span<const std::string> needed_models) {
    if (!f.forest.empty()) return load_forest(f.forest, needed_models);
    if (f.tree.empty() && f.preset.empty())
        return Status{ErrorCode::invalid_argument,
                      "give the tree with --tree FILE or --preset NAME" +
                          std::string(app.get_option_no_throw("--forest") ? " (or --forest FILE)" : "")};
    Result<TreeModel> tree = f.tree.empty() ? generate_preset(f.preset) : load_tree(f.tree);
    if (!tree) return tree.status();
    if (app.get_option_no_throw("--instances") && app.count("--instances") > 0) {
        if (f.instances == 0) return Status{ErrorCode::invalid_argument, "--instances must be >= 1"};
        // The library's instance limit (Simulation::create's), before anything is built.
        if (f.instances > kMaxInstances)
            return Status{ErrorCode::unsupported, "scene too large: --instances " + std::to_string(f.instances) +
                                                      ", at most " + std::to_string(kMaxInstances) +
                                                      " instances are supported"};
        if (app.count("--origin") || app.count("--yaw"))
            return Status{ErrorCode::invalid_argument,
                          "--origin and --yaw place a single instance; they cannot be used with --instances"};
        if (options) {
            // The flattened buffers hold at most 2^32 - 1 mesh vertices: size the scene from one
            // model's counts before the instance list (or anything else) is allocated.
            auto hierarchy = build_hierarchy(*tree, *options);
            if (!hierarchy) return hierarchy.status();
            const uint64_t per_instance = build_mesh(*tree, *hierarchy, *options).vertices.size();
            const uint64_t limit = std::numeric_limits<uint32_t>::max();
            // The same limit and class as Simulation::create's (a limit of this build: exit 1).
            if (per_instance * uint64_t(f.instances) >= limit)
                return Status{ErrorCode::unsupported,
                              "scene too large: --instances " + std::to_string(f.instances) + " would have " +
                                  std::to_string(per_instance * uint64_t(f.instances)) + " mesh vertices (" +
                                  std::to_string(per_instance) + " per instance; at most 2^32 - 1 are supported)"};
        }
        return grid_scene(std::move(tree).value(), f.instances, f.spacing, f.seed);
    }
    auto origin = parse_vec3(f.origin, "--origin");
    if (!origin) return origin.status();
    if (!std::isfinite(f.yaw)) return Status{ErrorCode::invalid_argument, "--yaw must be finite"};
    return single_tree_scene(std::move(tree).value(), *origin, f.yaw);
}

/// The value of flag `name` when the subcommand has it and it was given.
std::optional<double> given(CLI::App& app, const char* name) {
    const CLI::Option* option = app.get_option_no_throw(name);
    if (!option || option->count() == 0) return std::nullopt;
    return option->as<double>();
}

}  // namespace

Result<Scene> load_scene(const SourceFlags& f, CLI::App& app, const ModelOptions* options,
                         std::span<const std::string> needed_models) {
    auto scene = load_scene_as_given(f, app, options, needed_models);
    if (!scene) return scene;
    // The coupled dynamics' flags given on the command line override a tree file's material and
    // leaf state (docs/model.md 4.1); not given, the file's stand.
    const std::optional<double> modulus = given(app, "--modulus"), density = given(app, "--wood-density");
    const bool leaf_off = app.get_option_no_throw("--leaf-off") && app.count("--leaf-off") > 0;
    for (TreeModel& tree : scene->models) {
        if (tree.material && (modulus || density)) {
            tree.material->species.clear();  // no longer the preset's wood
            if (modulus) tree.material->modulus = *modulus;
            if (density) tree.material->density = *density;
        }
        if (leaf_off) tree.leaves_on = false;
    }
    return scene;
}

void add_model_flags(CLI::App& app, ModelFlags& f) {
    app.add_option("--grouping", f.grouping,
                   "chain grouping: " + choices(kGroupingNames, Spelling::as_is, Grouping::direction));
    add_integer_option(app, "--max-chain-segments", f.options.max_chain_segments,
                       "cut chains after K nodes (0 = never, default)");
    add_integer_option(app, "--ring-sides", f.options.ring_sides, "vertices per branch ring (default 8)");
    app.add_option("--fix-weight", f.options.fix_weight, "contour fix-up weight in [0,1] (default 0.5)");
    app.add_option("--dynamics", f.dynamics,
                   "equations of motion: " + choices(kDynamicsNames, Spelling::as_is, Dynamics::paper) +
                       " (coupled: docs/model.md 3.13)");
    app.add_option("--exchange", f.exchange,
                   "coupled: how chains exchange loads: " + choices(kExchangeNames, Spelling::as_is, Exchange::held) +
                       " (articulated: the joints solved together each step)");
}

Result<ModelOptions> model_options(const ModelFlags& f) {
    auto grouping = parse_choice(kGroupingNames, f.grouping, "--grouping", Spelling::as_is);
    if (!grouping) return grouping.status();
    auto dynamics = parse_choice(kDynamicsNames, f.dynamics, "--dynamics", Spelling::as_is);
    if (!dynamics) return dynamics.status();
    auto exchange = parse_choice(kExchangeNames, f.exchange, "--exchange", Spelling::as_is);
    if (!exchange) return exchange.status();
    ModelOptions options = f.options;
    options.grouping = *grouping;
    options.dynamics = *dynamics;
    options.exchange = *exchange;
    HMSM_TRY(validate(options));
    return options;
}

void add_parameter_flags(CLI::App& app, Parameters& p) {
    app.add_option("--dt", p.dt, "time step in seconds (default 1/120)");
    app.add_option("--density", p.density, "density rho (default 1)");
    app.add_option("--stiffness", p.stiffness, "stiffness k (default 1e7)");
    app.add_option("--damping-ratio", p.damping_ratio, "damping ratio zeta (default 0.1)");
    app.add_option("--wind-gain", p.wind_gain, "wind gain gamma (default 0.2)");
    app.add_option("--max-angle", p.max_angle, "max joint angle in radians (default 0.8)");
    app.add_option("--max-frequency", p.max_frequency,
                   "frequency cap f_cap in Hz: no chain sways faster (default 4)");
    // The coupled dynamics (docs/model.md 3.13).
    app.add_option("--modulus", p.material.modulus, "coupled: wood's Young's modulus E in Pa (default 9e9)");
    app.add_option("--wood-density", p.material.density, "coupled: green wood density in kg/m^3 (default 900)");
    app.add_option("--structural-damping", p.structural_damping,
                   "coupled: damping ratio of the wood alone (default 0.03)");
    app.add_option("--wood-drag", p.wood_drag_coefficient, "coupled: drag coefficient of branches (default 1.2)");
    app.add_option("--leaf-mass", p.foliage.mass_per_area, "coupled: leaf mass per card area in kg/m^2 (default 0.2)");
    app.add_option("--leaf-drag", p.foliage.drag_coefficient, "coupled: leaf drag area per card area (default 0.3)");
    app.add_flag_callback("--leaf-off", [&p] { p.foliage.on = false; }, "coupled: leaves add no mass or drag");
}

void add_wind_flags(CLI::App& app, WindFlags& f) {
    app.add_option("--wind", f.profile,
                   "wind profile: " + choices(kWindProfileNames, Spelling::as_is, WindProfile::y1));
    app.add_option("--wind-dir", f.direction, "wind direction X,Y,Z (default 1,0,0)");
    f.strength_option = app.add_option("--wind-strength", f.wind.strength,
                                       "wind strength: dynamic pressure relative to a 6 m/s breeze (default 1)");
    app.add_option("--wind-speed", f.speed, "wind speed U in m/s instead of --wind-strength: strength (U/6)^2");
    app.add_option("--wind-frequency", f.wind.frequency, "profile frequency f (default 0.1)");
    app.add_option("--front-speed", f.wind.front_speed, "travelling front speed v (default 0: none)");
    app.add_option("--turbulence", f.wind.turbulence,
                   "turbulent profile: relative fluctuation sigma in [0, 2] (default 0.3)");
    add_integer_option(app, "--wind-seed", f.wind.seed,
                       "turbulent profile: seed of the modes' phases, 0..2^64-1 (default 0)");
    app.add_option("--wind-schedule", f.schedule,
                   "hmsm-schedule JSON file: wind, force fields and instances changed before given steps");
}

Result<Wind> wind_options(const WindFlags& f) {
    auto profile = parse_choice(kWindProfileNames, f.profile, "--wind", Spelling::as_is);
    if (!profile) return profile.status();
    auto direction = parse_vec3(f.direction, "--wind-dir");
    if (!direction) return direction.status();
    Wind wind = f.wind;
    wind.profile = *profile;
    wind.direction = *direction;
    if (f.speed) {
        if (f.strength_option && f.strength_option->count() > 0)
            return Status{ErrorCode::invalid_argument,
                          "--wind-strength and --wind-speed both set the wind's strength: give one"};
        if (!std::isfinite(*f.speed) || *f.speed < 0.0)
            return Status{ErrorCode::invalid_argument, "--wind-speed must be finite and >= 0 m/s"};
        wind.strength = wind_strength_for_speed(*f.speed);
    }
    if (!std::isfinite(wind.turbulence) || wind.turbulence < 0.0 || wind.turbulence > 2.0)
        return Status{ErrorCode::invalid_argument, "--turbulence must be within [0, 2]"};
    if (wind.front_speed > 0.0 && wind.front_speed < 0.01)
        return Status{ErrorCode::invalid_argument, "--front-speed must be 0 or >= 0.01 m/s"};
    Status valid = validate(wind);
    if (!valid) return valid;
    return wind;
}

Status apply_shared_options(SimulationConfig& config, const ModelFlags& model, const Parameters& parameters,
                            const WindFlags& wind) {
    auto options = model_options(model);
    if (!options) return options.status();
    HMSM_TRY(validate(parameters));
    auto parsed_wind = wind_options(wind);
    if (!parsed_wind) return parsed_wind.status();
    config.model = *options;
    config.parameters = parameters;
    config.wind = *parsed_wind;
    return {};
}

Result<std::optional<Schedule>> read_schedule_option(const WindFlags& f) {
    if (f.schedule.empty()) return std::optional<Schedule>();
    auto schedule = load_schedule(f.schedule);
    if (!schedule) return schedule.status();
    return std::optional<Schedule>(std::move(schedule).value());
}

std::vector<std::string> scheduled_models(const std::optional<Schedule>& schedule) {
    return schedule ? scheduled_model_names(*schedule) : std::vector<std::string>{};
}

Status check_schedule_option(const WindFlags& f, const std::optional<Schedule>& schedule, const Scene& scene,
                             const Wind& wind) {
    if (!schedule) return {};
    Status valid = validate_schedule(*schedule, all_model_names(scene), scene.instances.size(), wind);
    if (!valid) return Status{valid.code(), f.schedule + ": " + valid.message()};
    return {};
}

StagedOutputs::~StagedOutputs() {
    if (committed_) return;
    for (File& f : files_) {
        f.handle.reset();
        std::remove(f.temporary.c_str());
    }
}

void StagedOutputs::add_inputs(std::initializer_list<std::string> paths) {
    for (const std::string& path : paths)
        if (!path.empty()) inputs_.push_back(path);
}

namespace {

/// Whether two paths name one file: the same file if both exist, else the same absolute path.
bool same_file(const std::string& a, const std::string& b) {
    std::error_code ec;
    if (std::filesystem::equivalent(a, b, ec) && !ec) return true;
    const auto canonical_a = std::filesystem::weakly_canonical(a, ec);
    if (ec) return false;
    const auto canonical_b = std::filesystem::weakly_canonical(b, ec);
    return !ec && canonical_a == canonical_b;
}

}  // namespace

Result<size_t> StagedOutputs::stage(const std::string& path, const char* flag) {
    const std::string named = std::string(flag) + " " + detail::one_line(path);
    for (const File& other : files_)
        if (same_file(other.path, path))
            return Status{ErrorCode::invalid_argument,
                          named + ": " + other.flag + " writes the same file; give each output its own path"};
    for (const std::string& input : inputs_)
        if (same_file(input, path))
            return Status{ErrorCode::invalid_argument, named + ": is an input of this command; an output "
                                                                   "may not replace an input"};
    auto mode = detail::output_file_mode(path);
    if (!mode) return Status{mode.status().code(), std::string(flag) + " " + mode.status().message()};
    File f;
    f.path = path;
    f.flag = flag;
    f.mode = *mode;
    auto fd = detail::create_temporary_beside(path, f.temporary);
    if (!fd) return Status{ErrorCode::io, named + ": cannot open for writing"};
    f.handle.reset(::fdopen(*fd, "wb"));
    if (!f.handle) {
        ::close(*fd);
        std::remove(f.temporary.c_str());
        return Status{ErrorCode::io, named + ": cannot open for writing"};
    }
    files_.push_back(std::move(f));
    return files_.size() - 1;
}

Status StagedOutputs::write(size_t index, const void* data, size_t bytes) {
    File& f = files_[index];
    if (bytes && std::fwrite(data, 1, bytes, f.handle.get()) != bytes)
        return {ErrorCode::io, f.path + ": write error"};
    return {};
}

Status StagedOutputs::commit() {
    for (File& f : files_) {
        const bool moded = ::fchmod(::fileno(f.handle.get()), mode_t(f.mode)) == 0;
        if (std::fclose(f.handle.release()) != 0 || !moded) return {ErrorCode::io, f.path + ": write error"};
    }
    for (File& f : files_) {
        std::error_code ec;
        std::filesystem::rename(f.temporary, f.path, ec);
        if (ec) return {ErrorCode::io, f.path + ": cannot write (" + ec.message() + ")"};
    }
    committed_ = true;
    return {};
}

}  // namespace hmsm::cli
