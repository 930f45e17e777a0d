// The bad-input catalog (tests/data/bad/catalog.json): every malformed tree, forest and
// argument set makes the CLI exit 2 with one stderr line naming the problem and the item, leaves
// no output or temporary file, never crashes or hangs; the library API returns the same error
// class without the CLI.
#include "simulation_access.h"
#include "test_trees.h"

#include "backend.h"
#include "forwarding_backend.h"

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <csignal>
#include <fcntl.h>
#include <filesystem>
#include <fstream>
#include <limits>
#include <set>
#include <spawn.h>
#include <sstream>
#include <sys/wait.h>
#include <thread>
#include <unistd.h>

extern char** environ;

using namespace hmsm;
namespace fs = std::filesystem;
using nlohmann::json;

namespace {

const fs::path kCatalogDir = fs::path(HMSM_TEST_DATA) / "bad";
constexpr auto kTimeout = std::chrono::seconds(60);

struct Entry {
    std::string name;
    json spec;
};

void PrintTo(const Entry& e, std::ostream* os) { *os << e.name; }

std::vector<Entry> load_catalog() {
    std::ifstream in(kCatalogDir / "catalog.json");
    json doc = json::parse(in, nullptr, /*allow_exceptions=*/false);
    std::vector<Entry> entries;
    if (doc.is_discarded() || !doc.contains("entries")) return entries;  // CatalogIsComplete fails
    for (const json& e : doc["entries"]) entries.push_back({e.value("name", std::string("?")), e});
    return entries;
}

const std::vector<Entry>& catalog() {
    static const std::vector<Entry> entries = load_catalog();
    return entries;
}

std::string read_file(const fs::path& path) {
    std::ifstream in(path, std::ios::binary);
    std::stringstream s;
    s << in.rdbuf();
    return s.str();
}

ErrorCode parse_code(const std::string& name) {
    if (name == "invalid_argument") return ErrorCode::invalid_argument;
    if (name == "invalid_tree") return ErrorCode::invalid_tree;
    if (name == "io") return ErrorCode::io;
    ADD_FAILURE() << "catalog: unknown code " << name;
    return ErrorCode::internal;
}

/// JSON number, or "nan" / "inf" / "-inf" (JSON has no literal for them).
double number(const json& v) {
    if (v.is_number()) return v.get<double>();
    std::string s = v.get<std::string>();
    if (s == "nan") return std::numeric_limits<double>::quiet_NaN();
    if (s == "inf") return std::numeric_limits<double>::infinity();
    if (s == "-inf") return -std::numeric_limits<double>::infinity();
    ADD_FAILURE() << "catalog: not a number: " << v.dump();
    return 0.0;
}

glm::dvec3 vec3(const json& v) { return {number(v[0]), number(v[1]), number(v[2])}; }

struct Outcome {
    int exit_code = -1;    // -1: killed by a signal or timed out
    bool timed_out = false;
    int signal = 0;
    std::string err;
};

/// Runs argv with stdout and stderr to files, killing it after kTimeout. No shell: arguments
/// reach the CLI exactly as written in the catalog.
Outcome run_cli(const std::vector<std::string>& args, const fs::path& scratch) {
    std::vector<std::string> argv_storage = {HMSM_CLI_PATH};
    argv_storage.insert(argv_storage.end(), args.begin(), args.end());
    std::vector<char*> argv;
    for (auto& a : argv_storage) argv.push_back(a.data());
    argv.push_back(nullptr);
    const std::string out_path = (scratch / "stdout.txt").string();
    const std::string err_path = (scratch / "stderr.txt").string();
    posix_spawn_file_actions_t actions;
    posix_spawn_file_actions_init(&actions);
    posix_spawn_file_actions_addopen(&actions, 1, out_path.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
    posix_spawn_file_actions_addopen(&actions, 2, err_path.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
    posix_spawn_file_actions_addopen(&actions, 0, "/dev/null", O_RDONLY, 0);
    pid_t pid = -1;
    Outcome outcome;
    int spawned = posix_spawn(&pid, argv[0], &actions, nullptr, argv.data(), environ);
    posix_spawn_file_actions_destroy(&actions);
    if (spawned != 0) {
        outcome.err = "posix_spawn failed";
        return outcome;
    }
    const auto deadline = std::chrono::steady_clock::now() + kTimeout;
    int status = 0;
    for (;;) {
        pid_t done = waitpid(pid, &status, WNOHANG);
        if (done == pid) break;
        if (std::chrono::steady_clock::now() > deadline) {
            kill(pid, SIGKILL);
            waitpid(pid, &status, 0);
            outcome.timed_out = true;
            break;
        }
        std::this_thread::sleep_for(std::chrono::milliseconds(2));
    }
    if (!outcome.timed_out && WIFEXITED(status)) outcome.exit_code = WEXITSTATUS(status);
    if (WIFSIGNALED(status)) outcome.signal = WTERMSIG(status);
    outcome.err = read_file(err_path);
    return outcome;
}

class BadInput : public ::testing::TestWithParam<Entry> {
protected:
    void SetUp() override {
        dir_ = fs::temp_directory_path() / ("hmsm_bad_" + GetParam().name + "_" + std::to_string(getpid()));
        fs::remove_all(dir_);
        fs::create_directories(dir_ / "out");
        fs::create_directories(dir_ / "valid");
        ASSERT_TRUE(save_tree(test::small_tree(), valid_tree()).ok());
    }
    void TearDown() override { fs::remove_all(dir_); }

    std::string valid_tree() const { return (dir_ / "valid" / "tree.json").string(); }
    std::string out() const { return (dir_ / "out").string(); }

    /// {valid}, {out}, {file} and {bad:PATH} replaced by paths.
    std::string expand(std::string arg) const {
        const json& e = GetParam().spec;
        auto replace = [&](const std::string& key, const std::string& value) {
            for (size_t at; (at = arg.find(key)) != std::string::npos;) arg.replace(at, key.size(), value);
        };
        replace("{valid}", valid_tree());
        replace("{out}", out());
        if (e.contains("file")) replace("{file}", (kCatalogDir / e["file"].get<std::string>()).string());
        for (size_t at; (at = arg.find("{bad:")) != std::string::npos;) {
            size_t end = arg.find('}', at);
            arg.replace(at, end + 1 - at, (kCatalogDir / arg.substr(at + 5, end - at - 5)).string());
        }
        return arg;
    }

    std::vector<std::string> fragments(bool api) const {
        std::vector<std::string> list;
        const json& spec = GetParam().spec;
        for (const json& f : api && spec.contains("api_expect") ? spec["api_expect"] : spec["expect"]) {
            std::string s = f.get<std::string>();
            if (api && s.rfind("--", 0) == 0) continue;  // a flag name exists only in the CLI
            list.push_back(s);
        }
        return list;
    }

    /// Runs the CLI once and checks the contract of docs/model.md 5 for bad input.
    void expect_cli_rejects(std::vector<std::string> args) {
        std::string shown;
        for (auto& a : args) {
            a = expand(a);
            shown += " " + a;
        }
        SCOPED_TRACE("hmsm" + shown);
        // Ask for every output the subcommand has, so "no partial output" is checked for each.
        auto has = [&](const std::string& flag) { return std::find(args.begin(), args.end(), flag) != args.end(); };
        if (!args.empty() && args[0] == "simulate") {
            for (auto [flag, file] : {std::pair{"--dump-nodes", "nodes.csv"}, std::pair{"--dump-vertices", "vertices.bin"},
                                      std::pair{"--report", "report.json"}})
                if (!has(flag)) args.insert(args.end(), {flag, out() + "/" + file});
        } else if (!args.empty() && args[0] == "info" && !has("--chains")) {
            args.insert(args.end(), {"--chains", out() + "/chains.csv"});
        }
        Outcome r = run_cli(args, dir_);
        EXPECT_FALSE(r.timed_out) << "hung for " << kTimeout.count() << " s";
        EXPECT_EQ(r.signal, 0) << "killed by signal " << r.signal << "\n" << r.err;
        EXPECT_EQ(r.exit_code, 2) << r.err;
        EXPECT_EQ(std::count(r.err.begin(), r.err.end(), '\n'), 1) << "not one line:\n" << r.err;
        EXPECT_EQ(r.err.rfind("hmsm: error: ", 0), 0u) << r.err;
        for (const std::string& f : fragments(false))
            EXPECT_NE(r.err.find(f), std::string::npos) << "'" << f << "' not in: " << r.err;
        // No output file and no leftover temporary file anywhere the command could write.
        for (const auto& entry : fs::recursive_directory_iterator(dir_ / "out"))
            ADD_FAILURE() << "left behind: " << entry.path();
        for (const auto& entry : fs::directory_iterator(dir_ / "valid"))
            EXPECT_EQ(entry.path().filename(), "tree.json") << "left behind: " << entry.path();
    }

    /// The same input through the library: the same error class (and the same fragments, but
    /// for flag names).
    void expect_api_rejects(const Status& status) {
        const json& e = GetParam().spec;
        ErrorCode code = parse_code(e["code"].get<std::string>());
        ASSERT_FALSE(status.ok());
        EXPECT_EQ(status.code(), code) << to_string(status.code()) << ": " << status.message();
        EXPECT_TRUE(is_input_error(status.code()));
        EXPECT_EQ(status.message().find('\n'), std::string::npos) << status.message();
        for (const std::string& f : fragments(true))
            EXPECT_NE(status.message().find(f), std::string::npos)
                << "'" << f << "' not in: " << status.message();
    }

    void expect_api_rejects_args(const json& api);

    fs::path dir_;
};

void BadInput::expect_api_rejects_args(const json& api) {
    const TreeModel tree = test::small_tree();
    SimulationConfig config;
    config.backend = BackendKind::cpu;
    glm::dvec3 origin(0.0);
    double yaw = 0.0;
    for (auto it = api.begin(); it != api.end(); ++it) {
        const std::string& key = it.key();
        const json& v = it.value();
        if (key == "backend") {
            EXPECT_FALSE(parse_backend_kind(v.get<std::string>()).has_value());
            return;
        }
        if (key == "wind_profile") {
            EXPECT_FALSE(parse_wind_profile(v.get<std::string>()).has_value());
            return;
        }
        if (key == "grouping") {
            EXPECT_FALSE(parse_grouping(v.get<std::string>()).has_value());
            return;
        }
        if (key == "preset") return expect_api_rejects(generate_preset(v.get<std::string>()).status());
        if (key == "load_tree") return expect_api_rejects(load_tree(expand(v.get<std::string>())).status());
        if (key == "load_forest") return expect_api_rejects(load_forest(expand(v.get<std::string>())).status());
        if (key == "schedule") {  // parsed, then checked against one instance of the model "tree"
            auto schedule = load_schedule(expand(v.get<std::string>()));
            if (!schedule) return expect_api_rejects(schedule.status());
            const std::vector<std::string> names = {"tree"};
            return expect_api_rejects(validate_schedule(*schedule, names, 1, Wind{}));
        }
        if (key == "instances") {
            double spacing = api.contains("spacing") ? number(api["spacing"]) : 25.0;
            return expect_api_rejects(grid_scene(tree, v.get<uint32_t>(), spacing, 1).status());
        }
        if (key == "parameters") {
            Parameters& p = config.parameters;
            for (auto f = v.begin(); f != v.end(); ++f) {
                double x = number(f.value());
                if (f.key() == "dt") p.dt = x;
                else if (f.key() == "density") p.density = x;
                else if (f.key() == "stiffness") p.stiffness = x;
                else if (f.key() == "damping_ratio") p.damping_ratio = x;
                else if (f.key() == "wind_gain") p.wind_gain = x;
                else if (f.key() == "max_angle") p.max_angle = x;
                else if (f.key() == "max_frequency") p.max_frequency = x;
                else ADD_FAILURE() << "catalog: unknown parameter " << f.key();
            }
        } else if (key == "wind") {
            Wind& w = config.wind;
            for (auto f = v.begin(); f != v.end(); ++f) {
                if (f.key() == "direction") w.direction = vec3(f.value());
                else if (f.key() == "strength") w.strength = number(f.value());
                else if (f.key() == "frequency") w.frequency = number(f.value());
                else if (f.key() == "front_speed") w.front_speed = number(f.value());
                else ADD_FAILURE() << "catalog: unknown wind field " << f.key();
            }
        } else if (key == "model") {
            ModelOptions& m = config.model;
            for (auto f = v.begin(); f != v.end(); ++f) {
                if (f.key() == "ring_sides") m.ring_sides = f.value().get<int32_t>();
                else if (f.key() == "max_chain_segments") m.max_chain_segments = f.value().get<int32_t>();
                else if (f.key() == "fix_weight") m.fix_weight = number(f.value());
                else ADD_FAILURE() << "catalog: unknown model option " << f.key();
            }
        } else if (key == "origin") {
            origin = vec3(v);
        } else if (key == "yaw") {
            yaw = number(v);
        } else if (key != "spacing") {
            ADD_FAILURE() << "catalog: unknown api key " << key;
        }
    }
    auto sim = Simulation::create(single_tree_scene(tree, origin, yaw), config);
    expect_api_rejects(sim.status());
}

TEST_P(BadInput, CliExitsTwoWithOneLineAndNoOutput) {
    const json& e = GetParam().spec;
    const std::string kind = e["kind"];
    if (kind == "args") {
        expect_cli_rejects(e["args"].get<std::vector<std::string>>());
        return;
    }
    const std::string file = (kCatalogDir / e["file"].get<std::string>()).string();
    const std::string before = read_file(file);
    if (kind == "tree") {
        expect_cli_rejects({"simulate", "--tree", file, "--backend", "cpu", "--steps", "2"});
        expect_cli_rejects({"info", "--tree", file});
    } else {
        expect_cli_rejects({"simulate", "--forest", file, "--backend", "cpu", "--steps", "2"});
    }
    EXPECT_EQ(read_file(file), before) << "the input file changed";
}

TEST_P(BadInput, LibraryReturnsTheSameErrorClass) {
    const json& e = GetParam().spec;
    const std::string kind = e["kind"];
    if (kind == "tree") {
        const std::string file = (kCatalogDir / e["file"].get<std::string>()).string();
        expect_api_rejects(load_tree(file).status());
        expect_api_rejects(parse_tree(read_file(file), file).status());
    } else if (kind == "forest") {
        expect_api_rejects(load_forest((kCatalogDir / e["file"].get<std::string>()).string()).status());
    } else if (e.contains("api")) {
        expect_api_rejects_args(e["api"]);
    } else {
        ASSERT_TRUE(e.contains("cli_only")) << "an args entry needs 'api' or 'cli_only'";
        RecordProperty("cli_only", e["cli_only"].get<std::string>());  // nothing to call in the API
    }
}

INSTANTIATE_TEST_SUITE_P(Catalog, BadInput, ::testing::ValuesIn(catalog()),
                         [](const ::testing::TestParamInfo<Entry>& info) { return info.param.name; });

TEST(BadInputCatalog, IsCompleteAndEveryFileIsListed) {
    const auto& entries = catalog();
    ASSERT_GE(entries.size(), 30u);
    std::set<std::string> names, files;
    for (const auto& e : entries) {
        EXPECT_TRUE(names.insert(e.name).second) << "duplicate name " << e.name;
        EXPECT_TRUE(e.spec.contains("expect") && !e.spec["expect"].empty()) << e.name;
        EXPECT_TRUE(e.spec.contains("code")) << e.name;
        if (e.spec.contains("file")) files.insert(e.spec["file"].get<std::string>());
    }
    for (const char* sub : {"trees", "forests"})
        for (const auto& f : fs::directory_iterator(kCatalogDir / sub)) {
            std::string rel = std::string(sub) + "/" + f.path().filename().string();
            if (rel == "forests/ok_rod.json") continue;  // the valid model the forests refer to
            EXPECT_TRUE(files.count(rel)) << rel << " is not in catalog.json";
        }
    // The valid model the forests use really is valid, so their errors are their own.
    EXPECT_TRUE(load_tree((kCatalogDir / "forests" / "ok_rod.json").string()).ok());
}

}  // namespace

// Resource errors: a scene past the 2^32 - 1 vertex limit of the flattened buffers is refused
// with `unsupported` before anything scene-sized is allocated (one 100-segment rod of 1024-sided
// rings, ~103k vertices, times 42,000 instances: ~4.3e9 vertices, only the instance list exists).
TEST(Resources, SceneTooLargeIsUnsupportedWithoutAllocating) {
    TreeModel rod = test::rod(100, 50.0, 0.5);
    ModelOptions options;
    options.ring_sides = 1024;
    auto h = build_hierarchy(rod, options);
    ASSERT_TRUE(h.ok());
    const uint64_t per_instance = mesh_vertex_count(rod, *h, options);
    const uint64_t instances = (uint64_t(1) << 32) / per_instance + 1;
    Scene scene = single_tree_scene(rod);
    scene.instances.assign(instances, Instance{0, glm::dvec3(0.0), 0.0});
    SimulationConfig config;
    config.backend = BackendKind::cpu;
    config.model = options;
    auto sim = Simulation::create(scene, config);
    ASSERT_FALSE(sim.ok());
    EXPECT_EQ(sim.status().code(), ErrorCode::unsupported);
    EXPECT_NE(sim.status().message().find("scene too large"), std::string::npos) << sim.status().message();
    EXPECT_NE(sim.status().message().find(std::to_string(instances * per_instance)), std::string::npos)
        << sim.status().message();
    // One instance fewer than the limit allows is fine to describe (not run: it would need GBs).
    EXPECT_LT((instances - 2) * per_instance, uint64_t(1) << 32);
}

// The CLI maps it to exit 1 (not bad input; a limit of this build) with one line and no output.
TEST(Resources, CliSceneTooLargeExitsOneWithoutOutput) {
    auto dir = fs::temp_directory_path() / ("hmsm_resources_" + std::to_string(getpid()));
    fs::remove_all(dir);
    fs::create_directories(dir / "out");
    const std::string tree = (dir / "rod.json").string();
    ASSERT_TRUE(save_tree(test::rod(100, 50.0, 0.5), tree).ok());
    Outcome r = run_cli({"simulate", "--tree", tree, "--ring-sides", "1024", "--instances", "42000", "--backend", "cpu",
                         "--steps", "1", "--dump-nodes", (dir / "out" / "n.csv").string()},
                        dir);
    EXPECT_EQ(r.exit_code, 1) << r.err;
    EXPECT_NE(r.err.find("scene too large"), std::string::npos) << r.err;
    EXPECT_EQ(std::count(r.err.begin(), r.err.end(), '\n'), 1) << r.err;
    EXPECT_TRUE(fs::is_empty(dir / "out"));
    fs::remove_all(dir);
}

// Device failures through an injected backend: the CPU backend wrapped so that upload runs out
// of memory, or the device is lost at the Nth run() and stays lost (as VK_ERROR_DEVICE_LOST and
// sticky CUDA errors do). Simulation must hand each failure back as a value, of a device class
// (CLI exit 1), without crashing, leaking or pretending the steps were done. The Vulkan and CUDA
// backends need the same through a fault-injection hook of their own.
namespace {

class FailingBackend final : public test::ForwardingBackend {
public:
    enum class Fault { upload_oom, lost_at_run };
    FailingBackend(Fault fault, int fail_at_run)
        : ForwardingBackend(std::move(detail::create_cpu_backend(false)).value()), fault_(fault),
          fail_at_run_(fail_at_run) {}
    std::string device_name() const override { return "failing test device"; }
    Status upload(const detail::SceneData& scene) override {
        if (fault_ == Fault::upload_oom)
            return {ErrorCode::out_of_memory, "failing test device: out of device memory (injected)"};
        return ForwardingBackend::upload(scene);
    }
    Status run(std::span<const detail::Dispatch> program, std::span<const detail::RunStep> steps,
               uint64_t program_id = 0) override {
        if (!lost_ && ++runs_ == fail_at_run_) lost_ = true;
        return ForwardingBackend::run(program, steps, program_id);
    }

private:
    Status gate() const override {
        if (lost_) return {ErrorCode::device_error, "failing test device: device lost (injected)"};
        return {};
    }
    Fault fault_;
    int fail_at_run_;
    int runs_ = 0;
    bool lost_ = false;
};

}  // namespace

TEST(DeviceFailure, UploadOutOfMemoryIsReturnedFromCreate) {
    auto sim = detail::SimulationAccess::create(single_tree_scene(test::small_tree()), {},
                                  std::make_unique<FailingBackend>(FailingBackend::Fault::upload_oom, 0));
    ASSERT_FALSE(sim.ok());
    EXPECT_EQ(sim.status().code(), ErrorCode::out_of_memory);
    EXPECT_FALSE(is_input_error(sim.status().code()));
    EXPECT_NE(sim.status().message().find("out of device memory"), std::string::npos);
}

TEST(DeviceFailure, LostDeviceFailsStepsAndReadsWithoutCrashing) {
    // run() 1 poses the scene at rest in create(); the device is lost at the third step() call.
    auto created = detail::SimulationAccess::create(single_tree_scene(test::small_tree()), {},
                                      std::make_unique<FailingBackend>(FailingBackend::Fault::lost_at_run, 4));
    ASSERT_TRUE(created.ok()) << created.status().message();
    Simulation& sim = **created;
    ASSERT_TRUE(sim.step(10).ok());
    ASSERT_TRUE(sim.step(10).ok());
    EXPECT_EQ(sim.steps_done(), 20u);
    for (int attempt = 0; attempt < 3; ++attempt) {
        Status s = sim.step(10);
        ASSERT_FALSE(s.ok());
        EXPECT_EQ(s.code(), ErrorCode::device_error);
        EXPECT_NE(s.message().find("device lost"), std::string::npos) << s.message();
        EXPECT_EQ(sim.steps_done(), 20u) << "failed steps must not count";
    }
    std::vector<float> nodes;
    Status read = sim.read(Output::node_positions, nodes);
    EXPECT_EQ(read.code(), ErrorCode::device_error);
    (void)sim.pass_times();  // still answers
}  // destroying a simulation on a lost device is fine
