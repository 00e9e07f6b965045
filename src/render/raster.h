/* The mesh renderer's state, shared by the rasterizer (render.c) and the
 * overlays drawn over its panels (render_overlays.c): limits and constants,
 * the lattice tables, the per-view and per-picture state, the per-thread
 * scratch.
 * SPDX-License-Identifier: GPL-2.0-or-later
 */
#ifndef HOC_RENDER_RASTER_H
#define HOC_RENDER_RASTER_H

#include "render/render_impl.h"

#include <stddef.h>
#include <stdint.h>

enum {
  SS = 3,                 /* samples per output pixel along each axis */
  MAX_SUB = 48,           /* finest subdivision of an element edge */
  WORST_COUNT = 5,        /* elements considered by zoom_worst */
  MAX_MARKERS = 1000,     /* rings around tangled elements */
  BAND_SAMPLES = 1 << 19, /* samples in a band buffer (about 4 MB with the depths) */
  MAX_THREADS = 16,       /* bounds the memory of the band buffers */
  OUT_BYTES = 1 << 25     /* finished rows held before writing (at least one band a thread) */
};
#define FRAME_FILL 0.9 /* the frame fills 90% of the panel's limiting side */
#define SUB_PIXELS 4.0 /* target sub-triangle size on screen (output pixels) */
#define EDGE_OPACITY 0.9
#define MARKER_BELOW 12.0 /* tangled elements smaller than this (pixels) get a ring */
#define AMBIENT 0.42
#define DIFFUSE 0.58

/* The reference triangle cut into n^2 sub-triangles, with the basis at the lattice points. */
typedef struct lattice_table {
  int n;      /* subdivisions per edge */
  int npts;   /* (n+1)(n+2)/2 lattice points */
  int ntri;   /* n^2 sub-triangles */
  double *rs; /* [npts][2] lattice points (i/n, j/n) */
  double *N;  /* [npts][np] basis values */
  double *dN; /* [npts][np][2] d/dr, d/ds */
  int *tri;   /* [ntri][3] lattice point indices */
} lattice_table;

/* Per-view state. */
typedef struct view_state {
  const hoc_render_mesh *mesh;
  int np;
  lattice_table tab; /* the view's subdivision */
  double *box;       /* [n_elems][4] screen-space node bbox: xmin, xmax, ymin, ymax */
  int32_t *bands;    /* [n_elems][2] first and last band touched (first > last: none) */
  int x0, x1;        /* panel columns [x0, x1) */
  double cx, cy;     /* panel centre (pixels) */
} view_state;

/* Everything a band needs, read-only while rendering. */
typedef struct render_ctx {
  int width, height, transparent, edges;
  int n_views;
  view_state *views;
  double right[3], up[3], dir[3], light[3];
  double fx, fy, fz; /* frame centre: screen x, screen y, depth (model units) */
  double scale;      /* output pixels per model unit */
  double zclip;      /* elements wholly nearer than this (depth) are not drawn (zoom_worst) */
  int panel_y0;      /* first row of the panels (below the title band) */
  int band_rows, n_bands;
  hoc_render_scale qscale;
  /* layout of the overlays */
  int title_scale, label_scale, pad, has_title, has_stats;
  double edge_half_width; /* output pixels: 0.55 (small pictures) to 0.75 (1200 rows) and up */
  int bar_x0, bar_x1, bar_y0, bar_y1; /* colour bar rectangle */
  char (*stats)[96];                  /* [n_views] statistics line */
  double *markers; /* [n_markers][3] x, y (pixels), view: rings around small tangled elements */
  size_t n_markers;
} render_ctx;

/* Per-thread scratch. */
typedef struct workspace {
  float *z;       /* [band_rows SS][width SS] depth, larger is nearer */
  uint32_t *rgba; /* [band_rows SS][width SS] packed sample colours */
  double *x;      /* [np][3] element nodes */
  double *pts;    /* [MAX_PTS][4] screen x, y (samples), depth, intensity */
} workspace;

#define MAX_PTS ((MAX_SUB + 1) * (MAX_SUB + 2) / 2)

/* A double clamped to [lo, hi] as an int (NaN gives lo). */
static inline int clamp_int(double v, int lo, int hi) {
  if (!(v > lo)) return lo;
  if (v > hi) return hi;
  return (int)v;
}

/** Find the tangled elements too small to see (ctx->markers, n_markers). */
hoc_status hoc_render_find_markers(render_ctx *ctx);
/** Draw the titles, statistics lines, rings and colour bar on a band. */
void hoc_render_draw_overlays(const render_ctx *ctx, hoc_canvas *c);

#endif
