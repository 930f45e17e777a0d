/* HMSM_API marks hmsm's public functions and classes (C++ and C). The library is compiled with
 * hidden visibility, so only what carries HMSM_API is exported from libhmsm.so (docs/engine.md).
 * Plain C, so hmsm/hmsm_c.h can include it. */
#ifndef HMSM_EXPORT_H
#define HMSM_EXPORT_H

#if defined(_WIN32)
#  if defined(HMSM_BUILDING_LIBRARY) && defined(HMSM_SHARED)
#    define HMSM_API __declspec(dllexport)
#  elif defined(HMSM_SHARED)
#    define HMSM_API __declspec(dllimport)
#  else
#    define HMSM_API
#  endif
#elif defined(__GNUC__) || defined(__clang__)
#  define HMSM_API __attribute__((visibility("default")))
#else
#  define HMSM_API
#endif

#endif /* HMSM_EXPORT_H */
