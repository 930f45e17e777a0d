// CUDA interop for engines that keep hmsm's outputs on the GPU: the device pointers of the
// outputs of a Simulation running on the CUDA backend, and running its steps on the engine's
// own stream. Needs no CUDA header: a stream is passed as its handle type, CUstream_st*
// (which is what cudaStream_t and CUstream are).
#pragma once

#include <hmsm/export.h>

#include <hmsm/simulation.h>
#include <hmsm/status.h>

#include <cstdint>

struct CUstream_st;

namespace hmsm::cuda {

/// Device pointers of a simulation's outputs, valid until the Simulation is destroyed or its
/// instances are added or removed (which moves state and may reallocate), and current after each step()
/// returns (after enqueue_steps: in stream order); nullptr (count 0) for outputs the simulation does not produce
/// (SimulationConfig::outputs). Every element is 4 floats (a CUDA float4, 16-byte
/// aligned), instance-major, in the order of Simulation::read in the packed layout
/// (SimulationConfig::instance_layout); in the placed layout each instance's elements begin at
/// Simulation::instance_placement and the counts cover every slot held (free ones too), so
/// skin an instance from its placement's first_chain.
struct DeviceOutputs {
    int device = 0;                           ///< CUDA device ordinal that holds the buffers
    const float* node_positions = nullptr;    ///< node_count x (x, y, z, 1), nodes in input order
    const float* vertex_positions = nullptr;  ///< vertex_count x (x, y, z, 1)
    /// vertex_count x (x, y, z, 0), unit length; nullptr in VertexLayout::packed, where each
    /// vertex_positions w holds the normal word instead (docs/cuda.md: decode with
    /// oct_decode(unpack_snorm2x16(__float_as_uint(w)))).
    const float* vertex_normals = nullptr;
    uint64_t node_count = 0;
    uint64_t vertex_count = 0;
    VertexLayout vertex_layout = VertexLayout::separate;  ///< the simulation's config().vertex_layout
    /// chain_count x 12 floats: the joint matrix M_c = [R_c | O_c] as three float4 rows
    /// (R row i, O_i), 48 bytes per chain (docs/cuda.md); always produced.
    const float* joint_matrices = nullptr;
    uint64_t chain_count = 0;
};

#ifdef HMSM_HAVE_CUDA

/// The outputs on the device; invalid_argument when `simulation` does not run on CUDA.
HMSM_API Result<DeviceOutputs> device_outputs(const Simulation& simulation);

/// Runs later work of `simulation` (steps, uploads of live changes, readbacks) on `stream`
/// (nullptr: hmsm's own stream), after waiting for what ran on the previous one if it differs.
/// step() still returns when the step is complete, so the outputs are ready for work enqueued
/// after it. `stream` must stay valid while the simulation uses it.
HMSM_API Status set_stream(Simulation& simulation, CUstream_st* stream);

/// A frame's step without waiting for the GPU: makes `stream` the simulation's stream (as
/// set_stream), enqueues `count` steps on it and returns once they are enqueued. The outputs
/// (device_outputs) are then ready for work the engine enqueues on `stream` after this call;
/// work on another stream must wait for an event recorded on `stream` after it. Live changes
/// made before the call (set_wind, set_force_fields, instance settings) are copied from pinned
/// host memory in stream order, so the host may change them again at once (docs/cuda.md).
/// Simulation::step(), read() and take_read() wait for everything enqueued before them;
/// request_read() is enqueued behind the steps. Blocks like step() when profile_passes is on.
/// Same threading as Simulation::step().
HMSM_API Status enqueue_steps(Simulation& simulation, CUstream_st* stream, uint32_t count = 1);

#else

inline Result<DeviceOutputs> device_outputs(const Simulation&) {
    return Status{ErrorCode::no_device, "cuda: this build of hmsm has no CUDA backend"};
}
inline Status set_stream(Simulation&, CUstream_st*) {
    return {ErrorCode::no_device, "cuda: this build of hmsm has no CUDA backend"};
}
inline Status enqueue_steps(Simulation&, CUstream_st*, uint32_t = 1) {
    return {ErrorCode::no_device, "cuda: this build of hmsm has no CUDA backend"};
}

#endif

}  // namespace hmsm::cuda
