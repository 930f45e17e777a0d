// The step program: the dispatches of the seven passes over every instance group, in the
// order of the pass table (pass_table.h), for one composition (docs/model.md 3.7).
#pragma once

#include "backend.h"
#include "scene_data.h"

#include <hmsm/pass.h>
#include <hmsm/config.h>

#include <cstdint>
#include <span>
#include <vector>

namespace hmsm::detail {

/// Whether Composition::pointer_jumping runs a group's rounds in one dispatch (step_program.cpp
/// gives the measurements behind the rule).
bool rounds_in_dispatch_pay(uint32_t instances, uint32_t chains, bool dispatches_are_expensive);

/// The dispatch form of Composition::pointer_jumping: chosen per group by size
/// (rounds_in_dispatch_pay), or forced, for tests that cover both kernels and for the bench that
/// compares them. Models of more than 16,384 chains take one dispatch per round in every form.
enum class JumpingForm {
    by_size,
    per_round,    // one dispatch per round over every chain of every instance
    in_dispatch,  // every round in one dispatch per pass: one workgroup per instance
};

/// Appends the dispatches of `pass` for every group.
void append_pass(std::vector<Dispatch>& program, const SceneData& d,
                 const std::vector<InstanceGroup>& groups, Pass pass, Composition composition,
                 bool dispatches_are_expensive, JumpingForm jumping_form = JumpingForm::by_size);

/// The program of the passes from `first` on whose bit is set in `passes`, less the passes
/// whose outputs the scene does not produce (outputs on demand). `walk_ahead`
/// (BackendCapabilities::walks_ahead): a path-walk step of a forest whose every instance is active
/// composes by the walk that integrates ahead (gpu_layout.h HMSM_DISPATCH_WALK_AHEAD).
std::vector<Dispatch> build_program(const SceneData& d, const std::vector<InstanceGroup>& groups,
                                    Composition composition, bool dispatches_are_expensive,
                                    Pass first, uint32_t passes, bool walk_ahead = false,
                                    JumpingForm jumping_form = JumpingForm::by_size);

/// The runs of consecutive dispatches of `program` that one launch may run together: the same
/// pass, kind, round and halves over different groups (ascending instance_begin), none listed
/// (a listed dispatch, already one per model, is a run of its own). Groups share
/// no state, so no dispatch of a run reads what another writes, and a backend may run a run as
/// one launch whose workgroups each find their dispatch's constants. The runs cover `program`
/// in order; build_program orders a pass's dispatches round by round (level by level) over all
/// groups, so a forest of many groups takes as many runs as a scene of one.
std::vector<std::span<const Dispatch>> dispatch_batches(std::span<const Dispatch> program);

/// Deepest chain depth (levels below the trunk) for which Composition::automatic keeps the path
/// walk on a backend that prefers it: the walk costs depth-many dependent products per chain, the
/// rounds of pointer jumping log2 of the depth, so past a break-even depth the rounds win. On the
/// H100 the walk is even with the rounds at depth 15 and twice as slow at 31 on CUDA (`hmsm bench
/// --composition-depths`: docs/benchmarks/nvidia-h100.md); 15 is also the deepest path a walk
/// record holds (HMSM_WALK_PATH_CAPACITY).
inline constexpr int32_t kPathWalkMaxDepth = HMSM_WALK_PATH_CAPACITY;

/// What Composition::automatic resolves to: the path walk where the backend prefers it and no
/// model is deeper than kPathWalkMaxDepth, else pointer jumping.
Composition automatic_composition(bool backend_prefers_path_walk, int32_t deepest_chain_depth);

/// The deepest level whose chains the walk ahead's top poses cover (gpu_layout.h
/// HMSM_DISPATCH_WALK_TOP_POSES) for a model of levels `level_begin` (ModelRange::level_begin:
/// max depth + 2 entries): at least 1 (0 for a lone trunk). Every deeper chain walks only the
/// levels below it, a chain of depth d then d - top levels, one of the top d levels from the
/// trunk. Raising top from t to t + 1 saves one level of every chain deeper than t + 1 and costs
/// each chain of depth t + 1 t more (its walk from the trunk instead of one level); the top
/// poses are a dispatch of their own that the walk ahead waits for, so their levels count
/// twice: top rises while the deeper chains outnumber 2 t times the chains of depth t + 1. Deep
/// models gain most: the coupled dynamics splits chains into links (paper-1: depth 4 becomes
/// 10; top 4, where the walk ahead walks 2.8 levels per chain rather than 5.8).
uint32_t walk_top_depth(std::span<const uint32_t> level_begin);

/// What a backend runs for each AheadStep of a program with the walk ahead: `whole` the program,
/// `without_wind` the program less its wind_force dispatches (AheadStep::take), `plain` the
/// plain walk (no top poses, the walk ahead a plain pose walk: the dispatches build_program
/// gives without walk_ahead).
struct AheadVariants {
    std::vector<Dispatch> whole, without_wind, plain;
};
AheadVariants ahead_variants(std::span<const Dispatch> program);
/// The same into `into`, reusing its vectors' memory (a forest's program changes every frame
/// while trees stream and switch levels, and has tens of thousands of dispatches).
void ahead_variants(std::span<const Dispatch> program, AheadVariants& into);

/// The step layer's side of the walk that integrates ahead: from the simulation's change flags
/// it decides how each step of a run of a walk-ahead program runs (AheadStep). The angles a run's
/// last step integrated ahead are the next run's first step's where nothing changed in between
/// (live_change() was not called): the wind table's step slots continue the clock, so the slot
/// the walk ahead read is the one that step reads. Within a run, a step takes what the step
/// before integrated ahead. A whole step costs a little more than the plain walk (the top poses,
/// the next angles written), so after kChangedRunsBeforePlain runs in a row each preceded by a
/// live change (a force field that follows a character), a run's first step walks plain, but
/// every kRetryWalkAhead-th such run, which tries the walk ahead again; a run without a change
/// before it ends the streak.
class AheadSchedule {
public:
    static constexpr uint32_t kChangedRunsBeforePlain = 2;
    static constexpr uint32_t kRetryWalkAhead = 8;

    /// Anything a step reads changed (but the wind table's step slots), or the program did: the
    /// angles integrated ahead are stale.
    void live_change() {
        ready_ = false;
        changed_ = true;
    }
    /// Sets how each step of the next run of a walk-ahead program runs (RunStep::ahead; at
    /// least one step).
    void plan(std::span<RunStep> steps);
    /// A run that failed, or that ran a program without the walk ahead: nothing is integrated
    /// ahead.
    void forget() { ready_ = false; }

private:
    bool ready_ = false;    // the last run's last step integrated ahead, nothing changed since
    bool changed_ = true;   // a live change since the last run
    uint32_t changed_runs_ = 0;  // runs in a row with a live change before them
};

}  // namespace hmsm::detail
