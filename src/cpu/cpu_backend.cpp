// The CPU backend: plain serial loops over host vectors, float (`cpu`, the paper's baseline) or
// double (`cpu64`, the oracle of every conformance test); and `cpu-parallel`, the same float
// pass functions with each dispatch's work items split into chunks that the threads of a pool
// run as a step plan says (src/cpu/step_plan.h; bitwise the results of `cpu`). Per-pass times
// are host wall clock.
#include "cpu_state.h"
#include "step_plan.h"
#include "../capacity_growth.h"
#include "thread_pool.h"

#include <algorithm>
#include <charconv>
#include <chrono>
#include <cstdlib>
#include <cstring>
#include <new>
#include <type_traits>

namespace hmsm::detail {
namespace cpu {
namespace {

template <class T, class V>
std::vector<V> convert_vec4(const std::vector<glm::dvec4>& src) {
    std::vector<V> out(src.size());
    for (size_t i = 0; i < src.size(); ++i) out[i] = V(src[i]);
    return out;
}

/// Copies between a typed host buffer and scalars laid out as gpu_layout.h stores them.
template <class T>
struct ScalarView {
    // Scalars per stored element, and the element -> scalar mapping.
    static void get(const std::vector<int32_t>& b, uint64_t i, double* out) { out[0] = b[i]; }
    static void get(const std::vector<glm::ivec2>& b, uint64_t i, double* out) {
        out[0] = b[i].x; out[1] = b[i].y;
    }
    static void get(const std::vector<glm::ivec4>& b, uint64_t i, double* out) {
        for (int k = 0; k < 4; ++k) out[k] = b[i][k];
    }
    static void get(const std::vector<glm::vec<2, T>>& b, uint64_t i, double* out) {
        out[0] = double(b[i].x); out[1] = double(b[i].y);
    }
    static void get(const std::vector<glm::vec<4, T>>& b, uint64_t i, double* out) {
        for (int k = 0; k < 4; ++k) out[k] = double(b[i][k]);
    }
    static void get(const std::vector<glm::mat<3, 3, T>>& b, uint64_t i, double* out) {
        for (int c = 0; c < 3; ++c) {
            for (int r = 0; r < 3; ++r) out[c * 4 + r] = double(b[i][c][r]);
            out[c * 4 + 3] = 0.0;
        }
    }
    static void get(const std::vector<glm::mat<3, 4, T>>& b, uint64_t i, double* out) {
        for (int r = 0; r < 3; ++r)
            for (int k = 0; k < 4; ++k) out[r * 4 + k] = double(b[i][r][k]);
    }
    static void set(std::vector<glm::mat<3, 4, T>>& b, uint64_t i, const double* in) {
        for (int r = 0; r < 3; ++r)
            for (int k = 0; k < 4; ++k) b[i][r][k] = T(in[r * 4 + k]);
    }
    template <size_t N>
    static void get(const std::vector<std::array<T, N>>& b, uint64_t i, double* out) {
        for (size_t k = 0; k < N; ++k) out[k] = double(b[i][k]);
    }
    template <size_t N>
    static void set(std::vector<std::array<T, N>>& b, uint64_t i, const double* in) {
        for (size_t k = 0; k < N; ++k) b[i][k] = T(in[k]);
    }
    static void set(std::vector<int32_t>& b, uint64_t i, const double* in) { b[i] = int32_t(in[0]); }
    static void set(std::vector<glm::ivec2>& b, uint64_t i, const double* in) {
        b[i] = glm::ivec2(int32_t(in[0]), int32_t(in[1]));
    }
    static void set(std::vector<glm::ivec4>& b, uint64_t i, const double* in) {
        for (int k = 0; k < 4; ++k) b[i][k] = int32_t(in[k]);
    }
    static void set(std::vector<glm::vec<2, T>>& b, uint64_t i, const double* in) {
        b[i] = glm::vec<2, T>(T(in[0]), T(in[1]));
    }
    static void set(std::vector<glm::vec<4, T>>& b, uint64_t i, const double* in) {
        for (int k = 0; k < 4; ++k) b[i][k] = T(in[k]);
    }
    static void set(std::vector<glm::mat<3, 3, T>>& b, uint64_t i, const double* in) {
        for (int c = 0; c < 3; ++c)
            for (int r = 0; r < 3; ++r) b[i][c][r] = T(in[c * 4 + r]);
    }
};

template <class T>
class CpuBackend final : public Backend {
public:
    CpuBackend() = default;
    /// The parallel variant: `threads` >= 1 threads (the caller's included); a dispatch is
    /// split only into chunks of at least `min_chunk_elements` cost units (step_plan.h).
    CpuBackend(uint32_t threads, uint32_t min_chunk_elements)
        : pool_(std::make_unique<ThreadPool>(threads)), min_chunk_elements_(min_chunk_elements) {}

