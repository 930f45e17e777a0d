#include "cuda_emulation_backend.h"

#include "cuda/launch_dispatch.h"
#include "capacity_growth.h"
#include "cuda/launch_plan.h"
#include "device_words.h"
#include "element_moves.h"
#include "step_program.h"
#include "../../kernels/cuda/copy_ranges.h"

#include <algorithm>
#include <cstring>
#include <array>
#include <string>
#include <vector>

namespace hmsm::test {
namespace {

using detail::BufferId;

class CudaEmulationBackend final : public detail::Backend {
public:
    CudaEmulationBackend(EmulatedAheadSteps* ahead, bool batch_runs, uint32_t max_blocks)
        : ahead_(ahead), batch_runs_(batch_runs),
          max_blocks_(max_blocks != 0 ? max_blocks : detail::cuda::max_launch_blocks()) {}
    BackendKind kind() const override { return BackendKind::cuda; }
    std::string device_name() const override { return "CUDA kernels emulated on the host"; }
    detail::BackendCapabilities capabilities() const override {
        detail::BackendCapabilities can;
        can.walks_ahead = ahead_ != nullptr;
        can.prefers_path_walk = true;  // as the CUDA backend
        can.grows_on_device = true;
        can.copies_patterns = true;
        return can;
    }

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
        next_state_.assign(bytes_[uint32_t(BufferId::chain_state)].size(), std::byte{0});
        bind();
        return {};
    }

    /// The CUDA backend's growth (src/cuda/device_buffers.cpp) over the host images: each
    /// capacity-sized buffer anew, its live elements copied as capacity_growth.h plans them.
    Status grow(const detail::SceneData& scene) override {
        for (const detail::BufferInfo& info : detail::kBufferTable) {
            const uint32_t b = uint32_t(info.id);
            const uint64_t count = scene.element_count(info.id);
            const detail::GrowthPlan plan = detail::growth_plan(info.id, counts_[b], count,
                                                                detail::live_elements(scene, info.id));
            if (!plan.reallocates) continue;
            const uint64_t element_bytes = detail::device_element_bytes(info.id);
            std::vector<std::byte> grown(std::max<size_t>(count * element_bytes, 16), std::byte{0});
            for (const detail::GrowthCopy& c : plan.copies)
                std::memcpy(grown.data() + c.dst * element_bytes, bytes_[b].data() + c.src * element_bytes,
                            c.count * element_bytes);
            bytes_[b] = std::move(grown);
            counts_[b] = count;
            if (info.id == BufferId::chain_state) next_state_.assign(bytes_[b].size(), std::byte{0});
        }
        bind();
        return {};
    }

