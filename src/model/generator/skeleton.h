// Growth of the branch skeleton: each branch is a polyline grown segment by segment (tropism
// plus a small random turn) whose interior nodes carry lateral branches of the next order.
//
// The generator knows the chain structure it produces (docs/model.md 3.2, direction grouping): a
// lateral leaves its parent at >= kMinLateralAngle while the parent itself turns by at most
// kMaxTurn per segment, so the continuation child is always the parent's own next node; a
// fork's continuing leader bends by less than the other leaders. Hence every branch is one
// chain and its depth is known while growing, which caps the hierarchy at kTwigDepth.
#pragma once

#include "params.h"
#include "../random.h"

#include <hmsm/tree.h>

#include <glm/geometric.hpp>

#include <algorithm>
#include <cmath>
#include <numbers>
#include <vector>

namespace hmsm::detail::gen {

inline constexpr double kMinLateralAngle = 0.45;  ///< rad; > kMaxTurn + the fork bend
inline constexpr double kMaxTurn = 0.2;           ///< rad per segment, tropism plus wobble
inline constexpr double kMinSegment = 0.1;        ///< m
inline constexpr double kMaxSegment = 1.0;        ///< m
/// Thinnest radius of a branch at each chain depth (m): twigs of a few millimetres, and each
/// floor well below 0.85 of the one above, so a child always starts thinner than its parent.
inline constexpr double kMinRadius[kTwigDepth + 1] = {0.015, 0.011, 0.0075, 0.005, 0.0035};
inline constexpr double kGoldenAngle = 2.399963229728653;  ///< pi (3 - sqrt 5)

/// A standard normal clamped to +-limit, so no parameter ever runs away.
inline double clamped_normal(Random& rng, double limit = 2.5) {
    return std::clamp(rng.normal(), -limit, limit);
}

/// A unit vector perpendicular to unit `d`, as close to `hint` as possible.
inline glm::dvec3 perpendicular(const glm::dvec3& d, const glm::dvec3& hint) {
    glm::dvec3 p = hint - glm::dot(hint, d) * d;
    if (glm::length(p) < 1e-6) {
        glm::dvec3 other = std::abs(d.x) < 0.9 ? glm::dvec3(1, 0, 0) : glm::dvec3(0, 0, 1);
        p = other - glm::dot(other, d) * d;
    }
    return glm::normalize(p);
}

/// The result of growing: the skeleton, the leaf-bearing nodes (with the direction of the
/// segment that ends there) and the chain structure the generator built.
struct Skeleton {
    TreeModel tree;
    std::vector<int32_t> leaf_nodes;
    std::vector<glm::dvec3> leaf_dirs;
    int32_t chains = 0;
    int32_t max_depth = 0;
};

/// Seed of the k-th branch spawned by a branch with seed `seed`: every branch draws from its own
/// stream, so changing how many twigs grow elsewhere never moves the limbs.
inline uint64_t child_seed(uint64_t seed, uint64_t k) {
    uint64_t z = seed + (k + 1) * 0x9e3779b97f4a7c15ull;
    z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ull;
    z = (z ^ (z >> 27)) * 0x94d049bb133111ebull;
    return z ^ (z >> 31);
}

/// One branch waiting to be grown.
struct BranchSpec {
    uint64_t seed = 0;      ///< its own random stream
    int32_t attach = 0;     ///< node it starts from (owned by the parent branch)
    glm::dvec3 dir{0, 1, 0};   ///< direction of its first segment (unit)
    glm::dvec3 side{1, 0, 0};  ///< azimuth reference, perpendicular to dir (unit)
    double length = 1.0;
    double base_radius = 0.1;
    double tip_radius = 0.01;
    int kind = 0;           ///< parameter order (leaders are order 0 at depth 1)
    int depth = 0;          ///< chain depth: continuations keep their parent's
    int laterals = 1;       ///< 0: no laterals; 1: order kind+1 laterals; 2: bole of a fork
};

class SkeletonGrower {
public:
    /// `fine_density` scales the branching density of the two finest orders (levels 3 and 4):
    /// the knob the generator turns to size the skeleton without changing the limbs.
    SkeletonGrower(const PresetSpec& spec, uint64_t seed, double fine_density)
        : spec_(spec), seed_(seed), fine_density_(fine_density) {}

