// The open world's endless grid of trees (bench_open_world.cpp): which cells lie within the
// streaming radius of a viewer, and which leave and come as the viewer moves.
#pragma once

#include <hmsm/scene.h>

#include <glm/vec2.hpp>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <utility>
#include <vector>

namespace hmsm::cli::bench {

/// The endless grid: the tree of cell (i, j) stands at (i, 0, j) * spacing with a yaw drawn
/// from its cell, so a tree streamed out and back in is the same tree. The simulated trees are
/// the cells strictly within `radius` of the viewer (on the ground plane).
struct Grid {
    double spacing = 25.0, radius = 0.0;

    static uint64_t key(int64_t i, int64_t j) {
        return (uint64_t(uint32_t(int32_t(i))) << 32) | uint64_t(uint32_t(int32_t(j)));
    }
    Instance tree(int64_t i, int64_t j) const {
        uint64_t h = key(i, j) * 0x9E3779B97F4A7C15ull;
        h ^= h >> 29;
        Instance t;
        t.origin = {double(i) * spacing, 0.0, double(j) * spacing};
        t.yaw = double(h % 62832) * 1e-4;
        t.wind_phase = double((h >> 20) % 1000) * 1e-3;
        return t;
    }
    /// The cells of row j within the radius of (x, z): [first, last] (first > last: none).
    std::pair<int64_t, int64_t> row(int64_t j, double x, double z) const {
        const double dz = double(j) * spacing - z;
        if (std::abs(dz) >= radius) return {1, 0};
        const double half = std::sqrt(radius * radius - dz * dz);
        int64_t first = int64_t(std::ceil((x - half) / spacing)), last = int64_t(std::floor((x + half) / spacing));
        if (std::hypot(double(first) * spacing - x, dz) >= radius) ++first;
        if (std::hypot(double(last) * spacing - x, dz) >= radius) --last;
        return {first, last};
    }
    std::pair<int64_t, int64_t> rows(double z0, double z1) const {
        return {int64_t(std::floor((std::min(z0, z1) - radius) / spacing)),
                int64_t(std::ceil((std::max(z0, z1) + radius) / spacing))};
    }
};

struct Cell {
    int64_t i, j;
};

/// Appends the cells (i, j) of row j with i in [a, b] but not in [c, d] (each first > last:
/// none), ascending.
inline void row_difference(int64_t j, int64_t a, int64_t b, int64_t c, int64_t d, std::vector<Cell>& out) {
    if (c > d) {  // nothing taken away
        for (int64_t i = a; i <= b; ++i) out.push_back({i, j});
        return;
    }
    for (int64_t i = a; i <= std::min(b, c - 1); ++i) out.push_back({i, j});
    for (int64_t i = std::max(a, d + 1); i <= b; ++i) out.push_back({i, j});
}

/// The cells within the radius of `from` but not of `to` (leaving) and the reverse (entering),
/// row by row ascending: O(rows + cells that change), as an engine's streaming costs.
inline void stream_cells(const Grid& g, glm::dvec2 from, glm::dvec2 to, std::vector<Cell>& leaving,
                         std::vector<Cell>& entering) {
    leaving.clear();
    entering.clear();
    const auto [j0, j1] = g.rows(from.y, to.y);
    for (int64_t j = j0; j <= j1; ++j) {
        const auto [a0, b0] = g.row(j, from.x, from.y);
        const auto [a1, b1] = g.row(j, to.x, to.y);
        row_difference(j, a0, b0, a1, b1, leaving);
        row_difference(j, a1, b1, a0, b0, entering);
    }
}

}  // namespace hmsm::cli::bench
