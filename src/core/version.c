/* Library version.
 * SPDX-License-Identifier: GPL-2.0-or-later */
#include "hocad.h"

#ifndef HOC_VERSION_STRING
#define HOC_VERSION_STRING "0.1.0"
#endif

const char *hoc_version(void) { return HOC_VERSION_STRING; }
