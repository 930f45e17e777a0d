# The Vulkan backend, include()d by the top CMakeLists.txt when HMSM_VULKAN is AUTO or ON.
#
# Needs glslangValidator (shaders -> SPIR-V at build time), the Vulkan headers and volk
# (Debian's libvulkan-volk-dev ships volk.h and volk.c, which we compile ourselves). The library
# never links libvulkan: volk loads the loader at run time, so a machine without Vulkan still
# runs every other backend. With AUTO a missing piece disables the backend with a message; with
# ON it is an error.

set(_hmsm_vulkan_missing "")

find_program(HMSM_GLSLANG_VALIDATOR NAMES glslangValidator)
if(NOT HMSM_GLSLANG_VALIDATOR)
  list(APPEND _hmsm_vulkan_missing "glslangValidator (glslang-tools)")
endif()

find_package(VulkanHeaders CONFIG QUIET)
if(NOT TARGET Vulkan::Headers)
  find_package(Vulkan QUIET)  # FindVulkan also defines Vulkan::Headers (CMake >= 3.21)
endif()
if(NOT TARGET Vulkan::Headers)
  list(APPEND _hmsm_vulkan_missing "Vulkan headers (libvulkan-dev)")
endif()

find_path(HMSM_VOLK_DIR NAMES volk.h volk.c PATHS /usr/include NO_DEFAULT_PATH)
if(NOT HMSM_VOLK_DIR OR NOT EXISTS "${HMSM_VOLK_DIR}/volk.c")
  list(APPEND _hmsm_vulkan_missing "volk.h and volk.c (libvulkan-volk-dev)")
endif()

if(_hmsm_vulkan_missing)
  list(JOIN _hmsm_vulkan_missing ", " _hmsm_vulkan_missing_text)
  if(HMSM_VULKAN STREQUAL "ON")
    message(FATAL_ERROR "HMSM_VULKAN=ON but the Vulkan backend needs: ${_hmsm_vulkan_missing_text}")
  endif()
  message(STATUS "hmsm: Vulkan backend disabled (missing: ${_hmsm_vulkan_missing_text})")
  return()
endif()

# --- volk: compiled into libhmsm itself (object files), so the installed static library has
# no extra link dependency to export. Device-level calls go through a VolkDeviceTable per
# device; instance-level entry points are volk's globals.
enable_language(C)
add_library(hmsm_volk OBJECT "${HMSM_VOLK_DIR}/volk.c")
target_compile_definitions(hmsm_volk PRIVATE VK_NO_PROTOTYPES)
target_link_libraries(hmsm_volk PRIVATE Vulkan::Headers)
set_target_properties(hmsm_volk PROPERTIES POSITION_INDEPENDENT_CODE ON)

# --- shaders: one SPIR-V header of uint32_t words per pass, generated in the build folder and
# compiled into the library (never committed, never read from disk at run time).
set(HMSM_VULKAN_PASSES wind_force integrate compose node_relative root_positions node_world contour)
set(_hmsm_glsl_dir "${CMAKE_CURRENT_SOURCE_DIR}/shaders/glsl")
set(_hmsm_spirv_dir "${CMAKE_CURRENT_BINARY_DIR}/hmsm_spirv")
file(MAKE_DIRECTORY "${_hmsm_spirv_dir}")
set(_hmsm_spirv_headers "")
# copy_bandwidth is no pass: the device copy `hmsm bench` measures its roofline with.
foreach(pass IN LISTS HMSM_VULKAN_PASSES ITEMS copy_bandwidth)
  set(_out "${_hmsm_spirv_dir}/${pass}.h")
  add_custom_command(
    OUTPUT "${_out}"
    COMMAND "${HMSM_GLSLANG_VALIDATOR}" -V --target-env vulkan1.1 --quiet
            "-I${CMAKE_CURRENT_SOURCE_DIR}/src" "-I${_hmsm_glsl_dir}"
            --vn "hmsm_spirv_${pass}" -o "${_out}" "${_hmsm_glsl_dir}/${pass}.comp"
    DEPENDS "${_hmsm_glsl_dir}/${pass}.comp" "${_hmsm_glsl_dir}/common.glsl"
            "${_hmsm_glsl_dir}/octahedral.glsl"
            "${CMAKE_CURRENT_SOURCE_DIR}/src/gpu_layout.h"
    COMMENT "hmsm: compiling shaders/glsl/${pass}.comp to SPIR-V"
    VERBATIM)
  list(APPEND _hmsm_spirv_headers "${_out}")
endforeach()
add_custom_target(hmsm_spirv DEPENDS ${_hmsm_spirv_headers})

# --- the backend's host side.
set(_hmsm_vulkan_sources
  src/vulkan/vk_error.cpp
  src/vulkan/device.cpp
  src/vulkan/device_buffer.cpp
  src/vulkan/pipelines.cpp
  src/vulkan/recorder.cpp
  src/vulkan/windows.cpp
  src/vulkan/vulkan_backend.cpp
  src/vulkan/copy_bandwidth.cpp
  src/vulkan/interop.cpp)
target_sources(hmsm PRIVATE ${_hmsm_vulkan_sources} $<TARGET_OBJECTS:hmsm_volk>)
# `VkFooCreateInfo info{VK_STRUCTURE_TYPE_FOO}` (zero the rest) is the Vulkan idiom; -Wextra
# would flag every one of them.
set_source_files_properties(${_hmsm_vulkan_sources} PROPERTIES
  COMPILE_OPTIONS -Wno-missing-field-initializers)
add_dependencies(hmsm hmsm_spirv)
target_include_directories(hmsm PRIVATE "${HMSM_VOLK_DIR}" "${CMAKE_CURRENT_BINARY_DIR}")
target_compile_definitions(hmsm PRIVATE VK_NO_PROTOTYPES PUBLIC HMSM_HAVE_VULKAN=1)
# Header-only and build-only: include/hmsm/vulkan.h users bring their own Vulkan headers.
target_link_libraries(hmsm PRIVATE $<BUILD_INTERFACE:Vulkan::Headers> ${CMAKE_DL_LIBS})

# For hmsm's own Vulkan tests (not exported): the private headers of src/ and src/vulkan/.
add_library(hmsm_vulkan_internal INTERFACE)
target_include_directories(hmsm_vulkan_internal INTERFACE
  "${CMAKE_CURRENT_SOURCE_DIR}/src" "${HMSM_VOLK_DIR}")
target_compile_definitions(hmsm_vulkan_internal INTERFACE VK_NO_PROTOTYPES)
target_link_libraries(hmsm_vulkan_internal INTERFACE hmsm Vulkan::Headers)

set(HMSM_HAVE_VULKAN_BOOL TRUE)
message(STATUS "hmsm: Vulkan backend enabled (glslangValidator: ${HMSM_GLSLANG_VALIDATOR})")

# The offscreen renderer draws on the backend's device (cmake/HmsmRender.cmake).
include(${CMAKE_CURRENT_LIST_DIR}/HmsmRender.cmake OPTIONAL)
