#include "render/camera.h"

#include <glm/gtc/matrix_transform.hpp>

#include <algorithm>
#include <cmath>

namespace hmsm::render {

Camera frame_camera(const Bounds& bounds, const CameraSettings& s, double aspect, bool forest,
                    double fill) {
    Camera camera;
    camera.fov_degrees = s.fov_degrees;
    const glm::dvec3 centre = 0.5 * (bounds.min + bounds.max);
    camera.target = s.look_at.value_or(centre);
    const double yaw = glm::radians(s.yaw_degrees);
    const double pitch = glm::radians(s.pitch_degrees.value_or(forest ? 15.0 : 8.0));
    // From the target towards the eye.
    const glm::dvec3 back(std::sin(yaw) * std::cos(pitch), std::sin(pitch),
                          std::cos(yaw) * std::cos(pitch));
    const glm::dvec3 forward = -back;
    const glm::dvec3 right = glm::normalize(glm::cross(forward, glm::dvec3(0, 1, 0)));
    const glm::dvec3 up = glm::cross(right, forward);
    const double tan_y = std::tan(0.5 * glm::radians(s.fov_degrees)) * fill;
    const double tan_x = tan_y * aspect;

    double distance = 1.0;
    if (s.distance) {
        distance = *s.distance;
    } else {
        // Corner r (relative to the target) sits at depth d + r.forward; it is inside the
        // frame when |r.right| <= tan_x * depth and |r.up| <= tan_y * depth.
        for (int k = 0; k < 8; ++k) {
            const glm::dvec3 corner((k & 1) ? bounds.max.x : bounds.min.x,
                                    (k & 2) ? bounds.max.y : bounds.min.y,
                                    (k & 4) ? bounds.max.z : bounds.min.z);
            const glm::dvec3 r = corner - camera.target;
            distance = std::max(distance, std::abs(glm::dot(r, right)) / tan_x - glm::dot(r, forward));
            distance = std::max(distance, std::abs(glm::dot(r, up)) / tan_y - glm::dot(r, forward));
        }
    }
    camera.eye = camera.target + back * distance;
    const double radius = 0.5 * glm::length(bounds.max - bounds.min);
    camera.near = std::max(0.01, std::min(0.05 * distance, distance - 1.5 * radius));
    camera.far = 40.0 * (distance + radius);
    camera.view = glm::lookAtRH(camera.eye, camera.target, up);
    camera.projection = glm::perspectiveRH_ZO(glm::radians(s.fov_degrees), aspect, camera.near, camera.far);
    camera.projection[1][1] *= -1.0;  // Vulkan's framebuffer y points down
    return camera;
}

}  // namespace hmsm::render
