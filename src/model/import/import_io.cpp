// File entry points of the importers, format detection, and leaves for scanned (leafless) trees.
#include "import/cylinders.h"
#include "json_util.h"
#include "random.h"

#include <glm/geometric.hpp>

#include <algorithm>
#include <cctype>
#include <cmath>
#include <fstream>
#include <limits>
#include <numbers>
#include <sstream>

namespace hmsm {

namespace {

/// A unit vector perpendicular to unit `d`, as close to `hint` as possible.
glm::dvec3 perpendicular(const glm::dvec3& d, const glm::dvec3& hint) {
    glm::dvec3 p = hint - glm::dot(hint, d) * d;
    if (glm::length(p) < 1e-6) {
        const glm::dvec3 other = std::abs(d.x) < 0.9 ? glm::dvec3(1, 0, 0) : glm::dvec3(0, 0, 1);
        p = other - glm::dot(other, d) * d;
    }
    return glm::normalize(p);
}

}  // namespace

Result<ImportedTree> import_treeqsm(const std::string& path) {
    auto text = detail::read_text_file(path, /*regular_file_only=*/true);
    if (!text) return text.status();
    return parse_treeqsm(*text, path);
}

Result<ImportedTree> import_simpleforest(const std::string& path) {
    auto text = detail::read_text_file(path, /*regular_file_only=*/true);
    if (!text) return text.status();
    return parse_simpleforest(*text, path);
}

Result<ImportedTree> parse_cylinders(std::string_view text, std::string_view source) {
    // Only SimpleForest's header names a parentID column.
    const size_t end = std::min(text.find('\n'), text.size());
    std::string first;
    for (char c : text.substr(0, end))
        if (std::isalnum(static_cast<unsigned char>(c))) first += char(std::tolower(static_cast<unsigned char>(c)));
    if (first.find("parentid") != std::string::npos) return parse_simpleforest(text, source);
    return parse_treeqsm(text, source);
}

Status scatter_leaves(TreeModel& tree, uint64_t count, uint64_t seed, double width, double height) {
    HMSM_TRY(validate_tree(tree));
    if (!(width > 0.0 && height > 0.0) || !std::isfinite(width) || !std::isfinite(height))
        return {ErrorCode::invalid_argument, "leaf size must be finite and > 0"};
    if (count > 10'000'000) return {ErrorCode::invalid_argument, "at most 10,000,000 leaves"};
    if (count == 0) return {};
    const size_t n = tree.nodes.size();
    std::vector<uint8_t> has_child(n, 0);
    for (const TreeNode& node : tree.nodes)
        if (node.parent >= 0) has_child[size_t(node.parent)] = 1;
    double thinnest_tip = std::numeric_limits<double>::infinity();
    for (size_t i = 0; i < n; ++i)
        if (!has_child[i] && tree.nodes[i].parent >= 0) thinnest_tip = std::min(thinnest_tip, tree.nodes[i].radius);
    // The thinnest branches: tips, and nodes no thicker than twice the thinnest tip or than the
    // thinnest quarter of all nodes (scans end in a few very thin twig cylinders).
    std::vector<double> radii;
    for (size_t i = 0; i < n; ++i)
        if (tree.nodes[i].parent >= 0) radii.push_back(tree.nodes[i].radius);
    std::nth_element(radii.begin(), radii.begin() + radii.size() / 4, radii.end());
    const double thin = std::max(2.0 * thinnest_tip, radii[radii.size() / 4]);
    std::vector<int32_t> sites;
    for (size_t i = 0; i < n; ++i)
        if (tree.nodes[i].parent >= 0 && (!has_child[i] || tree.nodes[i].radius <= thin))
            sites.push_back(int32_t(i));
    detail::Random rng(seed ^ 0x6c656166ull);  // "leaf"
    tree.leaves.reserve(tree.leaves.size() + count);
    for (uint64_t k = 0; k < count; ++k) {
        const int32_t node = sites[rng.below(sites.size())];
        const TreeNode& here = tree.nodes[size_t(node)];
        const glm::dvec3 d = glm::normalize(here.position - tree.nodes[size_t(here.parent)].position);
        const glm::dvec3 side = perpendicular(d, glm::dvec3(0, 1, 0));
        const glm::dvec3 binormal = glm::cross(d, side);
        // A petiole at 35-75 degrees to the twig, any way round it; the blade faces the sky.
        const double azimuth = rng.uniform(0.0, 2.0 * std::numbers::pi);
        const double tilt = rng.uniform(0.6, 1.3);
        const glm::dvec3 radial = std::cos(azimuth) * side + std::sin(azimuth) * binormal;
        const glm::dvec3 up = glm::normalize(std::cos(tilt) * d + std::sin(tilt) * radial);
        const glm::dvec3 sky(rng.uniform(-0.4, 0.4), 1.0, rng.uniform(-0.4, 0.4));
        const double scale = rng.uniform(0.75, 1.25);
        // Anywhere along the segment that ends at the node (it moves with the node's chain).
        const glm::dvec3 along = -rng.uniform() * (here.position - tree.nodes[size_t(here.parent)].position);
        TreeLeaf leaf;
        leaf.node = node;
        leaf.size = glm::dvec2(width * scale, height * scale);
        leaf.up = up;
        leaf.normal = perpendicular(up, sky);
        leaf.offset = along + (here.radius + 0.5 * leaf.size.y) * up;
        tree.leaves.push_back(leaf);
    }
    return validate_tree(tree);
}

}  // namespace hmsm
