#include "test_compositions.h"

#include "simulation_access.h"

#include <gtest/gtest.h>

namespace hmsm::test {

std::string name_of(TestComposition composition) {
    std::string name = to_string(composition.composition);
    if (composition.composition != Composition::pointer_jumping) return name;
    switch (composition.jumping_form) {
    case detail::JumpingForm::per_round: return name + "_per_round";
    case detail::JumpingForm::in_dispatch: return name + "_in_dispatch";
    case detail::JumpingForm::by_size: break;
    }
    return name;
}

Result<std::unique_ptr<Simulation>> create_simulation(const Scene& scene, SimulationConfig config,
                                                      TestComposition composition) {
    config.composition = composition.composition;
    return detail::SimulationAccess::create(scene, config, composition.jumping_form);
}

std::unique_ptr<Simulation> create_simulation_or_skip(const Scene& scene, SimulationConfig config,
                                                      BackendKind kind, std::string& skip,
                                                      detail::JumpingForm jumping_form) {
    config.backend = kind;
    auto sim = detail::SimulationAccess::create(scene, config, jumping_form);
    if (!sim.ok()) {
        if (sim.status().code() == ErrorCode::no_device) skip = sim.status().message();
        else ADD_FAILURE() << to_string(kind) << ": " << sim.status().message();
        return nullptr;
    }
    return std::move(sim).value();
}

}  // namespace hmsm::test
