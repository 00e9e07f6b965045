/* Sizes graded down to CAD curves far shorter than the mesh around them
 * and to faces far narrower: the size field of a second linear meshing
 * (hoc_linear_grading_*).
 *
 * A CAD curve much shorter than the edges around it (a blunt trailing
 * edge's end, a sliver face's short side, a small edge a fillet leaves)
 * gets one segment, and the triangles on it have that segment as one side
 * and the surrounding size as the two others: slivers of q about
 * sqrt(3) L / h. A face much narrower than the edges (a thin plate's rim,
 * a blunt trailing edge along the span) gets one row of such slivers
 * across. gmsh's curvature sizing does not grade toward either, and
 * gmsh 4.8 clamps every size, its size callback's too, to its minimum
 * size (a tenth of the maximum by default), so no size field alone can.
 * The second meshing lowers the minimum and turns gmsh's curvature sizing
 * off (below the old minimum it would refine every tight radius) and its
 * extension of the curves' sizes into the faces (it would carry a thin
 * face's size into the faces beside it); this field gives both back: at
 * each node of the first mesh the size gmsh gave it (2 pi / (n kappa)
 * within [hmin, hmax], kappa the largest curvature of the node's faces
 * and curves, by differences of the CAD's derivatives, at most the first
 * mesh's mean edge there and the bound of a face meshed finer), linear in
 * the first mesh's triangle at the point (found from the nearest node),
 * and within reach of a short curve HOC_LINEAR_SHORT_SIZE x its length,
 * of a thin face that times its width, growing by HOC_LINEAR_GRADE per
 * unit of distance (mesh.h).
 * SPDX-License-Identifier: GPL-2.0-or-later */
#include "cad/cad.h"
#include "core/geometry.h"
#include "core/hash.h"
#include "mesh/mesh.h"

#include <math.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

struct hoc_linear_grading {
  /* the first mesh's nodes, sorted by grid cell, and their sizes */
  size_t n;
  double *xyz, *h;
  double origin[3], cell;
  hoc_hash cells; /* cell key -> first node of the cell in the sorted order */
  size_t *end;    /* [n]: one past the last node of the cell of node i (at its first) */
  /* its triangles (sorted node indices) and each node's, CSR */
  size_t *tri, *adj_start, *adj;
  /* the short curves' segments [n_seg][6] and their curves' lengths */
  size_t n_seg;
  double *seg, *seg_h;
  /* the segments near each cell of side seg_cell (segment_grid): cell key
   * -> its first place i in seg_list, seg_end[i] one past its last */
  double seg_cell, seg_half; /* seg_half: the longest segment's half length */
  hoc_hash seg_cells;
  size_t *seg_list, *seg_end;
  double min_size;
  int n_curves; /* the short curves */
  int n_faces;  /* the faces with thin triangles */
};

static double dist2(const double *a, const double *b) {
  double d0 = a[0] - b[0], d1 = a[1] - b[1], d2 = a[2] - b[2];
  return d0 * d0 + d1 * d1 + d2 * d2;
}

/* Distance from x to the segment a-b. */
static double seg_dist(const double *x, const double *a, const double *b) {
  double ab[3], ax[3], p[3];
  for (int d = 0; d < 3; ++d) {
    ab[d] = b[d] - a[d];
    ax[d] = x[d] - a[d];
  }
  double l2 = hoc_dot3(ab, ab), t = l2 > 0 ? hoc_dot3(ab, ax) / l2 : 0;
  t = t < 0 ? 0 : t > 1 ? 1 : t;
  for (int d = 0; d < 3; ++d)
    p[d] = a[d] + t * ab[d];
  return hoc_dist3(x, p);
}

#define CELL_BITS 21
#define CELL_MAX ((1 << CELL_BITS) - 1)

static int64_t cell_index(double x, double o, double c) {
  double i = floor((x - o) / c);
  return i < 0 ? 0 : i > CELL_MAX ? CELL_MAX : (int64_t)i;
}

