// Live control between steps (docs/model.md 3.9): wind, force fields, per-instance settings,
// adding and removing instances.
#include <hmsm/simulation.h>

#include "simulation_impl.h"

#include <cmath>
#include <string>

namespace hmsm {

namespace {

bool finite(const Vec3& v) { return std::isfinite(v.x) && std::isfinite(v.y) && std::isfinite(v.z); }

}  // namespace

Status validate_force_fields(std::span<const ForceField> fields) {
    if (fields.size() > kMaxForceFields)
        return {ErrorCode::invalid_argument, std::to_string(fields.size()) + " force fields: at most " +
                                                 std::to_string(kMaxForceFields) + " may act at once"};
    for (size_t i = 0; i < fields.size(); ++i) {
        const ForceField& f = fields[i];
        const std::string name = "force field " + std::to_string(i);
        if (f.kind != ForceField::Kind::directional && f.kind != ForceField::Kind::radial)
            return {ErrorCode::invalid_argument, name + ": kind must be directional or radial"};
        if (!finite(f.center)) return {ErrorCode::invalid_argument, name + ": center is not finite"};
        if (!std::isfinite(f.radius) || !(f.radius > 0.0))
            return {ErrorCode::invalid_argument, name + ": radius must be finite and > 0"};
        if (!finite(f.directional))
            return {ErrorCode::invalid_argument, name + ": directional is not finite"};
        if (!std::isfinite(f.radial)) return {ErrorCode::invalid_argument, name + ": radial is not finite"};
    }
    return {};
}

namespace {
Status not_yet(const char* what) {
    return {ErrorCode::unsupported, std::string(what) + " is not implemented yet"};
}
}  // namespace

Status Simulation::set_wind(const Wind&) { return not_yet("set_wind"); }
Status Simulation::set_force_fields(std::span<const ForceField>) { return not_yet("set_force_fields"); }
Status Simulation::set_instance_wind_scale(uint64_t, double) { return not_yet("set_instance_wind_scale"); }
Status Simulation::set_instance_wind_phase(uint64_t, double) { return not_yet("set_instance_wind_phase"); }
Status Simulation::set_instance_active(uint64_t, bool) { return not_yet("set_instance_active"); }
Status Simulation::add_instances(std::span<const Instance>) { return not_yet("add_instances"); }
Status Simulation::remove_instances(std::span<const uint64_t>) { return not_yet("remove_instances"); }

}  // namespace hmsm
