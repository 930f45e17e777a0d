#include "listed_groups.h"

#include <algorithm>
#include <atomic>
#include <cstdlib>
#include <string_view>

namespace hmsm::detail {
namespace {

std::atomic<int> g_listing_mode{-1};

/// HMSM_LIST_INSTANCES from the environment, read once: 0 never, 1 always, else -1 (by size).
int environment_mode() {
    static const int mode = [] {
        const char* value = std::getenv("HMSM_LIST_INSTANCES");
        if (!value) return -1;
        const std::string_view v(value);
        return v == "0" ? 0 : v == "1" ? 1 : -1;
    }();
    return mode;
}

constexpr uint64_t kMaxTableWord = 0x7fffffffu;

}  // namespace

void set_listing_for_tests(int mode) { g_listing_mode = mode; }

bool listing_pays(size_t contiguous, size_t listed) {
    const int hook = g_listing_mode.load();
    const int mode = hook >= 0 ? hook : environment_mode();
    if (mode == 0 || mode == 1) return mode == 1;
    return contiguous >= kListedGroupsFrom && contiguous >= 4 * listed;
}

bool scene_can_be_listed(const SceneData& d) {
    return d.chain_capacity <= kMaxTableWord && d.node_capacity <= kMaxTableWord &&
           d.vertex_capacity <= kMaxTableWord && d.instance_capacity <= kMaxTableWord;
}

void append_listed_groups(const SceneData& d, uint32_t model, uint32_t begin, uint32_t end,
                          std::vector<InstanceGroup>& into) {
    const ModelRange& m = d.models[model];
    const uint64_t per_instance =
        std::max({uint64_t(1), uint64_t(m.chain_count), uint64_t(m.node_count), uint64_t(m.vertex_count)});
    const uint32_t most = uint32_t(std::max<uint64_t>(1, kMaxGroupElements / per_instance));
    for (uint32_t at = begin; at < end;) {
        InstanceGroup g;
        g.model = model;
        g.instance_begin = at;
        g.instance_count = std::min(most, end - at);
        g.listed = true;
        into.push_back(g);
        at += g.instance_count;
    }
}

void list_groups(const SceneData& d, std::span<const InstanceGroup> groups, std::span<const Instance> instances,
                 ListedGroups& into, const InstancePlacements* placed) {
    auto active = [&](const InstanceGroup& g, uint32_t k) {
        return !g.covers_paused || instances[g.instance_begin + k].active;
    };
    // Entries per model, then each model's first entry.
    std::vector<uint32_t> next(d.models.size() + 1, 0);
    for (const InstanceGroup& g : groups) {
        if (!g.covers_paused) {
            next[g.model + 1] += g.instance_count;
            continue;
        }
        for (uint32_t k = 0; k < g.instance_count; ++k) next[g.model + 1] += active(g, k) ? 1u : 0u;
    }
    for (size_t m = 1; m < next.size(); ++m) next[m] += next[m - 1];
    const std::vector<uint32_t> first(next.begin(), next.end() - 1);
    into.table.resize(size_t(4) * next.back());  // every entry is written below
    for (const InstanceGroup& g : groups) {
        const ModelRange& m = d.models[g.model];
        for (uint32_t k = 0; k < g.instance_count; ++k) {
            if (!active(g, k)) continue;
            double* entry = &into.table[size_t(4) * next[g.model]++];
            if (placed) {
                const ElementCounts& at = (*placed)[g.instance_begin + k];
                entry[0] = double(at.chains);
                entry[1] = double(at.nodes);
                entry[2] = double(at.vertices);
            } else {
                entry[0] = double(g.chain_begin + uint64_t(k) * m.chain_count);
                entry[1] = double(g.node_begin + uint64_t(k) * m.node_count);
                entry[2] = double(g.vertex_begin + uint64_t(k) * m.vertex_count);
            }
            entry[3] = double(g.instance_begin + k);
        }
    }
    into.groups.clear();
    for (uint32_t model = 0; model < d.models.size(); ++model)
        append_listed_groups(d, model, first[model], next[model], into.groups);
}

void list_instances(const SceneData& d, std::span<const uint32_t> indices, std::span<const Instance> instances,
                    const InstancePlacements& placed, ListedGroups& into) {
    std::vector<uint32_t> next(d.models.size() + 1, 0);  // entries per model, then each model's next
    for (uint32_t i : indices) ++next[instances[i].model + 1];
    for (size_t m = 1; m < next.size(); ++m) next[m] += next[m - 1];
    const std::vector<uint32_t> first(next.begin(), next.end() - 1);
    into.table.resize(size_t(4) * indices.size());
    for (uint32_t i : indices) {
        double* entry = &into.table[size_t(4) * next[instances[i].model]++];
        entry[0] = double(placed[i].chains);
        entry[1] = double(placed[i].nodes);
        entry[2] = double(placed[i].vertices);
        entry[3] = double(i);
    }
    into.groups.clear();
    for (uint32_t model = 0; model < d.models.size(); ++model)
        append_listed_groups(d, model, first[model], next[model], into.groups);
}

}  // namespace hmsm::detail
