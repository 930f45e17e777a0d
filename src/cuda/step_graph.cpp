#include "step_graph.h"

#include "cuda_error.h"
#include "launch_dispatch.h"
#include "launch_plan.h"

#include <algorithm>
#include <cstring>

namespace hmsm::detail::cuda {
namespace {

/// The node that the last operation captured on `stream` added (the stream's only dependency).
cudaError_t last_captured_node(cudaStream_t stream, cudaGraphNode_t* node) {
    cudaStreamCaptureStatus status;
    const cudaGraphNode_t* dependencies = nullptr;
    size_t count = 0;
#if CUDART_VERSION >= 13000
    cudaError_t error = cudaStreamGetCaptureInfo(stream, &status, nullptr, nullptr, &dependencies,
                                                 nullptr, &count);
#else
    cudaError_t error =
        cudaStreamGetCaptureInfo(stream, &status, nullptr, nullptr, &dependencies, &count);
#endif
    if (error != cudaSuccess) return error;
    if (status != cudaStreamCaptureStatusActive || count != 1) return cudaErrorStreamCaptureInvalidated;
    *node = dependencies[0];
    return cudaSuccess;
}

bool same_bytes(const void* a, const void* b, size_t n) { return std::memcmp(a, b, n) == 0; }

/// Whether launch y must wait for launch x: one writes a buffer the other reads or writes.
bool depends(const PlannedLaunch& x, const PlannedLaunch& y) {
    return ((x.writes & (y.reads | y.writes)) | (x.reads & y.writes)) != 0;
}

/// Events and the side stream of one capture, released on every path.
struct ForkResources {
    cudaStream_t side = nullptr;
    cudaEvent_t before = nullptr, after = nullptr;
    ~ForkResources() {
        if (side) (void)cudaStreamDestroy(side);
        if (before) (void)cudaEventDestroy(before);
        if (after) (void)cudaEventDestroy(after);
    }
    cudaError_t create() {
        cudaError_t e = cudaStreamCreateWithFlags(&side, cudaStreamNonBlocking);
        if (e == cudaSuccess) e = cudaEventCreateWithFlags(&before, cudaEventDisableTiming);
        if (e == cudaSuccess) e = cudaEventCreateWithFlags(&after, cudaEventDisableTiming);
        return e;
    }
};

}  // namespace

/// Field by field: Dispatch has padding between pass and constants, PassConstants has none.
bool same_dispatch(const Dispatch& a, const Dispatch& b) {
    static_assert(sizeof(gpu::PassConstants) == 20 * 4 + 2 * 16, "PassConstants must be unpadded");
    return a.pass == b.pass && same_bytes(&a.constants, &b.constants, sizeof a.constants);
}

bool same_dispatches(std::span<const Dispatch> a, std::span<const Dispatch> b) {
    return std::equal(a.begin(), a.end(), b.begin(), b.end(), same_dispatch);
}

bool same_program(std::span<const Dispatch> a, uint64_t a_id, std::span<const Dispatch> b, uint64_t b_id) {
    if (a_id != 0 && b_id != 0) return a_id == b_id;
    return same_dispatches(a, b);
}

StepGraph::~StepGraph() { release(); }

void StepGraph::release() {
    if (exec_) (void)cudaGraphExecDestroy(exec_);
    if (graph_) (void)cudaGraphDestroy(graph_);
    exec_ = nullptr;
    graph_ = nullptr;
    wind_nodes_.clear();
    program_.clear();
    program_id_ = 0;
    plan_.launches.clear();  // the vectors keep their memory for the next capture
    plan_.constants.clear();
    plan_.block_begin.clear();
}

bool StepGraph::matches(std::span<const Dispatch> program, const BufferPointers& buffers, uint64_t program_id) const {
    if (!exec_ || !same_bytes(&buffers, &buffers_, sizeof buffers)) return false;
    return same_program(program, program_id, program_, program_id_);
}

Status StepGraph::capture(std::span<const Dispatch> program, const BufferPointers& buffers, bool batch_runs,
                          cudaStream_t stream, uint64_t program_id) {
    release();
    program_.assign(program.begin(), program.end());
    program_id_ = program_id;
    plan_launches(program_, batch_runs, max_launch_blocks(), plan_);
    HMSM_TRY(table_.upload(plan_, stream));  // before the capture: the graph's launches read it
    const std::vector<PlannedLaunch>& launches = plan_.launches;
    // A launch that does not depend on the one before it (the path walk's node pair and contour,
    // both reading only the joint matrices) runs beside it: the graph forks after the launch
    // both follow and joins before the next, so a step waits for one of the two launches, not
    // both in turn. Every other edge stays in program order.
    ForkResources fork;
    CUDA_TRY(fork.create());
    std::vector<bool> beside(launches.size(), false);  // launch i runs beside launch i - 1
    for (size_t i = 1; i < launches.size(); ++i) beside[i] = !beside[i - 1] && !depends(launches[i - 1], launches[i]);
    CUDA_TRY(cudaStreamBeginCapture(stream, cudaStreamCaptureModeThreadLocal));
    cudaError_t error = cudaSuccess;
    std::vector<WindNode> wind_nodes;
    for (size_t i = 0; i < launches.size() && error == cudaSuccess; ++i) {
        const PlannedLaunch& launch = launches[i];
        if (i + 1 < launches.size() && beside[i + 1]) error = cudaEventRecord(fork.before, stream);
        cudaStream_t on = stream;
        if (error == cudaSuccess && beside[i]) {
            on = fork.side;
            error = cudaStreamWaitEvent(fork.side, fork.before, 0);
        }
        if (error == cudaSuccess) error = enqueue_launch(plan_, launch, program_, table_, buffers, 0, on);
        const bool launched = launch.entries > 0 ? launch.shape.blocks > 0
                                                 : program_[launch.dispatch].constants.element_count > 0;
        if (error == cudaSuccess && launch.reads_wind_slot && launched) {
            WindNode wind{};
            if (launch.entries > 0) wind.batch = plan_.batch(launch, table_.constants(), table_.block_begin(), 0);
            else wind.constants = program_[launch.dispatch].constants;
            wind.batched = launch.entries > 0;
            error = last_captured_node(on, &wind.node);
            if (error == cudaSuccess) error = cudaGraphKernelNodeGetParams(wind.node, &wind.launch);
            wind_nodes.push_back(wind);
        }
        if (error == cudaSuccess && beside[i]) {
            error = cudaEventRecord(fork.after, fork.side);
            if (error == cudaSuccess) error = cudaStreamWaitEvent(stream, fork.after, 0);
        }
    }
    cudaGraph_t graph = nullptr;
    const cudaError_t end_error = cudaStreamEndCapture(stream, &graph);
    if (error == cudaSuccess) error = end_error;
    if (error != cudaSuccess) {
        if (graph) (void)cudaGraphDestroy(graph);
        return cuda_status(error, "capturing the step program", __FILE__, __LINE__);
    }
    graph_ = graph;
    CUDA_TRY(cudaGraphInstantiate(&exec_, graph_, 0));
    buffers_ = buffers;
    wind_nodes_ = std::move(wind_nodes);
    return {};
}

Status StepGraph::replay(uint32_t wind_slot, cudaStream_t stream) {
    for (WindNode& wind : wind_nodes_) {
        wind.constants.wind_slot = wind_slot;
        wind.batch.wind_slot = wind_slot;
        void* arguments[] = {&buffers_, wind.batched ? static_cast<void*>(&wind.batch) : &wind.constants};
        cudaKernelNodeParams params = wind.launch;
        params.kernelParams = arguments;
        params.extra = nullptr;
        CUDA_TRY(cudaGraphExecKernelNodeSetParams(exec_, wind.node, &params));
    }
    CUDA_TRY(cudaGraphLaunch(exec_, stream));
    return {};
}

}  // namespace hmsm::detail::cuda