    /// The CUDA backend hands each step's wind-table slot to the kernels, and runs each
    /// step of a walk-ahead program as `ahead` says (src/cuda/cuda_backend.cpp).
    Status run(std::span<const detail::Dispatch> program, std::span<const detail::RunStep> steps,
               uint64_t /*program_id: derives its plans anew each run*/ = 0) override {
        const bool walks = ahead_ && std::any_of(program.begin(), program.end(), detail::is_walk_ahead);
        const detail::AheadVariants variants = walks ? detail::ahead_variants(program) : detail::AheadVariants{};
        auto plan_of = [&](std::span<const detail::Dispatch> dispatches) {
            return detail::cuda::plan_launches(dispatches, batch_runs_, max_blocks_);
        };
        const detail::cuda::LaunchPlan whole = plan_of(program), without_wind = plan_of(variants.without_wind),
                                       plain = plan_of(variants.plain);
        for (const detail::RunStep& run_step : steps) {
            const detail::AheadStep how = walks ? run_step.ahead : detail::AheadStep::whole;
            std::span<const detail::Dispatch> step = program;
            const detail::cuda::LaunchPlan* plan = &whole;
            if (how == detail::AheadStep::take) {
                std::swap(bytes_[uint32_t(BufferId::chain_state)], next_state_);
                pointers_.chain_state = reinterpret_cast<float4*>(bytes_[uint32_t(BufferId::chain_state)].data());
                pointers_.chain_state_next = reinterpret_cast<float4*>(next_state_.data());
                step = variants.without_wind;
                plan = &without_wind;
                ++ahead_->taken;
            } else if (how == detail::AheadStep::plain) {
                step = variants.plain;
                plan = &plain;
                ++ahead_->plain;
            }
            for (const detail::cuda::PlannedLaunch& launch : plan->launches)
                detail::cuda::emulate_launch(*plan, launch, step, pointers_, run_step.wind_slot);
        }
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

    /// As the CUDA backend batches them (src/cuda/range_transfers.cpp): per batch of
    /// plan_move_batches the range copy's gather into scratch, then its scatter.
    Status move_elements(BufferId id, std::span<const detail::ElementMove> moves) override {
        const uint64_t element_bytes = detail::device_element_bytes(id);
        for (const detail::ElementMove& m : moves) {
            HMSM_TRY(check_range(id, m.src, m.count));
            HMSM_TRY(check_range(id, m.dst, m.count));
        }
        const detail::MoveBatches plan =
            detail::plan_move_batches(moves, std::max<uint64_t>(1, detail::kMoveScratchBytes / element_bytes));
        size_t begin = 0;
        for (size_t end : plan.ends) {
            std::vector<detail::cuda::WordRange> table;
            const uint64_t words = detail::cuda::append_word_ranges(
                table, std::span(plan.pieces).subspan(begin, end - begin), element_bytes / 4);
            move_batch(id, table, words);
            begin = end;
        }
        return {};
    }

    /// As the CUDA backend (src/cuda/range_transfers.cpp): the same tables, each buffer's
    /// copies through the kernel's body.
    Status copy_patterns(std::span<const BufferId> ids, uint64_t capacity,
                         std::span<const detail::MovePattern> patterns,
                         std::span<const detail::PatternCopy> copies) override {
        Result<detail::PatternTables> tables = detail::pattern_tables(patterns, copies);
        if (!tables) return tables.status();
        HMSM_TRY(detail::check_pattern_ranges(*tables, ids, capacity, [&](BufferId id, uint64_t first, uint64_t count) {
            return check_range(id, first, count);
        }));
        // The host tables as the device reads them (the same layout: copy_ranges.h).
        std::vector<detail::cuda::PatternCopyEntry> entries(tables->entries.size());
        std::vector<detail::cuda::PatternMoveEntry> moves(tables->moves.size());
        std::memcpy(entries.data(), tables->entries.data(), entries.size() * sizeof entries[0]);
        std::memcpy(moves.data(), tables->moves.data(), moves.size() * sizeof moves[0]);
        for (BufferId id : ids) {
            const uint32_t words = uint32_t(detail::device_element_bytes(id) / 4);
            detail::cuda::emulate_copy_patterns(reinterpret_cast<uint32_t*>(bytes_[uint32_t(id)].data()), words,
                                                capacity * words, detail::halves_of(id), entries.data(),
                                                uint32_t(entries.size()), moves.data());
        }
        return {};
    }

    /// The range copy's gather into scratch, then the words converted as read() does.
    Status read_ranges(BufferId id, std::span<const detail::ElementRange> ranges, void* dst,
                       detail::Scalar as) const override {
        std::vector<detail::cuda::WordRange> table;
        const Result<uint64_t> words = word_table(id, ranges, true, table);
        if (!words) return words.status();
        std::vector<uint32_t> scratch(*words);
        gather(id, table, scratch);
        const detail::Shape shape = detail::buffer_info(id).shape;
        detail::words_to_scalars(shape, scratch.data(), scratch.size(), dst, as);
        return {};
    }

    /// The words converted as write() does, then the range copy's scatter (ranges that overlap:
    /// one by one, as the CUDA backend).
    Status write_ranges(BufferId id, std::span<const detail::ElementRange> ranges, const void* src,
                        detail::Scalar as) override {
        if (detail::ranges_overlap(ranges)) return Backend::write_ranges(id, ranges, src, as);
        std::vector<detail::cuda::WordRange> table;
        const Result<uint64_t> words = word_table(id, ranges, false, table);
        if (!words) return words.status();
        std::vector<uint32_t> scratch(*words);
        detail::scalars_to_words(detail::buffer_info(id).shape, src, scratch.size(), scratch.data(), as);
        detail::cuda::emulate_copy_ranges(reinterpret_cast<uint32_t*>(bytes_[uint32_t(id)].data()), scratch.data(),
                                          table.data(), uint32_t(table.size()), scratch.size(),
                                          detail::cuda::RangeCopy::scatter);
        return {};
    }

    void set_profiling(bool) override {}
    PassTimes pass_times() const override { return {}; }

private:
    /// The word ranges of `ranges` (read from: `reads`), packed back to back; their total words.
    Result<uint64_t> word_table(BufferId id, std::span<const detail::ElementRange> ranges, bool reads,
                                std::vector<detail::cuda::WordRange>& table) const {
        std::vector<detail::ElementMove> pieces;
        for (const detail::ElementRange& r : ranges) {
            HMSM_TRY(check_range(id, r.first, r.count));
            pieces.push_back({reads ? r.first : 0, reads ? 0 : r.first, r.count});
        }
        return detail::cuda::append_word_ranges(table, pieces, detail::device_element_bytes(id) / 4);
    }
    void gather(BufferId id, const std::vector<detail::cuda::WordRange>& table, std::vector<uint32_t>& scratch) const {
        // Gathering only reads the buffer.
        auto* buffer = const_cast<uint32_t*>(reinterpret_cast<const uint32_t*>(bytes_[uint32_t(id)].data()));
        detail::cuda::emulate_copy_ranges(buffer, scratch.data(),
                                          table.data(), uint32_t(table.size()), scratch.size(),
                                          detail::cuda::RangeCopy::gather);
    }
    /// One batch of moves: gather every source, then scatter every destination.
    void move_batch(BufferId id, const std::vector<detail::cuda::WordRange>& table, uint64_t words) {
        std::vector<uint32_t> scratch(words);
        auto* buffer = reinterpret_cast<uint32_t*>(bytes_[uint32_t(id)].data());
        detail::cuda::emulate_copy_ranges(buffer, scratch.data(), table.data(), uint32_t(table.size()), words,
                                          detail::cuda::RangeCopy::gather);
        detail::cuda::emulate_copy_ranges(buffer, scratch.data(), table.data(), uint32_t(table.size()), words,
                                          detail::cuda::RangeCopy::scatter);
    }
    void bind() {
#define HMSM_EMULATION_BIND(name, binding, shape, scope) \
    pointers_.name = reinterpret_cast<detail::cuda::DeviceType_##shape*>(bytes_[binding].data());
        HMSM_BUFFERS(HMSM_EMULATION_BIND)
#undef HMSM_EMULATION_BIND
        pointers_.chain_state_next = reinterpret_cast<float4*>(next_state_.data());
    }

    Status check_range(BufferId id, uint64_t first, uint64_t count) const {
        if (first + count <= counts_[uint32_t(id)] && first + count >= first) return {};
        return {ErrorCode::invalid_argument, "cuda emulation: elements [" + std::to_string(first) + ", " +
                                                 std::to_string(first + count) + ") of " +
                                                 std::string(detail::buffer_info(id).name) + " are out of range"};
    }

    EmulatedAheadSteps* ahead_;
    bool batch_runs_;
    uint32_t max_blocks_;
    std::vector<std::byte> next_state_;  // chain_state's twin (BufferPointers::chain_state_next)
    std::array<std::vector<std::byte>, detail::kBufferCount> bytes_;
    std::array<uint64_t, detail::kBufferCount> counts_{};
    detail::cuda::BufferPointers pointers_;
};

}  // namespace

std::unique_ptr<detail::Backend> create_cuda_emulation_backend(EmulatedAheadSteps* ahead, bool batch_runs,
                                                               uint32_t max_blocks) {
    return std::make_unique<CudaEmulationBackend>(ahead, batch_runs, max_blocks);
}

}  // namespace hmsm::test
