# The CUDA backend (kernels/cuda: one .cu per pass; src/cuda: host side). Included by the top
# CMakeLists after enable_language(CUDA); CMAKE_CUDA_ARCHITECTURES defaults to 90 (H100/H200)
# there, one architecture to keep CI's compile time small. The CUDA runtime is linked
# statically, so binaries need nothing from the toolkit where they run.
find_package(CUDAToolkit REQUIRED)

# One kernel per pass of HMSM_PASSES (top CMakeLists); a missing one stops the configure.
hmsm_pass_sources(_hmsm_pass_kernels kernels/cuda cu)
target_sources(hmsm PRIVATE
  ${_hmsm_pass_kernels}
  src/cuda/cuda_backend.cpp
  src/cuda/cuda_error.cpp
  src/cuda/device_buffers.cpp
  src/cuda/cuda_interop.cpp
  src/cuda/launch_dispatch.cpp
  src/cuda/step_graph.cpp)
target_compile_definitions(hmsm PUBLIC HMSM_HAVE_CUDA=1)
target_link_libraries(hmsm PRIVATE CUDA::cudart_static)
set_target_properties(hmsm PROPERTIES
  CUDA_STANDARD 17
  CUDA_STANDARD_REQUIRED ON)
# -lineinfo: compute-sanitizer and Nsight map reports to source lines (no run-time cost).
target_compile_options(hmsm PRIVATE $<$<COMPILE_LANGUAGE:CUDA>:-lineinfo -Xptxas=-warn-spills>)

# cmake/hmsmConfig.cmake.in: consumers of an installed static hmsm find CUDA::cudart_static.
set(HMSM_HAVE_CUDA_BOOL TRUE)

# Forest throughput of this backend on the lent GPU (tools/gpu/run.sh); not installed.
if(HMSM_BUILD_TOOLS)
  add_executable(hmsm_cuda_throughput tools/gpu/cuda_throughput.cpp)
  target_link_libraries(hmsm_cuda_throughput PRIVATE hmsm::hmsm)
  set_target_properties(hmsm_cuda_throughput PROPERTIES RUNTIME_OUTPUT_DIRECTORY ${PROJECT_BINARY_DIR})
endif()
