// SimpleForest QSM CSV (docs/model.md 4): a header naming ID, parentID (-1 = root), the start
// and end points and radius; other columns are ignored.
#include "import/cylinders.h"

#include <glm/geometric.hpp>

#include <cctype>
#include <cmath>
#include <unordered_map>

namespace hmsm {

using namespace detail::import;

namespace {

Status bad(std::string message) { return {ErrorCode::invalid_tree, std::move(message)}; }

/// Column names compared by letters and digits only, any case: "parentID", "parent_id" match.
std::string key(std::string_view name) {
    std::string out;
    for (char c : name)
        if (std::isalnum(static_cast<unsigned char>(c))) out += char(std::tolower(static_cast<unsigned char>(c)));
    return out;
}

bool is_integer(double v) { return v == std::floor(v) && std::fabs(v) < 9e15; }

}  // namespace

Result<ImportedTree> parse_simpleforest(std::string_view text, std::string_view source) {
    HMSM_TRY(check_line_count(text, source));
    const std::vector<Line> lines = split_lines(text);
    if (lines.empty()) return bad(std::string(source) + ": empty file (no header, no cylinder rows)");
    const std::string_view header = lines[0].text;
    const std::string_view separators =
        header.find(',') != std::string_view::npos ? "," : (header.find(';') != std::string_view::npos ? ";" : "\t");
    const auto names = split_fields(header, separators, false);
    static constexpr const char* kNeeded[] = {"id", "parentid", "startx", "starty", "startz",
                                              "endx", "endy", "endz", "radius"};
    size_t column[9];
    for (size_t k = 0; k < 9; ++k) {
        column[k] = names.size();
        for (size_t j = 0; j < names.size(); ++j)
            if (key(names[j]) == kNeeded[k]) {
                column[k] = j;
                break;
            }
        if (column[k] == names.size())
            return bad(where(source, lines[0].number) + "not a SimpleForest header: no column '" +
                       kNeeded[k] + "' (needs ID, parentID, startX..Z, endX..Z, radius)");
    }
    if (lines.size() == 1) return bad(std::string(source) + ": no cylinder rows after the header");
    std::vector<Cylinder> cylinders;
    std::vector<int64_t> parent_id;
    std::unordered_map<int64_t, int64_t> row_of_id;
    cylinders.reserve(lines.size() - 1);
    for (size_t i = 1; i < lines.size(); ++i) {
        const Line& line = lines[i];
        const auto fields = split_fields(line.text, separators, false);
        if (fields.size() != names.size())
            return bad(where(source, line.number) + "expected " + std::to_string(names.size()) +
                       " columns as in the header, got " + std::to_string(fields.size()));
        double v[9];
        for (size_t k = 0; k < 9; ++k)
            if (!parse_number(fields[column[k]], v[k]))
                return bad(where(source, line.number) + "column " + quote(names[column[k]]) +
                           " value " + quote(fields[column[k]]) + " is not a finite number");
        if (!is_integer(v[0]) || !is_integer(v[1]))
            return bad(where(source, line.number) + "ID and parentID must be integers");
        if (!row_of_id.emplace(int64_t(v[0]), int64_t(cylinders.size())).second)
            return bad(where(source, line.number) + "ID " + std::to_string(int64_t(v[0])) + " repeats an earlier row");
        if (!(v[8] > 0.0)) return bad(where(source, line.number) + "radius must be > 0");
        Cylinder cyl;
        cyl.line = line.number;
        cyl.radius = v[8];
        cyl.start = glm::dvec3(v[2], v[3], v[4]);
        cyl.end = glm::dvec3(v[5], v[6], v[7]);
        if (!(glm::length(cyl.end - cyl.start) > 0.0))
            return bad(where(source, line.number) + "length must be > 0 (start and end points coincide)");
        cylinders.push_back(cyl);
        parent_id.push_back(int64_t(v[1]));
    }
    for (size_t c = 0; c < cylinders.size(); ++c) {
        if (parent_id[c] == -1) continue;
        auto it = row_of_id.find(parent_id[c]);
        if (it == row_of_id.end())
            return bad(where(source, cylinders[c].line) + "parentID " + std::to_string(parent_id[c]) +
                       " is no row's ID (and not -1)");
        if (size_t(it->second) == c) return bad(where(source, cylinders[c].line) + "cylinder is its own parent");
        cylinders[c].parent = it->second;
    }
    return cylinders_to_tree(cylinders, source, CylinderFormat::simpleforest);
}

}  // namespace hmsm
