/* Minimal test harness: checks count failures, main returns their number.
 * Each test program ends with the line "N passed, N failed".
 * SPDX-License-Identifier: GPL-2.0-or-later */
#ifndef HOC_TEST_UTIL_H
#define HOC_TEST_UTIL_H

#include <float.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>

static int test_passed_, test_failed_;

#define CHECK(cond)                                                                               \
  do {                                                                                            \
    if (cond) {                                                                                   \
      ++test_passed_;                                                                             \
    } else {                                                                                      \
      ++test_failed_;                                                                             \
      fprintf(stderr, "%s:%d: CHECK failed: %s\n", __FILE__, __LINE__, #cond);                   \
    }                                                                                             \
  } while (0)

/* |a - b| <= tol, printing both on failure (NaN always fails). */
#define CHECK_NEAR(a, b, tol)                                                                     \
  do {                                                                                            \
    double a_ = (a), b_ = (b), t_ = (tol);                                                        \
    if (fabs(a_ - b_) <= t_) {                                                                    \
      ++test_passed_;                                                                             \
    } else {                                                                                      \
      ++test_failed_;                                                                             \
      fprintf(stderr, "%s:%d: CHECK_NEAR failed: %s = %.17g, %s = %.17g, |diff| = %.3g > %.3g\n", \
              __FILE__, __LINE__, #a, a_, #b, b_, fabs(a_ - b_), t_);                            \
    }                                                                                             \
  } while (0)

/* A library call that must succeed. */
#define CHECK_OK(call)                                                                            \
  do {                                                                                            \
    hoc_status s_ = (call);                                                                       \
    if (s_ == HOC_OK) {                                                                           \
      ++test_passed_;                                                                             \
    } else {                                                                                      \
      ++test_failed_;                                                                             \
      fprintf(stderr, "%s:%d: %s failed: %s: %s\n", __FILE__, __LINE__, #call,                    \
              hoc_status_string(s_), hoc_last_error());                                          \
    }                                                                                             \
  } while (0)

/* A library call that must fail with a given status. */
#define CHECK_STATUS(call, expected)                                                              \
  do {                                                                                            \
    hoc_status s_ = (call);                                                                       \
    if (s_ == (expected)) {                                                                       \
      ++test_passed_;                                                                             \
    } else {                                                                                      \
      ++test_failed_;                                                                             \
      fprintf(stderr, "%s:%d: %s returned %s, expected %s (%s)\n", __FILE__, __LINE__, #call,     \
              hoc_status_string(s_), hoc_status_string(expected), hoc_last_error());             \
    }                                                                                             \
  } while (0)

static inline int test_report(void) {
  printf("%d passed, %d failed\n", test_passed_, test_failed_);
  return test_failed_ ? 1 : 0;
}

#endif
