// The pass sequence, written once: every backend runs the same program of dispatches built here.
#include "step_program.h"

#include "pass_table.h"

#include <algorithm>
#include <cstdlib>

namespace hmsm::detail {

namespace {
/// Models of more than this many chains (16 per thread of the largest workgroup) always take
/// one dispatch per round.
constexpr uint32_t kMaxChainsForRoundsInDispatch = 16 * HMSM_MAX_ROUNDS_WORKGROUP_SIZE;

/// Path walk: steps whose groups cover at most this many instances read the walk records whole (one
/// round of loads, HMSM_DISPATCH_POSE_WALK_FROM_RECORDS); larger ones follow chain_parent up: the records help
/// one tree, and in forests their 128 distinct bytes per thread cost more L2 sectors than the
/// parent links siblings share (measured: docs/benchmarks/history/2026-11-26-nvidia-h100-4967ccd.md,
/// analysis, change 3).
constexpr uint32_t kWalkRecordsMaxInstances = 1;

/// A dispatch of `per_instance` threads for each instance of group g (a listed group's threads
/// per instance in listed_threads: gpu_layout.h PassConstants.instance_list).
void size_for(gpu::PassConstants& pc, const InstanceGroup& g, uint32_t per_instance) {
    pc.element_count = g.instance_count * per_instance;
    pc.listed_threads = g.listed ? per_instance : 0u;
}

}  // namespace

uint32_t walk_top_depth(std::span<const uint32_t> level_begin) {
    if (level_begin.size() < 3) return 0;  // the trunk alone
    const uint32_t max_depth = uint32_t(level_begin.size()) - 2, chains = level_begin.back();
    auto level_size = [&](uint32_t depth) { return level_begin[depth + 1] - level_begin[depth]; };
    uint32_t top = 1;
    while (top + 1 < max_depth && uint64_t(chains - level_begin[top + 2]) > 2ull * top * level_size(top + 1)) ++top;
    return top;
}

/// Whether Composition::pointer_jumping runs a group's rounds in one dispatch (one workgroup per
/// instance, round after round) rather than one dispatch per round over every chain. The rounds
/// in one dispatch win for forests (64+ instances) and for single trees whose chains one workgroup
/// covers in one go (paper-5, 393 chains); they lose where a few workgroups each loop over many
/// chains while the GPU idles (one paper-1 tree, 2,345 chains). Between 512 and 1,024 chains they
/// pay only where dispatches are expensive (Vulkan). Measured: docs/benchmarks/history/
/// 2026-11-22-nvidia-h100-e7f0bd9.md, analysis, item 3 (the "PJ/1" columns).
bool rounds_in_dispatch_pay(uint32_t instances, uint32_t chains, bool dispatches_are_expensive) {
    return instances >= 64 || chains <= 512 || (dispatches_are_expensive && chains <= 1024);
}

/// Appends the dispatches of `pass` for every group. Passes 3 and 5 accumulate down the
/// hierarchy: in pointer jumping, round r reads half (r-1)&1 and writes half r&1 (round 0
/// starts from T, resp. u), so the last round leaves the pose in final_half; level by level
/// writes final_half in place, one depth per dispatch.
void append_pass(std::vector<Dispatch>& program, const SceneData& d,
                 const std::vector<InstanceGroup>& groups, Pass pass,
                 Composition composition, bool dispatches_are_expensive, JumpingForm jumping_form) {
    const uint32_t final_half = HMSM_FINAL_HALF(d.jump_rounds);
    if (!is_hierarchical(pass)) {
        for (const auto& g : groups) {
            Dispatch dispatch{pass, group_constants(d, g, final_half)};
            const auto& m = d.models[g.model];
            const uint32_t per_domain[] = {m.chain_count, m.node_count, m.vertex_count};
            const uint32_t per_instance = per_domain[uint32_t(pass_domain(pass))];
            size_for(dispatch.constants, g, per_instance);
            if (pass_domain(pass) == PassDomain::vertex)
                dispatch.constants.kind = d.packed_vertices() ? HMSM_DISPATCH_CONTOUR_PACKED
                                                              : HMSM_DISPATCH_CONTOUR_SEPARATE;
            if (pass == Pass::integrate && d.articulated()) dispatch.constants.kind = HMSM_DISPATCH_INSTANCE_SWEEP;
            if (dispatch.constants.element_count > 0) program.push_back(dispatch);
        }
        return;
    }
    if (composition != Composition::level_by_level) {
        // Groups whose rounds run in one dispatch per pass come first; the others take one
        // dispatch per round.
        auto in_dispatch = [&](const InstanceGroup& g) {
            const uint32_t chains = d.models[g.model].chain_count;
            if (chains > kMaxChainsForRoundsInDispatch) return false;
            switch (jumping_form) {
            case JumpingForm::per_round: return false;
            case JumpingForm::in_dispatch: return true;
            case JumpingForm::by_size: break;
            }
            return rounds_in_dispatch_pay(g.instance_count, chains, dispatches_are_expensive);
        };
        for (const auto& g : groups) {
            if (!in_dispatch(g)) continue;
            Dispatch dispatch{pass, group_constants(d, g, final_half)};
            size_for(dispatch.constants, g, d.models[g.model].chain_count);
            dispatch.constants.kind = HMSM_DISPATCH_JUMP_ROUNDS_IN_DISPATCH;
            dispatch.constants.round = d.jump_rounds;
            if (dispatch.constants.element_count > 0) program.push_back(dispatch);
        }
        for (uint32_t r = 0; r < d.jump_rounds; ++r) {
            for (const auto& g : groups) {
                if (in_dispatch(g)) continue;
                Dispatch dispatch{pass, group_constants(d, g, final_half)};
                size_for(dispatch.constants, g, d.models[g.model].chain_count);
                dispatch.constants.kind = HMSM_DISPATCH_JUMP_ROUND;
                dispatch.constants.round = r;
                dispatch.constants.src_half = HMSM_HALF_READ(r);  // unused in round 0
                dispatch.constants.dst_half = HMSM_HALF_WRITTEN(r);
                program.push_back(dispatch);
            }
        }
        return;
    }
    size_t levels = 0;
    for (const auto& m : d.models) levels = std::max(levels, m.level_begin.size() - 1);
    for (size_t level = 0; level < levels; ++level) {
        for (const auto& g : groups) {
            const auto& m = d.models[g.model];
            if (level + 1 >= m.level_begin.size()) continue;
            uint32_t count = m.level_begin[level + 1] - m.level_begin[level];
            if (count == 0) continue;
            Dispatch dispatch{pass, group_constants(d, g, final_half)};
            dispatch.constants.kind = HMSM_DISPATCH_LEVEL;
            dispatch.constants.level_begin = m.level_begin[level];
            dispatch.constants.level_count = count;
            size_for(dispatch.constants, g, count);
            program.push_back(dispatch);
        }
    }
}

namespace {

/// The depth of model m's top poses: walk_top_depth, or HMSM_CUDA_WALK_TOP_DEPTH=N (N >= 1) from
/// the environment, at most the model's deepest level, for measurements; read once.
uint32_t top_depth_of(const ModelRange& m) {
    static const uint32_t fixed = [] {
        const char* value = std::getenv("HMSM_CUDA_WALK_TOP_DEPTH");
        const unsigned long parsed = value ? std::strtoul(value, nullptr, 10) : 0;
        return parsed >= 1 && parsed <= HMSM_WALK_PATH_CAPACITY ? uint32_t(parsed) : 0u;
    }();
    const uint32_t max_depth = uint32_t(m.level_begin.size()) - 2;
    return fixed != 0 ? std::min(fixed, max_depth) : walk_top_depth(m.level_begin);
}

/// The walk that integrates ahead (gpu_layout.h): the top poses of every group (one thread per
/// chain of depth 0 .. walk_top_depth: the first level_count model chains, chains being stored
/// by depth), then the walk ahead of every group.
void append_walk_ahead(std::vector<Dispatch>& program, const SceneData& d, const std::vector<InstanceGroup>& groups) {
    for (uint32_t kind : {HMSM_DISPATCH_WALK_TOP_POSES, HMSM_DISPATCH_WALK_AHEAD}) {
        for (const auto& g : groups) {
            const auto& m = d.models[g.model];
            Dispatch dispatch{Pass::compose, group_constants(d, g, HMSM_FINAL_HALF(d.jump_rounds))};
            dispatch.constants.kind = kind;
            dispatch.constants.level_count = m.level_begin[top_depth_of(m) + 1];
            const uint32_t per_instance = kind == HMSM_DISPATCH_WALK_AHEAD ? m.chain_count : dispatch.constants.level_count;
            size_for(dispatch.constants, g, per_instance);
            if (dispatch.constants.element_count > 0) program.push_back(dispatch);
        }
    }
}

/// Composition::path_walk: the passes from `first` on whose bit is set in `wanted` (those the
/// outputs need), each walk pair (the pass table's `walk` column) in one dispatch of its leader
/// where both run: the wind pair only before the walk, the node pair where no level-by-level
/// root_positions needs its u. compose and root_positions apart (a program of only one of
/// them) run level by level, whose poses the walk reproduces bit for bit; node_relative, which
/// the walk does not read, runs only for node_world, with it after the walk.
std::vector<Dispatch> build_path_walk_program(const SceneData& d, const std::vector<InstanceGroup>& groups,
                                              bool dispatches_are_expensive, uint32_t wanted, bool walk_ahead) {
    auto bit = [](Pass pass) { return 1u << uint32_t(pass); };
    const bool walk_poses = (wanted & walk_passes(Pass::compose)) == walk_passes(Pass::compose);
    if (walk_poses && !(wanted & bit(Pass::node_world))) wanted &= ~bit(Pass::node_relative);
    // The records only for groups covering one instance (an active one: a group starts and ends
    // at active instances): the same rule for every group, so that scenes of the same instances
    // grouped differently (reshaped in place, uploaded anew) run the same kernels, bit for bit.
    uint64_t instances = 0;
    for (const auto& g : groups) instances += g.instance_count;
    const bool from_records = instances <= kWalkRecordsMaxInstances;
    // The wind pair only before a walk: it stores no T, which level by level would read. The
    // node pair wherever no level-by-level root_positions reads its u (after a walk, or without
    // pass 5: the outputs recomputed for moved instances read the pose from the joint matrices).
    const bool node_pair_runs = walk_poses || !(wanted & bit(Pass::root_positions));
    // The walk integrates ahead in a step (the wind pair runs before it) of a forest whose every
    // instance is active: the next step's angles are written for every chain, so that the step
    // after may take them whole (a paused instance's would be left behind).
    const bool wind_pair_runs = (wanted & walk_passes(Pass::wind_force)) == walk_passes(Pass::wind_force);
    bool all_active = instances == d.instance_count();
    for (const auto& g : groups) all_active = all_active && !g.covers_paused;
    const bool ahead = walk_ahead && walk_poses && wind_pair_runs && !from_records && all_active && !d.articulated();
    std::vector<Dispatch> program;
    program.reserve(4 * groups.size());  // a dispatch per group and pass pair (and top poses)
    uint32_t done = 0;
    for (Pass pass : kAllPasses) {
        if (!(wanted & bit(pass)) || (done & bit(pass))) continue;
        const uint32_t pair = walk_passes(pass);
        const bool pair_runs = pair != 0 && (wanted & pair) == pair &&
                               (pass == Pass::compose || (pass == Pass::wind_force ? walk_poses : node_pair_runs));
        if (!pair_runs) {
            append_pass(program, d, groups, pass, Composition::level_by_level, dispatches_are_expensive);
            done |= bit(pass);
            continue;
        }
        auto per_domain = [&](const InstanceGroup& g) {
            const auto& m = d.models[g.model];
            return pass_domain(pass) == PassDomain::node ? m.node_count : m.chain_count;
        };
        if (pass == Pass::compose && ahead) {
            append_walk_ahead(program, d, groups);
            done |= pair;
            continue;
        }
        const uint32_t kind = pass == Pass::wind_force ? HMSM_DISPATCH_WIND_PAIR
                              : pass == Pass::node_relative ? HMSM_DISPATCH_NODE_PAIR
                              : from_records                ? HMSM_DISPATCH_POSE_WALK_FROM_RECORDS
                                                            : HMSM_DISPATCH_POSE_WALK;
        for (const auto& g : groups) {
            Dispatch dispatch{pass, group_constants(d, g, HMSM_FINAL_HALF(d.jump_rounds))};
            size_for(dispatch.constants, g, per_domain(g));
            dispatch.constants.kind = kind;
            if (dispatch.constants.element_count > 0) program.push_back(dispatch);
        }
        // The articulated exchange's wind pair runs pass 1 only: integrate, which sweeps whole
        // instances, follows as a dispatch of its own.
        done |= pass == Pass::wind_force && d.articulated() ? bit(pass) : pair;
    }
    return program;
}

}  // namespace

std::vector<Dispatch> build_program(const SceneData& d, const std::vector<InstanceGroup>& groups,
                                    Composition composition, bool dispatches_are_expensive, Pass first,
                                    uint32_t passes, bool walk_ahead, JumpingForm jumping_form) {
    if (composition == Composition::path_walk) {
        uint32_t wanted = 0;
        for (Pass pass : kAllPasses)
            if (uint32_t(pass) >= uint32_t(first) && (passes >> uint32_t(pass) & 1u) && pass_runs_for(pass, d.outputs))
                wanted |= 1u << uint32_t(pass);
        return build_path_walk_program(d, groups, dispatches_are_expensive, wanted, walk_ahead);
    }
    std::vector<Dispatch> program;
    for (Pass pass : kAllPasses) {
        if (uint32_t(pass) < uint32_t(first) || !(passes >> uint32_t(pass) & 1u)) continue;
        // Outputs on demand: passes whose outputs the step does not produce are not dispatched.
        if (!pass_runs_for(pass, d.outputs)) continue;
        append_pass(program, d, groups, pass, composition, dispatches_are_expensive, jumping_form);
    }
    return program;
}

std::vector<std::span<const Dispatch>> dispatch_batches(std::span<const Dispatch> program) {
    auto joins = [](const Dispatch& run_last, const Dispatch& next) {
        const gpu::PassConstants &a = run_last.constants, &b = next.constants;
        return next.pass == run_last.pass && b.kind == a.kind && b.round == a.round &&
               b.src_half == a.src_half && b.dst_half == a.dst_half && b.instance_begin > a.instance_begin &&
               a.instance_list == 0 && b.instance_list == 0;  // a listed dispatch launches alone
    };
    std::vector<std::span<const Dispatch>> runs;
    size_t begin = 0;
    for (size_t i = 1; i <= program.size(); ++i) {
        if (i < program.size() && joins(program[i - 1], program[i])) continue;
        runs.push_back(program.subspan(begin, i - begin));
        begin = i;
    }
    return runs;
}

Composition automatic_composition(bool backend_prefers_path_walk, int32_t deepest_chain_depth) {
    return backend_prefers_path_walk && deepest_chain_depth <= kPathWalkMaxDepth ? Composition::path_walk
                                                                                 : Composition::pointer_jumping;
}

AheadVariants ahead_variants(std::span<const Dispatch> program) {
    AheadVariants v;
    ahead_variants(program, v);
    return v;
}

void ahead_variants(std::span<const Dispatch> program, AheadVariants& v) {
    v.whole.assign(program.begin(), program.end());
    v.without_wind.clear();
    v.plain.clear();
    v.without_wind.reserve(program.size());
    v.plain.reserve(program.size());
    for (Dispatch d : program) {
        if (d.pass != Pass::wind_force) v.without_wind.push_back(d);
        if (is_top_poses_walk(d)) continue;
        if (is_walk_ahead(d)) {  // as build_path_walk_program builds the plain walk of a forest
            d.constants.kind = HMSM_DISPATCH_POSE_WALK;
            d.constants.level_count = 0;
        }
        v.plain.push_back(d);
    }
}

void AheadSchedule::plan(std::span<RunStep> steps) {
    const bool take = ready_;
    changed_runs_ = changed_ ? changed_runs_ + 1 : 0;
    const bool plain = !take && changed_runs_ >= kChangedRunsBeforePlain && changed_runs_ % kRetryWalkAhead != 0;
    for (RunStep& step : steps) step.ahead = AheadStep::take;
    steps[0].ahead = take ? AheadStep::take : plain ? AheadStep::plain : AheadStep::whole;
    if (plain && steps.size() > 1) steps[1].ahead = AheadStep::whole;  // nothing was integrated ahead for it
    changed_ = false;
    ready_ = steps.size() > 1 || !plain;
}

}  // namespace hmsm::detail
