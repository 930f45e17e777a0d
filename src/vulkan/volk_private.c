/* volk.c compiled with hmsm's private names (src/vulkan/volk_private.h). */
#include "volk_private.h"
#include <volk.c>
