// Name tables: each named enum lists its values once, beside the enum, with the name its
// to_string() gives and its parse_*() accepts (e.g. kBackendKindNames in config.h); the hmsm
// command line derives its choices, help and error texts from the same tables.
#pragma once

#include <cstddef>
#include <optional>
#include <string_view>

namespace hmsm {

/// One row of a name table.
template <class Enum>
struct NamedValue {
    Enum value;
    const char* name;
};

/// The name of `value` in `table`; "?" for a value the table lacks.
template <class Enum, std::size_t N>
constexpr const char* name_in(const NamedValue<Enum> (&table)[N], Enum value) {
    for (const NamedValue<Enum>& row : table)
        if (row.value == value) return row.name;
    return "?";
}

/// The value named `name` in `table` (exact, case-sensitive), if any.
template <class Enum, std::size_t N>
constexpr std::optional<Enum> value_named(const NamedValue<Enum> (&table)[N], std::string_view name) {
    for (const NamedValue<Enum>& row : table)
        if (name == row.name) return row.value;
    return std::nullopt;
}

}  // namespace hmsm
