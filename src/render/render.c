/* Pictures of curved meshes coloured by quality: a software rasterizer.
 * Its state is declared in raster.h; the titles, statistics, rings and
 * colour bar drawn over the panels are in render_overlays.c.
 * SPDX-License-Identifier: GPL-2.0-or-later
 *
 * How a picture is made:
 *  - camera: orthographic, looking along -view; screen x = `right`, screen
 *    y = `up` (the model's +z projected, or +y when looking along z), depth
 *    towards the eye along `view`. The frame is the screen-space bounding
 *    box of every node the elements use (all views), or with zoom_worst that
 *    of the worst elements of the first view (see zoom_frame); it is centred in each view's panel
 * and fills FRAME_FILL of the panel's limiting side. Panels are side by side under a title band; a
 * colour bar column is on the right when some view has q. Without titles and q the single panel is
 * the whole picture.
 *  - elements: each is evaluated with the Lagrange basis of its node set at
 *    the points of a reference lattice of n subdivisions per edge (n a
 *    multiple of p, one per view, see choose_subdivision), and the n^2
 *    sub-triangles are rasterized with a z-buffer at SS x SS samples per
 *    output pixel, then box-filtered down (anti-aliasing).
 *  - shading: Lambert with ambient on the surface normal x_r x x_s of the
 *    element at each lattice point (flipped towards the eye: two-sided),
 *    interpolated over the sub-triangles (Gouraud).
 *  - edges: the reference coordinates (r, s) are interpolated exactly over
 *    the sub-triangles; a sample closer (in screen pixels, to first order)
 *    than half the edge width to the element's boundary s = 0, r + s = 1, r = 0
 *    takes the edge colour. Only visible surface is drawn, so hidden edges
 *    never show, and the lines follow the curved element exactly.
 *  - memory: the picture is made in bands of rows; each band is rendered by
 *    one thread from its own buffers (so the result does not depend on the
 *    thread count) and written to the PNG in order.
 */
#include "render/raster.h"
#include "render/render_impl.h"

#include "basis/basis.h"

#include <float.h>
#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#ifdef _OPENMP
#include <omp.h>
#endif

static double dot3(const double *a, const double *b) {
  return a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
}

static void cross3(const double *a, const double *b, double *c) {
  c[0] = a[1] * b[2] - a[2] * b[1];
  c[1] = a[2] * b[0] - a[0] * b[2];
  c[2] = a[0] * b[1] - a[1] * b[0];
}

static void normalize3(double *a) {
  double l = sqrt(dot3(a, a));
  if (l > 0) a[0] /= l, a[1] /= l, a[2] /= l;
}

static uint32_t pack(hoc_rgb c, unsigned a) {
  return (uint32_t)c.r | (uint32_t)c.g << 8 | (uint32_t)c.b << 16 | (uint32_t)a << 24;
}

/* Minimum and maximum without libm calls (the arguments are never NaN here). */
static inline double min2(double a, double b) { return a < b ? a : b; }
static inline double max2(double a, double b) { return a > b ? a : b; }

/* Input checks ------------------------------------------------------------ */

static hoc_status check_view(const hoc_render_mesh *v, int k) {
  HOC_CHECK(v->order >= 1 && v->order <= HOC_MAX_ORDER, HOC_ERR_ARGUMENT,
            "view %d: order %d out of range 1..%d", k, v->order, HOC_MAX_ORDER);
  int np = hoc_tri_num_nodes(v->order);
  HOC_CHECK(v->rs, HOC_ERR_ARGUMENT, "view %d: NULL reference nodes", k);
  for (int i = 0; i < 2 * np; ++i)
    HOC_CHECK(isfinite(v->rs[i]), HOC_ERR_ARGUMENT, "view %d: reference node %d not finite", k,
              i / 2);
  HOC_CHECK(v->n_elems == 0 || (v->conn && v->xyz), HOC_ERR_ARGUMENT,
            "view %d: NULL %s with %zu elements", k, v->conn ? "coordinates" : "connectivity",
            v->n_elems);
  if (v->n_elems == 0) return HOC_OK;
  for (size_t i = 0; i < 3 * v->n_nodes; ++i)
    HOC_CHECK(fabs(v->xyz[i]) <= 1e100, HOC_ERR_ARGUMENT,
              "view %d: coordinate %zu of node %zu is %g (not finite, or beyond 1e100)", k, i % 3,
              i / 3, v->xyz[i]);
  for (size_t e = 0; e < v->n_elems; ++e)
    for (int a = 0; a < np; ++a)
      HOC_CHECK(v->conn[e * (size_t)np + (size_t)a] < v->n_nodes, HOC_ERR_ARGUMENT,
                "view %d: element %zu uses node %zu of %zu", k, e,
                v->conn[e * (size_t)np + (size_t)a], v->n_nodes);
  return HOC_OK;
}

/* Tables ------------------------------------------------------------------ */

static void lattice_free(lattice_table *t) {
  free(t->rs);
  free(t->N);
  free(t->dN);
  free(t->tri);
  memset(t, 0, sizeof *t);
}

