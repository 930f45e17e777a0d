#include "windows.h"

#include "vk_error.h"

#include <algorithm>
#include <atomic>
#include <cstdlib>
#include <numeric>

namespace hmsm::detail {
namespace {
std::atomic<uint64_t> g_window_bytes{0};
std::atomic<uint64_t> g_window_alignment{0};
}  // namespace

void vulkan_set_window_bytes(uint64_t bytes, uint64_t alignment) {
    g_window_bytes = bytes;
    g_window_alignment = alignment;
}

namespace vk {
namespace {

constexpr uint64_t element_bytes(BufferId id) { return shape_scalars(buffer_info(id).shape) * 4; }

/// Scopes whose buffers are bound at a per-segment window (state and instance buffers).
bool windowed(Scope s) {
    return s == Scope::instance || s == Scope::chain || s == Scope::chain_halves || s == Scope::node ||
           s == Scope::vertex;
}

/// The scope whose *_begin constant indexes a buffer of scope `s` (halves go with chains).
Scope begin_scope(Scope s) { return s == Scope::chain_halves ? Scope::chain : s; }

/// Per windowed scope: the alignment quantum in elements (a window start that is a multiple of
/// it is aligned for every buffer of the scope) and the largest buffer (element size, name).
struct ScopeRule {
    uint64_t quantum = 1;
    uint64_t max_bytes = 0;  // largest element of the scope's buffers
    std::string_view widest;
};

/// Buffers without elements (outputs the simulation does not produce) take no part.
ScopeRule scope_rule(const SceneData& scene, Scope scope, uint64_t alignment, bool halves_only = false) {
    ScopeRule rule;
    for (const BufferInfo& info : kBufferTable) {
        Scope s = info.scope;
        bool member = halves_only ? s == Scope::chain_halves : begin_scope(s) == scope;
        if (!member || scene.element_count(info.id) == 0) continue;
        const uint64_t eb = element_bytes(info.id);
        rule.quantum = std::lcm(rule.quantum, alignment / std::gcd(alignment, eb));
        if (eb > rule.max_bytes) {
            rule.max_bytes = eb;
            rule.widest = info.name;
        }
    }
    return rule;
}

uint64_t round_up(uint64_t v, uint64_t q) { return (v + q - 1) / q * q; }

}  // namespace

Result<WindowPlan> WindowPlan::build(const SceneData& scene, uint64_t window_bytes, uint64_t alignment,
                                     const std::string& device_name) {
    WindowPlan plan;
    plan.window_bytes_ = window_bytes;
    plan.total_chains_ = scene.chain_capacity;  // logical half h starts at h * chain_capacity
    for (const InstanceGroup& g : scene.groups) plan.group_instances_[g.instance_begin] = g.instance_count;
    alignment = std::max<uint64_t>(alignment, 1);

    // Everything within one window: one segment, the unsplit layout.
    bool fits = true;
    for (const BufferInfo& info : kBufferTable)
        if (windowed(info.scope) && scene.element_count(info.id) * element_bytes(info.id) > window_bytes)
            fits = false;
    if (fits) {
        Segment s;
        s.instance_begin = 0;
        // The window covers the allocated capacity (instances added later fit in it).
        s.instance_end = scene.instance_count();
        s.instance = {0, 0, scene.instance_capacity};
        s.chain = {0, 0, scene.chain_capacity};
        s.node = {0, 0, scene.node_capacity};
        s.vertex = {0, 0, scene.vertex_capacity};
        s.halves_base = 0;
        s.halves_stride = scene.chain_capacity;
        plan.segments_.push_back(s);
        plan.physical_halves_ = 2 * scene.chain_capacity;
        return plan;
    }

    plan.windowed_ = true;
    const ScopeRule instance_rule = scope_rule(scene, Scope::instance, alignment);
    const ScopeRule chain_rule = scope_rule(scene, Scope::chain, alignment);
    const ScopeRule halves_rule = scope_rule(scene, Scope::chain, alignment, true);
    const ScopeRule node_rule = scope_rule(scene, Scope::node, alignment);
    const ScopeRule vertex_rule = scope_rule(scene, Scope::vertex, alignment);

    // Bytes the windows of `s` need per scope, and the first that does not fit (or empty).
    auto overflow = [&](const Segment& s, uint64_t& needed) -> std::string_view {
        struct Check {
            uint64_t bytes;
            std::string_view name;
        };
        const Check checks[] = {
            {(s.instance.end - s.instance.base) * instance_rule.max_bytes, instance_rule.widest},
            {(s.chain.end - s.chain.base) * chain_rule.max_bytes, chain_rule.widest},
            {2 * round_up(s.chain.end - s.chain.base, chain_rule.quantum) * halves_rule.max_bytes,
             halves_rule.widest},
            {(s.node.end - s.node.base) * node_rule.max_bytes, node_rule.widest},
            {(s.vertex.end - s.vertex.base) * vertex_rule.max_bytes, vertex_rule.widest},
        };
        for (const Check& c : checks)
            if (c.bytes > window_bytes) {
                needed = c.bytes;
                return c.name;
            }
        return {};
    };
    auto start = [&](uint32_t instance, uint64_t chain, uint64_t node, uint64_t vertex) {
        Segment s;
        s.instance_begin = s.instance_end = instance;
        auto open = [](uint64_t begin, uint64_t quantum) {
            uint64_t base = begin / quantum * quantum;
            return ScopeWindow{base, begin, begin};
        };
        s.instance = open(instance, instance_rule.quantum);
        s.chain = open(chain, chain_rule.quantum);
        s.node = open(node, node_rule.quantum);
        s.vertex = open(vertex, vertex_rule.quantum);
        return s;
    };
    auto close = [&](Segment& s) {
        s.halves_base = plan.physical_halves_;
        s.halves_stride = round_up(s.chain.end - s.chain.base, chain_rule.quantum);
        plan.physical_halves_ += 2 * s.halves_stride;
        plan.segments_.push_back(s);
    };

    Segment current = start(0, 0, 0, 0);
    for (const InstanceGroup& g : scene.groups) {
        const ModelRange& m = scene.models[g.model];
        for (uint32_t k = 0; k < g.instance_count; ++k) {
            const uint32_t instance = g.instance_begin + k;
            const uint64_t chain = g.chain_begin + uint64_t(k) * m.chain_count;
            const uint64_t node = g.node_begin + uint64_t(k) * m.node_count;
            const uint64_t vertex = g.vertex_begin + uint64_t(k) * m.vertex_count;
            Segment grown = current;
            grown.instance_end = instance + 1;
            grown.instance.end = instance + 1;
            grown.chain.end = chain + m.chain_count;
            grown.node.end = node + m.node_count;
            grown.vertex.end = vertex + m.vertex_count;
            uint64_t needed = 0;
            if (overflow(grown, needed).empty()) {
                current = grown;
                continue;
            }
            if (current.instance_end > current.instance_begin) {
                close(current);
                current = start(instance, chain, node, vertex);
                grown = current;
                grown.instance_end = instance + 1;
                grown.instance.end = instance + 1;
                grown.chain.end = chain + m.chain_count;
                grown.node.end = node + m.node_count;
                grown.vertex.end = vertex + m.vertex_count;
            }
            std::string_view buffer = overflow(grown, needed);
            if (!buffer.empty())
                return Status{ErrorCode::unsupported,
                              "vulkan: instance " + std::to_string(instance) + " alone needs " +
                                  std::to_string(needed) + " bytes of buffer " + std::string(buffer) +
                                  " in one binding, more than the " + std::to_string(window_bytes) +
                                  "-byte window (maxStorageBufferRange) of " + device_name};
            current = grown;
        }
    }
    if (current.instance_end > current.instance_begin || plan.segments_.empty()) close(current);
    return plan;
}

uint64_t WindowPlan::physical_elements(BufferId id, const SceneData& scene) const {
    if (buffer_info(id).scope == Scope::chain_halves) return physical_halves_;
    return scene.element_count(id);
}

std::vector<WindowPlan::Piece> WindowPlan::pieces(BufferId id, uint64_t first, uint64_t count) const {
    if (count == 0) return {};
    if (!split() || buffer_info(id).scope != Scope::chain_halves) return {{first, first, count}};
    std::vector<Piece> out;
    const uint64_t total = total_chains_;
    for (uint64_t e = first, end = first + count; e < end;) {
        const uint64_t half = e / total, chain = e % total;
        // The segment holding `chain`: the last with chain.begin <= chain and chain.end > chain.
        auto it = std::upper_bound(segments_.begin(), segments_.end(), chain,
                                   [](uint64_t c, const Segment& s) { return c < s.chain.begin; });
        while (it != segments_.begin() && (it - 1)->chain.end <= chain) --it;
        const Segment& s = *(it - 1);
        const uint64_t n = std::min(end - e, s.chain.end - chain);
        out.push_back({e, s.halves_base + half * s.halves_stride + (chain - s.chain.base), n});
        e += n;
    }
    return out;
}

WindowPlan::Range WindowPlan::window(BufferId id, uint32_t index) const {
    const Segment& s = segments_[index];
    const uint64_t eb = element_bytes(id);
    switch (buffer_info(id).scope) {
        case Scope::instance: return {s.instance.base * eb, (s.instance.end - s.instance.base) * eb};
        case Scope::chain: return {s.chain.base * eb, (s.chain.end - s.chain.base) * eb};
        case Scope::chain_halves: return {s.halves_base * eb, 2 * s.halves_stride * eb};
        case Scope::node: return {s.node.base * eb, (s.node.end - s.node.base) * eb};
        case Scope::vertex: return {s.vertex.base * eb, (s.vertex.end - s.vertex.base) * eb};
        default: return {};
    }
}

uint32_t WindowPlan::dispatch_instances(const Dispatch& d) const {
    const gpu::PassConstants& c = d.constants;
    // Threads per instance by pass and kind. A dispatch may cover part of a group (the runs of
    // active instances, tests), so the group's own count holds only where the threads match it.
    const uint32_t per = threads_per_instance(d);
    if (auto it = group_instances_.find(c.instance_begin);
        it != group_instances_.end() && uint64_t(it->second) * per == c.element_count)
        return it->second;
    return per ? c.element_count / per : 0;
}

void WindowPlan::for_each_part_split(
    const Dispatch& d, const std::function<void(uint32_t, const gpu::PassConstants&)>& part) const {
    const gpu::PassConstants& c = d.constants;
    const uint32_t instances = dispatch_instances(d);
    if (instances == 0 || c.element_count == 0) return;
    const uint32_t per_instance = c.element_count / instances;
    auto it = std::upper_bound(segments_.begin(), segments_.end(), c.instance_begin,
                               [](uint32_t i, const Segment& s) { return i < s.instance_begin; });
    uint32_t index = uint32_t(it - segments_.begin()) - 1;
    for (uint32_t a = c.instance_begin, end = c.instance_begin + instances; a < end; ++index) {
        const Segment& s = segments_[index];
        const uint32_t b = std::min(end, s.instance_end);
        const uint64_t k = a - c.instance_begin;
        gpu::PassConstants p = c;
        p.element_count = (b - a) * per_instance;
        p.instance_begin = uint32_t(a - s.instance.base);
        p.chain_begin = uint32_t(c.chain_begin + k * c.model_chain_count - s.chain.base);
        p.node_begin = uint32_t(c.node_begin + k * c.model_node_count - s.node.base);
        p.vertex_begin = uint32_t(c.vertex_begin + k * c.model_vertex_count - s.vertex.base);
        p.total_chains = uint32_t(s.halves_stride);
        part(index, p);
        a = b;
    }
}

std::vector<WindowPlan::Part> WindowPlan::expand(std::span<const Dispatch> program) const {
    std::vector<Part> parts;
    parts.reserve(program.size());
    for (const Dispatch& d : program) {
        const size_t first = parts.size();
        for_each_part(d, [&](uint32_t segment, const gpu::PassConstants& c) {
            parts.push_back({Dispatch{d.pass, c}, segment, false});
        });
        if (parts.size() == first) parts.push_back({d, 0, false});
        parts.back().last = true;
    }
    return parts;
}

Result<std::unique_ptr<WindowSets>> WindowSets::create(const Device& device, VkDescriptorSetLayout layout,
                                                       const WindowPlan& plan,
                                                       std::span<const Buffer, kBufferCount> buffers) {
    std::unique_ptr<WindowSets> w(new WindowSets(device));
    const VolkDeviceTable& vk = device.vk();
    const uint32_t count = uint32_t(plan.segments().size());
    VkDescriptorPoolSize size{VK_DESCRIPTOR_TYPE_STORAGE_BUFFER, count * kBufferCount};
    VkDescriptorPoolCreateInfo pool_info{VK_STRUCTURE_TYPE_DESCRIPTOR_POOL_CREATE_INFO};
    pool_info.maxSets = count;
    pool_info.poolSizeCount = 1;
    pool_info.pPoolSizes = &size;
    HMSM_VK_TRY(vk.vkCreateDescriptorPool(device.handle(), &pool_info, nullptr, &w->pool_));
    std::vector<VkDescriptorSetLayout> layouts(count, layout);
    w->sets_.resize(count);
    VkDescriptorSetAllocateInfo allocate{VK_STRUCTURE_TYPE_DESCRIPTOR_SET_ALLOCATE_INFO};
    allocate.descriptorPool = w->pool_;
    allocate.descriptorSetCount = count;
    allocate.pSetLayouts = layouts.data();
    HMSM_VK_TRY(vk.vkAllocateDescriptorSets(device.handle(), &allocate, w->sets_.data()));

    for (uint32_t s = 0; s < count; ++s) {
        std::array<VkDescriptorBufferInfo, kBufferCount> infos{};
        std::array<VkWriteDescriptorSet, kBufferCount> writes{};
        for (uint32_t b = 0; b < kBufferCount; ++b) {
            const Buffer& buffer = buffers[b];
            WindowPlan::Range range = plan.window(BufferId(b), s);
            if (!plan.split() || range.bytes == 0 || buffer.size() == 0) {
                // Static model buffers, the unsplit scene, a scope the segment has no element
                // of, and a buffer without elements (an output the simulation does not
                // produce): the whole buffer, or its first element when that is too large.
                const bool whole = buffer.size() <= device.limits().max_storage_buffer_range;
                infos[b] = {buffer.handle(), 0, whole ? VK_WHOLE_SIZE : VkDeviceSize(16)};
            } else {
                infos[b] = {buffer.handle(), range.offset, range.bytes};
            }
            writes[b].sType = VK_STRUCTURE_TYPE_WRITE_DESCRIPTOR_SET;
            writes[b].dstSet = w->sets_[s];
            writes[b].dstBinding = b;
            writes[b].descriptorCount = 1;
            writes[b].descriptorType = VK_DESCRIPTOR_TYPE_STORAGE_BUFFER;
            writes[b].pBufferInfo = &infos[b];
        }
        vk.vkUpdateDescriptorSets(device.handle(), kBufferCount, writes.data(), 0, nullptr);
    }
    return w;
}

WindowSets::~WindowSets() {
    if (pool_) device_.vk().vkDestroyDescriptorPool(device_.handle(), pool_, nullptr);
}

uint64_t requested_window_alignment() { return g_window_alignment.load(); }

uint64_t requested_window_bytes() {
    if (uint64_t hook = g_window_bytes.load()) return hook;
    if (const char* env = std::getenv("HMSM_VULKAN_WINDOW_BYTES")) {
        char* end = nullptr;
        unsigned long long v = std::strtoull(env, &end, 10);
        if (end != env && *end == '\0') return v;
    }
    return 0;
}

}  // namespace vk
}  // namespace hmsm::detail
