// The renderer's camera: an orbit around a target point (yaw about +y, pitch above the
// horizon, distance), framed by default so that a bounding box fills the picture.
#pragma once

#include <glm/glm.hpp>

#include <optional>

namespace hmsm::render {

struct Bounds {
    glm::dvec3 min{0.0}, max{0.0};
    bool empty() const { return !(min.x <= max.x && min.y <= max.y && min.z <= max.z); }
};

/// What the user may set; anything left empty is chosen from the bounds.
struct CameraSettings {
    std::optional<double> distance;  ///< metres from the target
    double yaw_degrees = 0.0;        ///< 0 looks along -z (camera on +z), x to the right
    std::optional<double> pitch_degrees;  ///< above the horizon, looking down; default 8 (forest 15)
    std::optional<glm::dvec3> look_at;
    double fov_degrees = 35.0;       ///< vertical field of view
};

struct Camera {
    glm::dvec3 eye{0.0}, target{0.0};
    double fov_degrees = 35.0;
    double near = 0.1, far = 1000.0;
    glm::dmat4 view{1.0}, projection{1.0};  ///< Vulkan clip space: depth 0..1, y down
    glm::dmat4 view_projection() const { return projection * view; }
};

/// Places the camera: the target defaults to the bounds' centre, the distance to the closest one
/// at which every corner of the bounds lies inside `fill` (0..1) of the picture's half extents.
Camera frame_camera(const Bounds& bounds, const CameraSettings& settings, double aspect,
                    bool forest, double fill = 0.9);

}  // namespace hmsm::render
