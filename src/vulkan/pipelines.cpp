#include "pipelines.h"

#include "vk_error.h"

#include "../common/run_table_layout.h"

#include <algorithm>
#include <vector>

// Generated at build time by cmake/HmsmVulkan.cmake (glslangValidator --vn hmsm_spirv_NAME).
#include "hmsm_spirv/compose.h"
#include "hmsm_spirv/contour.h"
#include "hmsm_spirv/integrate.h"
#include "hmsm_spirv/node_relative.h"
#include "hmsm_spirv/node_world.h"
#include "hmsm_spirv/root_positions.h"
#include "hmsm_spirv/wind_force.h"

namespace hmsm::detail::vk {

std::span<const uint32_t> pass_spirv(Pass pass) {
    switch (pass) {
#define HMSM_PASS_SPIRV(name) \
    case Pass::name: return hmsm_spirv_##name;
        HMSM_PASSES(HMSM_PASS_SPIRV)
#undef HMSM_PASS_SPIRV
    }
    return {};
}

Status storage_buffer_set_layout(const Device& device, uint32_t count, VkDescriptorSetLayout& layout) {
    std::vector<VkDescriptorSetLayoutBinding> bindings(count);
    for (uint32_t b = 0; b < count; ++b) {
        bindings[b].binding = b;
        bindings[b].descriptorType = VK_DESCRIPTOR_TYPE_STORAGE_BUFFER;
        bindings[b].descriptorCount = 1;
        bindings[b].stageFlags = VK_SHADER_STAGE_COMPUTE_BIT;
    }
    VkDescriptorSetLayoutCreateInfo info{VK_STRUCTURE_TYPE_DESCRIPTOR_SET_LAYOUT_CREATE_INFO};
    info.bindingCount = count;
    info.pBindings = bindings.data();
    HMSM_VK_TRY(device.vk().vkCreateDescriptorSetLayout(device.handle(), &info, nullptr, &layout));
    return {};
}

Result<VkPipeline> compute_pipeline(const Device& device, VkPipelineLayout layout, std::span<const uint32_t> code,
                                    const uint32_t* workgroup_size) {
    const VolkDeviceTable& vk = device.vk();
    VkDevice dev = device.handle();
    VkShaderModuleCreateInfo module_info{VK_STRUCTURE_TYPE_SHADER_MODULE_CREATE_INFO};
    module_info.codeSize = code.size_bytes();
    module_info.pCode = code.data();
    VkShaderModule module;
    HMSM_VK_TRY(vk.vkCreateShaderModule(dev, &module_info, nullptr, &module));
    const VkSpecializationMapEntry entry{0, 0, sizeof(uint32_t)};
    VkSpecializationInfo specialization{1, &entry, sizeof(uint32_t), workgroup_size};
    VkComputePipelineCreateInfo info{VK_STRUCTURE_TYPE_COMPUTE_PIPELINE_CREATE_INFO};
    info.stage.sType = VK_STRUCTURE_TYPE_PIPELINE_SHADER_STAGE_CREATE_INFO;
    info.stage.stage = VK_SHADER_STAGE_COMPUTE_BIT;
    info.stage.module = module;
    info.stage.pName = "main";
    if (workgroup_size) info.stage.pSpecializationInfo = &specialization;
    info.layout = layout;
    VkPipeline pipeline = VK_NULL_HANDLE;
    VkResult result = vk.vkCreateComputePipelines(dev, VK_NULL_HANDLE, 1, &info, nullptr, &pipeline);
    vk.vkDestroyShaderModule(dev, module, nullptr);
    HMSM_VK_TRY(result);
    return pipeline;
}

Result<std::unique_ptr<Pipelines>> Pipelines::create(const Device& device) {
    const DeviceLimits& limits = device.limits();
    if (limits.max_storage_buffers_per_stage < kStorageBuffersPerStage ||
        limits.max_storage_buffers_per_set < kStorageBuffersPerStage)
        return Status{ErrorCode::unsupported,
                      "vulkan: " + device.name() + " allows " +
                          std::to_string(limits.max_storage_buffers_per_stage) +
                          " storage buffers per stage (maxPerStageDescriptorStorageBuffers); hmsm needs " +
                          std::to_string(kStorageBuffersPerStage)};
    if (limits.max_push_constants_size < sizeof(gpu::PassConstants))
        return Status{ErrorCode::unsupported, "vulkan: maxPushConstantsSize below " +
                                                  std::to_string(sizeof(gpu::PassConstants))};
    if (limits.max_workgroup_size_x < HMSM_WORKGROUP_SIZE ||
        limits.max_workgroup_invocations < HMSM_WORKGROUP_SIZE)
        return Status{ErrorCode::unsupported, "vulkan: workgroups of " +
                                                  std::to_string(HMSM_WORKGROUP_SIZE) +
                                                  " invocations are not supported by " + device.name()};

    std::unique_ptr<Pipelines> p(new Pipelines(device));
    const VolkDeviceTable& vk = device.vk();
    VkDevice dev = device.handle();

    HMSM_TRY(storage_buffer_set_layout(device, kBufferCount, p->set_layout_));
    HMSM_TRY(storage_buffer_set_layout(device, kRunTableBindings, p->table_set_layout_));

    static_assert(HMSM_RUN_TABLE_SET == 1, "set 0 binds the scene's buffers, set 1 the run table");
    const std::array<VkDescriptorSetLayout, 2> set_layouts{p->set_layout_, p->table_set_layout_};
    VkPushConstantRange push{VK_SHADER_STAGE_COMPUTE_BIT, 0, sizeof(gpu::PassConstants)};
    VkPipelineLayoutCreateInfo layout_info{VK_STRUCTURE_TYPE_PIPELINE_LAYOUT_CREATE_INFO};
    layout_info.setLayoutCount = uint32_t(set_layouts.size());
    layout_info.pSetLayouts = set_layouts.data();
    layout_info.pushConstantRangeCount = 1;
    layout_info.pPushConstantRanges = &push;
    HMSM_VK_TRY(vk.vkCreatePipelineLayout(dev, &layout_info, nullptr, &p->layout_));

    for (Pass pass : kAllPasses) {
        auto pipeline = p->create_pipeline(pass, HMSM_WORKGROUP_SIZE);
        if (!pipeline) return pipeline.status();
        p->pipelines_[uint32_t(pass)] = *pipeline;
    }

    return p;
}

namespace {

/// The hierarchical passes (compose, root_positions) and integrate (its instance sweeps) take
/// their workgroup size as specialization constant 0.
bool has_specialized_workgroup_size(Pass pass) { return is_hierarchical(pass) || pass == Pass::integrate; }

uint32_t rounds_slot(Pass pass) { return pass == Pass::compose ? 0 : pass == Pass::root_positions ? 1 : 2; }

/// Whether a dispatch takes a workgroup per instance, of a size of its own.
bool sized_per_instance(const Dispatch& d) { return runs_rounds_in_dispatch(d) || sweeps_instances(d); }

uint32_t size_index(uint32_t workgroup_size) {
    uint32_t index = 0;
    while ((64u << index) < workgroup_size) ++index;
    return index;
}

}  // namespace

static_assert((64u << 4) == HMSM_MAX_ROUNDS_WORKGROUP_SIZE, "one rounds pipeline per power of two");

Result<VkPipeline> Pipelines::create_pipeline(Pass pass, uint32_t workgroup_size) const {
    return create_pipeline(pass_spirv(pass), has_specialized_workgroup_size(pass), workgroup_size);
}

Result<VkPipeline> Pipelines::create_pipeline(std::span<const uint32_t> code, bool specialized,
                                              uint32_t workgroup_size) const {
    return compute_pipeline(device_, layout_, code, specialized ? &workgroup_size : nullptr);
}

uint32_t Pipelines::per_instance_size(const Dispatch& dispatch) const {
    // The launch shape's size, or the largest power of two below it the device allows (at least
    // HMSM_WORKGROUP_SIZE, checked in create()); the shaders loop over an instance's chains with
    // any size.
    const DeviceLimits& limits = device_.limits();
    const uint32_t device_max = std::min(limits.max_workgroup_size_x, limits.max_workgroup_invocations);
    uint32_t size = launch_shape(dispatch).workgroup_size;
    while (size > device_max) size /= 2;
    return size;
}

Pipelines::Choice Pipelines::pipeline_for(const Dispatch& dispatch) const {
    if (!sized_per_instance(dispatch)) return {pipeline(dispatch.pass), HMSM_WORKGROUP_SIZE};
    const uint32_t size = per_instance_size(dispatch);
    return {rounds_pipelines_[rounds_slot(dispatch.pass)][size_index(size)], size};
}

Status Pipelines::prepare(std::span<const Dispatch> program) {
    for (const Dispatch& dispatch : program) {
        if (!sized_per_instance(dispatch)) continue;
        const uint32_t size = per_instance_size(dispatch);
        VkPipeline& slot = rounds_pipelines_[rounds_slot(dispatch.pass)][size_index(size)];
        if (slot) continue;
        auto pipeline = create_pipeline(dispatch.pass, size);
        if (!pipeline) return pipeline.status();
        slot = *pipeline;
    }
    return {};
}

Pipelines::~Pipelines() {
    const VolkDeviceTable& vk = device_.vk();
    VkDevice dev = device_.handle();
    for (VkPipeline pipeline : pipelines_)
        if (pipeline) vk.vkDestroyPipeline(dev, pipeline, nullptr);
    for (const auto& sizes : rounds_pipelines_)
        for (VkPipeline pipeline : sizes)
            if (pipeline) vk.vkDestroyPipeline(dev, pipeline, nullptr);
    if (layout_) vk.vkDestroyPipelineLayout(dev, layout_, nullptr);
    if (set_layout_) vk.vkDestroyDescriptorSetLayout(dev, set_layout_, nullptr);
    if (table_set_layout_) vk.vkDestroyDescriptorSetLayout(dev, table_set_layout_, nullptr);
}

}  // namespace hmsm::detail::vk
