// The compositions as the tests run them: the public ones and pointer jumping in each of its
// internal dispatch forms (detail::JumpingForm), so that both pointer-jumping kernels stay
// covered although pointer jumping chooses its form by size.
#pragma once

#include <hmsm/hmsm.h>

#include "step_program.h"

#include <memory>
#include <ostream>
#include <string>

namespace hmsm::test {

/// A composition as the tests run it: a public one and, for pointer jumping, its dispatch form
/// (by size, or forced so that both pointer-jumping kernels stay covered).
struct TestComposition {
    constexpr TestComposition(Composition composition,  // NOLINT: implicit, a plain composition is one
                              detail::JumpingForm jumping_form = detail::JumpingForm::by_size)
        : composition(composition), jumping_form(jumping_form) {}
    Composition composition;
    detail::JumpingForm jumping_form;
};
inline constexpr TestComposition kJumpingPerRound{Composition::pointer_jumping, detail::JumpingForm::per_round};
inline constexpr TestComposition kJumpingInDispatch{Composition::pointer_jumping, detail::JumpingForm::in_dispatch};
/// Pointer jumping by size, per round and in one dispatch, level by level, path walk.
inline constexpr TestComposition kEveryComposition[] = {
    Composition::pointer_jumping, kJumpingPerRound, kJumpingInDispatch, Composition::level_by_level,
    Composition::path_walk};
/// "pointer_jumping", "pointer_jumping_per_round", "pointer_jumping_in_dispatch", "level_by_level", ...
std::string name_of(TestComposition composition);

/// Simulation::create() with `composition` (config.composition and pointer jumping's form).
Result<std::unique_ptr<Simulation>> create_simulation(const Scene& scene, SimulationConfig config,
                                                      TestComposition composition);

/// create_simulation_or_skip (test_trees.h) with pointer jumping's dispatch form forced.
std::unique_ptr<Simulation> create_simulation_or_skip(const Scene& scene, SimulationConfig config,
                                                      BackendKind kind, std::string& skip,
                                                      detail::JumpingForm jumping_form);

/// Test names and failure messages show a composition by name_of().
inline void PrintTo(TestComposition composition, std::ostream* os) { *os << name_of(composition); }

}  // namespace hmsm::test
