// The name tables (include/hmsm/names.h): every value of each enum has one row, names are
// distinct, and to_string / parse_* are the table read both ways.
#include <hmsm/config.h>
#include <hmsm/options.h>

#include <gtest/gtest.h>

#include <set>
#include <string>

using namespace hmsm;

namespace {

/// `last` is the enum's last enumerator: values 0..last are all its values.
template <class Enum, std::size_t N, class Parse>
void expect_table(const NamedValue<Enum> (&table)[N], Enum last, Parse parse) {
    const auto count = static_cast<std::size_t>(last) + 1;
    EXPECT_EQ(N, count) << "one row per value";
    std::set<std::string> names;
    for (std::size_t i = 0; i < count; ++i) {
        const auto value = static_cast<Enum>(i);
        const std::string name = to_string(value);
        EXPECT_NE(name, "?") << "value " << i << " has no row";
        EXPECT_TRUE(names.insert(name).second) << "name '" << name << "' twice";
        EXPECT_EQ(parse(name), value) << name;
    }
    for (const NamedValue<Enum>& row : table) EXPECT_STREQ(to_string(row.value), row.name);
    EXPECT_STREQ(to_string(static_cast<Enum>(count)), "?");
    EXPECT_FALSE(parse("").has_value());
    EXPECT_FALSE(parse("not a name").has_value());
}

}  // namespace

TEST(Names, EveryTableCoversItsEnumAndRoundTrips) {
    expect_table(kBackendKindNames, BackendKind::cpu_parallel, parse_backend_kind);
    expect_table(kCompositionNames, Composition::automatic, parse_composition);
    expect_table(kVertexLayoutNames, VertexLayout::packed, parse_vertex_layout);
    expect_table(kOutputsNames, Outputs::all, parse_outputs);
    expect_table(kGroupingNames, Grouping::width, parse_grouping);
    expect_table(kWindProfileNames, WindProfile::atmospheric, parse_wind_profile);
}

TEST(Names, PublicSpellingsAreStable) {
    EXPECT_STREQ(to_string(BackendKind::cpu_parallel), "cpu-parallel");
    EXPECT_STREQ(to_string(BackendKind::automatic), "auto");
    EXPECT_STREQ(to_string(Outputs::joints_and_nodes), "nodes");
    EXPECT_STREQ(to_string(Composition::path_walk), "path_walk");
    EXPECT_STREQ(to_string(WindProfile::y3), "y3");
    EXPECT_FALSE(parse_backend_kind("cpu_parallel").has_value());
    EXPECT_FALSE(parse_composition("path-walk").has_value());  // the CLI maps '-' to '_'
}