/* Fill the lattice and the sub-triangles and evaluate the basis. */
static hoc_status lattice_build(lattice_table *t, int n, const hoc_lagrange *basis, int np) {
  hoc_status status = HOC_OK;
  t->n = n;
  t->npts = (n + 1) * (n + 2) / 2;
  t->ntri = n * n;
  HOC_ALLOC_GOTO(t->rs, 2 * (size_t)t->npts, fail);
  HOC_ALLOC_GOTO(t->N, (size_t)t->npts * (size_t)np, fail);
  HOC_ALLOC_GOTO(t->dN, 2 * (size_t)t->npts * (size_t)np, fail);
  HOC_ALLOC_GOTO(t->tri, 3 * (size_t)t->ntri, fail);
  /* point (i, j), i + j <= n, has index j (n + 1) - j (j - 1) / 2 + i */
  for (int j = 0, k = 0; j <= n; ++j)
    for (int i = 0; i <= n - j; ++i, ++k) {
      t->rs[2 * k] = (double)i / n;
      t->rs[2 * k + 1] = (double)j / n;
    }
  int m = 0;
  for (int j = 0; j < n; ++j) {
    int row = j * (n + 1) - j * (j - 1) / 2, next = (j + 1) * (n + 1) - (j + 1) * j / 2;
    for (int i = 0; i < n - j; ++i) {
      /* "up" triangle (i,j) (i+1,j) (i,j+1), then "down" (i+1,j) (i+1,j+1) (i,j+1) */
      t->tri[3 * m] = row + i, t->tri[3 * m + 1] = row + i + 1, t->tri[3 * m + 2] = next + i;
      ++m;
      if (i < n - j - 1) {
        t->tri[3 * m] = row + i + 1, t->tri[3 * m + 1] = next + i + 1, t->tri[3 * m + 2] = next + i;
        ++m;
      }
    }
  }
  HOC_ASSERT(m == t->ntri);
  HOC_TRY_GOTO(hoc_lagrange_eval(basis, t->npts, t->rs, t->N, t->dN), fail);
  return HOC_OK;
fail:
  lattice_free(t);
  return status;
}

/* Camera and frame -------------------------------------------------------- */

static hoc_status camera_setup(render_ctx *ctx, const hoc_render_options *opt) {
  double d[3] = {1, 1, 1};
  if (opt) {
    for (int i = 0; i < 3; ++i)
      HOC_CHECK(isfinite(opt->view[i]), HOC_ERR_ARGUMENT, "render: view direction not finite");
    if (opt->view[0] != 0 || opt->view[1] != 0 || opt->view[2] != 0) memcpy(d, opt->view, sizeof d);
  }
  double scale = max2(fabs(d[0]), max2(fabs(d[1]), fabs(d[2])));
  for (int i = 0; i < 3; ++i)
    d[i] /= scale; /* no overflow in the norm */
  normalize3(d);
  double up0[3] = {0, 0, 1};
  if (fabs(d[2]) > 0.999) up0[1] = 1, up0[2] = 0;
  memcpy(ctx->dir, d, sizeof d);
  cross3(up0, d, ctx->right);
  normalize3(ctx->right);
  cross3(d, ctx->right, ctx->up);
  /* light from the upper left, in front */
  for (int i = 0; i < 3; ++i)
    ctx->light[i] = d[i] + 0.55 * ctx->up[i] - 0.45 * ctx->right[i];
  normalize3(ctx->light);
  return HOC_OK;
}

/* Screen-space bboxes of the elements' nodes (model units). */
static void node_boxes(const render_ctx *ctx, view_state *vs) {
  const hoc_render_mesh *m = vs->mesh;
  const int np = vs->np;
  const long long ne = (long long)m->n_elems;
#pragma omp parallel for schedule(static)
  for (long long e = 0; e < ne; ++e) {
    double b[4] = {INFINITY, -INFINITY, INFINITY, -INFINITY};
    const size_t *c = m->conn + (size_t)e * (size_t)np; /* [np] */
    for (int a = 0; a < np; ++a) {
      const double *p = m->xyz + 3 * c[a];
      double sx = dot3(p, ctx->right), sy = dot3(p, ctx->up);
      b[0] = min2(b[0], sx), b[1] = max2(b[1], sx);
      b[2] = min2(b[2], sy), b[3] = max2(b[3], sy);
    }
    memcpy(vs->box + 4 * (size_t)e, b, sizeof b);
  }
}

static void box_union(double *u, const double *b) {
  u[0] = min2(u[0], b[0]), u[1] = max2(u[1], b[1]);
  u[2] = min2(u[2], b[2]), u[3] = max2(u[3], b[3]);
}

/* The frame with zoom_worst: the worst element of a view (lowest q, ties by
 * index), with those of the next worst that lie next to it (centres within
 * twice its size), widened on each side by the size of that box.
 * @param[in,out] frame  in: the frame of all elements, out: the zoomed one */
