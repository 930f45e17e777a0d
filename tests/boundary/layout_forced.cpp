// A consumer that forces GLM's aligned and SIMD types (and is built with -mavx2 where the
// machine has it): hmsm's public structs must keep the library's layout.
#define GLM_FORCE_DEFAULT_ALIGNED_GENTYPES
#define GLM_FORCE_INTRINSICS
#include "layout_fields.h"

#include <glm/vec3.hpp>

// The forcing takes effect: GLM's default dvec3 is now padded to 32 bytes.
static_assert(sizeof(glm::dvec3) == 32 || !GLM_CONFIG_ALIGNED_GENTYPES,
              "GLM_FORCE_DEFAULT_ALIGNED_GENTYPES did not change glm::dvec3");

std::vector<size_t> layout_forced() { return HMSM_LAYOUT_VALUES; }
std::vector<double> simulate_forced()
#include "layout_simulate.inc"
