// The five paper presets (docs/model.md 6): real-world sizes, five branching orders, shapes after
// the paper's Fig. 9 (multi-branch and forked crowns). The skeleton parameters are chosen so
// that the leaves which fill the rest of the Table 1 vertex budget are a plausible number.
#pragma once

#include "params.h"

#include <array>
#include <string_view>

namespace hmsm::detail::gen {

namespace preset_detail {

/// Order-by-order parameters; fields not named keep the Level defaults.
constexpr Level level(double length, double segment, double angle, double angle_top,
                      double density, double radius_ratio, double tropism) {
    Level l;
    l.length = length;
    l.segment = segment;
    l.angle = angle;
    l.angle_top = angle_top;
    l.density = density;
    l.radius_ratio = radius_ratio;
    l.tropism = tropism;
    return l;
}

/// paper-1: a large open-grown broadleaf (oak-like), decurrent multi-branch crown.
constexpr PresetSpec paper1() {
    PresetSpec p;
    p.name = "paper-1";
    p.seed = 0x9a9e1001;
    p.target_vertices = 78563;
    p.height = 17.0;
    p.base_radius = 0.38;
    p.top_radius = 0.03;
    p.shape = CrownShape::ellipsoid;
    p.levels[0] = level(0, 0.5, 0, 0, 0, 0, 0.0);
    p.levels[0].wobble = 0.03;
    p.levels[1] = level(7.5, 0.4, 1.05, 0.7, 1.0, 0.5, 0.03);
    p.levels[1].start = 0.22;
    p.levels[1].end = 0.95;
    p.levels[1].tip_ratio = 0.12;
    p.levels[2] = level(2.6, 0.3, 0.8, 0.8, 2.0, 0.55, 0.1);
    p.levels[2].start = 0.15;
    p.levels[2].end = 0.95;
    p.levels[3] = level(1.0, 0.2, 0.75, 0.75, 3.5, 0.55, 0.15);
    p.levels[3].start = 0.1;
    p.levels[3].end = 0.95;
    p.levels[4] = level(0.35, 0.12, 0.7, 0.7, 3.5, 0.6, 0.2);
    p.levels[4].start = 0.1;
    p.levels[4].end = 0.95;
    p.leaf = LeafStyle{0.07, 0.11, 0.12, 0.02, 0.9};
    return p;
}

/// paper-2: a forked broadleaf: short bole splitting into two leaders.
constexpr PresetSpec paper2() {
    PresetSpec p;
    p.name = "paper-2";
    p.seed = 0x9a9e1002;
    p.target_vertices = 24902;
    p.height = 13.0;
    p.base_radius = 0.23;
    p.top_radius = 0.02;
    p.leaders = 2;
    p.fork_height = 0.3;
    p.fork_angle = 0.22;
    p.leader_angle = 0.6;
    p.bole_density = 0.3;
    p.shape = CrownShape::ellipsoid;
    p.levels[0] = level(0, 0.45, 0, 0, 0, 0, 0.05);
    p.levels[0].wobble = 0.03;
    p.levels[1] = level(4.6, 0.35, 1.0, 0.65, 1.0, 0.5, 0.07);
    p.levels[1].start = 0.15;
    p.levels[1].end = 0.95;
    p.levels[1].tip_ratio = 0.15;
    p.levels[2] = level(1.8, 0.25, 0.8, 0.8, 2.6, 0.55, 0.12);
    p.levels[3] = level(0.8, 0.18, 0.75, 0.75, 5.0, 0.55, 0.15);
    p.levels[4] = level(0.3, 0.12, 0.7, 0.7, 7.0, 0.6, 0.2);
    p.leaf = LeafStyle{0.08, 0.12, 0.12, 0.02, 0.9};
    return p;
}

/// paper-3: an excurrent conifer (spruce-like): straight leader, whorled near-horizontal limbs,
/// flat sprays, conical crown.
constexpr PresetSpec paper3() {
    PresetSpec p;
    p.name = "paper-3";
    p.seed = 0x9a9e1003;
    p.target_vertices = 37823;
    p.height = 16.0;
    p.base_radius = 0.3;
    p.top_radius = 0.015;
    p.lean = 0.01;
    p.shape = CrownShape::conical;
    p.levels[0] = level(0, 0.5, 0, 0, 0, 0, 0.0);
    p.levels[0].wobble = 0.01;
    p.levels[1] = level(4.5, 0.35, 1.45, 1.0, 1.4, 0.5, -0.02);
    p.levels[1].whorl = 3;
    p.levels[1].start = 0.12;
    p.levels[1].end = 0.97;
    p.levels[1].length_var = 0.1;
    p.levels[1].tip_ratio = 0.15;
    p.levels[2] = level(1.4, 0.25, 0.9, 0.9, 2.5, 0.5, 0.02);
    p.levels[2].planar = true;
    p.levels[3] = level(0.6, 0.15, 0.8, 0.8, 4.0, 0.55, 0.02);
    p.levels[3].planar = true;
    p.levels[4] = level(0.25, 0.1, 0.7, 0.7, 4.5, 0.6, 0.05);
    p.levels[4].planar = true;
    p.leaf = LeafStyle{0.04, 0.09, 0.1, 0.01, 0.6};
    return p;
}

/// paper-4: a forked crown with three leaders (vase-shaped, elm-like).
constexpr PresetSpec paper4() {
    PresetSpec p;
    p.name = "paper-4";
    p.seed = 0x9a9e1004;
    p.target_vertices = 26792;
    p.height = 14.0;
    p.base_radius = 0.28;
    p.top_radius = 0.02;
    p.leaders = 3;
    p.fork_height = 0.35;
    p.fork_angle = 0.24;
    p.leader_angle = 0.62;
    p.leader_radius = 0.66;
    p.bole_density = 0.2;
    p.shape = CrownShape::spreading;
    p.levels[0] = level(0, 0.45, 0, 0, 0, 0, 0.06);
    p.levels[0].wobble = 0.03;
    p.levels[1] = level(3.5, 0.35, 0.9, 0.6, 0.9, 0.5, 0.1);
    p.levels[1].start = 0.2;
    p.levels[1].end = 0.95;
    p.levels[1].tip_ratio = 0.15;
    p.levels[2] = level(1.6, 0.25, 0.8, 0.8, 2.8, 0.55, 0.12);
    p.levels[3] = level(0.7, 0.18, 0.75, 0.75, 5.0, 0.55, 0.15);
    p.levels[4] = level(0.3, 0.12, 0.7, 0.7, 7.0, 0.6, 0.2);
    p.leaf = LeafStyle{0.07, 0.11, 0.12, 0.02, 0.9};
    return p;
}

/// paper-5: a young broadleaf (maple-like), multi-branch crown on a central leader.
constexpr PresetSpec paper5() {
    PresetSpec p;
    p.name = "paper-5";
    p.seed = 0x9a9e1005;
    p.target_vertices = 15731;
    p.height = 11.0;
    p.base_radius = 0.16;
    p.top_radius = 0.015;
    p.shape = CrownShape::ellipsoid;
    p.levels[0] = level(0, 0.45, 0, 0, 0, 0, 0.0);
    p.levels[0].wobble = 0.04;
    p.levels[1] = level(4.3, 0.35, 1.0, 0.6, 1.7, 0.5, 0.08);
    p.levels[1].start = 0.3;
    p.levels[1].end = 0.95;
    p.levels[1].tip_ratio = 0.15;
    p.levels[2] = level(1.6, 0.25, 0.8, 0.8, 2.2, 0.55, 0.12);
    p.levels[3] = level(0.8, 0.15, 0.75, 0.75, 3.0, 0.55, 0.15);
    p.levels[4] = level(0.3, 0.12, 0.7, 0.7, 7.0, 0.6, 0.2);
    p.leaf = LeafStyle{0.09, 0.13, 0.12, 0.02, 0.9};
    return p;
}

}  // namespace preset_detail

inline const std::array<PresetSpec, 5>& presets() {
    static const std::array<PresetSpec, 5> table = {preset_detail::paper1(), preset_detail::paper2(),
                                                    preset_detail::paper3(), preset_detail::paper4(),
                                                    preset_detail::paper5()};
    return table;
}

}  // namespace hmsm::detail::gen