static hoc_status zoom_frame(const view_state *vs, double *frame) {
  const double full = max2(frame[1] - frame[0], frame[3] - frame[2]); /* all elements */
  const hoc_render_mesh *m = vs->mesh;
  HOC_CHECK(m->q, HOC_ERR_ARGUMENT, "render: zoom_worst needs the qualities of the views");
  size_t worst[WORST_COUNT];
  int nw = 0;
  /* the WORST_COUNT smallest (q, index) by insertion */
  for (size_t e = 0; e < m->n_elems; ++e) {
    double q = hoc_render_q(m, e);
    if (nw == WORST_COUNT && !(q < hoc_render_q(m, worst[nw - 1]))) continue;
    int k = nw < WORST_COUNT ? nw++ : nw - 1;
    while (k > 0 && q < hoc_render_q(m, worst[k - 1])) {
      worst[k] = worst[k - 1];
      --k;
    }
    worst[k] = e;
  }
  const double *b0 = vs->box + 4 * worst[0];
  double size0 = max2(b0[1] - b0[0], b0[3] - b0[2]);
  double c0x = 0.5 * (b0[0] + b0[1]), c0y = 0.5 * (b0[2] + b0[3]);
  memcpy(frame, b0, 4 * sizeof *frame);
  for (int k = 1; k < nw; ++k) {
    const double *b = vs->box + 4 * worst[k];
    double cx = 0.5 * (b[0] + b[1]), cy = 0.5 * (b[2] + b[3]);
    if (hypot(cx - c0x, cy - c0y) <= 2 * size0) box_union(frame, b);
  }
  double grow = max2(frame[1] - frame[0], frame[3] - frame[2]);
  if (!(grow > 1e-3 * full)) grow = 0.02 * full; /* a collapsed element: 5% of everything */
  frame[0] -= grow, frame[1] += grow, frame[2] -= grow, frame[3] += grow;
  return HOC_OK;
}

/* Layout ------------------------------------------------------------------ */

static void layout(render_ctx *ctx) {
  int w = ctx->width, h = ctx->height;
  int ts = (int)lround(min2(w, h) / 400.0);
  ctx->title_scale = ts < 1 ? 1 : ts > 8 ? 8 : ts;
  ctx->label_scale = ctx->title_scale > 1 ? ctx->title_scale - 1 : 1;
  ctx->pad = 4 * ctx->label_scale;
  ctx->edge_half_width = 0.45 + 0.1 * ctx->title_scale;
  ctx->has_title = ctx->has_stats = 0;
  for (int k = 0; k < ctx->n_views; ++k) {
    if (ctx->views[k].mesh->title) ctx->has_title = 1;
    if (ctx->views[k].mesh->q) ctx->has_stats = 1;
  }
  int band = 0;
  if (ctx->has_title || ctx->has_stats) {
    band = 2 * ctx->pad;
    if (ctx->has_title) band += HOC_FONT_LINE * ctx->title_scale;
    if (ctx->has_stats) band += HOC_FONT_LINE * ctx->label_scale;
  }
  ctx->panel_y0 = band;
  int bar_col = 0;
  if (ctx->qscale.has_q) {
    int ls = ctx->label_scale, bar_w = 8 * ls;
    int text = hoc_text_width("tangled", ls);
    bar_col = ctx->pad * 3 + bar_w + 2 * ctx->pad + text;
    if (bar_col > w / 3) bar_col = w / 3;
    ctx->bar_x0 = w - bar_col + ctx->pad;
    ctx->bar_x1 = ctx->bar_x0 + bar_w;
    int ph = h - band;
    ctx->bar_y0 = band + ph / 8 + HOC_FONT_LINE * ls;
    ctx->bar_y1 = band + ph * 3 / 4;
  }
  int pw = (w - bar_col) / ctx->n_views;
  for (int k = 0; k < ctx->n_views; ++k) {
    view_state *vs = &ctx->views[k];
    vs->x0 = k * pw;
    vs->x1 = k == ctx->n_views - 1 ? w - bar_col : (k + 1) * pw;
    vs->cx = 0.5 * (vs->x0 + vs->x1);
    vs->cy = 0.5 * (band + h);
  }
}

/* Fit the frame [xmin, xmax, ymin, ymax] (model units) into the panels. */
static void fit_frame(render_ctx *ctx, const double *frame, double zmid) {
  double ex = frame[1] - frame[0], ey = frame[3] - frame[2];
  if (!(ex >= 0 && ey >= 0)) ex = ey = 0; /* no element at all */
  double ext = max2(ex, ey);
  if (ext == 0) ext = ex = ey = 1;
  ex = max2(ex, 1e-9 * ext);
  ey = max2(ey, 1e-9 * ext);
  int pw = ctx->views[0].x1 - ctx->views[0].x0;
  for (int k = 1; k < ctx->n_views; ++k)
    if (ctx->views[k].x1 - ctx->views[k].x0 < pw) pw = ctx->views[k].x1 - ctx->views[k].x0;
  int ph = ctx->height - ctx->panel_y0;
  ctx->scale = FRAME_FILL * min2(pw / ex, ph / ey);
  ctx->fx = ex > 0 && frame[1] >= frame[0] ? 0.5 * (frame[0] + frame[1]) : 0;
  ctx->fy = ey > 0 && frame[3] >= frame[2] ? 0.5 * (frame[2] + frame[3]) : 0;
  ctx->fz = zmid;
}

/* Screen position of model point p in view vs: x, y in output pixels. */
static void project(const render_ctx *ctx, const view_state *vs, const double *p, double *x,
                    double *y, double *z) {
  *x = vs->cx + ctx->scale * (dot3(p, ctx->right) - ctx->fx);
  *y = vs->cy - ctx->scale * (dot3(p, ctx->up) - ctx->fy);
  *z = dot3(p, ctx->dir) - ctx->fz;
}

/* Elements: subdivision, exact extent, bands ---------------------------- */

/* Whether the nodes' box of element e, widened by half its size each way
 * (curved edges may bulge), can reach the view's panel. */
