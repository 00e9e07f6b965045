/* Library version.
 * SPDX-License-Identifier: GPL-2.0-or-later */
#include "hocad.h"

#ifndef HOCAD_VERSION_STRING
#define HOCAD_VERSION_STRING "0.1.0"
#endif

const char *hoc_version(void) { return HOCAD_VERSION_STRING; }
