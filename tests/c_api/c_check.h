/* What the C ABI tests share: a failure count and the checks that add to it. Included once per
   test program (each is one translation unit). */
#ifndef HMSM_TESTS_C_CHECK_H
#define HMSM_TESTS_C_CHECK_H

#include <hmsm/hmsm_c.h>

#include <stdio.h>

static int failures = 0;

#define CHECK(cond)                                                                  \
    do {                                                                             \
        if (!(cond)) {                                                               \
            fprintf(stderr, "%s:%d: CHECK failed: %s (last message: %s)\n", __FILE__, \
                    __LINE__, #cond, hmsm_status_message());                         \
            ++failures;                                                              \
        }                                                                            \
    } while (0)

/* A call that must return `code`. */
#define CHECK_STATUS(code, call)                                                             \
    do {                                                                                     \
        hmsm_status status_ = (call);                                                        \
        if (status_ != (code)) {                                                             \
            fprintf(stderr, "%s:%d: %s gave %s (%s), expected %s\n", __FILE__, __LINE__,     \
                    #call, hmsm_status_name(status_), hmsm_status_message(),                 \
                    hmsm_status_name(code));                                                 \
            ++failures;                                                                      \
        }                                                                                    \
    } while (0)

#endif