static int maybe_visible(const render_ctx *ctx, const view_state *vs, size_t e) {
  const double margin = 2; /* pixels: anti-aliasing and rounding */
  const double *b = vs->box + 4 * e;
  double wx = 0.5 * (b[1] - b[0]), wy = 0.5 * (b[3] - b[2]);
  double bx0 = vs->cx + ctx->scale * (b[0] - wx - ctx->fx);
  double bx1 = vs->cx + ctx->scale * (b[1] + wx - ctx->fx);
  double by0 = vs->cy - ctx->scale * (b[3] + wy - ctx->fy);
  double by1 = vs->cy - ctx->scale * (b[2] - wy - ctx->fy);
  return bx1 >= vs->x0 - margin && bx0 <= vs->x1 + margin && by1 >= ctx->panel_y0 - margin &&
         by0 <= ctx->height + margin;
}

/* Subdivisions per element edge of a view: one number for all its elements,
 * so that neighbours cut their common edge at the same points (per-element
 * numbers would leave cracks at T-junctions). A multiple of p giving
 * sub-triangles of about SUB_PIXELS for 95% of the elements that may show
 * (larger ones get coarser sub-triangles), at most MAX_SUB; 1 for straight
 * elements. */
static int choose_subdivision(const render_ctx *ctx, const view_state *vs) {
  const int p = vs->mesh->order;
  if (p == 1) return 1;
  const int kmax = MAX_SUB / p;
  size_t count[MAX_SUB + 1] = {0}, total = 0;
  for (size_t e = 0; e < vs->mesh->n_elems; ++e) {
    if (!maybe_visible(ctx, vs, e)) continue;
    const double *b = vs->box + 4 * e;
    double d = ctx->scale * hypot(b[1] - b[0], b[3] - b[2]); /* diameter in pixels */
    ++count[clamp_int(ceil(d / (SUB_PIXELS * p)), 1, kmax)];
    ++total;
  }
  size_t below = 0;
  int k = 1;
  for (; k < kmax; ++k) {
    below += count[k];
    if (below >= total - total / 20) break;
  }
  return k * p;
}

/* Gather the nodes of element e: x[np][3]. */
static void gather(const view_state *vs, size_t e, double *x) {
  const size_t *c = vs->mesh->conn + e * (size_t)vs->np; /* [np] */
  for (int a = 0; a < vs->np; ++a)
    memcpy(x + 3 * a, vs->mesh->xyz + 3 * c[a], 3 * sizeof *x);
}

/* Bands touched by each element, from its evaluated lattice points. */
static void element_bands(const render_ctx *ctx, view_state *vs, workspace *ws, int nthreads) {
  const long long ne = (long long)vs->mesh->n_elems;
  const int np = vs->np;
  const double margin = 2; /* pixels: anti-aliasing and rounding */
#pragma omp parallel for schedule(static) num_threads(nthreads)
  for (long long ee = 0; ee < ne; ++ee) {
    size_t e = (size_t)ee;
#ifdef _OPENMP
    workspace *w = &ws[omp_get_thread_num()];
#else
    workspace *w = &ws[0];
#endif
    int32_t *band = vs->bands + 2 * e;
    band[0] = 1, band[1] = 0;
    if (!maybe_visible(ctx, vs, e)) continue;
    const lattice_table *t = &vs->tab;
    gather(vs, e, w->x);
    double xmin = INFINITY, xmax = -INFINITY, ymin = INFINITY, ymax = -INFINITY;
    for (int i = 0; i < t->npts; ++i) {
      double p[3] = {0, 0, 0};
      const double *N = t->N + (size_t)i * (size_t)np; /* [np] */
      for (int a = 0; a < np; ++a)
        for (int c = 0; c < 3; ++c)
          p[c] += N[a] * w->x[3 * a + c];
      double x, y, z;
      project(ctx, vs, p, &x, &y, &z);
      xmin = min2(xmin, x), xmax = max2(xmax, x), ymin = min2(ymin, y), ymax = max2(ymax, y);
    }
    if (!(xmax >= vs->x0 - margin && xmin <= vs->x1 + margin && ymax >= ctx->panel_y0 - margin &&
          ymin <= ctx->height + margin))
      continue;
    band[0] = clamp_int(floor((ymin - margin) / ctx->band_rows), 0, ctx->n_bands - 1);
    band[1] = clamp_int(floor((ymax + margin) / ctx->band_rows), 0, ctx->n_bands - 1);
  }
}

/* Rasterizer -------------------------------------------------------------- */

/* What a sub-triangle needs besides its vertices. */
typedef struct tri_style {
  hoc_rgb base;           /* face colour */
  double edge_alpha;      /* opacity of the element's edges (0: none) */
  double edge_half;       /* half width of the edges in samples */
  int cx0, cx1, cy0, cy1; /* clip rectangle in samples, [cx0, cx1) x [cy0, cy1) */
  int sy0;                /* first sample row of the band buffer */
  int stride;             /* samples per row */
} tri_style;

/* Coefficients of an affine function f(x, y) = f0 + fx (x - x0) + fy (y - y0)
 * on a triangle from its values at the vertices. */
typedef struct plane {
  double f0, fx, fy;
} plane;

static plane plane_fit(const double *v0, const double *v1, const double *v2, double f0, double f1,
                       double f2, double inv_area) {
  plane p = {f0, ((f1 - f0) * (v2[1] - v0[1]) - (f2 - f0) * (v1[1] - v0[1])) * inv_area,
             ((f2 - f0) * (v1[0] - v0[0]) - (f1 - f0) * (v2[0] - v0[0])) * inv_area};
  return p;
}