    Skeleton grow() {
        Skeleton out;
        out_ = &out;
        Random rng(child_seed(seed_, 0));
        const double lean_azimuth = rng.uniform(0.0, 2.0 * std::numbers::pi);
        const glm::dvec3 trunk_dir = glm::normalize(glm::dvec3(
            std::sin(spec_.lean) * std::cos(lean_azimuth), std::cos(spec_.lean),
            std::sin(spec_.lean) * std::sin(lean_azimuth)));
        out.tree.nodes.push_back(TreeNode{-1, glm::dvec3(0.0), spec_.base_radius});
        out.chains = 1;

        BranchSpec trunk;
        trunk.seed = child_seed(seed_, 1);
        trunk.attach = 0;
        trunk.dir = trunk_dir;
        trunk.side = perpendicular(trunk_dir, glm::dvec3(1, 0, 0));
        trunk.base_radius = spec_.base_radius;
        if (spec_.leaders <= 1) {
            trunk.length = spec_.height;
            trunk.tip_radius = spec_.top_radius;
        } else {
            // Bole up to the fork; its tip radius is where the leaders start.
            trunk.length = spec_.height * spec_.fork_height;
            trunk.tip_radius = spec_.base_radius +
                               (spec_.top_radius - spec_.base_radius) * spec_.fork_height;
            trunk.laterals = 2;
        }
        pending_.push_back(trunk);
        while (!pending_.empty()) {
            BranchSpec branch = pending_.back();
            pending_.pop_back();
            grow_branch(branch);
        }
        return out;
    }

private:
    struct Member {
        int32_t node;
        glm::dvec3 dir;   // incoming segment direction
        glm::dvec3 side;  // rotation-minimizing azimuth reference
        double s;         // arc length from the attach node
    };

    void grow_branch(const BranchSpec& b) {
        Random rng(b.seed);
        uint64_t spawned_seeds = 0;
        const Level& level = spec_.levels[b.kind];
        auto& nodes = out_->tree.nodes;
        out_->max_depth = std::max(out_->max_depth, b.depth);

        int n = std::max(1, int(std::lround(b.length / level.segment)));
        n = std::max(n, int(std::ceil(b.length / kMaxSegment - 1e-9)));
        n = std::min(n, std::max(1, int(std::floor(b.length / kMinSegment + 1e-9))));
        const double seg = b.length / double(n);

        std::vector<Member> members;
        members.reserve(size_t(n));
        glm::dvec3 d = b.dir, side = b.side, pos = nodes[size_t(b.attach)].position;
        int32_t parent = b.attach;
        for (int j = 1; j <= n; ++j) {
            if (j > 1) {
                glm::dvec3 up = glm::dvec3(0, 1, 0) - d.y * d;  // towards +y, perpendicular to d
                glm::dvec3 binormal = glm::cross(d, side);
                glm::dvec3 turn = level.tropism * seg * up +
                                  level.wobble * (clamped_normal(rng) * side +
                                                  clamped_normal(rng) * binormal);
                double magnitude = glm::length(turn);
                if (magnitude > std::tan(kMaxTurn)) turn *= std::tan(kMaxTurn) / magnitude;
                d = glm::normalize(d + turn);
                side = perpendicular(d, side);
            }
            pos += seg * d;
            const double s = seg * double(j);
            const double radius = std::max(
                kMinRadius[b.depth], b.base_radius + (b.tip_radius - b.base_radius) * s / b.length);
            nodes.push_back(TreeNode{parent, pos, radius});
            parent = int32_t(nodes.size() - 1);
            members.push_back(Member{parent, d, side, s});
        }

        int spawned = 0;
        if (b.laterals == 2) spawned += spawn_fork(b, members, rng, spawned_seeds);
        if (b.laterals > 0 && b.depth < kTwigDepth)
            spawned += spawn_laterals(b, members, rng, spawned_seeds);
        if (b.kind == kTwigDepth || (spawned == 0 && b.kind >= 3)) {
            for (const Member& m : members) {
                out_->leaf_nodes.push_back(m.node);
                out_->leaf_dirs.push_back(m.dir);
            }
        }
    }

    /// The leaders at the top of a forked bole: one continues the trunk's chain (smallest bend),
    /// the others start chains of depth 1 and carry the same order-1 laterals.
    int spawn_fork(const BranchSpec& bole, const std::vector<Member>& members, Random& rng,
                   uint64_t& seeds) {
        const Member& top = members.back();
        const double remaining = spec_.height - bole.length;
        const double leader_radius = out_->tree.nodes[size_t(top.node)].radius * spec_.leader_radius;
        const double phase = rng.uniform(0.0, 2.0 * std::numbers::pi);
        const int count = spec_.leaders;
        // Push the continuing leader last so it grows first; order does not change the chains.
        for (int k = count - 1; k >= 0; --k) {
            const bool continuing = k == 0;
            const double azimuth = phase + 2.0 * std::numbers::pi * double(k) / double(count) +
                                   0.25 * clamped_normal(rng);
            double angle = continuing ? spec_.fork_angle
                                      : std::max(kMinLateralAngle,
                                                 spec_.leader_angle + 0.08 * clamped_normal(rng));
            BranchSpec leader;
            leader.seed = child_seed(bole.seed, seeds++);
            leader.attach = top.node;
            leader.dir = lateral_direction(top, azimuth, angle);
            leader.side = perpendicular(leader.dir, top.dir);
            leader.length = remaining * (continuing ? 1.0 : spec_.leader_length *
                                                                (1.0 + 0.06 * clamped_normal(rng)));
            leader.base_radius = leader_radius * (continuing ? 1.0 : 0.92);
            leader.tip_radius = spec_.top_radius;
            leader.kind = 0;
            leader.depth = continuing ? bole.depth : bole.depth + 1;
            if (!continuing) ++out_->chains;
            pending_.push_back(leader);
        }
        return count;
    }

