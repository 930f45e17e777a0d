// TreeQSM cylinder tables (docs/model.md 4): the text export (one header line, 17 numbers a row)
// and the headerless v2.3 text (15 numbers a row). Both start with radius, length, start xyz,
// axis xyz, parent, extension; parents are 1-based rows, 0 = none.
#include "import/cylinders.h"

#include <glm/geometric.hpp>

#include <algorithm>
#include <cctype>
#include <cmath>

namespace hmsm {

using namespace detail::import;

namespace {

Status bad(std::string message) { return {ErrorCode::invalid_tree, std::move(message)}; }

std::string lower(std::string_view text) {
    std::string out(text);
    for (char& c : out) c = char(std::tolower(static_cast<unsigned char>(c)));
    return out;
}

// Tabs (the export), spaces, commas and semicolons (re-saved tables) all separate columns.
constexpr std::string_view kSeparators = " \t,;";

}  // namespace

Result<ImportedTree> parse_treeqsm(std::string_view text, std::string_view source) {
    HMSM_TRY(check_line_count(text, source));
    const std::vector<Line> lines = split_lines(text);
    if (lines.empty()) return bad(std::string(source) + ": empty file (no cylinder rows)");
    size_t first_row = 0;
    size_t columns = 15;
    CylinderFormat format = CylinderFormat::treeqsm_v23;
    double probe = 0.0;
    const auto first_fields = split_fields(lines[0].text, kSeparators, true);
    if (first_fields.empty() || !parse_number(first_fields[0], probe)) {
        // A header: column names, tab separated, their exact spelling varies between versions.
        const std::string header = lower(lines[0].text);
        for (const char* name : {"radius", "length", "parent"})
            if (header.find(name) == std::string::npos)
                return bad(where(source, lines[0].number) +
                           "not a TreeQSM header (expected column names radius, length, start, "
                           "axis, parent, ...; missing '" + name + "')");
        first_row = 1;
        columns = 17;
        format = CylinderFormat::treeqsm_text;
        if (lines.size() == 1) return bad(std::string(source) + ": no cylinder rows after the header");
        // The v2.3 columns under a header line: the first row decides, every row must agree.
        if (split_fields(lines[1].text, kSeparators, true).size() == 15) {
            columns = 15;
            format = CylinderFormat::treeqsm_v23;
        }
    } else if (first_fields.size() == 17) {
        // The 17-column export saved without its header line.
        columns = 17;
        format = CylinderFormat::treeqsm_text;
    }
    const size_t rows = lines.size() - first_row;
    std::vector<Cylinder> cylinders;
    cylinders.reserve(rows);
    std::vector<double> v(columns);
    for (size_t i = first_row; i < lines.size(); ++i) {
        const Line& line = lines[i];
        const auto fields = split_fields(line.text, kSeparators, true);
        if (fields.size() != columns)
            return bad(where(source, line.number) + "expected " + std::to_string(columns) +
                       " numbers (" + to_string(format) + "), got " + std::to_string(fields.size()));
        for (size_t k = 0; k < columns; ++k)
            if (!parse_number(fields[k], v[k]))
                return bad(where(source, line.number) + "column " + std::to_string(k + 1) + " " +
                           quote(fields[k]) + " is not a finite number");
        Cylinder cyl;
        cyl.line = line.number;
        cyl.radius = v[0];
        if (!(v[0] > 0.0)) return bad(where(source, line.number) + "radius must be > 0");
        if (!(v[1] > 0.0)) return bad(where(source, line.number) + "length must be > 0");
        const glm::dvec3 axis(v[5], v[6], v[7]);
        const double norm = glm::length(axis);
        if (!(norm > 1e-12) || !std::isfinite(norm))
            return bad(where(source, line.number) + "axis direction is zero");
        cyl.start = glm::dvec3(v[2], v[3], v[4]);
        cyl.end = cyl.start + v[1] * (axis / norm);
        if (v[8] != std::floor(v[8]) || v[8] < 0.0 || v[8] > double(rows))
            return bad(where(source, line.number) + "parent " + quote(fields[8]) +
                       " is not a row number (1.." + std::to_string(rows) + ") or 0");
        if (size_t(v[8]) == i - first_row + 1)
            return bad(where(source, line.number) + "cylinder is its own parent");
        cyl.parent = int64_t(v[8]) - 1;
        cylinders.push_back(cyl);
    }
    return cylinders_to_tree(cylinders, source, format);
}

}  // namespace hmsm
