// Options and plumbing shared by the hmsm subcommands: exit codes (docs/model.md 5), scene sources,
// model/parameter/wind flags, and outputs that appear whole or not at all.
#pragma once

#include <hmsm/hmsm.h>

#include <CLI/CLI.hpp>

#include "model/input_limits.h"

#include <algorithm>
#include <charconv>
#include <initializer_list>
#include <limits>
#include <memory>
#include <optional>
#include <string>
#include <string_view>
#include <type_traits>
#include <vector>

namespace hmsm::cli {

inline constexpr int kExitOk = 0;
inline constexpr int kExitInternal = 1;
inline constexpr int kExitBadInput = 2;

/// Prints "hmsm: error: <message>" on stderr and returns the exit code for the status.
int fail(const Status& status);
int fail_input(const std::string& message);

/// Parses a whole decimal integer of type T; anything else (a sign T cannot hold, a fraction,
/// trailing text, a value beyond T's range) is an error naming `flag`.
template <class T>
Result<T> parse_integer(const std::string& text, const std::string& flag) {
    T value{};
    const char* end = text.data() + text.size();
    auto [next, ec] = std::from_chars(text.data(), end, value);
    if (text.empty() || ec != std::errc() || next != end)
        return Status{ErrorCode::invalid_argument,
                      flag + " '" + detail::quote_input(text) + "': expected an integer within " +
                          std::to_string(std::numeric_limits<T>::min()) + ".." +
                          std::to_string(std::numeric_limits<T>::max())};
    return value;
}

/// An integer flag checked against its type's range (CLI11 alone lets some overflowing values
/// through): a bad value is a parse error, exit 2.
template <class T>
CLI::Option* add_integer_option(CLI::App& app, const std::string& name, T& target, const std::string& help) {
    static_assert(std::is_integral_v<T>);
    return app.add_option_function<std::string>(
        name,
        [&target, name](const std::string& text) {
            Result<T> parsed = parse_integer<T>(text, name);
            if (!parsed) throw CLI::ValidationError(parsed.status().message());
            target = *parsed;
        },
        help);
}

/// How a flag spells the names of a name table (include/hmsm/names.h): as the table does, or
/// with '-' between words where the table has '_' (either is accepted then).
enum class Spelling { as_is, hyphens };

/// "a, b or c" (a alone, "a or b"), as a flag's help and error texts list its choices.
std::string join_choices(const std::vector<std::string>& names);
std::string spelled(std::string_view name, Spelling spelling);

/// The names of `table` in its order, spelled for a flag, without the `excluded` values;
/// `marked` is followed by " (default)".
template <class Enum, std::size_t N>
std::string choices(const NamedValue<Enum> (&table)[N], Spelling spelling,
                    std::type_identity_t<std::optional<Enum>> marked = std::nullopt,
                    std::type_identity_t<std::initializer_list<Enum>> excluded = {}) {
    std::vector<std::string> names;
    for (const NamedValue<Enum>& row : table) {
        if (std::find(excluded.begin(), excluded.end(), row.value) != excluded.end()) continue;
        names.push_back(spelled(row.name, spelling) + (marked && row.value == *marked ? " (default)" : ""));
    }
    return join_choices(names);
}

/// The value of `table` that a flag's `text` names (not one of `excluded`); otherwise the
/// error "FLAG 'TEXT': expected a, b or c".
template <class Enum, std::size_t N>
Result<Enum> parse_choice(const NamedValue<Enum> (&table)[N], const std::string& text, const std::string& flag,
                          Spelling spelling, std::type_identity_t<std::initializer_list<Enum>> excluded = {}) {
    std::string key = text;
    if (spelling == Spelling::hyphens) std::replace(key.begin(), key.end(), '-', '_');
    std::optional<Enum> value = value_named(table, key);
    if (value && std::find(excluded.begin(), excluded.end(), *value) == excluded.end()) return *value;
    return Status{ErrorCode::invalid_argument,
                  flag + " '" + detail::quote_input(text) + "': expected " + choices<Enum>(table, spelling, std::nullopt, excluded)};
}

/// The backend a flag names (`automatic`, spelled "auto", only where `allow_auto`); otherwise
/// the error "FLAG 'NAME': expected cpu, cpu64, ...".
Result<BackendKind> parse_backend(const std::string& name, const std::string& flag, bool allow_auto = true);
/// The backends a flag accepts, for its help; `marked` is the default.
std::string backend_choices(std::optional<BackendKind> marked, bool allow_auto = true);

/// Where the trees come from: one of --tree, --preset, --forest; plus a grid of instances.
struct SourceFlags {
    std::string tree, preset, forest;
    uint32_t instances = 1;
    double spacing = 25.0;
    uint64_t seed = 1;
    std::string origin = "0,0,0";
    double yaw = 0.0;
};
void add_source_flags(CLI::App& app, SourceFlags& flags, bool with_forest_and_instances);
/// Loads the scene. With `options`, a grid of --instances is first sized from the model's counts
/// (mesh vertices per instance) and refused before anything scene-sized is allocated.
/// A forest builds the models its instances place and those `needed_models` names (a schedule's).
Result<Scene> load_scene(const SourceFlags& flags, CLI::App& app, const ModelOptions* options = nullptr,
                         std::span<const std::string> needed_models = {});

/// Model options, parameters and wind as flags.
struct ModelFlags {
    std::string grouping = "direction";
    std::string dynamics = "paper";
    std::string exchange = "held";
    ModelOptions options;
};
void add_model_flags(CLI::App& app, ModelFlags& flags);
Result<ModelOptions> model_options(const ModelFlags& flags);

struct WindFlags {
    std::string profile = "y1";
    std::string direction = "1,0,0";
    Wind wind;
    std::optional<double> speed;  ///< --wind-speed U (m/s): strength (U / 6)^2
    std::string schedule;         ///< --wind-schedule FILE
    CLI::Option* strength_option = nullptr;
};
void add_parameter_flags(CLI::App& app, Parameters& parameters);
void add_wind_flags(CLI::App& app, WindFlags& flags);
/// The wind of the flags (--wind-strength and --wind-speed together are bad input).
Result<Wind> wind_options(const WindFlags& flags);
/// The model options, parameters and wind of the shared flags, each validated, set on `config`
/// (what every simulating subcommand starts from).
Status apply_shared_options(SimulationConfig& config, const ModelFlags& model, const Parameters& parameters,
                            const WindFlags& wind);
/// The --wind-schedule file, parsed; none when the flag is not given. Read it before the scene,
/// so that a forest builds the models the schedule adds (scheduled_models), then check it
/// against the scene and the flags' wind (check_schedule_option).
Result<std::optional<Schedule>> read_schedule_option(const WindFlags& flags);
std::vector<std::string> scheduled_models(const std::optional<Schedule>& schedule);
Status check_schedule_option(const WindFlags& flags, const std::optional<Schedule>& schedule, const Scene& scene,
                             const Wind& wind);

/// Parses "X,Y,Z" strictly (three finite numbers).
Result<glm::dvec3> parse_vec3(const std::string& text, const char* flag);

/// Output files staged as temporaries when the command starts (so an unwritable path fails
/// before any work) and renamed into place only by commit(); otherwise removed. Before any work
/// it refuses two outputs on one path, an output on an input, and replacing a symbolic link or
/// anything but a regular file; a replaced file keeps its mode (docs/cli.md, "Outputs").
class StagedOutputs {
public:
    ~StagedOutputs();
    /// Names the command's input files (empty names are ignored): no output may be one of them.
    void add_inputs(std::initializer_list<std::string> paths);
    /// Reserves `path`; returns the index to write through.
    Result<size_t> stage(const std::string& path, const char* flag);
    Status write(size_t index, const void* data, size_t bytes);
    Status commit();

private:
    struct File {
        std::string path, temporary, flag;
        uint32_t mode = 0644;
        std::unique_ptr<std::FILE, int (*)(std::FILE*)> handle{nullptr, &std::fclose};
    };
    std::vector<File> files_;
    std::vector<std::string> inputs_;
    bool committed_ = false;
};

/// Each subcommand: register its flags on `app` (before parsing), then run after parsing.
void register_generate_flags(CLI::App& app);
void register_info_flags(CLI::App& app);
void register_simulate_flags(CLI::App& app);
void register_bench_flags(CLI::App& app);
void register_import_flags(CLI::App& app);  // cmd_import.cpp
void register_analyze_flags(CLI::App& app);  // cmd_analyze.cpp
int run_generate(CLI::App& app);
int run_info(CLI::App& app);
int run_simulate(CLI::App& app);
int run_bench(CLI::App& app);
int run_import(CLI::App& app);
int run_analyze(CLI::App& app);
#ifdef HMSM_HAVE_RENDER
void register_render_flags(CLI::App& app);  // cmd_render.cpp: needs the Vulkan renderer
int run_render(CLI::App& app);
#endif

}  // namespace hmsm::cli
