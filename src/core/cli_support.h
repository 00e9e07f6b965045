/* Library functions only the command-line tool uses: not part of the public
 * interface (include/hocad.h), and free to change with the tool.
 * SPDX-License-Identifier: GPL-2.0-or-later */
#ifndef HOC_CORE_CLI_SUPPORT_H
#define HOC_CORE_CLI_SUPPORT_H

#include "hocad.h"

/** From a signal handler: remove every temporary output file the library
 *  has open (async-signal-safe), so an interrupted run leaves the previous
 *  outputs intact and no partial file behind. */
void hoc_abort_outputs_from_signal(void);

/** Picture (and histogram, if histogram_path is not NULL) of a .msh file
 *  without its CAD model. Without the CAD normals, Definition 2 measures
 *  each element against the normal of the plane through its three corners
 *  (equal to the CAD's verdict on all but strongly curved elements).
 *  @param[in]  msh_path        the mesh file
 *  @param[in]  measure         shape or Oddy
 *  @param[in]  png_path        the picture, written atomically
 *  @param[in]  histogram_path  NULL, or the histogram of q, written atomically
 *  @param[in]  options         NULL for defaults
 *  @param[out] stats           statistics of that measure, or NULL */
hoc_status hoc_picture_msh_file(const char *msh_path, hoc_measure measure, const char *png_path,
                                const char *histogram_path, const hoc_picture_options *options,
                                hoc_quality_stats *stats);

#endif
