// Where a level switch within the capacity builds the switched instances' new chains on the
// device (lod_switch.cpp in the packed layout, placed_layout.cpp in the placed one where the
// backend does not copy patterns; with pattern copies only the templates are staged): in a
// staging area above every chain the layout holds, first a copy of the switched instances' old
// chains, then each switched instance in its new layout, back to back, then a template of each
// new model that unfolds chains (every chain at rest, rest_chains), which the unfolded chains
// are copied from (in the placed layout with pattern copies, kept on the device: TemplateZone).
// The fine-grained copies (a chain or a few each) stay within the staging; the
// live chains are read and written only in whole instances and runs of them (shader copies of
// single chains once seemed to slow the standing step after them, which on the H200 was the
// GPU's clock: docs/vulkan.md).
#pragma once

#include "backend.h"
#include "level_carry.h"
#include "scene_data.h"

#include <cstdint>
#include <utility>
#include <vector>

namespace hmsm::detail {

struct LevelStaging {
    /// A template: a model's chains at rest (rest_chains of the model's Q_c).
    struct Template {
        uint32_t model = 0;
        uint64_t at = 0;  // its first chain
        const std::vector<glm::dmat3>* rest_rotation = nullptr;
    };
    std::vector<uint64_t> old_at;       // per switch, its old chains' copy
    std::vector<uint64_t> instance_at;  // per switch, its first staged chain
    std::vector<int32_t> template_of;   // per switch, its template in `templates`, or -1
    std::vector<Template> templates;    // one per model that unfolds chains
    uint64_t end = 0;                   // the chains the staging needs below it
};

/// Templates kept on the device from switch to switch (the placed layout with pattern copies):
/// every run model of a scene model with levels has its template in a zone at the top of the
/// chain capacity, written once and valid while the capacity stays, the buffers are not laid
/// out anew and no slot reaches the zone (slots are taken upwards: their end only grows until
/// the layout is packed anew).
struct TemplateZone {
    uint64_t capacity = 0;    // the chain capacity they were written for (0: none written)
    uint64_t base = 0;        // the zone's first chain
    std::vector<int64_t> at;  // per run model, its template's first chain, or -1
    void forget() {
        capacity = 0;
        at.clear();
    }
    bool valid_for(uint64_t chain_capacity, uint64_t slots_end) const {
        return capacity != 0 && capacity == chain_capacity && slots_end <= base;
    }
    /// The staging of `models` (index, new run model) carried by `carries` from the zone:
    /// templates only, the slots ending at `slots_end`.
    LevelStaging staging(uint64_t slots_end, const std::vector<std::pair<uint32_t, uint32_t>>& models,
                         const std::vector<const LevelCarry*>& carries) const;
};

/// Adds to `staging` a template for each model of `models` (index, new run model) whose carry
/// unfolds chains, one per model, at `template_at(model)` (asked once per model, in the order
/// the models first appear), and fills template_of.
template <class TemplateAt>
void add_templates(LevelStaging& staging, const std::vector<std::pair<uint32_t, uint32_t>>& models,
                   const std::vector<const LevelCarry*>& carries, TemplateAt&& template_at) {
    for (size_t k = 0; k < models.size(); ++k) {
        const uint32_t model = models[k].second;
        int32_t found = -1;
        if (!carries[k]->unfolded.empty()) {
            for (size_t t = 0; t < staging.templates.size() && found < 0; ++t)
                if (staging.templates[t].model == model) found = int32_t(t);
            if (found < 0) {
                found = int32_t(staging.templates.size());
                staging.templates.push_back({model, template_at(model), &carries[k]->rest_rotation});
            }
        }
        staging.template_of.push_back(found);
    }
}

inline LevelStaging TemplateZone::staging(uint64_t slots_end, const std::vector<std::pair<uint32_t, uint32_t>>& models,
                                          const std::vector<const LevelCarry*>& carries) const {
    LevelStaging out;
    add_templates(out, models, carries, [&](uint32_t model) { return uint64_t(at[model]); });
    out.end = slots_end;
    return out;
}

/// The templates alone from chain `base` on (old_at and instance_at empty): what a switch that
/// copies kept chains straight from slot to slot (Backend::copy_patterns) stages.
inline LevelStaging lay_out_templates(uint64_t base, const std::vector<std::pair<uint32_t, uint32_t>>& models,
                                      const std::vector<ModelRange>& ranges,
                                      const std::vector<const LevelCarry*>& carries) {
    LevelStaging staging;
    uint64_t at = base;
    add_templates(staging, models, carries, [&](uint32_t model) {
        const uint64_t first = at;
        at += ranges[model].chain_count;
        return first;
    });
    staging.end = at;
    return staging;
}

/// The staging from chain `base` on for the switches `models` (instance index, new run model;
/// `from_model` gives an index's run model before the switch) carried by `carries`.
template <class FromModel>
LevelStaging lay_out_staging(uint64_t base, const std::vector<std::pair<uint32_t, uint32_t>>& models,
                             FromModel&& from_model, const std::vector<ModelRange>& ranges,
                             const std::vector<const LevelCarry*>& carries) {
    uint64_t at = base;
    std::vector<uint64_t> old_at, instance_at;
    for (auto [i, model] : models) {
        old_at.push_back(at);
        at += ranges[from_model(i)].chain_count;
    }
    for (auto [i, model] : models) {
        instance_at.push_back(at);
        at += ranges[model].chain_count;
    }
    LevelStaging staging = lay_out_templates(at, models, ranges, carries);
    staging.old_at = std::move(old_at);
    staging.instance_at = std::move(instance_at);
    return staging;
}

/// The moves within the staging that build each switched instance's new chains: the kept
/// chains from its old chains' copy, the unfolded ones from its model's template.
inline void append_build_moves(std::vector<ElementMove>& moves, const LevelStaging& staging,
                               const std::vector<const LevelCarry*>& carries) {
    for (size_t k = 0; k < carries.size(); ++k) {
        const uint64_t from = staging.old_at[k], into = staging.instance_at[k];
        for (const ElementMove& m : carries[k]->kept) moves.push_back({from + m.src, into + m.dst, m.count});
        if (staging.template_of[k] < 0) continue;
        const uint64_t rest = staging.templates[size_t(staging.template_of[k])].at;
        for (const ElementRange& r : carries[k]->unfolded) moves.push_back({rest + r.first, into + r.first, r.count});
    }
}

/// Writes the templates of `staging` in every carried buffer (both halves where a buffer has
/// two), every buffer in one write_buffers, in the backend's scalar.
template <class V>
Status write_templates(Backend& backend, const std::vector<BufferId>& carried, uint64_t capacity, Scalar scalar,
                       const LevelStaging& staging) {
    std::vector<std::vector<ElementRange>> ranges(carried.size());
    std::vector<std::vector<V>> values(carried.size());
    std::vector<BufferRangesWrite> writes;
    for (size_t b = 0; b < carried.size(); ++b) {
        const uint32_t per = shape_scalars(buffer_info(carried[b]).shape);
        const uint32_t halves = halves_of(carried[b]);
        for (const LevelStaging::Template& t : staging.templates) {
            const std::vector<V> rest = rest_chains<V>(*t.rest_rotation, per, carried[b]);
            for (uint32_t h = 0; h < halves; ++h) {
                ranges[b].push_back({h * capacity + t.at, rest.size() / per});
                values[b].insert(values[b].end(), rest.begin(), rest.end());
            }
        }
        writes.push_back({carried[b], ranges[b], values[b].data()});
    }
    return backend.write_buffers(writes, scalar);
}

/// write_templates in the backend's own scalar (double on cpu64), where there are any.
inline Status write_staging_templates(Backend& backend, const std::vector<BufferId>& carried, uint64_t capacity,
                                      Scalar scalar, const LevelStaging& staging) {
    if (staging.templates.empty()) return {};
    return scalar == Scalar::f64 ? write_templates<double>(backend, carried, capacity, scalar, staging)
                                 : write_templates<float>(backend, carried, capacity, scalar, staging);
}

}  // namespace hmsm::detail