static uint64_t cell_key(int64_t i, int64_t j, int64_t k) {
  return ((uint64_t)i << (2 * CELL_BITS)) | ((uint64_t)j << CELL_BITS) | (uint64_t)k;
}

typedef struct keyed {
  uint64_t key;
  size_t node;
} keyed;

static int by_key(const void *a, const void *b) {
  const keyed *x = a, *y = b;
  if (x->key != y->key) return x->key < y->key ? -1 : 1;
  return x->node < y->node ? -1 : x->node > y->node;
}

/* Whether cell (i, j, k) is in the grid. */
static int in_grid(int64_t i, int64_t j, int64_t k) {
  return i >= 0 && j >= 0 && k >= 0 && i <= CELL_MAX && j <= CELL_MAX && k <= CELL_MAX;
}

/* order[n], sorted by key, in cells: cells maps each key to the first
 * place i of its run, end[i] is one past the run's last. */
static hoc_status index_cells(const keyed *order, size_t n, hoc_hash *cells, size_t *end) {
  HOC_TRY(hoc_hash_init(cells, n / 4 + 16));
  for (size_t i = 0, j; i < n; i = j) {
    for (j = i + 1; j < n && order[j].key == order[i].key; ++j) {
    }
    end[i] = j;
    HOC_TRY(hoc_hash_insert(cells, order[i].key, i, NULL, NULL));
  }
  return HOC_OK;
}

void hoc_linear_grading_free(hoc_linear_grading **g) {
  if (!g || !*g) return;
  free((*g)->xyz);
  free((*g)->h);
  free((*g)->end);
  free((*g)->tri);
  free((*g)->adj_start);
  free((*g)->adj);
  free((*g)->seg);
  free((*g)->seg_h);
  free((*g)->seg_list);
  free((*g)->seg_end);
  hoc_hash_free(&(*g)->cells);
  hoc_hash_free(&(*g)->seg_cells);
  free(*g);
  *g = NULL;
}

/* The larger principal curvature (absolute) of face f at uv, by central
 * differences of its first derivatives (one-sided at its bounds); -1
 * where the face degenerates (a pole), 0 where it cannot be evaluated. */
static double face_curvature(const hoc_model *model, int f, const double *uv) {
  const hoc_cad_face *face = &model->faces[f];
  double d[2], lo[2], hi[2];
  for (int k = 0; k < 2; ++k) {
    d[k] = 1e-4 * (face->hi[k] - face->lo[k]);
    if (!(d[k] > 0)) return 0;
    lo[k] = face->period[k] > 0 ? uv[k] - d[k] : fmax(face->lo[k], uv[k] - d[k]);
    hi[k] = face->period[k] > 0 ? uv[k] + d[k] : fmin(face->hi[k], uv[k] + d[k]);
    if (!(hi[k] > lo[k])) return 0;
  }
  double p[10] = {uv[0], uv[1], lo[0], uv[1], hi[0], uv[1], uv[0], lo[1], uv[0], hi[1]};
  double du[15], dv[15];
  if (hoc_cad_face_eval(model, f, 5, p, NULL, du, dv) != HOC_OK) return 0;
  double n[3], uu[3], uv2[3], vv[3];
  hoc_cross3(du, dv, n);
  double area = sqrt(hoc_dot3(n, n));
  if (!(area > 0)) return -1;
  for (int k = 0; k < 3; ++k) {
    n[k] /= area;
    uu[k] = (du[6 + k] - du[3 + k]) / (hi[0] - lo[0]);
    uv2[k] = (du[12 + k] - du[9 + k]) / (hi[1] - lo[1]);
    vv[k] = (dv[12 + k] - dv[9 + k]) / (hi[1] - lo[1]);
  }
  double E = hoc_dot3(du, du), F = hoc_dot3(du, dv), G = hoc_dot3(dv, dv);
  double L = hoc_dot3(n, uu), M = hoc_dot3(n, uv2), N = hoc_dot3(n, vv), det = E * G - F * F;
  if (!(det > 0)) return -1;
  double K = (L * N - M * M) / det, H = (E * N - 2 * F * M + G * L) / (2 * det);
  return fabs(H) + sqrt(fmax(H * H - K, 0));
}