    BackendCapabilities capabilities() const override {
        BackendCapabilities can;
        can.grows_on_device = true;
        return can;
    }

    BackendKind kind() const override {
        if (pool_) return BackendKind::cpu_parallel;
        return sizeof(T) == 8 ? BackendKind::cpu64 : BackendKind::cpu;
    }
    std::string device_name() const override {
        if (pool_) return "host CPU (" + std::to_string(pool_->threads()) + " threads, float)";
        return sizeof(T) == 8 ? "host CPU (serial, double)" : "host CPU (serial, float)";
    }

    Status upload(const SceneData& scene) override {
        try {
            upload_unchecked(scene);
        } catch (const std::bad_alloc&) {
            return {ErrorCode::out_of_memory, "cpu: not enough host memory for the scene"};
        }
        return {};
    }

    /// Each capacity-sized vector is built anew at its new size and takes its live elements;
    /// the vectors are swapped in only once all are built (bad_alloc leaves every one as it was).
    Status grow(const SceneData& scene) override {
        State<T> next;
        std::array<bool, kBufferCount> grown{};
        try {
#define HMSM_CPU_GROW(name, binding, shape, scope) \
    HMSM_TRY(grown_copy(s_.name, next.name, BufferId::name, scene, grown));
            HMSM_BUFFERS(HMSM_CPU_GROW)
#undef HMSM_CPU_GROW
        } catch (const std::bad_alloc&) {
            return {ErrorCode::out_of_memory, "cpu: not enough host memory to grow the scene's buffers"};
        }
#define HMSM_CPU_TAKE(name, binding, shape, scope) \
    if (grown[binding]) s_.name.swap(next.name);
        HMSM_BUFFERS(HMSM_CPU_TAKE)
#undef HMSM_CPU_TAKE
        s_.total_chains = scene.chain_capacity;  // the stride between ping-pong halves
        return {};
    }

    Status run(std::span<const Dispatch> program, std::span<const RunStep> steps, uint64_t program_id = 0) override {
        times_ = {};
        if (pool_ && !steps.empty()) {
            try {
                const bool known = plan_ && program_id != 0 && program_id == plan_id_;
                if (!known && (!plan_ || !plan_->matches(program)))
                    plan_ = std::make_unique<StepPlan>(program, pool_->threads(), min_chunk_elements_);
                plan_id_ = program_id;
            } catch (const std::bad_alloc&) {
                return {ErrorCode::out_of_memory, "cpu-parallel: not enough host memory for the step plan"};
            }
        }
        using clock = std::chrono::steady_clock;
        if (pool_ && !profiling_) {
            plan_->run(*pool_, steps.size(), [&](uint32_t d, size_t step, Range r) {
                run_range(program[d], steps[step].wind_slot, r);
            });
            return {};
        }
        for (const RunStep& step : steps) {
            const uint32_t x = step.wind_slot;
            for (uint32_t i = 0; i < program.size(); ++i) {
                const Dispatch& d = program[i];
                auto start = profiling_ ? clock::now() : clock::time_point{};
                if (!pool_) {
                    run_range(d, x, {0, work_items(d.pass, d.constants)});
                } else {
                    // Profiled: one job per dispatch over the plan's chunks, timed here.
                    const std::span<const Range> chunks = plan_->chunks(i);
                    pool_->for_each(uint32_t(chunks.size()), [&](uint32_t k) {
                        if (chunks[k].begin < chunks[k].end) run_range(d, x, chunks[k]);
                    });
                }
                if (profiling_)
                    times_.seconds[uint32_t(d.pass)] +=
                        std::chrono::duration<double>(clock::now() - start).count();
            }
        }
        times_.steps = profiling_ ? steps.size() : 0;
        return {};
    }

