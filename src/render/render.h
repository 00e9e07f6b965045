/* Pictures of curved meshes coloured by quality: a headless software
 * renderer writing PNG (libpng). Knows nothing of CAD: it draws arrays.
 * SPDX-License-Identifier: GPL-2.0-or-later
 */
#ifndef HOC_RENDER_H
#define HOC_RENDER_H

#include "core/error.h"

/** One mesh to draw: curved triangles of order p given by their nodes. */
typedef struct hoc_render_mesh {
  int order;             /* p, 1..HOC_MAX_ORDER */
  const double *rs;      /* [np][2] reference coordinates of the element nodes (gmsh ordering,
                            any node set: see src/basis/basis.h), used to evaluate each element */
  size_t n_nodes;
  const double *xyz;     /* [n_nodes][3] */
  size_t n_elems;
  const size_t *conn;    /* [n_elems][np] 0-based node indices */
  const double *q;       /* [n_elems] quality in [0,1], 0 = tangled; NULL: uniform grey */
  const char *title;     /* drawn above the view, may be NULL */
} hoc_render_mesh;

typedef struct hoc_render_options {
  int width, height;     /* size of the whole picture in pixels (0: 1600 x 1200) */
  double view[3];        /* direction from the model to the eye (0,0,0: isometric (1,1,1)) */
  int zoom_worst;        /* frame the worst elements of the first view instead of everything */
  int no_edges;          /* do not draw element edges */
  int transparent;       /* transparent background instead of white */
} hoc_render_options;

/** Draw n_views meshes side by side in one PNG (same camera for all, so
 *  stages compare), each coloured by q with a colour bar, tangled elements
 *  in a colour that stands out. Written atomically (io/io.h hoc_outfile). */
hoc_status hoc_render_png(const char *path, const hoc_render_mesh *views, int n_views,
                          const hoc_render_options *options);

/** Histogram of q per view (bins of 0.05; tangled elements counted apart),
 *  one panel per view side by side, as a PNG. */
hoc_status hoc_render_histogram_png(const char *path, const hoc_render_mesh *views, int n_views,
                                    const hoc_render_options *options);

#endif
