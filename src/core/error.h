/* Error values and internal helpers shared by every module.
 * SPDX-License-Identifier: GPL-2.0-or-later */
#ifndef HOC_CORE_ERROR_H
#define HOC_CORE_ERROR_H

#include "hocad.h"

#include <stddef.h>

/** Record a failure (message formatted printf-style, one line) and return
 *  `status`. The file/line/function are kept for hoc_last_error_location. */
hoc_status hoc_error_set(hoc_status status, const char *file, int line, const char *func,
                         const char *fmt, ...)
#if defined(__GNUC__)
    __attribute__((format(printf, 5, 6)))
#endif
    ;

/** Where the last error was raised: "file:line (function)". */
const char *hoc_last_error_location(void);

/** Forget the last error of this thread. */
void hoc_error_clear(void);

/** Seconds on a monotonic clock. */
double hoc_now(void);

/** The first failure inside a parallel region, carried to the calling
 *  thread (messages are per thread). */
typedef struct hoc_par_error {
  hoc_status status;
  char message[512], location[256];
} hoc_par_error;

/** Keep status st (with this thread's message) if it is the first failure. */
void hoc_par_error_catch(hoc_par_error *e, hoc_status st);

/** The kept failure as this thread's error (HOC_OK if none). */
hoc_status hoc_par_error_raise(const hoc_par_error *e);

#define HOC_ERROR(status, ...) hoc_error_set((status), __FILE__, __LINE__, __func__, __VA_ARGS__)

/** Check of the caller's input or of the outside world: always on. */
#define HOC_CHECK(cond, status, ...)                                                              \
  do {                                                                                            \
    if (!(cond)) return HOC_ERROR((status), __VA_ARGS__);                                        \
  } while (0)

/** Propagate a failing status. */
#define HOC_TRY(call)                                                                             \
  do {                                                                                            \
    hoc_status hoc_try_status_ = (call);                                                          \
    if (hoc_try_status_ != HOC_OK) return hoc_try_status_;                                        \
  } while (0)

/** Propagate a failing status through a cleanup label: needs a local
 *  `hoc_status status`. */
#define HOC_TRY_GOTO(call, label)                                                                 \
  do {                                                                                            \
    status = (call);                                                                              \
    if (status != HOC_OK) goto label;                                                             \
  } while (0)

/** Internal invariant: checked in debug builds only, reported as a bug. */
#ifdef NDEBUG
#define HOC_ASSERT(cond) ((void)0)
#else
#define HOC_ASSERT(cond)                                                                          \
  do {                                                                                            \
    if (!(cond)) return HOC_ERROR(HOC_ERR_INTERNAL, "internal check failed: %s", #cond);         \
  } while (0)
#endif

/** calloc of n elements of `size` bytes with overflow check; NULL on failure
 *  (n == 0 returns a valid unique pointer). */
void *hoc_calloc(size_t n, size_t size);
/** realloc of n elements of `size` bytes with overflow check. */
void *hoc_realloc(void *ptr, size_t n, size_t size);

/** Allocate `n` elements into `ptr` or return HOC_ERR_MEMORY. */
#define HOC_ALLOC(ptr, n)                                                                         \
  do {                                                                                            \
    (ptr) = hoc_calloc((n), sizeof *(ptr));                                                       \
    if (!(ptr)) return HOC_ERROR(HOC_ERR_MEMORY, "out of memory (%zu x %zu bytes)", (size_t)(n), \
                                 sizeof *(ptr));                                                  \
  } while (0)

/** Same as HOC_ALLOC through a cleanup label (needs `hoc_status status`). */
#define HOC_ALLOC_GOTO(ptr, n, label)                                                             \
  do {                                                                                            \
    (ptr) = hoc_calloc((n), sizeof *(ptr));                                                       \
    if (!(ptr)) {                                                                                 \
      status = HOC_ERROR(HOC_ERR_MEMORY, "out of memory (%zu x %zu bytes)", (size_t)(n),         \
                         sizeof *(ptr));                                                          \
      goto label;                                                                                 \
    }                                                                                             \
  } while (0)

#endif