/* v[k] = {x, y (samples), depth, intensity}, ref[k] = {r, s}. */
static void raster_triangle(workspace *ws, const tri_style *st, const double *v0, const double *v1,
                            const double *v2, const double *r0, const double *r1,
                            const double *r2) {
  double minx = min2(v0[0], min2(v1[0], v2[0])), maxx = max2(v0[0], max2(v1[0], v2[0]));
  double miny = min2(v0[1], min2(v1[1], v2[1])), maxy = max2(v0[1], max2(v1[1], v2[1]));
  int x0 = clamp_int(ceil(minx - 0.5), st->cx0, st->cx1);
  int x1 = clamp_int(floor(maxx - 0.5) + 1, st->cx0, st->cx1);
  int y0 = clamp_int(ceil(miny - 0.5), st->cy0, st->cy1);
  int y1 = clamp_int(floor(maxy - 0.5) + 1, st->cy0, st->cy1);
  if (x0 >= x1 || y0 >= y1) return; /* no sample centre in the clipped box (or NaN) */
  double area = (v1[0] - v0[0]) * (v2[1] - v0[1]) - (v2[0] - v0[0]) * (v1[1] - v0[1]);
  if (!(fabs(area) > 1e-12)) return;
  if (area < 0) { /* orient counter-clockwise in (x, y) */
    const double *tv = v1, *tr = r1;
    v1 = v2, r1 = r2, v2 = tv, r2 = tr;
    area = -area;
  }
  /* edge k is opposite vertex k: from v1 to v2, v2 to v0, v0 to v1, and
   * w_k = ex_k (y - ay_k) - ey_k (x - ax_k) >= 0 inside; a sample exactly on
   * an edge belongs to one side only (the two triangles sharing it run along
   * it in opposite directions) */
  const double *ea[3] = {v1, v2, v0}, *eb[3] = {v2, v0, v1};
  double ex[3], ey[3];
  int own[3];
  for (int k = 0; k < 3; ++k) {
    ex[k] = eb[k][0] - ea[k][0];
    ey[k] = eb[k][1] - ea[k][1];
    own[k] = ey[k] > 0 || (ey[k] == 0 && ex[k] < 0);
  }
  const double inv = 1 / area;
  plane z = plane_fit(v0, v1, v2, v0[2], v1[2], v2[2], inv);
  plane I = plane_fit(v0, v1, v2, v0[3], v1[3], v2[3], inv);
  /* distances (samples) to the element's boundary s = 0, r + s = 1, r = 0:
   * e / |grad e| with e affine on the sub-triangle, hence planes too; the
   * sub-triangle needs them only if a vertex is near the boundary (the
   * distances are affine, so their minimum is at a vertex) */
  const double half = st->edge_half;
  plane dist[3] = {{0}}; /* (set for the edges in near_edge, read only for those) */
  int near_edge = 0;
  if (st->edge_alpha > 0) {
    plane r = plane_fit(v0, v1, v2, r0[0], r1[0], r2[0], inv);
    plane s = plane_fit(v0, v1, v2, r0[1], r1[1], r2[1], inv);
    plane e[3] = {s, {1 - r.f0 - s.f0, -r.fx - s.fx, -r.fy - s.fy}, r};
    for (int k = 0; k < 3; ++k) {
      double g = sqrt(e[k].fx * e[k].fx + e[k].fy * e[k].fy);
      if (!(g > 0)) continue;
      dist[k] = (plane){e[k].f0 / g, e[k].fx / g, e[k].fy / g};
      const double *vv[3] = {v0, v1, v2};
      for (int m = 0; m < 3; ++m)
        if (dist[k].f0 + dist[k].fx * (vv[m][0] - v0[0]) + dist[k].fy * (vv[m][1] - v0[1]) <
            half + 1)
          near_edge |= 1 << k;
    }
  }
  for (int y = y0; y < y1; ++y) {
    const double py = y + 0.5;
    /* span of the row: each edge bounds x on one side (ey != 0) */
    double lo = x0, hi = x1 - 1;
    for (int k = 0; k < 3; ++k) {
      double c = ex[k] * (py - ea[k][1]); /* w_k = c - ey (x + 0.5 - ax) */
      if (ey[k] > 0)
        hi = min2(hi, floor(c / ey[k] + ea[k][0] - 0.5) + 1);
      else if (ey[k] < 0)
        lo = max2(lo, ceil(c / ey[k] + ea[k][0] - 0.5) - 1);
    }
    int xa = clamp_int(lo, x0, x1), xb = clamp_int(hi + 1, x0, x1);
    float *zrow = ws->z + (size_t)(y - st->sy0) * (size_t)st->stride;       /* [stride] */
    uint32_t *crow = ws->rgba + (size_t)(y - st->sy0) * (size_t)st->stride; /* [stride] */
    const double dy = py - v0[1];
    for (int x = xa; x < xb; ++x) {
      const double px = x + 0.5;
      int in = 1;
      for (int k = 0; k < 3; ++k) {
        double w = ex[k] * (py - ea[k][1]) - ey[k] * (px - ea[k][0]);
        if (w < 0 || (w == 0 && !own[k])) in = 0;
      }
      if (!in) continue;
      const double dx = px - v0[0];
      float zs = (float)(z.f0 + z.fx * dx + z.fy * dy);
      if (!(zs > zrow[x])) continue;
      zrow[x] = zs;
      double shade = I.f0 + I.fx * dx + I.fy * dy;
      double c[3] = {st->base.r * shade, st->base.g * shade, st->base.b * shade};
      if (near_edge) {
        double d = INFINITY;
        for (int k = 0; k < 3; ++k)
          if (near_edge >> k & 1) d = min2(d, dist[k].f0 + dist[k].fx * dx + dist[k].fy * dy);
        double a = half - d + 0.5;
        if (a > 0) {
          a = (a > 1 ? 1 : a) * st->edge_alpha;
          c[0] += a * (HOC_RENDER_EDGE.r - c[0]);
          c[1] += a * (HOC_RENDER_EDGE.g - c[1]);
          c[2] += a * (HOC_RENDER_EDGE.b - c[2]);
        }
      }
      hoc_rgb col = {(unsigned char)clamp_int(c[0] + 0.5, 0, 255),
                     (unsigned char)clamp_int(c[1] + 0.5, 0, 255),
                     (unsigned char)clamp_int(c[2] + 0.5, 0, 255)};
      crow[x] = pack(col, 255);
    }
  }
}

