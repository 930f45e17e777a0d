// A backend that hands every call to another: the base of the test backends that watch, refuse
// or break some calls of a real one. Every call goes to the inner backend's own method (batched
// transfers, growth and asynchronous reads included), so the inner backend does the work its own
// way; a wrapper overrides what it changes. Before each call that reaches the device, gate()
// may fail it instead (a device lost on purpose).
#pragma once

#include "backend.h"

#include <memory>
#include <utility>

namespace hmsm::test {

class ForwardingBackend : public detail::Backend {
public:
    explicit ForwardingBackend(std::unique_ptr<detail::Backend> inner) : inner_(std::move(inner)) {}

    BackendKind kind() const override { return inner_->kind(); }
    std::string device_name() const override { return inner_->device_name(); }
    Status upload(const detail::SceneData& scene) override {
        HMSM_TRY(gate());
        return inner_->upload(scene);
    }
    Status grow(const detail::SceneData& scene) override {
        HMSM_TRY(gate());
        return inner_->grow(scene);
    }
    Status run(std::span<const detail::Dispatch> program, std::span<const detail::RunStep> steps,
               uint64_t program_id = 0) override {
        HMSM_TRY(gate());
        return inner_->run(program, steps, program_id);
    }
    Status read(detail::BufferId id, uint64_t first, uint64_t count, void* dst, detail::Scalar as) const override {
        HMSM_TRY(gate());
        return inner_->read(id, first, count, dst, as);
    }
    Status write(detail::BufferId id, uint64_t first, uint64_t count, const void* src, detail::Scalar as) override {
        HMSM_TRY(gate());
        return inner_->write(id, first, count, src, as);
    }
    Status read_ranges(detail::BufferId id, std::span<const detail::ElementRange> ranges, void* dst,
                       detail::Scalar as) const override {
        HMSM_TRY(gate());
        return inner_->read_ranges(id, ranges, dst, as);
    }
    Status write_ranges(detail::BufferId id, std::span<const detail::ElementRange> ranges, const void* src,
                        detail::Scalar as) override {
        HMSM_TRY(gate());
        return inner_->write_ranges(id, ranges, src, as);
    }
    Status read_buffers(std::span<const detail::BufferRangesRead> reads, detail::Scalar as) const override {
        HMSM_TRY(gate());
        return inner_->read_buffers(reads, as);
    }
    Status write_buffers(std::span<const detail::BufferRangesWrite> writes, detail::Scalar as) override {
        HMSM_TRY(gate());
        return inner_->write_buffers(writes, as);
    }
    Status move_buffers(std::span<const detail::BufferMoves> moves) override {
        HMSM_TRY(gate());
        return inner_->move_buffers(moves);
    }
    Status copy_patterns(std::span<const detail::BufferId> ids, uint64_t capacity,
                         std::span<const detail::MovePattern> patterns,
                         std::span<const detail::PatternCopy> copies) override {
        HMSM_TRY(gate());
        return inner_->copy_patterns(ids, capacity, patterns, copies);
    }
    Status move_elements(detail::BufferId id, std::span<const detail::ElementMove> moves) override {
        HMSM_TRY(gate());
        return inner_->move_elements(id, moves);
    }
    void begin_instance_change() override { inner_->begin_instance_change(); }
    void end_instance_change() override { inner_->end_instance_change(); }
    detail::BackendCapabilities capabilities() const override { return inner_->capabilities(); }
    void set_profiling(bool enabled) override { inner_->set_profiling(enabled); }
    PassTimes pass_times() const override { return inner_->pass_times(); }
    Status request_read(uint32_t slot, detail::BufferId id, uint64_t first, uint64_t count) const override {
        HMSM_TRY(gate());
        return inner_->request_read(slot, id, first, count);
    }
    Result<const float*> take_read(uint32_t slot) const override {
        HMSM_TRY(gate());
        return inner_->take_read(slot);
    }
    Result<double> measure_copy_bandwidth(uint64_t bytes) override {
        HMSM_TRY(gate());
        return inner_->measure_copy_bandwidth(bytes);
    }

protected:
    /// Checked before every call that reaches the device; a failure is returned instead of it.
    virtual Status gate() const { return {}; }
    detail::Backend& inner() const { return *inner_; }

private:
    std::unique_ptr<detail::Backend> inner_;
};

}  // namespace hmsm::test
