// Shared by the C ABI's sources (include/hmsm/hmsm_c.h): the handle types, conversions between
// the C structs and the C++ ones, and the guard that turns every outcome into a status code and
// the calling thread's last message.
#pragma once

#include <hmsm/hmsm.h>
#include <hmsm/hmsm_c.h>
#include <hmsm/skin.h>

#include <cmath>
#include <cstring>
#include <memory>
#include <new>
#include <string>
#include <vector>

struct hmsm_tree {
    hmsm::TreeModel model;
};
struct hmsm_scene {
    hmsm::Scene scene;
};
struct hmsm_simulation {
    std::unique_ptr<hmsm::Simulation> simulation;
};
struct hmsm_skin {
    hmsm::SkinTemplate skin;
};

namespace hmsm::c_api {

/// Records `status` as the calling thread's last status and returns its code.
hmsm_status report(const Status& status);

inline Status bad(std::string message) { return {ErrorCode::invalid_argument, std::move(message)}; }

/// Reads and converts `count` caller instances (each struct_size-checked) for function `fn`.
Status read_instances(const char* fn, const hmsm_instance* instances, size_t count, std::vector<Instance>& out);

/// Runs `body` (returning a Status) so that no exception leaves it.
template <class Body>
hmsm_status guarded(Body&& body) noexcept {
    try {
        return report(body());
    } catch (const std::bad_alloc&) {
        return report({ErrorCode::out_of_memory, "out of host memory"});
    } catch (...) {
        return report({ErrorCode::internal, "unexpected exception inside hmsm"});
    }
}

/// The common shape of a read into a caller buffer: `*count` always receives the size needed;
/// values == NULL with capacity 0 is a size query.
template <class T>
inline Status copy_out(const char* fn, const std::vector<T>& source, T* values, size_t capacity,
                size_t* count) {
    if (!count) return bad(std::string(fn) + ": count is NULL");
    *count = source.size();
    if (!values && capacity == 0) return {};
    if (!values)
        return bad(std::string(fn) + ": values is NULL with capacity " + std::to_string(capacity));
    if (capacity < source.size())
        return bad(std::string(fn) + ": capacity " + std::to_string(capacity) + " is too small, " +
                   std::to_string(source.size()) + " needed");
    if (!source.empty()) std::memcpy(values, source.data(), source.size() * sizeof(T));
    return {};
}

inline bool finite3(const double v[3]) {
    return std::isfinite(v[0]) && std::isfinite(v[1]) && std::isfinite(v[2]);
}

Status to_cpp(const hmsm_wind& in, Wind& out);
void to_c(const Wind& in, hmsm_wind& out);
Status to_cpp(const hmsm_instance& in, Instance& out, const char* what);
void to_c(const Instance& in, hmsm_instance& out);
Status to_cpp(const hmsm_force_field& in, ForceField& out, const char* what);
Status to_cpp(const hmsm_config& in, SimulationConfig& out);
Status to_output(int32_t output, Output& out);

}  // namespace hmsm::c_api
