// Small hand-built trees shared by the tests, how they create a simulation and print a backend,
// and how they read and compare its outputs.
#pragma once

#include <hmsm/hmsm.h>

#include <cstring>
#include <functional>
#include <initializer_list>
#include <ostream>
#include <string>
#include <type_traits>
#include <vector>

namespace hmsm::test {

struct NodeSpec {
    int32_t parent;
    double x, y, z, radius;
};

TreeModel make_tree(std::initializer_list<NodeSpec> nodes);

/// Root and one straight vertical chain of `segments` segments of `length` metres.
TreeModel rod(int segments = 4, double length = 5.0, double radius = 0.2);

/// A small tree with side branches at several depths (max depth 3), a leaf, odd counts, and
/// parents listed after some children.
TreeModel small_tree();

/// A tree of `depth` + 1 chain levels (each chain one side branch deeper), for pointer jumping.
TreeModel deep_tree(int depth);

/// A trunk ending in `branches` one-segment branches: one continues the trunk, so the tree has
/// `branches` chains, of depth <= 1 (for models of a chosen chain count).
TreeModel broom(uint32_t branches);

/// `small_trees` small trees on a grid (5 m apart, seed 11), then one deep tree (depth 4) of a
/// second model, "deep": both models with levels of detail of 6, 3 and 1 chains.
Scene small_and_deep_with_levels(uint32_t small_trees);

/// Simulation::create() on `kind`; null with `skip` set to the reason when that backend is not
/// compiled in or has no device (the caller then GTEST_SKIPs); any other error fails the test.
std::unique_ptr<Simulation> create_simulation_or_skip(const Scene& scene, SimulationConfig config,
                                                      BackendKind kind, std::string& skip);

/// Max over elements of |a - b| for xyz arrays.
double max_abs_difference(const std::vector<double>& a, const std::vector<double>& b);
bool all_finite(const std::vector<double>& values);

/// Every output a simulation can produce.
/// A gusty Y4 wind at an angle (12, frequency 0.7): the live-reshape and level-switch suites
/// run under it so that every chain moves.
inline SimulationConfig windy_config() {
    SimulationConfig config;
    config.wind.profile = WindProfile::y4;
    config.wind.strength = 12.0;
    config.wind.direction = {1.0, 0.2, 0.6};
    config.wind.frequency = 0.7;
    return config;
}

inline constexpr Output kEveryOutput[] = {Output::node_positions,  Output::vertex_positions, Output::vertex_normals,
                                          Output::chain_rotations, Output::chain_origins,    Output::chain_angles,
                                          Output::joint_matrices};

/// The same size and the same bytes: equal bit for bit, NaNs and the sign of zero included.
template <class T>
bool same_bits(const std::vector<T>& a, const std::vector<T>& b) {
    static_assert(std::is_trivially_copyable_v<T>);
    return a.size() == b.size() && std::memcmp(a.data(), b.data(), a.size() * sizeof(T)) == 0;
}
template <class T>
bool same_bits(const std::vector<std::vector<T>>& a, const std::vector<std::vector<T>>& b) {
    if (a.size() != b.size()) return false;
    for (size_t k = 0; k < a.size(); ++k)
        if (!same_bits(a[k], b[k])) return false;
    return true;
}

/// Every output of kEveryOutput, as float, one vector per output; a failed read fails the test.
std::vector<std::vector<float>> every_output(const Simulation& sim);
/// One output as double; a failed read fails the test.
std::vector<double> read_output(const Simulation& sim, Output output);

/// A release: `sim` steps `bend_steps` under its wind, the wind calms (WindProfile::none), and
/// `probe(sim)` is recorded after each of the next `record_steps` steps. A failed step or wind
/// change fails the test and ends the record there.
std::vector<double> released_record(Simulation& sim, uint32_t bend_steps, uint32_t record_steps,
                                    const std::function<double(const Simulation&)>& probe);

/// The coupled dynamics on `backend` with joints and nodes out, at time step dt.
inline SimulationConfig coupled_config(BackendKind backend = BackendKind::cpu64, double dt = 1.0 / 120.0) {
    SimulationConfig config;
    config.backend = backend;
    config.model.dynamics = Dynamics::coupled;
    config.outputs = Outputs::joints_and_nodes;
    config.parameters.dt = dt;
    return config;
}

/// Per instance, the index of its first element of `output` (a node, vertex or chain), and one
/// past the last instance's: instance i owns elements first[i] up to first[i + 1].
std::vector<uint64_t> first_elements(const Simulation& sim, Output output);

/// Instance i's scalars of `values`, the whole of `output` as read, where `first` is
/// first_elements(sim, output) of the simulation it was read from.
template <class T>
std::vector<T> instance_slice(const std::vector<T>& values, const std::vector<uint64_t>& first, size_t i,
                              Output output) {
    const uint64_t per = output_components(output);
    return {values.begin() + std::ptrdiff_t(first[i] * per), values.begin() + std::ptrdiff_t(first[i + 1] * per)};
}

/// Per instance, every_output's vectors cut to that instance.
std::vector<std::vector<std::vector<float>>> outputs_by_instance(const Simulation& sim);

}  // namespace hmsm::test

namespace hmsm {
/// Test names and failure messages show a backend by its name.
inline void PrintTo(BackendKind kind, std::ostream* os) { *os << to_string(kind); }
}  // namespace hmsm

namespace hmsm::test {
/// A backend as a test-name part ("cpu_parallel": test names take no '-').
inline std::string backend_test_name(BackendKind kind) {
    std::string name = to_string(kind);
    for (char& c : name)
        if (c == '-') c = '_';
    return name;
}
/// INSTANTIATE_TEST_SUITE_P's name generator for a suite over backends.
struct BackendTestName {
    template <class Info>
    std::string operator()(const Info& info) const { return backend_test_name(info.param); }
};
}  // namespace hmsm::test