/* Evaluate element e of view vs on its lattice and rasterize it. */
static void draw_element(const render_ctx *ctx, const view_state *vs, size_t e, workspace *ws,
                         tri_style *st) {
  const lattice_table *t = &vs->tab;
  const int np = vs->np;
  gather(vs, e, ws->x);
  for (int i = 0; i < t->npts; ++i) {
    double p[3] = {0, 0, 0}, tr[3] = {0, 0, 0}, ts[3] = {0, 0, 0};
    const double *N = t->N + (size_t)i * (size_t)np;       /* [np] */
    const double *dN = t->dN + 2 * (size_t)i * (size_t)np; /* [np][2] */
    for (int a = 0; a < np; ++a) {
      const double *xa = ws->x + 3 * a;
      for (int c = 0; c < 3; ++c) {
        p[c] += N[a] * xa[c];
        tr[c] += dN[2 * a] * xa[c];
        ts[c] += dN[2 * a + 1] * xa[c];
      }
    }
    double *q = ws->pts + 4 * (size_t)i; /* x, y, depth, intensity */
    double x, y, z, n[3];
    project(ctx, vs, p, &x, &y, &z);
    q[0] = x * SS, q[1] = y * SS, q[2] = z;
    /* two-sided Lambert on the normal x_r x x_s */
    cross3(tr, ts, n);
    double len = sqrt(dot3(n, n)), lambert = 0.5;
    if (len > 0 && isfinite(len)) {
      lambert = dot3(n, ctx->light) / len;
      if (dot3(n, ctx->dir) < 0) lambert = -lambert;
      if (lambert < 0) lambert = 0;
    }
    q[3] = AMBIENT + DIFFUSE * lambert;
  }
  const hoc_render_mesh *m = vs->mesh;
  st->base = m->q ? hoc_render_quality_colour(&ctx->qscale, hoc_render_q(m, e)) : HOC_RENDER_GREY;
  st->edge_alpha = 0;
  if (ctx->edges) {
    /* edges of elements a few pixels across fade out instead of blackening the mesh */
    const double *b = vs->box + 4 * e;
    double d = ctx->scale * hypot(b[1] - b[0], b[3] - b[2]);
    double f = d / 16;
    st->edge_alpha = EDGE_OPACITY * (f < 0.3 ? 0.3 : f > 1 ? 1 : f);
  }
  for (int k = 0; k < t->ntri; ++k) {
    const int *tri = t->tri + 3 * k; /* [3] */
    raster_triangle(ws, st, ws->pts + 4 * tri[0], ws->pts + 4 * tri[1], ws->pts + 4 * tri[2],
                    t->rs + 2 * tri[0], t->rs + 2 * tri[1], t->rs + 2 * tri[2]);
  }
}

/* Bands ------------------------------------------------------------------- */

/* Whether element e stands wholly in front of the near clip (its corners). */
static int clipped(const render_ctx *ctx, const view_state *vs, size_t e) {
  if (!(ctx->zclip < INFINITY)) return 0;
  const size_t *cn = vs->mesh->conn + e * (size_t)vs->np;
  for (int i = 0; i < 3; ++i)
    if (dot3(vs->mesh->xyz + 3 * cn[i], ctx->dir) - ctx->fz <= ctx->zclip) return 0;
  return 1;
}

