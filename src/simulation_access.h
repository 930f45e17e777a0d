// Internal access to a Simulation's backend, step program, flattened scene and pointer jumping's
// dispatch form, for hmsm's own interop code, tools and tests (an attorney: the public header
// declares Simulation::Access, a nested type and so a friend, and only this header defines it).
#pragma once

#include "simulation_impl.h"

struct __attribute__((visibility("hidden"))) hmsm::Simulation::Access {
    static detail::Backend& backend(const Simulation& sim) { return *sim.impl_->backend_; }
    static const std::vector<detail::Dispatch>& step_program(const Simulation& sim) {
        return sim.impl_->current_program();
    }
    static const detail::SceneData& scene_data(const Simulation& sim) { return *sim.impl_->data_; }
    static Simulation::Impl& impl(Simulation& sim) { return *sim.impl_; }
    /// Simulation::create on a backend the caller made (e.g. on an engine's Vulkan device);
    /// config.backend is ignored.
    static Result<std::unique_ptr<Simulation>> create(const Scene& scene,
                                                      const SimulationConfig& config,
                                                      std::unique_ptr<detail::Backend> backend,
                                                      detail::JumpingForm jumping_form = detail::JumpingForm::by_size) {
        return Simulation::Impl::create(scene, config, std::move(backend), jumping_form);
    }
    /// Simulation::create with pointer jumping's dispatch form forced (tests of both kernels,
    /// the bench's comparison of them); on a composition other than pointer jumping the form
    /// has no effect.
    static Result<std::unique_ptr<Simulation>> create(const Scene& scene, const SimulationConfig& config,
                                                      detail::JumpingForm jumping_form) {
        return Simulation::Impl::create(scene, config, nullptr, jumping_form);
    }
};

namespace hmsm::detail {

using SimulationAccess = Simulation::Access;

inline Backend& backend_of(const Simulation& sim) { return SimulationAccess::backend(sim); }
inline const std::vector<Dispatch>& step_program_of(const Simulation& sim) {
    return SimulationAccess::step_program(sim);
}
inline const SceneData& scene_data_of(const Simulation& sim) { return SimulationAccess::scene_data(sim); }
/// How often adding or removing instances re-uploaded the whole scene (live_control.cpp).
inline uint64_t full_uploads_of(Simulation& sim) { return SimulationAccess::impl(sim).full_uploads_; }
/// How often growth past the capacity reallocated the buffers on the device instead
/// (capacity_growth.cpp).
inline uint64_t device_growths_of(Simulation& sim) { return SimulationAccess::impl(sim).device_growths_; }

}  // namespace hmsm::detail
