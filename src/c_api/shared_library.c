/* libhmsm.so is linked from every object of libhmsm.a (CMakeLists.txt, hmsm_shared); a CMake
 * library target needs one source of its own, and this is it. */
#include <hmsm/hmsm_c.h>
