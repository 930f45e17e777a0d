# The runtime's layering: inside src/ and kernels/ only the files that implement the façade
# include <hmsm/simulation.h> (or the umbrella <hmsm/hmsm.h>); everything else takes the
# configuration vocabulary from <hmsm/config.h>. (Sources that implement a public API over a
# Simulation reach it through that API's header: schedules, the Vulkan and CUDA interop.)
# Usage: cmake -DROOT=<source dir> -P check_facade_includes.cmake
cmake_minimum_required(VERSION 3.25)
set(_allowed
  src/simulation.cpp          # Simulation's members
  src/simulation_impl.h       # Simulation::Impl, shared by the façade's sources
  src/live_control.cpp        # Simulation's live-control members
  src/simulation_read.cpp     # Simulation's read members
  src/c_api/c_api_internal.h  # the C ABI over Simulation
)
if(NOT ROOT)
  message(FATAL_ERROR "usage: cmake -DROOT=<source dir> -P check_facade_includes.cmake")
endif()
set(_facade_include "^[ \t]*#[ \t]*include[ \t]*[<\"]hmsm/(simulation|hmsm)\\.h[>\"]")
file(GLOB_RECURSE _files RELATIVE "${ROOT}" "${ROOT}/src/*" "${ROOT}/kernels/*")
set(_violations "")
set(_seen "")
foreach(_file IN LISTS _files)
  file(STRINGS "${ROOT}/${_file}" _lines REGEX "${_facade_include}")
  if(NOT _lines)
    continue()
  endif()
  if(_file IN_LIST _allowed)
    list(APPEND _seen "${_file}")
  else()
    list(APPEND _violations "${_file}")
  endif()
endforeach()
if(_violations)
  list(JOIN _violations ", " _list)
  message(FATAL_ERROR "the façade <hmsm/simulation.h> (or <hmsm/hmsm.h>) is included by ${_list}: "
                      "include <hmsm/config.h> for the configuration vocabulary instead")
endif()
# Every allowed file exists and includes the façade, so the pattern is known to match and the
# list names no file that no longer needs it.
foreach(_file IN LISTS _allowed)
  if(NOT _file IN_LIST _seen)
    message(FATAL_ERROR "${_file} is allowed to include the façade but does not (or is missing): "
                        "remove it from the list in check_facade_includes.cmake")
  endif()
endforeach()
list(LENGTH _files _count)
message(STATUS "façade includes: ${_count} files under src/ and kernels/ checked")