static void render_band(const render_ctx *ctx, int band, workspace *ws, hoc_canvas *out) {
  const int stride = ctx->width * SS;
  const int y0 = band * ctx->band_rows;
  const int rows = out->rows;
  const size_t ns = (size_t)stride * (size_t)(rows * SS);
  const uint32_t bg = ctx->transparent ? 0 : 0xffffffffu;
  for (size_t i = 0; i < ns; ++i)
    ws->z[i] = -FLT_MAX, ws->rgba[i] = bg;
  for (int k = 0; k < ctx->n_views; ++k) {
    const view_state *vs = &ctx->views[k];
    tri_style st = {.cx0 = vs->x0 * SS,
                    .cx1 = vs->x1 * SS,
                    .cy0 = (y0 > ctx->panel_y0 ? y0 : ctx->panel_y0) * SS,
                    .cy1 = (y0 + rows) * SS,
                    .sy0 = y0 * SS,
                    .edge_half = ctx->edge_half_width * SS,
                    .stride = stride};
    if (st.cy0 >= st.cy1) continue;
    for (size_t e = 0; e < vs->mesh->n_elems; ++e) {
      const int32_t *b = vs->bands + 2 * e;
      if (b[0] <= band && band <= b[1] && !clipped(ctx, vs, e)) draw_element(ctx, vs, e, ws, &st);
    }
  }
  /* box filter SS x SS samples -> one pixel, premultiplied by coverage */
  for (int y = 0; y < rows; ++y)
    for (int x = 0; x < ctx->width; ++x) {
      unsigned sum[4] = {0, 0, 0, 0};
      for (int j = 0; j < SS; ++j) {
        const uint32_t *s = ws->rgba + (size_t)(y * SS + j) * (size_t)stride + (size_t)x * SS;
        for (int i = 0; i < SS; ++i) {
          unsigned a = s[i] >> 24;
          sum[0] += (s[i] & 0xff) * a;
          sum[1] += (s[i] >> 8 & 0xff) * a;
          sum[2] += (s[i] >> 16 & 0xff) * a;
          sum[3] += a;
        }
      }
      unsigned char *p = out->rgba + 4 * ((size_t)y * (size_t)ctx->width + (size_t)x);
      if (sum[3] == 0) {
        p[0] = p[1] = p[2] = 255, p[3] = 0;
      } else {
        for (int c = 0; c < 3; ++c)
          p[c] = (unsigned char)((sum[c] + sum[3] / 2) / sum[3]);
        p[3] = (unsigned char)((sum[3] + SS * SS / 2) / (SS * SS));
      }
    }
  hoc_render_draw_overlays(ctx, out);
}

/* Entry point ------------------------------------------------------------- */

