#include "cuda_emulation_backend.h"

#include "cuda/launch_dispatch.h"
#include "device_words.h"

#include <cstring>
#include <array>
#include <string>
#include <vector>

namespace hmsm::test {
namespace {

using detail::BufferId;

class CudaEmulationBackend final : public detail::Backend {
public:
    BackendKind kind() const override { return BackendKind::cuda; }
    std::string device_name() const override { return "CUDA kernels emulated on the host"; }
    bool prefers_path_walk() const override { return true; }  // as the CUDA backend

    /// Static buffers converted like an upload, state zero-filled; every buffer has at least
    /// one 16-byte element behind it, as on the device (an empty vertex_normal's placeholder).
    Status upload(const detail::SceneData& scene) override {
        for (const detail::BufferInfo& info : detail::kBufferTable) {
            auto& bytes = bytes_[uint32_t(info.id)];
            counts_[uint32_t(info.id)] = scene.element_count(info.id);
            if (detail::is_static(info.id)) bytes = detail::device_image(scene, info.id);
            else bytes.assign(scene.element_count(info.id) * detail::device_element_bytes(info.id), std::byte{0});
            bytes.resize(std::max<size_t>(bytes.size(), 16));
        }
#define HMSM_EMULATION_BIND(name, binding, shape, scope) \
    pointers_.name = reinterpret_cast<detail::cuda::DeviceType_##shape*>(bytes_[binding].data());
        HMSM_BUFFERS(HMSM_EMULATION_BIND)
#undef HMSM_EMULATION_BIND
        return {};
    }

    /// The CUDA backend hands each step's wind phase to the kernels as a float.
    Status run(std::span<const detail::Dispatch> program, std::span<const double> wind_x) override {
        for (double x : wind_x)
            for (const detail::Dispatch& d : program) detail::cuda::emulate_dispatch(d, pointers_, float(x));
        return {};
    }

    Status read(BufferId id, uint64_t first, uint64_t count, void* dst, detail::Scalar as) const override {
        HMSM_TRY(check_range(id, first, count));
        const detail::Shape shape = detail::buffer_info(id).shape;
        detail::words_to_scalars(shape, bytes_[uint32_t(id)].data() + first * detail::device_element_bytes(id),
                                 count * detail::shape_scalars(shape), dst, as);
        return {};
    }

    Status write(BufferId id, uint64_t first, uint64_t count, const void* src, detail::Scalar as) override {
        HMSM_TRY(check_range(id, first, count));
        const detail::Shape shape = detail::buffer_info(id).shape;
        detail::scalars_to_words(shape, src, count * detail::shape_scalars(shape),
                                 bytes_[uint32_t(id)].data() + first * detail::device_element_bytes(id), as);
        return {};
    }

    Status move_elements(BufferId id, std::span<const detail::ElementMove> moves) override {
        const uint64_t element_bytes = detail::device_element_bytes(id);
        for (const detail::ElementMove& m : moves) {
            HMSM_TRY(check_range(id, m.src, m.count));
            HMSM_TRY(check_range(id, m.dst, m.count));
            std::byte* base = bytes_[uint32_t(id)].data();
            std::memmove(base + m.dst * element_bytes, base + m.src * element_bytes, m.count * element_bytes);
        }
        return {};
    }

    void set_profiling(bool) override {}
    PassTimes pass_times() const override { return {}; }

private:
    Status check_range(BufferId id, uint64_t first, uint64_t count) const {
        if (first + count <= counts_[uint32_t(id)] && first + count >= first) return {};
        return {ErrorCode::invalid_argument, "cuda emulation: elements [" + std::to_string(first) + ", " +
                                                 std::to_string(first + count) + ") of " +
                                                 std::string(detail::buffer_info(id).name) + " are out of range"};
    }

    std::array<std::vector<std::byte>, detail::kBufferCount> bytes_;
    std::array<uint64_t, detail::kBufferCount> counts_{};
    detail::cuda::BufferPointers pointers_;
};

}  // namespace

std::unique_ptr<detail::Backend> create_cuda_emulation_backend() {
    return std::make_unique<CudaEmulationBackend>();
}

}  // namespace hmsm::test