    /// Lateral branches of the next order on the interior nodes of a branch.
    int spawn_laterals(const BranchSpec& b, const std::vector<Member>& members, Random& rng,
                       uint64_t& seeds) {
        const int n = int(members.size());
        if (n < 2) return 0;
        const int child_depth = b.depth + 1;
        const int child_kind = child_depth >= kTwigDepth ? kTwigDepth : b.kind + 1;
        const Level& child = spec_.levels[child_kind];
        const Level& own = spec_.levels[b.kind];
        const bool bole = b.laterals == 2;
        const double density = bole ? spec_.bole_density
                                    : child.density * (child_kind >= 3 ? fine_density_ : 1.0);
        const double start = bole ? 0.25 : child.start, end = bole ? 0.9 : child.end;
        const double zone = (end - start) * b.length;
        const int sites = int(std::floor(density * zone + rng.uniform()));
        if (sites <= 0) return 0;
        // Shorter parents carry proportionally shorter children (order 1 follows the crown).
        const double parent_scale = b.kind == 0 ? 1.0 : std::min(1.0, b.length / own.length);
        double azimuth = rng.uniform(0.0, 2.0 * std::numbers::pi);
        int spawned = 0;
        for (int i = 0; i < sites; ++i) {
            const double u = (double(i) + 0.5 + 0.35 * clamped_normal(rng, 1.4)) / double(sites);
            const double s = start * b.length + std::clamp(u, 0.0, 1.0) * zone;
            const int j = std::clamp(int(std::lround(s / (b.length / n))), 1, n - 1);
            const Member& at = members[size_t(j - 1)];
            const double t = std::clamp((at.s / b.length - start) / std::max(end - start, 1e-9), 0.0, 1.0);
            double length_factor = child_kind == 1 ? crown_factor(t) : 1.0 - child.taper * at.s / b.length;
            azimuth += kGoldenAngle;
            for (int w = 0; w < child.whorl; ++w) {
                double length = child.length * length_factor * parent_scale *
                                (1.0 + child.length_var * clamped_normal(rng, 2.0));
                length = std::max(length, 1.5 * kMinSegment);
                double angle = child.angle + (child.angle_top - child.angle) * t +
                               child.angle_var * clamped_normal(rng, 2.0);
                angle = std::clamp(angle, kMinLateralAngle, 2.0);
                double phi = azimuth + 2.0 * std::numbers::pi * double(w) / double(child.whorl) +
                             0.15 * clamped_normal(rng);
                glm::dvec3 dir = child.planar ? planar_direction(at, i + w, angle, rng)
                                              : lateral_direction(at, phi, angle);
                const double parent_radius = out_->tree.nodes[size_t(at.node)].radius;
                double base = parent_radius * child.radius_ratio *
                              (0.55 + 0.45 * std::min(1.0, length / child.length));
                base = std::clamp(base, kMinRadius[child_depth], 0.85 * parent_radius);
                BranchSpec spec;
                spec.seed = child_seed(b.seed, seeds++);
                spec.attach = at.node;
                spec.dir = dir;
                spec.side = perpendicular(dir, at.dir);
                spec.length = length;
                spec.base_radius = base;
                spec.tip_radius = std::max(kMinRadius[child_depth], base * child.tip_ratio);
                spec.kind = child_kind;
                spec.depth = child_depth;
                pending_.push_back(spec);
                ++out_->chains;
                ++spawned;
            }
        }
        return spawned;
    }

    /// Direction at `angle` from the member's direction, at azimuth `phi` around it.
    static glm::dvec3 lateral_direction(const Member& at, double phi, double angle) {
        glm::dvec3 binormal = glm::cross(at.dir, at.side);
        glm::dvec3 radial = std::cos(phi) * at.side + std::sin(phi) * binormal;
        return glm::normalize(std::cos(angle) * at.dir + std::sin(angle) * radial);
    }

    /// Flat sprays: alternate left and right of the parent, tilted a little up or down.
    static glm::dvec3 planar_direction(const Member& at, int index, double angle, Random& rng) {
        glm::dvec3 up = perpendicular(at.dir, glm::dvec3(0, 1, 0));
        glm::dvec3 left = glm::cross(at.dir, up);
        const double sign = (index % 2 == 0) ? 1.0 : -1.0;
        const double lift = 0.25 + 0.2 * clamped_normal(rng, 2.0);
        glm::dvec3 radial = glm::normalize(sign * left + lift * up);
        return glm::normalize(std::cos(angle) * at.dir + std::sin(angle) * radial);
    }

    double crown_factor(double t) const {
        constexpr double pi = std::numbers::pi;
        switch (spec_.shape) {
            case CrownShape::conical: return 0.12 + 0.88 * (1.0 - t);
            case CrownShape::ellipsoid: return 0.3 + 0.7 * std::sin(pi * (0.15 + 0.85 * t));
            case CrownShape::spreading: return 0.5 + 0.5 * std::sin(pi * (0.25 + 0.7 * t));
        }
        return 1.0;
    }

    const PresetSpec& spec_;
    uint64_t seed_;
    double fine_density_;
    Skeleton* out_ = nullptr;
    std::vector<BranchSpec> pending_;
};

}  // namespace hmsm::detail::gen