/* The curvature of curve c at t (central differences of its derivative). */
static double curve_curvature(const hoc_model *model, int c, double t) {
  const hoc_cad_curve *curve = &model->curves[c];
  double d = 1e-4 * (curve->hi - curve->lo);
  if (!(d > 0)) return 0;
  double a = curve->period > 0 ? t - d : fmax(curve->lo, t - d);
  double b = curve->period > 0 ? t + d : fmin(curve->hi, t + d);
  if (!(b > a)) return 0;
  double ts[3] = {t, a, b}, dt[9];
  if (hoc_cad_curve_eval(model, c, 3, ts, NULL, dt) != HOC_OK) return 0;
  double dd[3], x[3];
  for (int k = 0; k < 3; ++k)
    dd[k] = (dt[6 + k] - dt[3 + k]) / (b - a);
  hoc_cross3(dt, dd, x);
  double s = sqrt(hoc_dot3(dt, dt));
  return s > 0 ? sqrt(hoc_dot3(x, x)) / (s * s * s) : 0;
}

/* Each node's size as gmsh's sizing gave it: the curvature's (2 pi / (n
 * kappa), kappa the largest of its faces' and curves' there), at most the
 * first mesh's mean edge at the node (gmsh's mesh is finer than its
 * curvature sizing where it extends its curves' sizes into the faces, and
 * the graded meshing does not: that extension carries the size graded
 * down along a thin face into every face beside it), within [hmin, hmax];
 * at a pole (no normal there) that mean edge; at most the bound of a face
 * meshed finer (face_size). */
static hoc_status node_sizes(const hoc_mesh *lin, double hmin, double hmax, double ncurv,
                             const double *face_size, double *h) {
  const hoc_model *model = lin->model;
  size_t nn = lin->n_nodes;
  hoc_status status = HOC_OK;
  unsigned char *pole = NULL;
  double *sum = NULL;
  size_t *count = NULL;
  HOC_ALLOC_GOTO(pole, nn + 1, done);
  HOC_ALLOC_GOTO(sum, nn + 1, done);
  HOC_ALLOC_GOTO(count, nn + 1, done);
  for (size_t i = 0; i < nn; ++i)
    h[i] = 0; /* kappa first */
  for (size_t s = 0; s < lin->n_slots; ++s) {
    double k = face_curvature(model, lin->slot_face[s], lin->slot_uv + 2 * s);
    size_t n = lin->slot_node[s];
    if (k < 0)
      pole[n] = 1;
    else if (k > h[n])
      h[n] = k;
  }
  for (size_t l = 0; l < lin->n_lines; ++l)
    for (size_t e = 0; e < 2; ++e) {
      double k = curve_curvature(model, lin->line_curve[l], lin->line_t[2 * l + e]);
      size_t n = lin->line_conn[2 * l + e];
      if (k > h[n]) h[n] = k;
    }
  for (size_t e = 0; e < lin->n_elems; ++e)
    for (size_t k = 0; k < 3; ++k) {
      size_t a = lin->conn[3 * e + k], b = lin->conn[3 * e + (k + 1) % 3];
      double l = hoc_dist3(lin->xyz + 3 * a, lin->xyz + 3 * b);
      sum[a] += l, sum[b] += l;
      count[a]++, count[b]++;
    }
  for (size_t i = 0; i < nn; ++i) {
    double size = h[i] > 0 && ncurv > 0 ? 2 * 3.14159265358979323846 / (ncurv * h[i]) : hmax;
    double mean = count[i] ? sum[i] / (double)count[i] : size;
    size = pole[i] ? mean : fmin(size, mean);
    h[i] = fmin(hmax, fmax(hmin, size));
  }
  for (size_t s = 0; face_size && s < lin->n_slots; ++s) {
    double b = face_size[lin->slot_face[s]];
    size_t n = lin->slot_node[s];
    if (b > 0 && b < h[n]) h[n] = b;
  }
done:
  free(pole);
  free(sum);
  free(count);
  return status;
}

