// Cylinder list -> hmsm skeleton (docs/model.md 4, "Imports"); conventions in hmsm/import.h.
#include "import/cylinders.h"
#include "input_limits.h"

#include <glm/geometric.hpp>

#include <algorithm>
#include <charconv>
#include <cmath>
#include <deque>
#include <limits>

namespace hmsm {

const char* to_string(CylinderFormat format) {
    switch (format) {
        case CylinderFormat::treeqsm_text: return "treeqsm-text";
        case CylinderFormat::treeqsm_v23: return "treeqsm-v2.3";
        case CylinderFormat::simpleforest: return "simpleforest";
    }
    return "unknown";
}

namespace detail::import {

namespace {

Status bad(std::string message) { return {ErrorCode::invalid_tree, std::move(message)}; }

/// z-up (scan) to y-up (hmsm): (x, y, z) -> (x, z, -y), a rotation (right-handedness kept).
glm::dvec3 to_y_up(const glm::dvec3& p) { return {p.x, p.z, -p.y}; }

}  // namespace

Status check_line_count(std::string_view text, std::string_view source) {
    const uint64_t lines = uint64_t(std::count(text.begin(), text.end(), '\n')) + 1;
    // One header line besides the rows.
    if (Status counted = check_count("lines", lines, size_limits().tree_nodes + 1); !counted)
        return {ErrorCode::invalid_tree, std::string(source) + ": " + counted.message()};
    return {};
}

std::vector<Line> split_lines(std::string_view text) {
    std::vector<Line> lines;
    size_t number = 0, begin = 0;
    while (begin <= text.size()) {
        size_t end = text.find('\n', begin);
        if (end == std::string_view::npos) end = text.size();
        ++number;
        std::string_view line = text.substr(begin, end - begin);
        while (!line.empty() && (line.back() == '\r' || line.back() == ' ' || line.back() == '\t'))
            line.remove_suffix(1);
        if (line.find_first_not_of(" \t\r") != std::string_view::npos) lines.push_back({line, number});
        if (end == text.size()) break;
        begin = end + 1;
    }
    return lines;
}

std::vector<std::string_view> split_fields(std::string_view line, std::string_view separators,
                                           bool merge_runs) {
    std::vector<std::string_view> fields;
    size_t begin = 0;
    if (merge_runs) {
        begin = line.find_first_not_of(separators);
        if (begin == std::string_view::npos) return fields;
    }
    while (true) {
        size_t end = line.find_first_of(separators, begin);
        if (end == std::string_view::npos) {
            fields.push_back(line.substr(begin));
            break;
        }
        fields.push_back(line.substr(begin, end - begin));
        begin = end + 1;
        if (merge_runs) {
            begin = line.find_first_not_of(separators, begin);
            if (begin == std::string_view::npos) break;
        }
    }
    return fields;
}

bool parse_number(std::string_view field, double& value) {
    while (!field.empty() && (field.front() == ' ' || field.front() == '\t')) field.remove_prefix(1);
    while (!field.empty() && (field.back() == ' ' || field.back() == '\t')) field.remove_suffix(1);
    if (field.size() >= 2 && field.front() == '"' && field.back() == '"') field = field.substr(1, field.size() - 2);
    if (!field.empty() && field.front() == '+') field.remove_prefix(1);
    if (field.empty()) return false;
    auto [end, ec] = std::from_chars(field.data(), field.data() + field.size(), value);
    return ec == std::errc() && end == field.data() + field.size() && std::isfinite(value);
}

std::string quote(std::string_view field) {
    std::string out = "'";
    for (size_t i = 0; i < field.size() && i < 32; ++i) {
        const unsigned char c = static_cast<unsigned char>(field[i]);
        out += c < 0x20 || c == 0x7f ? '?' : char(c);
    }
    return out + (field.size() > 32 ? "...'" : "'");
}

std::string where(std::string_view source, size_t line) {
    return std::string(source) + " line " + std::to_string(line) + ": ";
}

Result<ImportedTree> cylinders_to_tree(const std::vector<Cylinder>& cylinders,
                                       std::string_view source, CylinderFormat format) {
    const int64_t n = int64_t(cylinders.size());
    if (n == 0) return bad(std::string(source) + ": no cylinders");
    std::vector<glm::dvec3> start(n), end(n), axis(n);
    std::vector<double> length(n);
    for (int64_t c = 0; c < n; ++c) {
        const Cylinder& cyl = cylinders[c];
        if (!(cyl.radius > 0.0) || !std::isfinite(cyl.radius))
            return bad(where(source, cyl.line) + "radius must be finite and > 0");
        start[c] = to_y_up(cyl.start);
        end[c] = to_y_up(cyl.end);
        length[c] = glm::length(end[c] - start[c]);
        if (!(length[c] > 0.0) || !std::isfinite(length[c]))
            return bad(where(source, cyl.line) + "zero-length cylinder");
        axis[c] = (end[c] - start[c]) / length[c];
        if (cyl.parent < -1 || cyl.parent >= n)
            return bad(where(source, cyl.line) + "parent " + std::to_string(cyl.parent + 1) +
                       " is not a cylinder row");
        if (cyl.parent == c) return bad(where(source, cyl.line) + "cylinder is its own parent");
    }
    // The first parentless cylinder is the root; further parentless ones hang from it.
    int64_t root = -1;
    for (int64_t c = 0; c < n && root < 0; ++c)
        if (cylinders[c].parent < 0) root = c;
    if (root < 0)
        return bad(where(source, cylinders[0].line) +
                   "no cylinder without a parent from here on (the parents form a cycle)");
    std::vector<int64_t> parent(n);
    for (int64_t c = 0; c < n; ++c) parent[c] = c == root ? -1 : (cylinders[c].parent < 0 ? root : cylinders[c].parent);
    // Every cylinder must reach the root: walk up with marks (O(n) overall).
    {
        std::vector<int8_t> state(n, 0);  // 0 unknown, 1 on the current path, 2 reaches the root
        state[root] = 2;
        std::vector<int64_t> path;
        for (int64_t c = 0; c < n; ++c) {
            path.clear();
            int64_t k = c;
            while (state[k] == 0) {
                state[k] = 1;
                path.push_back(k);
                k = parent[k];
            }
            if (state[k] == 1) return bad(where(source, cylinders[k].line) + "cylinder is in a cycle of parents");
            for (int64_t m : path) state[m] = 2;
        }
    }
    // Where each child starts along its parent: the projection of its start on the parent axis.
    std::vector<std::vector<int64_t>> children(n);
    std::vector<double> along(n, 0.0);
    for (int64_t c = 0; c < n; ++c) {
        if (parent[c] < 0) continue;
        const int64_t p = parent[c];
        along[c] = std::clamp(glm::dot(start[c] - start[p], axis[p]), 0.0, length[p]);
        children[p].push_back(c);
    }
    for (auto& list : children)
        std::stable_sort(list.begin(), list.end(), [&](int64_t a, int64_t b) { return along[a] < along[b]; });

    ImportedTree out;
    out.summary.format = format;
    out.summary.cylinders = size_t(n);
    auto& nodes = out.tree.nodes;
    nodes.reserve(size_t(n) + size_t(n) / 2 + 1);
    // A node at `position` hanging from `from`, or `from` itself when it would be too close.
    auto add_node = [&](int32_t from, const glm::dvec3& position, double radius) -> int32_t {
        if (from >= 0 && glm::length(position - nodes[from].position) < kImportMergeDistance) {
            ++out.summary.merged_nodes;
            return from;
        }
        nodes.push_back({from, position, radius});
        return int32_t(nodes.size() - 1);
    };
    if (n + n / 2 + 1 > int64_t(std::numeric_limits<int32_t>::max() / 2))
        return bad(std::string(source) + ": too many cylinders");
    std::vector<int32_t> start_node(n, -1), attach(n, -1);
    start_node[root] = add_node(-1, start[root], cylinders[root].radius);
    std::deque<int64_t> queue{root};  // breadth first: a parent's nodes exist before its children's
    while (!queue.empty()) {
        const int64_t p = queue.front();
        queue.pop_front();
        const double r = cylinders[p].radius;
        int32_t current = start_node[p];
        std::vector<int64_t> at_end;
        // Starts within `snap` of the parent's ends attach to them: a radius is below what a
        // scan resolves along a stem, and rounding in the files (4 decimals of an axis) must not
        // split a cylinder a fraction of a millimetre before its end, leaving a stub there.
        const double snap = std::max(kImportMergeDistance, std::min(r, 0.5 * length[p]));
        for (int64_t c : children[p]) {
            if (along[c] >= length[p] - snap) {
                at_end.push_back(c);
                continue;
            }
            if (along[c] <= snap) {
                attach[c] = start_node[p];
                continue;
            }
            // A side branch part-way along the parent: split the parent there.
            current = add_node(current, start[p] + along[c] * axis[p], r);
            attach[c] = current;
        }
        const int32_t end_node = add_node(current, end[p], r);
        for (int64_t c : at_end) attach[c] = end_node;
        for (int64_t c : children[p]) {
            // A start inside the parent's wood is the attach point; one farther off keeps its node.
            const double gap = glm::length(start[c] - nodes[attach[c]].position);
            start_node[c] = gap > std::max(r, kImportMergeDistance)
                                ? add_node(attach[c], start[c], cylinders[c].radius)
                                : attach[c];
            queue.push_back(c);
        }
    }
    // Root at x = z = 0, lowest node at y = 0.
    double min_y = nodes[0].position.y, max_y = min_y;
    for (const TreeNode& node : nodes) {
        min_y = std::min(min_y, node.position.y);
        max_y = std::max(max_y, node.position.y);
    }
    const glm::dvec3 shift(nodes[0].position.x, min_y, nodes[0].position.z);
    for (TreeNode& node : nodes) node.position -= shift;
    out.summary.height = max_y - min_y;
    out.summary.base_radius = cylinders[root].radius;
    Status valid = validate_tree(out.tree);
    if (!valid) return bad(std::string(source) + ": the imported tree is invalid: " + valid.message());
    return out;
}

}  // namespace detail::import
}  // namespace hmsm
