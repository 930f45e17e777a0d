# The offscreen renderer (tools/render/, `hmsm render`; not part of the library), include()d at the end of HmsmVulkan.cmake
# once the Vulkan backend is enabled. It draws with a Vulkan graphics pipeline on the backend's
# device; shaders/glsl/render/ are compiled to embedded SPIR-V like the compute passes. Needs
# libpng (frames) and giflib (animated GIF); without them the renderer is skipped with a message.
find_package(PNG QUIET)
find_path(HMSM_GIF_INCLUDE_DIR NAMES gif_lib.h)
find_library(HMSM_GIF_LIBRARY NAMES gif)
if(NOT PNG_FOUND OR NOT HMSM_GIF_INCLUDE_DIR OR NOT HMSM_GIF_LIBRARY)
  message(STATUS "hmsm: renderer disabled (needs libpng-dev and libgif-dev)")
  return()
endif()

set(_hmsm_render_glsl_dir "${CMAKE_CURRENT_SOURCE_DIR}/shaders/glsl/render")
set(_hmsm_render_spirv_dir "${CMAKE_CURRENT_BINARY_DIR}/hmsm_spirv/render")
file(MAKE_DIRECTORY "${_hmsm_render_spirv_dir}")
set(_hmsm_render_spirv_headers "")
foreach(shader mesh.vert mesh.frag skinned.vert backdrop.vert backdrop.frag)
  string(REPLACE "." "_" _name "${shader}")
  set(_out "${_hmsm_render_spirv_dir}/${_name}.h")
  add_custom_command(
    OUTPUT "${_out}"
    COMMAND "${HMSM_GLSLANG_VALIDATOR}" -V --target-env vulkan1.1 --quiet
            "-I${_hmsm_render_glsl_dir}" "-I${CMAKE_CURRENT_SOURCE_DIR}/shaders/glsl" --vn "hmsm_spirv_render_${_name}"
            -o "${_out}" "${_hmsm_render_glsl_dir}/${shader}"
    DEPENDS "${_hmsm_render_glsl_dir}/${shader}" "${_hmsm_render_glsl_dir}/render_common.glsl"
            "${CMAKE_CURRENT_SOURCE_DIR}/shaders/glsl/octahedral.glsl"
            "${CMAKE_CURRENT_SOURCE_DIR}/shaders/glsl/skinning.glsl"
    COMMENT "hmsm: compiling shaders/glsl/render/${shader} to SPIR-V"
    VERBATIM)
  list(APPEND _hmsm_render_spirv_headers "${_out}")
endforeach()
add_custom_target(hmsm_render_spirv DEPENDS ${_hmsm_render_spirv_headers})

# Not installed: a tool-side library for `hmsm render` and its tests.
set(_hmsm_render_sources
  tools/render/camera.cpp
  tools/render/image_io.cpp
  tools/render/renderer.cpp
  tools/render/resources.cpp
  tools/render/vertex_sources.cpp
  tools/render/frame.cpp
  tools/render/skinned.cpp)
add_library(hmsm_render STATIC ${_hmsm_render_sources})
set_source_files_properties(${_hmsm_render_sources} PROPERTIES
  COMPILE_OPTIONS -Wno-missing-field-initializers)
add_dependencies(hmsm_render hmsm_render_spirv)
target_include_directories(hmsm_render PUBLIC "${CMAKE_CURRENT_SOURCE_DIR}/tools"
                           PRIVATE "${CMAKE_CURRENT_BINARY_DIR}" "${HMSM_GIF_INCLUDE_DIR}")
target_link_libraries(hmsm_render PUBLIC hmsm_vulkan_internal PRIVATE PNG::PNG ${HMSM_GIF_LIBRARY})
target_compile_options(hmsm_render PRIVATE -Wall -Wextra)
set(HMSM_HAVE_RENDER_BOOL TRUE)
message(STATUS "hmsm: renderer enabled (libpng ${PNG_VERSION_STRING}, giflib)")