/* The curves far shorter than the edges at their nodes: is_short[c] set
 * for each (is_short[n_curves]); their segments into g (NULL: only
 * counted), their number in *n. */
static hoc_status short_curves(const hoc_mesh *lin, double ratio, unsigned char *is_short,
                               hoc_linear_grading *g, size_t *n) {
  const hoc_model *model = lin->model;
  size_t nn = lin->n_nodes, nc = (size_t)model->n_curves;
  hoc_status status = HOC_OK;
  double *longest = NULL, *len = NULL, *around = NULL;
  HOC_ALLOC_GOTO(longest, nn + 1, done);
  HOC_ALLOC_GOTO(len, nc + 1, done);
  HOC_ALLOC_GOTO(around, nc + 1, done);
  for (size_t e = 0; e < lin->n_elems; ++e)
    for (size_t k = 0; k < 3; ++k) {
      size_t a = lin->conn[3 * e + k], b = lin->conn[3 * e + (k + 1) % 3];
      double l = hoc_dist3(lin->xyz + 3 * a, lin->xyz + 3 * b);
      longest[a] = fmax(longest[a], l);
      longest[b] = fmax(longest[b], l);
    }
  /* each curve's length, and the longest edge at its nodes */
  for (size_t l = 0; l < lin->n_lines; ++l) {
    int c = lin->line_curve[l];
    size_t a = lin->line_conn[2 * l], b = lin->line_conn[2 * l + 1];
    len[c] += hoc_dist3(lin->xyz + 3 * a, lin->xyz + 3 * b);
    around[c] = fmax(around[c], fmax(longest[a], longest[b]));
  }
  *n = 0;
  for (size_t c = 0; c < nc; ++c) {
    is_short[c] = len[c] > 0 && around[c] > ratio * len[c];
    if (g) g->n_curves += is_short[c];
  }
  for (size_t l = 0; l < lin->n_lines; ++l) {
    int c = lin->line_curve[l];
    if (!is_short[c]) continue;
    if (g) {
      memcpy(g->seg + 6 * *n, lin->xyz + 3 * lin->line_conn[2 * l], 3 * sizeof *g->seg);
      memcpy(g->seg + 6 * *n + 3, lin->xyz + 3 * lin->line_conn[2 * l + 1], 3 * sizeof *g->seg);
      g->seg_h[*n] = len[c];
      g->min_size = fmin(g->min_size, len[c]);
    }
    ++*n;
  }
done:
  free(longest);
  free(len);
  free(around);
  return status;
}

/* Is node i of lin on curve c (on it, or at one of its ends)? */
static int on_curve(const hoc_mesh *lin, size_t i, int c) {
  return hoc_node_on_curve(lin->model, lin->dim[i], lin->entity[i], c);
}

/* Is node i on a curve flagged in is_short (or at its end)? */
static int on_short(const hoc_mesh *lin, const unsigned char *is_short, size_t i) {
  if (lin->dim[i] == HOC_ON_CURVE) return is_short[lin->entity[i]];
  for (int c = 0; c < lin->model->n_curves; ++c)
    if (is_short[c] && on_curve(lin, i, c)) return 1;
  return 0;
}

/* The width of linear triangle e across its longest edge k..k+1 if its
 * face is narrower there than 1 / ratio of that edge, else 0: its three
 * corners lie on the face's boundary, on two curves or more (a face's
 * width runs between its sides; three nodes on one curve only make a
 * triangle as flat as the curve is straight) and none on a short curve
 * (short_curves grades those: the sliver on a short curve is narrow
 * along it only). */
