// include/hmsm/cuda.h: the CUDA backend behind a Simulation, for engines.
#include <hmsm/cuda.h>

#include "cuda_backend.h"
#include "../simulation_access.h"

namespace hmsm::cuda {
namespace {

Result<detail::cuda::CudaBackend*> cuda_backend_of(const Simulation& simulation) {
    auto* backend = dynamic_cast<detail::cuda::CudaBackend*>(&detail::SimulationAccess::backend(simulation));
    if (!backend)
        return Status{ErrorCode::invalid_argument,
                      std::string("cuda: the simulation runs on the ") +
                          to_string(simulation.backend_kind()) + " backend, not on cuda"};
    return backend;
}

}  // namespace

Result<DeviceOutputs> device_outputs(const Simulation& simulation) {
    auto backend = cuda_backend_of(simulation);
    if (!backend) return backend.status();
    const detail::cuda::BufferPointers& p = (*backend)->device_pointers();
    DeviceOutputs outputs;
    outputs.device = (*backend)->device();
    outputs.node_positions = reinterpret_cast<const float*>(p.node_world);
    outputs.vertex_positions = reinterpret_cast<const float*>(p.vertex_position);
    outputs.vertex_normals = reinterpret_cast<const float*>(p.vertex_normal);
    // Every element held: in the placed layout the slots, free ones included.
    const detail::SceneData& held = detail::scene_data_of(simulation);
    outputs.node_count = held.nodes_held();
    outputs.vertex_count = held.vertices_held();
    outputs.vertex_layout = simulation.config().vertex_layout;
    if (outputs.vertex_layout == VertexLayout::packed) outputs.vertex_normals = nullptr;
    outputs.joint_matrices = reinterpret_cast<const float*>(p.joint_matrix);
    outputs.chain_count = held.chains_held();
    if (simulation.config().outputs != Outputs::all) {
        outputs.vertex_positions = outputs.vertex_normals = nullptr;
        outputs.vertex_count = 0;
    }
    if (simulation.config().outputs == Outputs::joints) {
        outputs.node_positions = nullptr;
        outputs.node_count = 0;
    }
    return outputs;
}

Status set_stream(Simulation& simulation, CUstream_st* stream) {
    auto backend = cuda_backend_of(simulation);
    if (!backend) return backend.status();
    return (*backend)->set_stream(stream);
}

Status enqueue_steps(Simulation& simulation, CUstream_st* stream, uint32_t count) {
    auto backend = cuda_backend_of(simulation);
    if (!backend) return backend.status();
    // Fades run inside the enqueued steps (pass 2); the fades that are over switch here, before
    // the steps, as a switch made between frames (docs/driving.md).
    HMSM_TRY(detail::SimulationAccess::impl(simulation).fold_ready_fades());
    HMSM_TRY((*backend)->set_stream(stream));
    (*backend)->set_waits_for_steps(false);
    const Status stepped = simulation.step(count);
    (*backend)->set_waits_for_steps(true);
    return stepped;
}

}  // namespace hmsm::cuda
