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

/* A call that must fail with `code` and leave a message naming something. */
#define CHECK_FAILS(code, call)                                                        \
    do {                                                                               \
        hmsm_status status_ = (call);                                                  \
        if (status_ != (code) || hmsm_status_message()[0] == '\0') {                   \
            fprintf(stderr, "%s:%d: %s gave %s (%s), expected %s\n", __FILE__, __LINE__, \
                    #call, hmsm_status_name(status_), hmsm_status_message(),           \
                    hmsm_status_name(code));                                           \
            ++failures;                                                                \
        }                                                                              \
    } while (0)

/* A call that must succeed and leave no message. */
#define CHECK_OK(call)                                                                  \
    do {                                                                                \
        hmsm_status status_ = (call);                                                   \
        if (status_ != HMSM_OK || hmsm_status_message()[0] != '\0') {                   \
            fprintf(stderr, "%s:%d: %s gave %s: %s\n", __FILE__, __LINE__, #call,        \
                    hmsm_status_name(status_), hmsm_status_message());                  \
            ++failures;                                                                 \
        }                                                                               \
    } while (0)

/* A three-node tree as arrays, the C way to hand hmsm an engine's own skeleton: a trunk and a
   bent branch above it, 4 m tall. */
static inline hmsm_tree* small_tree(void) {
    const int32_t parents[3] = {-1, 0, 1};
    const double positions[9] = {0, 0, 0, 0, 2, 0, 0.3, 4, 0};
    const double radii[3] = {0.2, 0.15, 0.1};
    hmsm_tree* tree = NULL;
    CHECK_STATUS(HMSM_OK, hmsm_tree_from_nodes(parents, positions, radii, 3, &tree));
    return tree;
}

#endif
