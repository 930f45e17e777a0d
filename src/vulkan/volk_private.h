// volk, private to hmsm. volk defines one global function pointer per Vulkan entry point
// (vkCreateInstance, ...) and the volk* loader functions; in a library linked into an engine
// those globals would collide with the engine's own Vulkan loader or volk (an engine calling
// vkCreateInstance would jump through hmsm's pointer). hmsm_volk_names.h, generated from volk.h
// by cmake/HmsmVulkan.cmake, renames every one of them to hmsm_vk... / hmsm_volk... for hmsm's
// own sources and for volk.c (src/vulkan/volk_private.c), so libhmsm defines no vk* symbol.
// hmsm's sources include this header, never <volk.h> directly.
#pragma once

#include <hmsm_volk_names.h>
#include <volk.h>