hoc_status hoc_render_png(const char *path, const hoc_render_mesh *views, int n_views,
                          const hoc_render_options *options) {
  int width, height;
  HOC_TRY(hoc_render_check_common(path, views, n_views, options, &width, &height));
  for (int k = 0; k < n_views; ++k)
    HOC_TRY(check_view(&views[k], k));

  hoc_status status = HOC_OK;
  render_ctx ctx = {0};
  workspace *ws = NULL;
  unsigned char *out_buf = NULL;
  hoc_png_out *png = NULL;
  int nthreads = 1;
#ifdef _OPENMP
  nthreads = omp_get_max_threads();
#endif
  if (nthreads > MAX_THREADS) nthreads = MAX_THREADS;
  ctx.width = width;
  ctx.height = height;
  ctx.n_views = n_views;
  ctx.transparent = options ? options->transparent != 0 : 0;
  ctx.edges = options ? !options->no_edges : 1;
  /* zoom_worst: the view holding the worst element of all (the first on
   * ties); without a given direction, look at that element from the side of
   * its corners' normal nearer the isometric eye, a little tilted */
  int kw = -1;
  size_t ew = 0;
  hoc_render_options opt_local;
  if (options && options->zoom_worst) {
    double qw = INFINITY;
    for (int k = 0; k < n_views; ++k)
      for (size_t e = 0; views[k].q && e < views[k].n_elems; ++e)
        if (hoc_render_q(&views[k], e) < qw) qw = hoc_render_q(&views[k], e), kw = k, ew = e;
    if (kw < 0 && views[0].n_elems > 0) kw = 0; /* no q: zoom_frame says so */
    if (kw >= 0 && views[kw].q && options->view[0] == 0 && options->view[1] == 0 &&
        options->view[2] == 0) {
      const hoc_render_mesh *m = &views[kw];
      const size_t *cn = m->conn + ew * hoc_tri_num_nodes(m->order);
      const double *x0 = m->xyz + 3 * cn[0], *x1 = m->xyz + 3 * cn[1], *x2 = m->xyz + 3 * cn[2];
      double a[3], b[3], n[3];
      for (int d = 0; d < 3; ++d) a[d] = x1[d] - x0[d], b[d] = x2[d] - x0[d];
      cross3(a, b, n);
      double len = sqrt(dot3(n, n));
      opt_local = *options;
      if (len > 0 && isfinite(len)) {
        double iso = 1 / sqrt(3.0), side = n[0] + n[1] + n[2] < 0 ? -1 : 1;
        for (int d = 0; d < 3; ++d) opt_local.view[d] = side * n[d] / len + 0.3 * iso;
        options = &opt_local;
      }
    }
  }
  HOC_TRY(camera_setup(&ctx, options));
  hoc_render_scale_compute(views, n_views, &ctx.qscale);

  HOC_ALLOC_GOTO(ctx.views, (size_t)n_views, done);
  HOC_ALLOC_GOTO(ctx.stats, (size_t)n_views, done);
  for (int k = 0; k < n_views; ++k) {
    view_state *vs = &ctx.views[k];
    const hoc_render_mesh *m = &views[k];
    vs->mesh = m;
    vs->np = hoc_tri_num_nodes(m->order);
    HOC_ALLOC_GOTO(vs->box, 4 * m->n_elems, done);
    HOC_ALLOC_GOTO(vs->bands, 2 * m->n_elems, done);
    node_boxes(&ctx, vs);
  }
  layout(&ctx);
  for (int k = 0; k < n_views; ++k)
    hoc_render_stats_line(&views[k], ctx.stats[k], sizeof ctx.stats[k]);

  /* frame: every node used, or the worst elements of view 0 */
  double frame[4] = {INFINITY, -INFINITY, INFINITY, -INFINITY};
  double zlo = INFINITY, zhi = -INFINITY;
  for (int k = 0; k < n_views; ++k) {
    const view_state *vs = &ctx.views[k];
    for (size_t e = 0; e < vs->mesh->n_elems; ++e)
      box_union(frame, vs->box + 4 * e);
    for (size_t i = 0; i < vs->mesh->n_nodes && vs->mesh->n_elems; ++i) {
      double z = dot3(vs->mesh->xyz + 3 * i, ctx.dir);
      zlo = min2(zlo, z), zhi = max2(zhi, z);
    }
  }
  ctx.zclip = INFINITY;
  if (kw >= 0) HOC_TRY_GOTO(zoom_frame(&ctx.views[kw], frame), done);
  fit_frame(&ctx, frame, zlo <= zhi ? 0.5 * (zlo + zhi) : 0);
  if (kw >= 0 && views[kw].q) {
    /* near clip: what stands in front of the worst element by more than the
     * frame's size does not hide it */
    const hoc_render_mesh *m = &views[kw];
    const size_t *cn = m->conn + ew * hoc_tri_num_nodes(m->order);
    double zw = -INFINITY;
    for (int i = 0; i < hoc_tri_num_nodes(m->order); ++i)
      zw = max2(zw, dot3(m->xyz + 3 * cn[i], ctx.dir) - ctx.fz);
    ctx.zclip = zw + max2(frame[1] - frame[0], frame[3] - frame[2]);
  }
  HOC_TRY_GOTO(hoc_render_find_markers(&ctx), done);

  /* subdivision and evaluation table of each view */
  for (int k = 0; k < n_views; ++k) {
    view_state *vs = &ctx.views[k];
    hoc_lagrange *basis = NULL;
    HOC_TRY_GOTO(hoc_lagrange_create(vs->mesh->order, vs->mesh->rs, &basis), done);
    status = lattice_build(&vs->tab, choose_subdivision(&ctx, vs), basis, vs->np);
    hoc_lagrange_destroy(&basis);
    if (status != HOC_OK) goto done;
  }

  /* bands and per-thread buffers */
  int band_rows = BAND_SAMPLES / (width * SS * SS);
  ctx.band_rows = band_rows < 4 ? 4 : band_rows > 64 ? 64 : band_rows;
  ctx.n_bands = (height + ctx.band_rows - 1) / ctx.band_rows;
  size_t band_samples = (size_t)width * SS * (size_t)ctx.band_rows * SS;
  HOC_ALLOC_GOTO(ws, (size_t)nthreads, done);
  for (int t = 0; t < nthreads; ++t) {
    HOC_ALLOC_GOTO(ws[t].z, band_samples, done);
    HOC_ALLOC_GOTO(ws[t].rgba, band_samples, done);
    HOC_ALLOC_GOTO(ws[t].x, 3 * (size_t)hoc_tri_num_nodes(HOC_MAX_ORDER), done);
    HOC_ALLOC_GOTO(ws[t].pts, 4 * (size_t)MAX_PTS, done);
  }
  for (int k = 0; k < n_views; ++k)
    element_bands(&ctx, &ctx.views[k], ws, nthreads);

  size_t band_bytes = 4 * (size_t)width * (size_t)ctx.band_rows;
  int group = 4 * nthreads; /* bands rendered between two writes */
  if ((size_t)group * band_bytes > OUT_BYTES) group = (int)(OUT_BYTES / band_bytes);
  if (group < nthreads) group = nthreads;
  if (group > ctx.n_bands) group = ctx.n_bands;
  HOC_ALLOC_GOTO(out_buf, band_bytes * (size_t)group, done);
  HOC_TRY_GOTO(hoc_png_out_open(path, width, height, ctx.transparent, &png), done);
  for (int g0 = 0; g0 < ctx.n_bands; g0 += group) {
    int gn = ctx.n_bands - g0 < group ? ctx.n_bands - g0 : group;
#pragma omp parallel for schedule(dynamic, 1) num_threads(nthreads)
    for (int i = 0; i < gn; ++i) {
      int band = g0 + i, y0 = band * ctx.band_rows;
      hoc_canvas c = {out_buf + band_bytes * (size_t)i, width, height, y0,
                      height - y0 < ctx.band_rows ? height - y0 : ctx.band_rows};
#ifdef _OPENMP
      render_band(&ctx, band, &ws[omp_get_thread_num()], &c);
#else
      render_band(&ctx, band, &ws[0], &c);
#endif
    }
    for (int i = 0; i < gn; ++i) {
      int y0 = (g0 + i) * ctx.band_rows;
      hoc_canvas c = {out_buf + band_bytes * (size_t)i, width, height, y0,
                      height - y0 < ctx.band_rows ? height - y0 : ctx.band_rows};
      HOC_TRY_GOTO(hoc_png_out_rows(png, &c), done);
    }
  }
  HOC_TRY_GOTO(hoc_png_out_close(&png), done);

done:
  hoc_png_out_abort(&png);
  free(out_buf);
  if (ws)
    for (int t = 0; t < nthreads; ++t)
      free(ws[t].z), free(ws[t].rgba), free(ws[t].x), free(ws[t].pts);
  free(ws);
  if (ctx.views)
    for (int k = 0; k < n_views; ++k) {
      view_state *vs = &ctx.views[k];
      lattice_free(&vs->tab);
      free(vs->box), free(vs->bands);
    }
  free(ctx.views);
  free(ctx.stats);
  free(ctx.markers);
  return status;
}
