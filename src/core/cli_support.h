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

/* Option values of the command line, checked: HOC_OK, or HOC_ERR_ARGUMENT
 * with the one-line message "OPT expects ..., got 'S'" (S may be NULL: a
 * missing value). ----------------------------------------------------------- */

/** An integer in lo..hi. */
hoc_status hoc_cli_parse_int(const char *opt, const char *s, int lo, int hi, int *out);

/** A finite number above 0. */
hoc_status hoc_cli_parse_positive(const char *opt, const char *s, double *out);

/** A direction towards the eye: iso, front, back, top, bottom, side, left,
 *  right, or x,y,z (not all zero). */
hoc_status hoc_cli_parse_view(const char *opt, const char *s, double view[3]);

/** WIDTHxHEIGHT of a picture in pixels, 64..16384 a side, into options. */
hoc_status hoc_cli_parse_picture_size(const char *opt, const char *s, hoc_picture_options *options);

/** shape or oddy. */
hoc_status hoc_cli_parse_measure(const char *opt, const char *s, hoc_measure *out);

/** equispaced, fekete or warp-blend. */
hoc_status hoc_cli_parse_nodeset(const char *opt, const char *s, hoc_nodeset *out);

/** 4.1 (or 4) or 2.2 (or 2), as hoc_msh_options.version (41 or 22). */
hoc_status hoc_cli_parse_msh_version(const char *opt, const char *s, int *version);

/** The default output of `hocad mesh`: the model's base name without its
 *  extension, then _pP.msh (_pP.vtu above order 10, which MSH cannot
 *  hold), in the current directory; truncated to `size`. */
void hoc_cli_default_output(const char *model, int order, char *buf, size_t size);

/** The largest distance of a node of `mesh` from its CAD entity, and that
 *  as a share of the diagonal of the model's bounding box (0 if the box
 *  is a point). */
hoc_status hoc_cli_cad_offset(const hoc_mesh *mesh, const hoc_model *model, double *offset,
                              double *relative);

#endif