static double thin_width(const hoc_mesh *lin, double ratio, const unsigned char *is_short,
                         size_t e, int *k) {
  const size_t *t = lin->conn + 3 * e;
  double longest = 0;
  for (int i = 0; i < 3; ++i) {
    if (lin->dim[t[i]] == HOC_ON_FACE) return 0;
    double len = hoc_dist3(lin->xyz + 3 * t[i], lin->xyz + 3 * t[(i + 1) % 3]);
    if (len > longest) longest = len, *k = i;
  }
  double e1[3], e2[3], c[3];
  for (int d = 0; d < 3; ++d) {
    e1[d] = lin->xyz[3 * t[1] + d] - lin->xyz[3 * t[0] + d];
    e2[d] = lin->xyz[3 * t[2] + d] - lin->xyz[3 * t[0] + d];
  }
  hoc_cross3(e1, e2, c);
  double w = longest > 0 ? sqrt(hoc_dot3(c, c)) / longest : 0;
  if (!(w > 0 && longest > ratio * w)) return 0;
  /* one curve through all three: a curve node's curve is the only one */
  for (int i = 0; i < 3; ++i)
    if (lin->dim[t[i]] == HOC_ON_CURVE) {
      int cv = lin->entity[t[i]];
      if (on_curve(lin, t[0], cv) && on_curve(lin, t[1], cv) && on_curve(lin, t[2], cv)) return 0;
      break;
    }
  /* (three vertex nodes: no curve has three ends) */
  for (int i = 0; i < 3; ++i)
    if (on_short(lin, is_short, t[i])) return 0;
  return w;
}

/* The thin triangles' longest edges as segments of their widths into g
 * (NULL: only counted), their number in *n; the faces they lie on
 * counted in g->n_faces. */
static hoc_status thin_faces(const hoc_mesh *lin, double ratio, const unsigned char *is_short,
                             hoc_linear_grading *g, size_t *n) {
  unsigned char *face_seen = NULL;
  if (g) HOC_ALLOC(face_seen, (size_t)lin->model->n_faces + 1);
  *n = 0;
  for (size_t e = 0; e < lin->n_elems; ++e) {
    int k = 0;
    double w = thin_width(lin, ratio, is_short, e, &k);
    if (!(w > 0)) continue;
    if (g) {
      size_t s = g->n_seg + *n;
      const size_t *t = lin->conn + 3 * e;
      memcpy(g->seg + 6 * s, lin->xyz + 3 * t[k], 3 * sizeof *g->seg);
      memcpy(g->seg + 6 * s + 3, lin->xyz + 3 * t[(k + 1) % 3], 3 * sizeof *g->seg);
      g->seg_h[s] = w;
      g->min_size = fmin(g->min_size, w);
      int f = lin->elem_face[e];
      g->n_faces += !face_seen[f];
      face_seen[f] = 1;
    }
    ++*n;
  }
  free(face_seen);
  return HOC_OK;
}

/* g's grid of lin's nodes (cells of the mean edge length) and its node
 * sizes h (by lin's node index), sorted by cell. */
