// The open-world benchmark's streaming (tools/hmsm/bench_open_world_grid.h): the cells that
// leave and come as the viewer moves, by rows, against every cell of the grid tested one by one.
#include "bench_open_world_grid.h"

#include <gtest/gtest.h>

#include <cmath>
#include <random>
#include <set>
#include <utility>

namespace hmsm::cli::bench {
namespace {

using CellSet = std::set<std::pair<int64_t, int64_t>>;

/// Every cell within the radius of `at`, each tested alone.
CellSet within(const Grid& g, glm::dvec2 at) {
    CellSet cells;
    const auto reach = int64_t(std::ceil(g.radius / g.spacing)) + 1;
    const int64_t ci = int64_t(std::floor(at.x / g.spacing)), cj = int64_t(std::floor(at.y / g.spacing));
    for (int64_t j = cj - reach; j <= cj + reach; ++j)
        for (int64_t i = ci - reach; i <= ci + reach; ++i)
            if (std::hypot(double(i) * g.spacing - at.x, double(j) * g.spacing - at.y) < g.radius) cells.insert({i, j});
    return cells;
}

TEST(OpenWorldGrid, StreamedCellsAreTheDifferenceOfTheDiscs) {
    Grid g;
    g.spacing = 25.0;
    g.radius = 310.0;
    std::mt19937 random(7);
    std::uniform_real_distribution<double> step(-90.0, 90.0);
    glm::dvec2 viewer(3.0, -11.0);
    for (int k = 0; k < 60; ++k) {
        // Small moves, moves along an axis, none at all, and jumps past the whole disc.
        glm::dvec2 move(step(random), step(random));
        if (k % 5 == 1) move.y = 0.0;
        if (k % 7 == 2) move = {0.0, 0.0};
        if (k % 11 == 3) move *= 10.0;
        const glm::dvec2 to = viewer + move;
        std::vector<Cell> leaving, entering;
        stream_cells(g, viewer, to, leaving, entering);
        const CellSet before = within(g, viewer), after = within(g, to);
        CellSet left, came;
        for (const auto& c : before)
            if (!after.count(c)) left.insert(c);
        for (const auto& c : after)
            if (!before.count(c)) came.insert(c);
        CellSet got_left, got_came;
        for (const Cell& c : leaving) EXPECT_TRUE(got_left.insert({c.i, c.j}).second) << "twice: " << c.i << ", " << c.j;
        for (const Cell& c : entering) EXPECT_TRUE(got_came.insert({c.i, c.j}).second) << "twice: " << c.i << ", " << c.j;
        EXPECT_EQ(got_left, left) << "move " << k;
        EXPECT_EQ(got_came, came) << "move " << k;
        viewer = to;
    }
}

}  // namespace
}  // namespace hmsm::cli::bench
