// The state behind hmsm::Simulation (pimpl): everything a step needs, kept out of the public
// header so that adding a member changes no installed layout.
#pragma once

#include <hmsm/simulation.h>

#include "backend.h"
#include "scene_data.h"

#include <memory>
#include <mutex>
#include <vector>

namespace hmsm {

// Hidden: a nested class of the exported Simulation would otherwise be exported from libhmsm.so.
struct __attribute__((visibility("hidden"))) Simulation::Impl {
    static Result<std::unique_ptr<Simulation>> create(const Scene& scene,
                                                      const SimulationConfig& config,
                                                      std::unique_ptr<detail::Backend> backend);

    Status step(uint32_t count);
    Status read_elements(Output output, std::vector<double>* as_double,
                         std::vector<float>* as_float) const;
    Status read_packed_normals(std::vector<double>* as_double, std::vector<float>* as_float) const;

    SimulationConfig config_;
    Scene scene_;
    std::vector<Hierarchy> hierarchies_;
    std::vector<MeshTemplate> meshes_;
    std::unique_ptr<detail::SceneData> data_;
    std::unique_ptr<detail::Backend> backend_;
    std::vector<detail::Dispatch> step_program_;
    std::vector<ForceField> force_fields_;
    std::vector<double> wind_phases_;  // scratch: one entry per step of a step() call
    // Scratch for read(): elements as the backend stores them, kept between calls so a
    // per-frame readback neither allocates nor zero-fills.
    mutable std::vector<float> stored_f32_;
    mutable std::vector<double> stored_f64_;
    // Serializes read(): the scratch above and the backends' readback paths (a staging buffer
    // and a queue submission on Vulkan, pinned memory on CUDA) are shared, and const calls may
    // run concurrently (the threading contract in include/hmsm/simulation.h).
    mutable std::mutex read_mutex_;
    uint64_t steps_done_ = 0;
};

}  // namespace hmsm