static hoc_status node_grid(const hoc_mesh *lin, const double *h, hoc_linear_grading *g) {
  const hoc_model *model = lin->model;
  size_t nn = lin->n_nodes, ne = lin->n_elems;
  hoc_status status = HOC_OK;
  keyed *order = NULL;
  size_t *rank = NULL, *fill = NULL;
  double sum = 0;
  for (size_t e = 0; e < ne; ++e)
    for (size_t k = 0; k < 3; ++k)
      sum += hoc_dist3(lin->xyz + 3 * lin->conn[3 * e + k],
                       lin->xyz + 3 * lin->conn[3 * e + (k + 1) % 3]);
  g->cell = fmax(ne ? sum / (double)(3 * ne) : 0, 1e-9 * model->diagonal);
  /* (at most 2^21 cells a side: coarser where the model is wider) */
  for (int d = 0; d < 3; ++d) {
    g->origin[d] = model->bbox[d];
    double side = model->bbox[d + 3] - model->bbox[d];
    if (side / g->cell > CELL_MAX / 2) g->cell = side / (CELL_MAX / 2);
  }
  g->n = nn;
  HOC_ALLOC_GOTO(order, nn + 1, done);
  for (size_t i = 0; i < nn; ++i) {
    const double *x = lin->xyz + 3 * i;
    order[i].key =
        cell_key(cell_index(x[0], g->origin[0], g->cell), cell_index(x[1], g->origin[1], g->cell),
                 cell_index(x[2], g->origin[2], g->cell));
    order[i].node = i;
  }
  qsort(order, nn, sizeof *order, by_key);
  HOC_ALLOC_GOTO(g->xyz, 3 * nn + 1, done);
  HOC_ALLOC_GOTO(g->h, nn + 1, done);
  HOC_ALLOC_GOTO(g->end, nn + 1, done);
  HOC_ALLOC_GOTO(rank, nn + 1, done);
  for (size_t i = 0; i < nn; ++i) {
    memcpy(g->xyz + 3 * i, lin->xyz + 3 * order[i].node, 3 * sizeof *g->xyz);
    g->h[i] = h[order[i].node];
    rank[order[i].node] = i;
  }
  /* the triangles on the sorted nodes, and each node's */
  HOC_ALLOC_GOTO(g->tri, 3 * ne + 1, done);
  HOC_ALLOC_GOTO(g->adj_start, nn + 2, done);
  HOC_ALLOC_GOTO(g->adj, 3 * ne + 1, done);
  HOC_ALLOC_GOTO(fill, nn + 1, done);
  for (size_t i = 0; i < 3 * ne; ++i) {
    g->tri[i] = rank[lin->conn[i]];
    g->adj_start[g->tri[i] + 1]++;
  }
  for (size_t i = 0; i < nn; ++i)
    g->adj_start[i + 1] += g->adj_start[i];
  for (size_t i = 0; i < 3 * ne; ++i)
    g->adj[g->adj_start[g->tri[i]] + fill[g->tri[i]]++] = i / 3;
  HOC_TRY_GOTO(index_cells(order, nn, &g->cells, g->end), done);
done:
  free(order);
  free(rank);
  free(fill);
  return status;
}

/* For each grid cell near a short curve, the segments that can lower a
 * size there: a segment lowers the size below h only within (h -
 * HOC_LINEAR_SHORT_SIZE L) / HOC_LINEAR_GRADE of it, the cell's side is
 * that reach at the largest node size (plus half the longest segment), and
 * each segment is listed in the 27 cells around its middle's, so one
 * lookup finds them (a coarse mesh of a model with hundreds of short
 * curves asks gmsh's size callback for sizes millions of times). */
static hoc_status segment_grid(const hoc_model *model, const double *h, size_t nn,
                               hoc_linear_grading *g) {
  size_t ns = g->n_seg, m = 27 * ns;
  hoc_status status = HOC_OK;
  keyed *order = NULL;
  double hmax = 0;
  for (size_t i = 0; i < nn; ++i)
    hmax = fmax(hmax, h[i]);
  g->seg_half = 0;
  for (size_t s = 0; s < ns; ++s)
    g->seg_half = fmax(g->seg_half, 0.5 * hoc_dist3(g->seg + 6 * s, g->seg + 6 * s + 3));
  g->seg_cell = fmax(hmax / HOC_LINEAR_GRADE + g->seg_half, 1e-9 * model->diagonal);
  for (int d = 0; d < 3; ++d) {
    double side = model->bbox[d + 3] - model->bbox[d];
    if (side / g->seg_cell > CELL_MAX / 2) g->seg_cell = side / (CELL_MAX / 2);
  }
  HOC_ALLOC_GOTO(order, m + 1, done);
  size_t n = 0;
  for (size_t s = 0; s < ns; ++s) {
    int64_t c[3];
    for (int d = 0; d < 3; ++d)
      c[d] =
          cell_index(0.5 * (g->seg[6 * s + d] + g->seg[6 * s + 3 + d]), g->origin[d], g->seg_cell);
    for (int64_t i = c[0] - 1; i <= c[0] + 1; ++i)
      for (int64_t j = c[1] - 1; j <= c[1] + 1; ++j)
        for (int64_t k = c[2] - 1; k <= c[2] + 1; ++k) {
          if (!in_grid(i, j, k)) continue;
          order[n].key = cell_key(i, j, k);
          order[n++].node = s;
        }
  }
  qsort(order, n, sizeof *order, by_key);
  HOC_ALLOC_GOTO(g->seg_list, n + 1, done);
  HOC_ALLOC_GOTO(g->seg_end, n + 1, done);
  for (size_t i = 0; i < n; ++i)
    g->seg_list[i] = order[i].node;
  HOC_TRY_GOTO(index_cells(order, n, &g->seg_cells, g->seg_end), done);
done:
  free(order);
  return status;
}