    Status read(BufferId id, uint64_t first, uint64_t count, void* dst, Scalar as) const override {
        return visit(const_cast<State<T>&>(s_), id, first, count, [&](auto& buffer) {
            using Element = typename std::decay_t<decltype(buffer)>::value_type;
            if constexpr (std::is_same_v<Element, glm::vec4>) {
                // Float vec4 as float: copied bit for bit, since in the packed vertex layout a
                // position's w is a normal word (src/common/octahedral.h) that may read as a
                // signalling NaN, which a round trip through double would quiet.
                if (as == Scalar::f32) {
                    if (count > 0) std::memcpy(dst, buffer.data() + first, count * sizeof(Element));
                    return;
                }
            }
            if constexpr (std::is_same_v<Element, glm::mat<3, 4, T>> || std::is_same_v<Element, glm::vec<4, T>>) {
                // Joint matrices (rows of [R | O]) and vec4s in the backend's own precision:
                // their scalars lie in memory in the order read() returns them, so a copy
                // gives what the conversion through double would, at the copy's speed.
                static_assert(sizeof(Element) == sizeof(T) * (std::is_same_v<Element, glm::vec<4, T>> ? 4 : 12));
                if (as == (std::is_same_v<T, double> ? Scalar::f64 : Scalar::f32)) {
                    if (count > 0) std::memcpy(dst, buffer.data() + first, count * sizeof(Element));
                    return;
                }
            }
            const uint32_t n = shape_scalars(buffer_info(id).shape);
            double tmp[36];
            for (uint64_t i = 0; i < count; ++i) {
                ScalarView<T>::get(buffer, first + i, tmp);
                for (uint32_t k = 0; k < n; ++k) {
                    if (as == Scalar::f64) static_cast<double*>(dst)[i * n + k] = tmp[k];
                    else static_cast<float*>(dst)[i * n + k] = float(tmp[k]);
                }
            }
        });
    }

    Status write(BufferId id, uint64_t first, uint64_t count, const void* src, Scalar as) override {
        return visit(s_, id, first, count, [&](auto& buffer) {
            const uint32_t n = shape_scalars(buffer_info(id).shape);
            double tmp[36];
            for (uint64_t i = 0; i < count; ++i) {
                for (uint32_t k = 0; k < n; ++k)
                    tmp[k] = as == Scalar::f64 ? static_cast<const double*>(src)[i * n + k]
                                               : double(static_cast<const float*>(src)[i * n + k]);
                ScalarView<T>::set(buffer, first + i, tmp);
            }
        });
    }

