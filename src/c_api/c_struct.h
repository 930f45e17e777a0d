// Sized structs of the C ABI (include/hmsm/hmsm_c.h, "Sized structs"): each begins with
// `uint32_t struct_size`, the size of the caller's definition. Fields are only appended, so a
// layout a caller may pass is a prefix of the current struct ending after one of its fields;
// such a struct is read into a full one (the missing fields keep hmsm's defaults) and written
// back only up to the end of its last field. Any other size is refused before anything is read
// or written.
#pragma once

#include "c_api_internal.h"

#include <algorithm>
#include <array>
#include <cstddef>
#include <cstring>
#include <string>
#include <vector>

namespace hmsm::c_api {

struct FieldSpan {
    size_t offset;
    size_t size;
    size_t align;
};

/// A struct_size a caller may pass and the bytes of that layout's fields (no tail padding: the
/// padding of a prefix may overlap the next field of the full struct).
struct KnownLayout {
    size_t struct_size;
    size_t field_bytes;
};

/// The prefix layouts of a struct whose fields are `fields` (fields[0] is struct_size): the
/// k-th ends after fields[k] and is padded to the largest alignment among fields[0..k].
template <size_t N>
constexpr std::array<KnownLayout, N - 1> prefix_layouts(const std::array<FieldSpan, N>& fields) {
    std::array<KnownLayout, N - 1> layouts{};
    size_t align = fields[0].align;
    for (size_t k = 1; k < N; ++k) {
        align = std::max(align, fields[k].align);
        const size_t end = fields[k].offset + fields[k].size;
        layouts[k - 1] = {(end + align - 1) / align * align, end};
    }
    return layouts;
}

/// Every prefix has its own size (else a size could not tell two layouts apart: a new field
/// must grow the struct) and the longest is the struct itself.
template <class T, size_t N>
constexpr bool layouts_are_distinct(const std::array<KnownLayout, N>& layouts) {
    for (size_t k = 1; k < N; ++k)
        if (layouts[k].struct_size <= layouts[k - 1].struct_size) return false;
    return layouts[N - 1].struct_size == sizeof(T) && offsetof(T, struct_size) == 0;
}

#define HMSM_C_FIELD(T, f) FieldSpan{offsetof(T, f), sizeof(T::f), alignof(decltype(T::f))}

template <class T>
struct CStruct;

template <>
struct CStruct<hmsm_wind> {
    static constexpr const char* name = "hmsm_wind";
    static constexpr auto layouts = prefix_layouts(std::array{
        HMSM_C_FIELD(hmsm_wind, struct_size), HMSM_C_FIELD(hmsm_wind, profile),
        HMSM_C_FIELD(hmsm_wind, direction), HMSM_C_FIELD(hmsm_wind, strength),
        HMSM_C_FIELD(hmsm_wind, frequency), HMSM_C_FIELD(hmsm_wind, front_speed),
        HMSM_C_FIELD(hmsm_wind, turbulence), HMSM_C_FIELD(hmsm_wind, seed)});
};
template <>
struct CStruct<hmsm_config> {
    static constexpr const char* name = "hmsm_config";
    static constexpr auto layouts = prefix_layouts(std::array{
        HMSM_C_FIELD(hmsm_config, struct_size), HMSM_C_FIELD(hmsm_config, backend),
        HMSM_C_FIELD(hmsm_config, composition), HMSM_C_FIELD(hmsm_config, vertex_layout),
        HMSM_C_FIELD(hmsm_config, profile_passes), HMSM_C_FIELD(hmsm_config, outputs),
        HMSM_C_FIELD(hmsm_config, model), HMSM_C_FIELD(hmsm_config, parameters),
        HMSM_C_FIELD(hmsm_config, wind), HMSM_C_FIELD(hmsm_config, dynamics),
        HMSM_C_FIELD(hmsm_config, coupled), HMSM_C_FIELD(hmsm_config, instance_layout),
        HMSM_C_FIELD(hmsm_config, exchange)});
};
template <>
struct CStruct<hmsm_instance> {
    static constexpr const char* name = "hmsm_instance";
    static constexpr auto layouts = prefix_layouts(std::array{
        HMSM_C_FIELD(hmsm_instance, struct_size), HMSM_C_FIELD(hmsm_instance, model),
        HMSM_C_FIELD(hmsm_instance, origin), HMSM_C_FIELD(hmsm_instance, yaw),
        HMSM_C_FIELD(hmsm_instance, wind_scale), HMSM_C_FIELD(hmsm_instance, wind_phase),
        HMSM_C_FIELD(hmsm_instance, active), HMSM_C_FIELD(hmsm_instance, level)});
};
template <>
struct CStruct<hmsm_force_field> {
    static constexpr const char* name = "hmsm_force_field";
    static constexpr auto layouts = prefix_layouts(std::array{
        HMSM_C_FIELD(hmsm_force_field, struct_size), HMSM_C_FIELD(hmsm_force_field, kind),
        HMSM_C_FIELD(hmsm_force_field, center), HMSM_C_FIELD(hmsm_force_field, radius),
        HMSM_C_FIELD(hmsm_force_field, directional), HMSM_C_FIELD(hmsm_force_field, radial)});
};
template <>
struct CStruct<hmsm_counts> {
    static constexpr const char* name = "hmsm_counts";
    static constexpr auto layouts = prefix_layouts(std::array{
        HMSM_C_FIELD(hmsm_counts, struct_size), HMSM_C_FIELD(hmsm_counts, instances),
        HMSM_C_FIELD(hmsm_counts, chains), HMSM_C_FIELD(hmsm_counts, nodes),
        HMSM_C_FIELD(hmsm_counts, vertices), HMSM_C_FIELD(hmsm_counts, steps_done),
        HMSM_C_FIELD(hmsm_counts, time)});
};

template <>
struct CStruct<hmsm_level_options> {
    static constexpr const char* name = "hmsm_level_options";
    static constexpr auto layouts = prefix_layouts(std::array{
        HMSM_C_FIELD(hmsm_level_options, struct_size), HMSM_C_FIELD(hmsm_level_options, max_joints)});
};

template <>
struct CStruct<hmsm_instance_placement> {
    static constexpr const char* name = "hmsm_instance_placement";
    static constexpr auto layouts = prefix_layouts(std::array{
        HMSM_C_FIELD(hmsm_instance_placement, struct_size), HMSM_C_FIELD(hmsm_instance_placement, first_chain),
        HMSM_C_FIELD(hmsm_instance_placement, first_node), HMSM_C_FIELD(hmsm_instance_placement, first_vertex)});
};

#undef HMSM_C_FIELD

static_assert(layouts_are_distinct<hmsm_wind>(CStruct<hmsm_wind>::layouts));
static_assert(layouts_are_distinct<hmsm_config>(CStruct<hmsm_config>::layouts));
static_assert(layouts_are_distinct<hmsm_instance>(CStruct<hmsm_instance>::layouts));
static_assert(layouts_are_distinct<hmsm_force_field>(CStruct<hmsm_force_field>::layouts));
static_assert(layouts_are_distinct<hmsm_counts>(CStruct<hmsm_counts>::layouts));
static_assert(layouts_are_distinct<hmsm_level_options>(CStruct<hmsm_level_options>::layouts));
static_assert(layouts_are_distinct<hmsm_instance_placement>(CStruct<hmsm_instance_placement>::layouts));

/// hmsm's defaults in every field, struct_size = sizeof(T), padding zero.
void set_defaults(hmsm_config& out);
void set_defaults(hmsm_wind& out);
void set_defaults(hmsm_instance& out);
void set_defaults(hmsm_force_field& out);
void set_defaults(hmsm_counts& out);
void set_defaults(hmsm_level_options& out);
void set_defaults(hmsm_instance_placement& out);

/// The field bytes of a caller's T of `struct_size` bytes; `what` names it in the message
/// ("hmsm_simulation_create: config").
template <class T>
Status field_bytes(const std::string& what, size_t struct_size, size_t& bytes) {
    constexpr auto& layouts = CStruct<T>::layouts;
    const std::string sizes = std::to_string(struct_size) + " bytes, " + CStruct<T>::name + " is " +
                              std::to_string(sizeof(T)) + " bytes in this library";
    if (struct_size == 0)
        return bad(what + ": struct_size is 0; set it with " + CStruct<T>::name + "'s init function (" +
                   CStruct<T>::name + " is " + std::to_string(sizeof(T)) + " bytes in this library)");
    if (struct_size < layouts.front().struct_size)
        return bad(what + ": struct_size " + sizes + " and its smallest layout " +
                   std::to_string(layouts.front().struct_size) + " bytes");
    if (struct_size > sizeof(T))
        return bad(what + ": struct_size " + sizes + " (a newer header than the library?)");
    for (const KnownLayout& layout : layouts)
        if (layout.struct_size == struct_size) {
            bytes = layout.field_bytes;
            return {};
        }
    return bad(what + ": struct_size " + sizes + ", and no earlier layout has that size");
}

/// The caller's struct at `in` (any known layout) as a full T: its fields, then defaults.
template <class T>
Status read_struct(const std::string& what, const void* in, T& out) {
    uint32_t struct_size = 0;
    std::memcpy(&struct_size, in, sizeof struct_size);
    size_t bytes = 0;
    HMSM_TRY(field_bytes<T>(what, struct_size, bytes));
    T full;
    set_defaults(full);
    std::memcpy(static_cast<void*>(&full), in, bytes);
    full.struct_size = sizeof(T);
    out = full;
    return {};
}

/// Writes `full` into the caller's struct at `out` of layout `struct_size` (checked by the
/// caller with field_bytes): its fields only, struct_size kept.
template <class T>
void write_struct(const T& full, void* out, uint32_t struct_size, size_t bytes) {
    T copy = full;
    copy.struct_size = struct_size;
    std::memcpy(out, &copy, bytes);
}

/// An array of `count` caller structs whose stride is element 0's struct_size; every element
/// must carry the same size.
template <class T>
Status read_array(const std::string& what, const T* items, size_t count, std::vector<T>& out) {
    std::vector<T> converted(count);
    if (count == 0) {
        out = std::move(converted);
        return {};
    }
    const uint32_t stride = items[0].struct_size;
    size_t bytes = 0;
    HMSM_TRY(field_bytes<T>(what + "[0]", stride, bytes));
    const auto* base = reinterpret_cast<const unsigned char*>(items);
    for (size_t i = 0; i < count; ++i) {
        const unsigned char* item = base + i * stride;
        uint32_t size = 0;
        std::memcpy(&size, item, sizeof size);
        if (size != stride)
            return bad(what + "[" + std::to_string(i) + "]: struct_size " + std::to_string(size) +
                       " differs from element 0's " + std::to_string(stride));
        HMSM_TRY(read_struct(what, item, converted[i]));
    }
    out = std::move(converted);
    return {};
}

}  // namespace hmsm::c_api