hoc_status hoc_linear_grading_make(const hoc_mesh *lin, double ratio, double hmin, double hmax,
                                   double ncurv, const double *face_size,
                                   hoc_linear_grading **out) {
  *out = NULL;
  hoc_status status = HOC_OK;
  hoc_linear_grading *g = NULL;
  double *h = NULL;
  unsigned char *is_short = NULL;
  size_t n_short, n_thin;
  HOC_ALLOC_GOTO(is_short, (size_t)lin->model->n_curves + 1, done);
  HOC_TRY_GOTO(short_curves(lin, ratio, is_short, NULL, &n_short), done);
  HOC_TRY_GOTO(thin_faces(lin, ratio, is_short, NULL, &n_thin), done);
  if (!n_short && !n_thin) goto done; /* nothing to grade */
  HOC_ALLOC_GOTO(g, 1, done);
  HOC_ALLOC_GOTO(g->seg, 6 * (n_short + n_thin), done);
  HOC_ALLOC_GOTO(g->seg_h, n_short + n_thin, done);
  g->min_size = INFINITY;
  HOC_TRY_GOTO(short_curves(lin, ratio, is_short, g, &g->n_seg), done);
  HOC_TRY_GOTO(thin_faces(lin, ratio, is_short, g, &n_thin), done);
  g->n_seg += n_thin;
  HOC_ALLOC_GOTO(h, lin->n_nodes + 1, done);
  HOC_TRY_GOTO(node_sizes(lin, hmin, hmax, ncurv, face_size, h), done);
  HOC_TRY_GOTO(node_grid(lin, h, g), done);
  HOC_TRY_GOTO(segment_grid(lin->model, h, lin->n_nodes, g), done);
  *out = g;
  g = NULL;
done:
  hoc_linear_grading_free(&g);
  free(h);
  free(is_short);
  return status;
}

size_t hoc_linear_grading_segments(const hoc_linear_grading *g) { return g ? g->n_seg : 0; }

int hoc_linear_grading_curves(const hoc_linear_grading *g) { return g ? g->n_curves : 0; }

int hoc_linear_grading_faces(const hoc_linear_grading *g) { return g ? g->n_faces : 0; }

double hoc_linear_grading_min_size(const hoc_linear_grading *g) { return g->min_size; }

/* The first mesh's size at its node nearest to x (rings of cells around
 * x's until no nearer node can be found). */
