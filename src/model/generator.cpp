// The paper presets (docs/model.md 6): grow a deterministic skeleton from the preset's parameters
// and seed, then fill the rest of the paper's Table 1 vertex budget with leaf cards.
#include <hmsm/generator.h>
#include <hmsm/hierarchy.h>
#include <hmsm/mesh.h>

#include "generator/leaves.h"
#include "generator/presets.h"
#include "generator/skeleton.h"
#include "random.h"

#include <algorithm>
#include <cmath>
#include <string>

namespace hmsm {

const std::vector<std::string_view>& preset_names() {
    static const std::vector<std::string_view> names = [] {
        std::vector<std::string_view> list;
        for (const auto& spec : detail::gen::presets()) list.push_back(spec.name);
        return list;
    }();
    return names;
}

namespace {

using detail::gen::PresetSpec;
using detail::gen::Skeleton;

/// Branch-mesh vertices of a grown skeleton (docs/model.md 3.8): every branch is one chain with
/// members + 1 rings and ends in a tip, and the members are all nodes but the root.
int64_t branch_vertex_count(const Skeleton& skeleton, int32_t ring_sides) {
    const int64_t members = int64_t(skeleton.tree.nodes.size()) - 1;
    return (members + skeleton.chains) * ring_sides + skeleton.chains;
}

/// Grows the skeleton with the fine-order density scaled so that the branches take about
/// `branch_share` of the vertex budget: a bisection on the scale (log scale, the count grows
/// with it), keeping the closest. Limbs do not change with the scale (per-branch streams).
Skeleton grow_to_share(const PresetSpec& spec, uint64_t seed, int32_t ring_sides) {
    const double wanted = spec.branch_share * double(spec.target_vertices);
    double lo = 0.25, hi = 4.0, scale = 1.0;
    Skeleton best;
    double best_error = -1.0;
    for (int iteration = 0; iteration < 14; ++iteration) {
        Skeleton candidate = detail::gen::SkeletonGrower(spec, seed, scale).grow();
        const double count = double(branch_vertex_count(candidate, ring_sides));
        const double error = std::abs(count - wanted);
        if (best_error < 0.0 || error < best_error) {
            best = std::move(candidate);
            best_error = error;
        }
        if (best_error < 0.01 * wanted) break;
        (count < wanted ? lo : hi) = scale;
        scale = std::sqrt(lo * hi);
    }
    return best;
}

}  // namespace

Result<TreeModel> generate_preset(std::string_view name, uint64_t seed) {
    using namespace detail::gen;
    const PresetSpec* spec = nullptr;
    for (const auto& candidate : presets())
        if (candidate.name == name) spec = &candidate;
    if (spec == nullptr) {
        std::string known;
        for (std::string_view n : preset_names()) known += (known.empty() ? "" : ", ") + std::string(n);
        return Status{ErrorCode::invalid_argument,
                      "unknown preset '" + std::string(name) + "' (known: " + known + ")"};
    }

    const uint64_t tree_seed = seed == 0 ? spec->seed : seed;
    const ModelOptions options;
    const int64_t target = int64_t(spec->target_vertices);
    Skeleton skeleton = grow_to_share(*spec, tree_seed, options.ring_sides);

    // The chain structure must be the one the grower built, and so its vertex count.
    auto hierarchy = build_hierarchy(skeleton.tree, options);
    if (!hierarchy) return hierarchy.status();
    const int64_t branch_vertices = int64_t(mesh_vertex_count(skeleton.tree, *hierarchy, options));
    if (int64_t(hierarchy->chains.size()) != skeleton.chains ||
        hierarchy->max_depth != kTwigDepth || skeleton.max_depth != kTwigDepth ||
        branch_vertices != branch_vertex_count(skeleton, options.ring_sides) ||
        skeleton.leaf_nodes.empty())
        return Status{ErrorCode::internal,
                      "preset '" + std::string(name) + "': generated chain structure is off (" +
                          std::to_string(hierarchy->chains.size()) + " chains, depth " +
                          std::to_string(hierarchy->max_depth) + ")"};

    // Leaves fill the rest of the budget, 4 vertices per card (at least one per two leaf
    // sites, should the skeleton alone exceed the budget).
    const int64_t sites = int64_t(skeleton.leaf_nodes.size());
    const int64_t leaves = std::max((target - branch_vertices + 2) / 4, std::max<int64_t>(1, sites / 2));
    detail::Random leaf_rng(child_seed(tree_seed, 2));
    add_leaves(skeleton, uint64_t(leaves), spec->leaf, leaf_rng);

    HMSM_TRY(validate_tree(skeleton.tree));
    return std::move(skeleton.tree);
}

}  // namespace hmsm
