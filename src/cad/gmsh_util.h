/* Helpers shared by the files that call gmsh (the CAD backend and the
 * linear mesher).
 * SPDX-License-Identifier: GPL-2.0-or-later */
#ifndef HOC_CAD_GMSH_UTIL_H
#define HOC_CAD_GMSH_UTIL_H

#include "core/error.h"

#include <stdio.h>

/** Initialise gmsh once (silent, no configuration files). */
hoc_status hoc_gmsh_start(void);

/** HOC_ERR_CAD with gmsh's last logged error, prefixed by `what`. */
hoc_status hoc_gmsh_error(const char *what);

/** stdout/stderr redirected to a scratch file while the kernel may print. */
typedef struct hoc_quiet {
  FILE *sink;
  int saved_out, saved_err;
} hoc_quiet;

hoc_status hoc_quiet_begin(hoc_quiet *q);
/** Restore the descriptors; copy the first error line printed (if any) into
 *  first_error (may be NULL). */
void hoc_quiet_end(hoc_quiet *q, char *first_error, size_t size);

#endif