static double background(const hoc_linear_grading *g, const double *x) {
  int64_t c[3];
  for (int d = 0; d < 3; ++d)
    c[d] = cell_index(x[d], g->origin[d], g->cell);
  double best = INFINITY, h = 0;
  size_t near = 0;
  for (int64_t r = 0; r <= CELL_MAX; ++r) {
    /* every node in a ring r is at least (r - 1) cells away */
    if (r > 0 && (double)(r - 1) * g->cell > sqrt(best)) break;
    for (int64_t i = c[0] - r; i <= c[0] + r; ++i)
      for (int64_t j = c[1] - r; j <= c[1] + r; ++j) {
        /* only the ring's surface: inside its sides in i and j, its two
         * cells in k */
        int side = llabs(i - c[0]) == r || llabs(j - c[1]) == r;
        int64_t step = side || r == 0 ? 1 : 2 * r;
        for (int64_t k = c[2] - r; k <= c[2] + r; k += step) {
          if (!in_grid(i, j, k)) continue;
          size_t first = hoc_hash_get(&g->cells, cell_key(i, j, k));
          if (first == SIZE_MAX) continue;
          for (size_t n = first; n < g->end[first]; ++n) {
            double d2 = dist2(x, g->xyz + 3 * n);
            if (d2 < best) best = d2, h = g->h[n], near = n;
          }
        }
      }
    if (r > 64 && isfinite(best)) break; /* (far from every node: the nearest found) */
  }
  /* linear in the triangle around that node that holds x's projection best */
  double best_b = -INFINITY;
  for (size_t a = g->adj_start[near]; a < g->adj_start[near + 1]; ++a) {
    const size_t *t = g->tri + 3 * g->adj[a];
    const double *p0 = g->xyz + 3 * t[0], *p1 = g->xyz + 3 * t[1], *p2 = g->xyz + 3 * t[2];
    double e1[3], e2[3], w[3];
    for (int d = 0; d < 3; ++d) {
      e1[d] = p1[d] - p0[d];
      e2[d] = p2[d] - p0[d];
      w[d] = x[d] - p0[d];
    }
    double a11 = hoc_dot3(e1, e1), a12 = hoc_dot3(e1, e2), a22 = hoc_dot3(e2, e2);
    double r1 = hoc_dot3(e1, w), r2 = hoc_dot3(e2, w);
    double det = a11 * a22 - a12 * a12;
    if (!(det > 0)) continue;
    double b1 = (a22 * r1 - a12 * r2) / det, b2 = (a11 * r2 - a12 * r1) / det, b0 = 1 - b1 - b2;
    double worst = fmin(b0, fmin(b1, b2));
    if (worst <= best_b) continue;
    best_b = worst;
    b0 = fmax(b0, 0), b1 = fmax(b1, 0), b2 = fmax(b2, 0);
    double sum = b0 + b1 + b2;
    h = (b0 * g->h[t[0]] + b1 * g->h[t[1]] + b2 * g->h[t[2]]) / sum;
  }
  return h;
}

/* The size segment s asks for at x. */
static double graded_size(const hoc_linear_grading *g, size_t s, const double *x) {
  return HOC_LINEAR_SHORT_SIZE * g->seg_h[s] +
         HOC_LINEAR_GRADE * seg_dist(x, g->seg + 6 * s, g->seg + 6 * s + 3);
}

double hoc_linear_grading_size(const hoc_linear_grading *g, const double *x) {
  double h = background(g, x);
  /* only segments whose middle lies within reach can lower h: one of a
   * curve of length L lowers it within (h - HOC_LINEAR_SHORT_SIZE L) /
   * HOC_LINEAR_GRADE of itself, and L >= g->min_size */
  double reach = (h - HOC_LINEAR_SHORT_SIZE * g->min_size) / HOC_LINEAR_GRADE + g->seg_half;
  if (!(reach > 0)) return h;
  if (!(reach <= g->seg_cell)) { /* (a size above the nodes' largest: every segment) */
    for (size_t i = 0; i < g->n_seg; ++i)
      h = fmin(h, graded_size(g, i, x));
    return h;
  }
  size_t first = hoc_hash_get(&g->seg_cells, cell_key(cell_index(x[0], g->origin[0], g->seg_cell),
                                                      cell_index(x[1], g->origin[1], g->seg_cell),
                                                      cell_index(x[2], g->origin[2], g->seg_cell)));
  if (first == SIZE_MAX) return h;
  for (size_t i = first; i < g->seg_end[first]; ++i)
    h = fmin(h, graded_size(g, g->seg_list[i], x));
  return h;
}
