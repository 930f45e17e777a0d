// Options and plumbing shared by the hmsm subcommands: exit codes (docs/model.md 5), scene sources,
// model/parameter/wind flags, and outputs that appear whole or not at all.
#pragma once

#include <hmsm/hmsm.h>

#include <CLI/CLI.hpp>

#include <memory>
#include <string>
#include <vector>

namespace hmsm::cli {

inline constexpr int kExitOk = 0;
inline constexpr int kExitInternal = 1;
inline constexpr int kExitBadInput = 2;

/// Prints "hmsm: error: <message>" on stderr and returns the exit code for the status.
int fail(const Status& status);
int fail_input(const std::string& message);

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
Result<Scene> load_scene(const SourceFlags& flags, CLI::App& app);

/// Model options, parameters and wind as flags.
struct ModelFlags {
    std::string grouping = "direction";
    ModelOptions options;
};
void add_model_flags(CLI::App& app, ModelFlags& flags);
Result<ModelOptions> model_options(const ModelFlags& flags);

struct WindFlags {
    std::string profile = "y1";
    std::string direction = "1,0,0";
    Wind wind;
};
void add_parameter_flags(CLI::App& app, Parameters& parameters);
void add_wind_flags(CLI::App& app, WindFlags& flags);
Result<Wind> wind_options(const WindFlags& flags);

/// Parses "X,Y,Z" strictly (three finite numbers).
Result<glm::dvec3> parse_vec3(const std::string& text, const char* flag);

/// Output files staged as temporaries when the command starts (so an unwritable path fails
/// before any work) and renamed into place only by commit(); otherwise removed.
class StagedOutputs {
public:
    ~StagedOutputs();
    /// Reserves `path`; returns the index to write through.
    Result<size_t> stage(const std::string& path, const char* flag);
    Status write(size_t index, const void* data, size_t bytes);
    Status commit();

private:
    struct File {
        std::string path, temporary;
        std::unique_ptr<std::FILE, int (*)(std::FILE*)> handle{nullptr, &std::fclose};
    };
    std::vector<File> files_;
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