    void set_profiling(bool enabled) override { profiling_ = enabled; }
    PassTimes pass_times() const override { return times_; }

private:
    void upload_unchecked(const SceneData& d) {
        using vec4 = typename State<T>::vec4;
        s_.chain_parent = d.chain_parent;
        s_.chain_jump = d.chain_jump;
        s_.chain_walk = d.chain_walk;
        s_.chain_attach = d.chain_attach;
        s_.node_owner = d.node_owner;
        s_.vertex_chain = d.vertex_chain;
        s_.chain_rest_rotation.assign(d.chain_rest_rotation.begin(), d.chain_rest_rotation.end());
        s_.chain_keep_level = d.chain_keep_level;
        s_.chain_keep_level.resize(d.chain_rest_rotation.size(), 0u);
        s_.chain_constants = convert_vec4<T, vec4>(d.chain_constants);
        s_.node_local = convert_vec4<T, vec4>(d.node_local);
        constexpr size_t record = 4 * HMSM_CHAIN_DYNAMICS_VEC4S;
        s_.chain_dynamics.assign(d.chain_dynamics.size() / record, {});
        for (size_t c = 0; c < s_.chain_dynamics.size(); ++c)
            for (size_t k = 0; k < record; ++k) s_.chain_dynamics[c][k] = T(d.chain_dynamics[record * c + k]);
        constexpr size_t articulated = 4 * HMSM_CHAIN_ARTICULATED_VEC4S;
        s_.chain_articulated.assign(d.chain_articulated.size() / articulated, {});
        for (size_t c = 0; c < s_.chain_articulated.size(); ++c)
            for (size_t k = 0; k < articulated; ++k)
                s_.chain_articulated[c][k] = T(d.chain_articulated[articulated * c + k]);
        s_.vertex_rest_position = convert_vec4<T, vec4>(d.vertex_rest_position);
        s_.vertex_rest_normal = convert_vec4<T, vec4>(d.vertex_rest_normal);
        s_.vertex_parent_position = convert_vec4<T, vec4>(d.vertex_parent_position);
        s_.vertex_parent_normal = convert_vec4<T, vec4>(d.vertex_parent_normal);
        // Instance and state buffers are allocated to the capacities (zeros past the live ones).
        s_.instance_origin = convert_vec4<T, vec4>(d.instance_origin);
        s_.instance_origin.resize(d.element_count(BufferId::instance_origin), vec4(0));
        s_.instance_yaw = convert_vec4<T, vec4>(d.instance_yaw);
        s_.instance_yaw.resize(d.element_count(BufferId::instance_yaw), vec4(0));
        s_.instance_wind.assign(d.element_count(BufferId::instance_wind), {});
        for (size_t i = 0; i < d.instance_count(); ++i)
            for (size_t k = 0; k < 36; ++k) s_.instance_wind[i][k] = T(d.instance_wind[36 * i + k]);
        s_.wind_table.assign(HMSM_WIND_TABLE_ELEMENTS, vec4(0));
        s_.instance_table.assign(d.element_count(BufferId::instance_table), glm::ivec4(0));
        s_.chain_state.assign(d.element_count(BufferId::chain_state), vec4(0));
        s_.chain_force.assign(d.element_count(BufferId::chain_force), typename State<T>::vec2(0));
        s_.chain_load.assign(d.element_count(BufferId::chain_load), typename State<T>::vec2(0));
        s_.chain_local.assign(d.element_count(BufferId::chain_local), typename State<T>::mat3(0));
        s_.chain_rotation.assign(d.element_count(BufferId::chain_rotation), typename State<T>::mat3(0));
        s_.node_relative.assign(d.element_count(BufferId::node_relative), vec4(0));
        s_.chain_origin.assign(d.element_count(BufferId::chain_origin), vec4(0));
        s_.node_world.assign(d.element_count(BufferId::node_world), vec4(0));  // 0 if not produced
        s_.vertex_position.assign(d.element_count(BufferId::vertex_position), vec4(0));
        s_.vertex_normal.assign(d.element_count(BufferId::vertex_normal), vec4(0));  // 0 if packed
        s_.joint_matrix.assign(d.element_count(BufferId::joint_matrix), typename State<T>::joint(0));
        s_.dt = T(d.dt);
        s_.max_angle = T(d.max_angle);
        s_.fix_weight = T(d.fix_weight);
        s_.total_chains = d.chain_capacity;  // the stride between ping-pong halves
    }

    /// Runs pass function `f` (src/cpu/NAME.cpp); wind_force and integrate take the step's slot.
    template <class F>
    void call_pass(F f, const Dispatch& d, uint32_t wind_slot, Range r) {
        if constexpr (std::is_invocable_v<F, State<T>&, const gpu::PassConstants&, uint32_t, Range>)
            f(s_, d.constants, wind_slot, r);
        else
            f(s_, d.constants, r);
    }

