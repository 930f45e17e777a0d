// Shared by the cylinder-model importers: a text line splitter, strict number parsing and the
// conversion of a cylinder list into an hmsm skeleton (docs/model.md 4, "Imports").
#pragma once

#include <hmsm/import.h>

#include <glm/vec3.hpp>

#include <string>
#include <string_view>
#include <vector>

namespace hmsm::detail::import {

/// One cylinder as read (file coordinates, z up). `parent` is a 0-based row index or -1.
struct Cylinder {
    double radius = 0.0;
    glm::dvec3 start{0.0};
    glm::dvec3 end{0.0};
    int64_t parent = -1;
    size_t line = 0;  ///< 1-based line in the file, for messages
};

/// Lines of a text with their 1-based numbers; blank lines (only spaces, tabs, CR) are dropped.
struct Line {
    std::string_view text;
    size_t number = 0;
};
std::vector<Line> split_lines(std::string_view text);
/// Refuses a text of more lines than a tree may have nodes (docs/model.md 3.11; every cylinder
/// row makes at least one node) before anything per line is allocated.
Status check_line_count(std::string_view text, std::string_view source);

/// Splits on any of `separators`; runs of separators count as one when `merge_runs`.
std::vector<std::string_view> split_fields(std::string_view line, std::string_view separators,
                                           bool merge_runs);

/// A finite double, the whole field (surrounding spaces allowed); false otherwise.
bool parse_number(std::string_view field, double& value);

/// A field as quoted in a message: control bytes shown as '?', at most 32 characters, so the
/// message stays one printable line whatever the file holds.
std::string quote(std::string_view field);

/// "SOURCE line N: " for messages.
std::string where(std::string_view source, size_t line);

/// Builds the skeleton (conventions in include/hmsm/import.h) and validates it.
Result<ImportedTree> cylinders_to_tree(const std::vector<Cylinder>& cylinders,
                                       std::string_view source, CylinderFormat format);

}  // namespace hmsm::detail::import
