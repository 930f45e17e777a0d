// Parameters of the procedural tree generator: one set per branching order plus the trunk,
// fork and leaf settings of a preset (docs/model.md 6). Plain data; the presets live in presets.h.
#pragma once

#include <cstdint>
#include <string_view>

namespace hmsm::detail::gen {

/// Maximum chain depth of every preset: five branching orders, trunk = 0 ... twigs = 4.
inline constexpr int kTwigDepth = 4;

/// How the length of the trunk's (or a leader's) lateral branches varies with their height in
/// the crown, t in [0, 1] from the lowest to the highest branch.
enum class CrownShape {
    conical,    ///< longest at the bottom (excurrent conifers)
    ellipsoid,  ///< longest a little below the middle (decurrent broadleaves)
    spreading,  ///< long low and middle limbs, still wide near the top (open-grown, vase)
};

/// How one branching order is attached to its parent and how it grows. Angles in radians,
/// lengths in metres. Order 0 uses only the growth fields (segment, tropism, wobble).
struct Level {
    double length = 1.0;        ///< nominal length of a branch of this order
    double length_var = 0.15;   ///< relative standard deviation of that length
    double taper = 0.5;         ///< child length shrinks by this fraction from parent base to tip
    double segment = 0.3;       ///< target segment length (actual: length / round(length / this))
    double angle = 0.8;         ///< angle to the parent's direction at the lowest site
    double angle_top = 0.8;     ///< ... and at the highest site (linear in between)
    double angle_var = 0.12;    ///< standard deviation of the angle
    double density = 2.0;       ///< branching sites per metre of the parent's branching zone
    int whorl = 1;              ///< branches per site (evenly spread azimuths)
    double start = 0.2;         ///< branching zone on the parent, fraction of its length
    double end = 0.9;
    double radius_ratio = 0.55; ///< base radius / parent's radius at the site (full length)
    double tip_ratio = 0.25;    ///< tip radius / base radius
    double tropism = 0.1;       ///< turn towards +y (negative: droop) per metre, as a vector gain
    double wobble = 0.05;       ///< random turn per segment (standard deviation, rad)
    bool planar = false;        ///< spread left/right of the parent (flat sprays) instead of spiral
};

/// Leaf cards: size (width x height, m), how far from the twig axis they stand, angle to it.
struct LeafStyle {
    double width = 0.07;
    double height = 0.11;
    double size_var = 0.12;     ///< relative standard deviation of both dimensions
    double petiole = 0.02;      ///< gap between the node and the card's near edge
    double angle = 0.9;         ///< angle between the twig direction and the card's up axis
};

/// Everything that defines one preset. Orders: levels[1] are the trunk's (or the leaders')
/// laterals, levels[2], levels[3] the next ones, levels[4] the leaf-bearing twigs.
struct PresetSpec {
    std::string_view name;
    uint64_t seed = 1;
    uint64_t target_vertices = 0;  ///< the paper's Table 1 mesh vertex count

    double height = 15.0;          ///< trunk length (m) to the top of the main leader
    double base_radius = 0.3;      ///< trunk radius at the ground (m)
    double top_radius = 0.02;      ///< trunk radius at its tip
    double lean = 0.03;            ///< trunk lean from vertical (rad)

    // Forked crown: the trunk splits at fork_height into `leaders` stems (1 = no fork).
    int leaders = 1;
    double fork_height = 0.0;      ///< fraction of `height`
    double fork_angle = 0.18;      ///< the continuing leader's bend at the fork (rad)
    double leader_angle = 0.55;    ///< the other leaders' angle to the bole (rad)
    double leader_length = 0.9;    ///< other leaders' length relative to the continuing one
    double leader_radius = 0.72;   ///< leader base radius / bole radius at the fork
    double bole_density = 0.0;     ///< order-1 sites per metre on the bole below a fork

    /// Share of the vertex budget spent on branches; leaf cards take the rest. The generator
    /// scales the density of the finest orders until the skeleton is close to this share.
    double branch_share = 0.7;

    CrownShape shape = CrownShape::ellipsoid;
    Level levels[5];
    LeafStyle leaf;
};

}  // namespace hmsm::detail::gen