    void run_range(const Dispatch& d, uint32_t wind_slot, Range r) {
        // A walk pair runs the pass and its walk partner over the same elements (pass_table.h
        // `walk`); the other kinds run the pass's own function, which reads the kind.
        switch (dispatch_kind(d)) {
            case DispatchKind::wind_pair: return wind_force_and_integrate<T>(s_, d.constants, wind_slot, r);
            case DispatchKind::pose_walk:
            case DispatchKind::pose_walk_from_records: return path_walk<T>(s_, d.constants, r);
            case DispatchKind::node_pair: return node_relative_and_world<T>(s_, d.constants, r);
            case DispatchKind::walk_top_poses:
            case DispatchKind::walk_ahead: return;  // never asked for (capabilities: no walk ahead)
            default: break;
        }
        switch (d.pass) {
#define HMSM_CPU_PASS_CASE(name) \
    case Pass::name: return call_pass(name<T>, d, wind_slot, r);
            HMSM_PASSES(HMSM_CPU_PASS_CASE)
#undef HMSM_CPU_PASS_CASE
        }
    }

public:
    Status move_elements(BufferId id, std::span<const ElementMove> moves) override {
        for (const ElementMove& m : moves) {
            HMSM_TRY(visit(s_, id, std::max(m.src, m.dst), m.count, [&](auto& buffer) {
                const auto from = buffer.begin() + std::ptrdiff_t(m.src);
                const auto to = buffer.begin() + std::ptrdiff_t(m.dst);
                if (m.dst < m.src) std::copy(from, from + std::ptrdiff_t(m.count), to);
                else std::copy_backward(from, from + std::ptrdiff_t(m.count), to + std::ptrdiff_t(m.count));
            }));
        }
        return {};
    }

private:
    /// `out`: buffer `id` of `old` grown to its element count under `scene` (capacity_growth.h),
    /// where growth reallocates it (`grown[id]` then set).
    template <class E>
    static Status grown_copy(const std::vector<E>& old, std::vector<E>& out, BufferId id, const SceneData& scene,
                             std::array<bool, kBufferCount>& grown) {
        const uint64_t count = scene.element_count(id);
        if (!sized_by_capacity(id) || count == old.size()) return {};
        if (count < old.size())
            return {ErrorCode::internal, "cpu: grow() would shrink buffer " + std::string(buffer_info(id).name)};
        E zero;
        std::memset(static_cast<void*>(&zero), 0, sizeof zero);
        out.assign(count, zero);
        for (const GrowthCopy& c : growth_plan(id, old.size(), count, live_elements(scene, id)).copies)
            std::copy_n(old.begin() + std::ptrdiff_t(c.src), c.count, out.begin() + std::ptrdiff_t(c.dst));
        grown[uint32_t(id)] = true;
        return {};
    }

    /// Calls f(buffer) for the host vector behind `id` after a range check.
    template <class F>
    static Status visit(State<T>& s, BufferId id, uint64_t first, uint64_t count, F&& f) {
        auto checked = [&](auto& buffer) -> Status {
            if (first + count > buffer.size())
                return {ErrorCode::invalid_argument,
                        "cpu: range past the end of buffer " + std::string(buffer_info(id).name)};
            f(buffer);
            return {};
        };
        switch (id) {
#define HMSM_CPU_VISIT(name, binding, shape, scope) \
    case BufferId::name: return checked(s.name);
            HMSM_BUFFERS(HMSM_CPU_VISIT)
#undef HMSM_CPU_VISIT
        }
        return {ErrorCode::internal, "cpu: unknown buffer"};
    }

    State<T> s_;
    std::unique_ptr<ThreadPool> pool_;  // null: the serial backends
    uint32_t min_chunk_elements_ = 0;
    std::unique_ptr<StepPlan> plan_;    // cpu-parallel: the plan of the last program run
    uint64_t plan_id_ = 0;              // its program_id (0: none given)
    bool profiling_ = false;
    PassTimes times_;
};

}  // namespace
}  // namespace cpu

Result<std::unique_ptr<Backend>> create_cpu_backend(bool double_precision) {
    if (double_precision) return std::unique_ptr<Backend>(new cpu::CpuBackend<double>());
    return std::unique_ptr<Backend>(new cpu::CpuBackend<float>());
}

Result<uint32_t> cpu_thread_count(uint32_t requested) {
    if (requested > kMaxCpuThreads)
        return Status{ErrorCode::invalid_argument, "cpu_threads " + std::to_string(requested) +
                                                       ": expected at most " + std::to_string(kMaxCpuThreads)};
    if (requested > 0) return requested;
    if (const char* env = std::getenv("HMSM_CPU_THREADS"); env && *env) {
        const std::string text = env;
        uint32_t n = 0;
        auto [end, error] = std::from_chars(text.data(), text.data() + text.size(), n);
        if (error != std::errc{} || end != text.data() + text.size() || n < 1 || n > kMaxCpuThreads)
            return Status{ErrorCode::invalid_argument, "HMSM_CPU_THREADS='" + text +
                                                           "': expected a thread count in [1, " +
                                                           std::to_string(kMaxCpuThreads) + "]"};
        return n;
    }
    return std::max(1u, std::thread::hardware_concurrency());
}

Result<std::unique_ptr<Backend>> create_cpu_parallel_backend(uint32_t threads, uint32_t min_chunk_elements) {
    auto count = cpu_thread_count(threads);
    if (!count) return count.status();
    return std::unique_ptr<Backend>(new cpu::CpuBackend<float>(*count, std::max(1u, min_chunk_elements)));
}

}  // namespace hmsm::detail
