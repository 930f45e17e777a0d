// hmsm bench: one run over backends, presets and forest sizes. BenchRun creates each case's
// simulation, times it (bench_measure.h) and records the figures as JSON entries in the schema
// of docs/benchmarks/README.md; cases that do not fit are recorded as skips with the reason.
#pragma once

#include "bench_measure.h"
#include "bench_model.h"
#include "step_program.h"

#include <hmsm/hmsm.h>

#include <nlohmann/json.hpp>

#include <array>
#include <memory>
#include <optional>
#include <string>
#include <vector>

namespace hmsm::cli::bench {

std::string format_seconds(double s);

struct Model {
    std::string name;
    TreeModel tree;
};

struct BackendRun {
    BackendKind kind;
    bool available = true;
    std::string device;
    std::optional<CopyBandwidth> copy;
};

/// The host-CPU backends: cpu, cpu-parallel and cpu64.
bool is_host_kind(BackendKind k);

/// Keeps only positive, finite figures (the schema's promise).
void put(nlohmann::json& j, const char* key, double value);

constexpr std::array<VertexLayout, 2> kVertexLayouts = {VertexLayout::separate, VertexLayout::packed};

class BenchRun {
public:
    BenchRun(const Settings& settings, uint64_t device_copy_bytes, uint64_t host_copy_bytes,
             Progress& progress)
        : settings_(settings), device_copy_bytes_(device_copy_bytes),
          host_copy_bytes_(host_copy_bytes), progress_(progress) {}

    std::vector<BackendRun> backends;
    nlohmann::json presets = nlohmann::json::array(), forest = nlohmann::json::array(),
                   skipped = nlohmann::json::array();
    int failures = 0;

    /// Creates a simulation (pointer jumping in `jumping_form`); on failure records why (a skip,
    /// an unavailable backend or a failure) under `where` and returns null.
    std::unique_ptr<Simulation> create(const Scene& scene, BackendRun& b, Composition composition,
                                       nlohmann::json where, VertexLayout layout = VertexLayout::separate,
                                       detail::JumpingForm jumping_form = detail::JumpingForm::by_size);
    void record_failure(nlohmann::json where, const Status& s);
    /// Measures b's roofline once (again on a larger scene when the first was a host-transfer
    /// estimate over a smaller block).
    void copy_bandwidth(BackendRun& b, Simulation& sim);
    /// One preset on one backend: the Table-1 rates, per-pass times and the compositions.
    void preset_case(const Model& m, BackendRun& b);
    /// Each forest size in both vertex layouts, side by side: the contour pass writes 32 bytes
    /// per vertex in the separate layout and 16 in the packed one.
    void forest_cases(const Model& model, BackendRun& b, const std::vector<uint32_t>& counts,
                      double spacing, double state_per_instance);

private:
    Settings settings_;
    uint64_t device_copy_bytes_, host_copy_bytes_;
    std::optional<CopyBandwidth> host_copy_;
    Progress& progress_;
};

/// Adds to each preset entry `speedup_over_cpu` and `speedup_over_best_cpu` (per_call,
/// batched, readback) with `best_cpu` (the backend behind each), and to each forest entry
/// the same for steps_per_second, against the CPU backends' rates of the same preset, resp.
/// the same instance count and layout, in this run. Figures without a CPU rate are left out.
void add_speedups(nlohmann::json& presets, nlohmann::json& forest);

}  // namespace hmsm::cli::bench
