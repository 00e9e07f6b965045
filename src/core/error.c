/* Per-thread error messages.
 * SPDX-License-Identifier: GPL-2.0-or-later */
#include "core/error.h"

#include <stdarg.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

static _Thread_local char error_message[512];
static _Thread_local char error_location[256];

hoc_status hoc_error_set(hoc_status status, const char *file, int line, const char *func,
                         const char *fmt, ...) {
  va_list ap;
  va_start(ap, fmt);
  vsnprintf(error_message, sizeof error_message, fmt, ap);
  va_end(ap);
  /* one line: newlines from foreign messages become spaces */
  for (char *c = error_message; *c; ++c)
    if (*c == '\n' || *c == '\r') *c = ' ';
  const char *base = strrchr(file, '/');
  snprintf(error_location, sizeof error_location, "%s:%d (%s)", base ? base + 1 : file, line,
           func);
  return status;
}

double hoc_now(void) {
  struct timespec ts;
  clock_gettime(CLOCK_MONOTONIC, &ts);
  return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

const char *hoc_last_error(void) { return error_message; }

const char *hoc_last_error_location(void) { return error_location; }

void hoc_error_clear(void) {
  error_message[0] = '\0';
  error_location[0] = '\0';
}

void hoc_par_error_catch(hoc_par_error *e, hoc_status st) {
  if (st == HOC_OK) return;
#pragma omp critical(hoc_par_error)
  if (e->status == HOC_OK) {
    e->status = st;
    snprintf(e->message, sizeof e->message, "%s", error_message);
    snprintf(e->location, sizeof e->location, "%s", error_location);
  }
}

hoc_status hoc_par_error_raise(const hoc_par_error *e) {
  if (e->status == HOC_OK) return HOC_OK;
  snprintf(error_message, sizeof error_message, "%s", e->message);
  snprintf(error_location, sizeof error_location, "%s", e->location);
  return e->status;
}

const char *hoc_status_string(hoc_status status) {
  switch (status) {
  case HOC_OK: return "ok";
  case HOC_ERR_ARGUMENT: return "invalid argument";
  case HOC_ERR_IO: return "input/output error";
  case HOC_ERR_FORMAT: return "malformed file";
  case HOC_ERR_CAD: return "CAD error";
  case HOC_ERR_MESH: return "meshing error";
  case HOC_ERR_MISMATCH: return "mesh does not match the model";
  case HOC_ERR_MEMORY: return "out of memory";
  case HOC_ERR_INTERRUPTED: return "interrupted";
  case HOC_ERR_UNSUPPORTED: return "unsupported";
  case HOC_ERR_INTERNAL: return "internal error";
  }
  return "unknown status";
}

void *hoc_calloc(size_t n, size_t size) {
  if (size && n > SIZE_MAX / size) return NULL;
  return calloc(n ? n : 1, size ? size : 1);
}

void *hoc_realloc(void *ptr, size_t n, size_t size) {
  if (size && n > SIZE_MAX / size) return NULL;
  size_t bytes = n * size;
  return realloc(ptr, bytes ? bytes : 1);
}
