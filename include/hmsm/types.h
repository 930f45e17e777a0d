// Vector and matrix types of the public API. They are GLM types with an explicit packed
// qualifier, so a consumer's GLM_FORCE_* settings (GLM_FORCE_DEFAULT_ALIGNED_GENTYPES,
// GLM_FORCE_INTRINSICS, ...) cannot change the layout of hmsm's public structs; inside hmsm,
// built with GLM's defaults, they are the same types as glm::dvec3 and glm::dmat3. Units are
// metres unless a field says otherwise; y is up.
#pragma once

#include <glm/mat3x3.hpp>
#include <glm/vec2.hpp>
#include <glm/vec3.hpp>

namespace hmsm {

using Vec2 = glm::vec<2, double, glm::packed_highp>;
using Vec3 = glm::vec<3, double, glm::packed_highp>;
/// Column-major 3x3 matrix acting on column vectors.
using Mat3 = glm::mat<3, 3, double, glm::packed_highp>;

}  // namespace hmsm
