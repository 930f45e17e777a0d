#include "vulkan_backend.h"

#include "recorder.h"
#include "vk_error.h"

#include "../device_words.h"
#include "../element_moves.h"

#include <algorithm>
#include <atomic>
#include <cstdlib>
#include <cstring>
#include <new>
#include <numeric>
#include <string_view>
#include <vector>

namespace hmsm::detail {
namespace vk {
namespace {

/// Dispatches per command buffer: large enough that submission costs nothing, small enough that
/// the host records one chunk while the device runs the other.
constexpr size_t kDispatchesPerChunk = 2048;

/// Buffers an engine may draw from directly (hmsm/vulkan.h SharedBuffers).
constexpr bool is_shared_output(BufferId id) {
    return id == BufferId::vertex_position || id == BufferId::vertex_normal || id == BufferId::node_world;
}

}  // namespace

Result<std::unique_ptr<VulkanBackend>> VulkanBackend::create(std::shared_ptr<Device> device,
                                                             uint32_t frames_in_flight) {
    if (frames_in_flight == 0 || frames_in_flight > kMaxFramesInFlight)
        return Status{ErrorCode::invalid_argument, "vulkan: frames_in_flight must be 1 to " +
                                                       std::to_string(kMaxFramesInFlight) + " (got " +
                                                       std::to_string(frames_in_flight) + ")"};
    std::unique_ptr<VulkanBackend> b(new VulkanBackend(std::move(device)));
    const Device& dev = *b->device_;
    b->ring_ = std::make_unique<FrameRing>(dev, frames_in_flight);
    auto pipelines = Pipelines::create(dev);
    if (!pipelines) return pipelines.status();
    b->pipelines_ = std::move(pipelines).value();
    auto table = RunTable::create(dev, b->pipelines_->table_set_layout());
    if (!table) return table.status();
    b->run_table_ = std::move(table).value();
    if (step_replay_requested()) {
        auto replay = StepReplay::create(dev, frames_in_flight);
        if (!replay) return replay.status();
        b->replay_ = std::move(replay).value();
    }
    auto read_slots = ReadSlots::create(dev);
    if (!read_slots) return read_slots.status();
    b->read_slots_ = std::move(read_slots).value();
    auto transfer = Transfer::create(dev);
    if (!transfer) return transfer.status();
    b->transfer_ = std::move(transfer).value();
    const char* shader_ranges = std::getenv("HMSM_VULKAN_SHADER_RANGES");
    b->shader_ranges_ = !(shader_ranges && std::string_view(shader_ranges) == "0");
    const char* range_copies = std::getenv("HMSM_VULKAN_RANGE_COPIES");
    if (!(range_copies && std::string_view(range_copies) == "0")) {
        auto copier = RangeCopier::create(dev);
        if (!copier) return copier.status();
        b->range_copier_ = std::move(copier).value();
    }

    const VolkDeviceTable& vk = dev.vk();
    VkCommandPoolCreateInfo pool{VK_STRUCTURE_TYPE_COMMAND_POOL_CREATE_INFO};
    pool.flags = VK_COMMAND_POOL_CREATE_RESET_COMMAND_BUFFER_BIT;
    pool.queueFamilyIndex = dev.queue_family();
    HMSM_VK_TRY(vk.vkCreateCommandPool(dev.handle(), &pool, nullptr, &b->pool_));
    for (Slot& slot : b->slots_) {
        VkCommandBufferAllocateInfo allocate{VK_STRUCTURE_TYPE_COMMAND_BUFFER_ALLOCATE_INFO};
        allocate.commandPool = b->pool_;
        allocate.level = VK_COMMAND_BUFFER_LEVEL_PRIMARY;
        allocate.commandBufferCount = 1;
        HMSM_VK_TRY(vk.vkAllocateCommandBuffers(dev.handle(), &allocate, &slot.command_buffer));
        VkFenceCreateInfo fence{VK_STRUCTURE_TYPE_FENCE_CREATE_INFO};
        HMSM_VK_TRY(vk.vkCreateFence(dev.handle(), &fence, nullptr, &slot.fence));
    }
    HMSM_TRY(b->device_->take_validation_messages());
    return b;
}

VulkanBackend::~VulkanBackend() {
    const VolkDeviceTable& vk = device_->vk();
    VkDevice dev = device_->handle();
    for (Slot& slot : slots_) {
        if (slot.in_flight) vk.vkWaitForFences(dev, 1, &slot.fence, VK_TRUE, UINT64_MAX);
        if (slot.fence) vk.vkDestroyFence(dev, slot.fence, nullptr);
        if (slot.timestamps) vk.vkDestroyQueryPool(dev, slot.timestamps, nullptr);
    }
    if (pool_) vk.vkDestroyCommandPool(dev, pool_, nullptr);
    // Buffers, pipelines and the transfer go before the device (member order would not ensure it
    // for the shared device).
    replay_.reset();
    read_slots_.reset();
    sets_.reset();
    run_table_.reset();
    ring_.reset();
    for (Buffer& b : buffers_) b = Buffer();
    pipelines_.reset();
    transfer_.reset();
}

Status VulkanBackend::plan_windows(const SceneData& scene) {
    const DeviceLimits& limits = device_->limits();
    // Static model data is bound whole (it is shared by all instances of a model).
    for (const BufferInfo& info : kBufferTable) {
        if (!is_static(info.id) || info.scope == Scope::instance) continue;
        VkDeviceSize bytes = scene.element_count(info.id) * device_element_bytes(info.id);
        if (bytes > limits.max_storage_buffer_range)
            return {ErrorCode::unsupported,
                    "vulkan: scene too large for " + device_->name() + ": model buffer " +
                        std::string(info.name) + " needs " + std::to_string(bytes) +
                        " bytes, more than maxStorageBufferRange (" +
                        std::to_string(limits.max_storage_buffer_range) +
                        " bytes); use fewer distinct models per simulation"};
    }
    uint64_t window = limits.max_storage_buffer_range;
    if (window_bytes_) window = std::min<uint64_t>(window, window_bytes_);
    uint64_t alignment = limits.min_storage_buffer_offset_alignment;
    if (window_alignment_) alignment = std::lcm<uint64_t>(alignment, window_alignment_);
    auto plan = WindowPlan::build(scene, window, alignment, device_->name());
    if (!plan) return plan.status();
    plan_ = std::make_unique<WindowPlan>(std::move(plan).value());
    return {};
}

namespace {
std::atomic<VulkanFault> g_injected_fault{VulkanFault::none};
std::atomic<uint32_t> g_injected_fault_after{0};
}  // namespace

VulkanBackend::VulkanBackend(std::shared_ptr<Device> device)
    : device_(std::move(device)),
      window_bytes_(requested_window_bytes()),
      window_alignment_(requested_window_alignment()),
      fault_(g_injected_fault.load()),
      submissions_before_fault_(g_injected_fault_after.load()) {
    batching_ = {requested_batch_runs().value_or(!device_->is_cpu()), requested_batch_workgroups()};
}

Status VulkanBackend::check_device_lost() const {
    if (device_lost_)
        return failure(VK_ERROR_DEVICE_LOST, "device lost earlier (injected)", __FILE__, __LINE__);
    return {};
}

Status VulkanBackend::check_range(BufferId id, uint64_t first, uint64_t count) const {
    if (first + count > element_counts_[uint32_t(id)] || first + count < first)
        return {ErrorCode::invalid_argument,
                "vulkan: range past the end of buffer " + std::string(buffer_info(id).name)};
    // A scene bound in windows places only the live chains of each ping-pong half.
    if (count > 0 && plan_ && plan_->split() && buffer_info(id).scope == Scope::chain_halves) {
        const uint64_t half = element_counts_[uint32_t(id)] / 2, mapped = plan_->mapped_chains();
        bool past = false;  // the part of the range in each half it touches
        for (uint64_t h = first / half; h * half < first + count; ++h)
            past = past || std::min(first + count, (h + 1) * half) - h * half > mapped;
        if (past)
            return {ErrorCode::invalid_argument, "vulkan: range past the live chains of buffer " +
                                                     std::string(buffer_info(id).name) +
                                                     " in a scene bound in windows"};
    }
    return {};
}

Status VulkanBackend::upload(const SceneData& scene) {
    HMSM_TRY(submit_held_back());
    HMSM_TRY(plan_windows(scene));
    if (fault_ == VulkanFault::out_of_device_memory_at_upload)
        return failure(VK_ERROR_OUT_OF_DEVICE_MEMORY, "vkAllocateMemory (injected)", __FILE__, __LINE__);
    for (const BufferInfo& info : kBufferTable) {
        const uint32_t b = uint32_t(info.id);
        element_counts_[b] = scene.element_count(info.id);
        auto buffer = Buffer::create(*device_, plan_->physical_elements(info.id, scene) * device_element_bytes(info.id),
                                     usage_of(info.id), MemoryUse::device_local, std::string(info.name));
        if (!buffer) return buffer.status();
        buffers_[b] = std::move(buffer).value();
    }
    try {
        for (const BufferInfo& info : kBufferTable)
            if (is_static(info.id)) HMSM_TRY(upload_static(info.id, scene));
    } catch (const std::bad_alloc&) {
        return {ErrorCode::out_of_memory, "vulkan: not enough host memory to stage the scene"};
    }
    // State starts at zero (S = V = 0; the simulation then poses the scene at rest).
    HMSM_TRY(transfer_->submit([&](VkCommandBuffer cmd) {
        for (const BufferInfo& info : kBufferTable)
            if (!is_static(info.id))
                device_->vk().vkCmdFillBuffer(cmd, buffers_[uint32_t(info.id)].handle(), 0,
                                              VK_WHOLE_SIZE, 0);
    }));
    recording_.clear();  // its descriptor sets go
    one_off_recording_.clear();
    auto sets = WindowSets::create(*device_, pipelines_->set_layout(), *plan_, buffers_);
    if (!sets) return sets.status();
    sets_ = std::move(sets).value();
    return device_->take_validation_messages();
}

VkBufferUsageFlags VulkanBackend::usage_of(BufferId id) {
    VkBufferUsageFlags usage =
        VK_BUFFER_USAGE_STORAGE_BUFFER_BIT | VK_BUFFER_USAGE_TRANSFER_SRC_BIT | VK_BUFFER_USAGE_TRANSFER_DST_BIT;
    if (is_shared_output(id)) usage |= VK_BUFFER_USAGE_VERTEX_BUFFER_BIT;
    return usage;
}

Result<uint64_t> VulkanBackend::move_scratch_bytes(BufferId id, std::span<const ElementMove> moves) const {
    const uint64_t element_bytes = device_element_bytes(id);
    auto checked = largest_move_bytes(moves, element_bytes,
                                      [&](uint64_t first, uint64_t count) { return check_range(id, first, count); });
    if (!checked) return checked.status();
    // Scratch for the largest batch of plan_move_batches (one by one: for the largest move that
    // overlaps itself), at most kMoveScratchBytes; none where the moves can be copied directly.
    uint64_t staged = 0;
    if (*checked == 0 || destinations_apart_from_sources(moves)) return staged;
    if (batch_transfers_)
        return plan_move_batches(moves, std::max<uint64_t>(1, kMoveScratchBytes / element_bytes)).largest * element_bytes;
    for (const ElementMove& m : moves)
        if (overlaps_itself(m)) staged = std::max(staged, std::min(m.count * element_bytes, kMoveScratchBytes));
    return staged;
}

Status VulkanBackend::move_elements(BufferId id, std::span<const ElementMove> moves) {
    HMSM_TRY(check_device_lost());
    if (!capabilities().reshapes_in_place)
        return {ErrorCode::unsupported, "vulkan: a scene split into windows cannot move state in place"};
    auto largest = largest_move_bytes(moves, device_element_bytes(id),
                                      [&](uint64_t first, uint64_t count) { return check_range(id, first, count); });
    if (!largest) return largest.status();
    if (*largest == 0) return {};
    auto staged = move_scratch_bytes(id, moves);
    if (!staged) return staged.status();
    HMSM_TRY(ensure_move_scratch(*staged));
    if (holding_back(moves.size() * sizeof(PatternRow))) {  // as a pattern copy's table at most
        HeldBack change{HeldBack::Kind::move, id};
        change.moves.assign(moves.begin(), moves.end());
        hold_back(std::move(change), moves.size() * sizeof(PatternRow));
        return {};
    }
    HMSM_TRY(submit_held_back());
    if (copies_by_shader({&id, 1})) {
        const BufferMoves one{id, moves};
        return shader_moves({&one, 1});
    }
    HMSM_TRY(transfer_->submit([&](VkCommandBuffer cmd) { record_moves(cmd, id, moves); }));
    return device_->take_validation_messages();
}

Status VulkanBackend::upload_static(BufferId id, const SceneData& scene) {
    const std::vector<std::byte> image = device_image(scene, id);
    return transfer_->upload(buffers_[uint32_t(id)], 0, image.size(),
                             [&](void* staging, VkDeviceSize first, VkDeviceSize count) {
                                 std::memcpy(staging, image.data() + first, count);
                             });
}

Status VulkanBackend::ensure_timestamp_capacity(Slot& slot, uint32_t queries) {
    if (slot.timestamps && slot.timestamp_capacity >= queries) return {};
    const VolkDeviceTable& vk = device_->vk();
    if (slot.timestamps) vk.vkDestroyQueryPool(device_->handle(), slot.timestamps, nullptr);
    slot.timestamps = VK_NULL_HANDLE;
    VkQueryPoolCreateInfo info{VK_STRUCTURE_TYPE_QUERY_POOL_CREATE_INFO};
    info.queryType = VK_QUERY_TYPE_TIMESTAMP;
    info.queryCount = queries;
    HMSM_VK_TRY(vk.vkCreateQueryPool(device_->handle(), &info, nullptr, &slot.timestamps));
    slot.timestamp_capacity = queries;
    return {};
}

Status VulkanBackend::submit_chunk(Slot& slot, const RecordingPlan& plan, std::span<const RunStep> steps) {
    const VolkDeviceTable& vk = device_->vk();
    const bool timed = profiling_ && device_->limits().timestamp_period_ns > 0.0;
    const size_t per_step = plan.timestamp_passes().size();
    if (timed) HMSM_TRY(ensure_timestamp_capacity(slot, uint32_t(steps.size() * per_step + 1)));
    HMSM_VK_TRY(vk.vkResetCommandBuffer(slot.command_buffer, 0));
    VkCommandBufferBeginInfo begin{VK_STRUCTURE_TYPE_COMMAND_BUFFER_BEGIN_INFO};
    begin.flags = VK_COMMAND_BUFFER_USAGE_ONE_TIME_SUBMIT_BIT;
    HMSM_VK_TRY(vk.vkBeginCommandBuffer(slot.command_buffer, &begin));
    record_steps(*device_, pipelines_->layout(), plan, slot.command_buffer, steps,
                 timed ? slot.timestamps : VK_NULL_HANDLE, run_table_->set());
    HMSM_VK_TRY(vk.vkEndCommandBuffer(slot.command_buffer));
    VkSubmitInfo submit{VK_STRUCTURE_TYPE_SUBMIT_INFO};
    submit.commandBufferCount = 1;
    submit.pCommandBuffers = &slot.command_buffer;
    HMSM_VK_TRY(vk.vkResetFences(device_->handle(), 1, &slot.fence));
    if (fault_ == VulkanFault::device_lost_at_submit && submissions_before_fault_-- == 0)
        device_lost_ = true;
    HMSM_TRY(check_device_lost());
    HMSM_VK_TRY(device_->submit(submit, slot.fence));
    ++submissions_;
    slot.in_flight = true;
    slot.steps = timed ? steps.size() : 0;
    slot.plan = &plan;
    return {};
}

Status VulkanBackend::finish_slot(Slot& slot) {
    if (!slot.in_flight) return {};
    const VolkDeviceTable& vk = device_->vk();
    slot.in_flight = false;
    HMSM_VK_TRY(vk.vkWaitForFences(device_->handle(), 1, &slot.fence, VK_TRUE, UINT64_MAX));
    if (slot.steps == 0 || !slot.plan) return {};
    const std::span<const Pass> passes = slot.plan->timestamp_passes();
    const uint32_t queries = uint32_t(slot.steps * passes.size() + 1);
    std::vector<uint64_t> ticks(queries);
    HMSM_VK_TRY(vk.vkGetQueryPoolResults(device_->handle(), slot.timestamps, 0, queries,
                                         ticks.size() * sizeof(uint64_t), ticks.data(),
                                         sizeof(uint64_t),
                                         VK_QUERY_RESULT_64_BIT | VK_QUERY_RESULT_WAIT_BIT));
    const DeviceLimits& limits = device_->limits();
    const uint64_t mask = limits.timestamp_valid_bits >= 64 ? ~uint64_t(0)
                                                            : (uint64_t(1) << limits.timestamp_valid_bits) - 1;
    // Timestamps are taken at the compute stage between dispatches, so dispatch j's time runs
    // from the completion of everything before it to its own completion.
    for (uint32_t j = 0; j + 1 < queries; ++j) {
        uint64_t delta = (ticks[j + 1] - ticks[j]) & mask;
        times_.seconds[uint32_t(passes[j % passes.size()])] +=
            double(delta) * limits.timestamp_period_ns * 1e-9;
    }
    return {};
}

Status VulkanBackend::run(std::span<const Dispatch> program, std::span<const RunStep> steps, uint64_t program_id) {
    times_ = {};
    if (program.empty() || steps.empty()) return {};
    if (!plan_ || !sets_) return {ErrorCode::internal, "vulkan: run() before upload()"};
    if (holding_back()) {
        HeldBack change{HeldBack::Kind::run};
        change.program.assign(program.begin(), program.end());
        change.steps.assign(steps.begin(), steps.end());
        hold_back(std::move(change), 0);
        return {};
    }
    if (!record_target_) HMSM_TRY(submit_held_back());
    const bool one_off = program_id == 0;
    HMSM_TRY(one_off ? prepare_one_off(program) : prepare_recording(program, program_id));
    const RecordingPlan& plan = one_off ? one_off_recording_ : recording_;
    if (record_target_) {
        ring_->record_copies(record_target_);
        // The step program replays from a secondary, which also carries the frame's wind table
        // (frame_ring.h); a one-off (program_id 0: an added instance's rest pose) is recorded
        // directly.
        const std::optional<FrameRing::WindCopy> wind = ring_->take_wind_copy();
        const VkBuffer wind_table = buffers_[uint32_t(BufferId::wind_table)].handle();
        if (replay_ && !one_off) {
            HMSM_TRY(replay_->record(record_target_, ring_->current(), recordings_, pipelines_->layout(), recording_,
                                     steps, run_table_->set(), wind ? &*wind : nullptr, wind_table));
        } else {
            if (wind) record_wind_copy(*wind);
            record_steps(*device_, pipelines_->layout(), plan, record_target_, steps, VK_NULL_HANDLE,
                         run_table_->set());
        }
        return device_->take_validation_messages();
    }
    const size_t steps_per_chunk = std::max<size_t>(1, kDispatchesPerChunk / program.size());
    Status status;
    size_t chunk = 0;
    for (size_t first = 0; first < steps.size() && status.ok(); first += steps_per_chunk, ++chunk) {
        Slot& slot = slots_[chunk % slots_.size()];
        status = finish_slot(slot);
        if (status.ok())
            status = submit_chunk(slot, plan, steps.subspan(first, std::min(steps_per_chunk, steps.size() - first)));
    }
    // Oldest first; after a failure still wait for whatever was submitted.
    for (size_t k = 0; k < slots_.size(); ++k) {
        Status finished = finish_slot(slots_[(chunk + k) % slots_.size()]);
        if (status.ok()) status = finished;
    }
    HMSM_TRY(status);
    // Every recorded frame precedes hmsm's own submissions (docs/vulkan.md): none reads a run
    // table that was replaced.
    run_table_->release_replaced();
    if (profiling_ && device_->limits().timestamp_period_ns > 0.0) times_.steps = steps.size();
    return device_->take_validation_messages();
}

Status VulkanBackend::prepare_recording(std::span<const Dispatch> program, uint64_t program_id) {
    auto built = recording_.prepare(*device_, *pipelines_, Windows{*plan_, *sets_}, program, batching_, program_id);
    if (!built) return built.status();
    if (!*built) return {};
    // The table travels with the recording that first runs the program (frames in flight may
    // still read the old contents), or is written now before the steps are submitted.
    Status status = record_target_ ? run_table_->stage(*ring_, recording_.table_constants(),
                                                       recording_.table_first_workgroups())
                                   : run_table_->upload(*transfer_, recording_.table_constants(),
                                                        recording_.table_first_workgroups());
    if (!status) recording_.clear();  // built again, with its table, by the next run
    return status;
}

Status VulkanBackend::prepare_one_off(std::span<const Dispatch> program) {
    RecordingPlan::Batching alone = batching_;
    alone.batch_runs = false;  // no run table: the step program's stays
    return one_off_recording_.prepare(*device_, *pipelines_, Windows{*plan_, *sets_}, program, alone).status();
}

Status VulkanBackend::read(BufferId id, uint64_t first, uint64_t count, void* dst, Scalar as) const {
    HMSM_TRY(check_device_lost());
    HMSM_TRY(check_range(id, first, count));
    if (count == 0) return {};
    // A read sees every change made before it: held-back ones are submitted first (the
    // buffers' contents, which read() does not change, then include them).
    HMSM_TRY(const_cast<VulkanBackend*>(this)->submit_held_back());
    const Shape shape = buffer_info(id).shape;
    const uint64_t scalar_bytes = as == Scalar::f64 ? 8 : 4;
    // Pieces: one unless a ping-pong buffer of a split scene is read across segments.
    for (const WindowPlan::Piece& piece : plan_->pieces(id, first, count)) {
        auto* out = static_cast<std::byte*>(dst) + (piece.logical - first) * shape_scalars(shape) * scalar_bytes;
        HMSM_TRY(transfer_->download(
            buffers_[uint32_t(id)], piece.physical * device_element_bytes(id), piece.count * device_element_bytes(id),
            [&](const void* staging, VkDeviceSize first_byte, VkDeviceSize bytes) {
                words_to_scalars(shape, staging, bytes / 4, out + first_byte / 4 * scalar_bytes, as);
            }));
    }
    return device_->take_validation_messages();
}

Status VulkanBackend::write(BufferId id, uint64_t first, uint64_t count, const void* src, Scalar as) {
    HMSM_TRY(check_device_lost());
    HMSM_TRY(check_range(id, first, count));
    if (count == 0) return {};
    if (record_target_) return stage_write(id, first, count, src, as);
    if (holding_back(count * device_element_bytes(id))) return hold_back_write(id, first, count, src, as);
    HMSM_TRY(submit_held_back());
    if (id == BufferId::wind_table) keep_wind_header(first, count, src, as);
    const Shape shape = buffer_info(id).shape;
    const uint64_t scalar_bytes = as == Scalar::f64 ? 8 : 4;
    for (const WindowPlan::Piece& piece : plan_->pieces(id, first, count)) {
        const auto* in =
            static_cast<const std::byte*>(src) + (piece.logical - first) * shape_scalars(shape) * scalar_bytes;
        HMSM_TRY(transfer_->upload(
            buffers_[uint32_t(id)], piece.physical * device_element_bytes(id), piece.count * device_element_bytes(id),
            [&](void* staging, VkDeviceSize first_byte, VkDeviceSize bytes) {
                scalars_to_words(shape, in + first_byte / 4 * scalar_bytes, bytes / 4, staging, as);
            }));
    }
    return device_->take_validation_messages();
}

}  // namespace vk

void vulkan_inject_fault(VulkanFault fault, uint32_t after) {
    vk::g_injected_fault_after = after;
    vk::g_injected_fault = fault;
}

Result<std::unique_ptr<Backend>> create_vulkan_backend() {
    auto device = vk::Device::create();
    if (!device) return device.status();
    auto backend = vk::VulkanBackend::create(std::move(device).value());
    if (!backend) return backend.status();
    return std::unique_ptr<Backend>(std::move(backend).value());
}

bool vulkan_backend_is_cpu_device(const Backend& backend) {
    const auto* vulkan = dynamic_cast<const vk::VulkanBackend*>(&backend);
    return vulkan && vulkan->device().is_cpu();
}

}  // namespace hmsm::detail
