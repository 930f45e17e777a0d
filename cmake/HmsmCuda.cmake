# The CUDA backend (kernels/cuda: one .cu per pass; src/cuda: host side). Included by the top
# CMakeLists after enable_language(CUDA); CMAKE_CUDA_ARCHITECTURES defaults to 90 (H100/H200)
# there, one architecture to keep CI's compile time small.
#
# The CUDA runtime is folded into hmsm: the backend's objects and the static runtime
# (libcudart_static.a) are linked into one relocatable object whose runtime symbols are then
# made local (cmake/fold_cudart.sh). libhmsm.a and libhmsm.so thus carry a private copy of the
# runtime: a consumer links neither the CUDA toolkit nor a CUDA runtime, runs on a machine
# without CUDA (the backend then reports no_device), and an engine that links its own CUDA
# runtime sees no duplicate symbol. The runtime's own needs are system libraries (dl, rt,
# pthread).
find_package(CUDAToolkit REQUIRED)

# One kernel per pass of HMSM_PASSES (top CMakeLists); a missing one stops the configure.
hmsm_pass_sources(_hmsm_pass_kernels kernels/cuda cu)
add_library(hmsm_cuda_objects OBJECT
  ${_hmsm_pass_kernels}
  src/cuda/cuda_backend.cpp
  src/cuda/cuda_error.cpp
  kernels/cuda/copy_ranges.cu
  src/cuda/device_buffers.cpp
  src/cuda/range_transfers.cpp
  src/cuda/host_slot.cpp
  src/cuda/upload_ring.cpp
  src/cuda/cuda_interop.cpp
  src/cuda/launch_dispatch.cpp
  src/cuda/launch_plan.cpp
  src/cuda/step_graph.cpp)
set_target_properties(hmsm_cuda_objects PROPERTIES
  CUDA_STANDARD 17 CUDA_STANDARD_REQUIRED ON
  CXX_VISIBILITY_PRESET hidden CUDA_VISIBILITY_PRESET hidden VISIBILITY_INLINES_HIDDEN ON)
# The library's own compile settings (include paths, HMSM_HAVE_* and HMSM_BUILDING_LIBRARY),
# and the runtime's headers.
target_include_directories(hmsm_cuda_objects PRIVATE
  $<TARGET_PROPERTY:hmsm,INCLUDE_DIRECTORIES>)
target_compile_definitions(hmsm_cuda_objects PRIVATE
  $<TARGET_PROPERTY:hmsm,COMPILE_DEFINITIONS> HMSM_HAVE_CUDA=1)
target_link_libraries(hmsm_cuda_objects PRIVATE glm::glm CUDA::cudart_static)
# -lineinfo: compute-sanitizer and Nsight map reports to source lines (no run-time cost).
target_compile_options(hmsm_cuda_objects PRIVATE $<$<COMPILE_LANGUAGE:CUDA>:-lineinfo -Xptxas=-warn-spills>
                       $<$<COMPILE_LANGUAGE:CXX>:-Wall -Wextra>)

# The backend's objects + the static runtime, partially linked, runtime symbols localized.
get_target_property(_hmsm_cudart_static CUDA::cudart_static IMPORTED_LOCATION)
if(NOT _hmsm_cudart_static)
  find_library(_hmsm_cudart_static NAMES cudart_static HINTS ${CUDAToolkit_LIBRARY_DIR} REQUIRED)
endif()
set(_hmsm_cuda_folded "${CMAKE_CURRENT_BINARY_DIR}/hmsm_cuda_folded.o")
add_custom_command(
  OUTPUT "${_hmsm_cuda_folded}"
  COMMAND "${CMAKE_CURRENT_SOURCE_DIR}/cmake/fold_cudart.sh" "${CMAKE_LINKER}" "${CMAKE_OBJCOPY}"
          "${CMAKE_NM}" "${CMAKE_READELF}" "${_hmsm_cuda_folded}" "${_hmsm_cudart_static}"
          "$<TARGET_OBJECTS:hmsm_cuda_objects>"
  DEPENDS hmsm_cuda_objects $<TARGET_OBJECTS:hmsm_cuda_objects> "${_hmsm_cudart_static}"
          "${CMAKE_CURRENT_SOURCE_DIR}/cmake/fold_cudart.sh"
  COMMAND_EXPAND_LISTS
  COMMENT "hmsm: folding the CUDA runtime into the CUDA backend's objects"
  VERBATIM)
set_source_files_properties("${_hmsm_cuda_folded}" PROPERTIES EXTERNAL_OBJECT TRUE GENERATED TRUE)
target_sources(hmsm PRIVATE "${_hmsm_cuda_folded}")
target_compile_definitions(hmsm PUBLIC HMSM_HAVE_CUDA=1)
# What the runtime itself calls: the dynamic loader, clocks, threads (all in the C library).
target_link_libraries(hmsm PRIVATE ${CMAKE_DL_LIBS} rt Threads::Threads)

set(HMSM_HAVE_CUDA_BOOL TRUE)

# Forest throughput of this backend on the lent GPU (tools/gpu/run.sh); not installed.
if(HMSM_BUILD_TOOLS)
  add_executable(hmsm_cuda_throughput tools/gpu/cuda_throughput.cpp)
  target_link_libraries(hmsm_cuda_throughput PRIVATE hmsm::hmsm)
  set_target_properties(hmsm_cuda_throughput PROPERTIES RUNTIME_OUTPUT_DIRECTORY ${PROJECT_BINARY_DIR})
endif()
