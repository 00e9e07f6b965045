/* Pinches: iso-lines inside a face's (u, v) whose image is one point, the
 * elements across them, and the cut of a linear mesh along them.
 * SPDX-License-Identifier: GPL-2.0-or-later
 *
 * A B-spline patch whose control row collapses to a point inside it (a
 * bow tie, a spline surface of an IGES file pinched between two lobes)
 * maps a whole line u = c (or v = c) to that point. An element whose
 * (u, v) crosses the line is curved through the point: its Jacobian
 * vanishes along the line inside it, and the more nodes it has there, the
 * closer its q comes to 0. Only a mesh with nodes on the line avoids it:
 * hoc_mesh_cut_pinches (below) makes one. */
#include "core/geometry.h"
#include "mesh/mesh.h"

#include <math.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

/* Iso-lines probed across each direction, points along each, and golden
 * section steps that find the narrowest line near each probed minimum. */
enum { LINES = 64, ALONG = 17, REFINE = 40 };

/* The largest side of a face's box. */
static double face_size(const hoc_cad_face *face) {
  double size = 0;
  for (int k = 0; k < 3; ++k)
    size = fmax(size, face->bbox[k + 3] - face->bbox[k]);
  return size;
}

/* The largest distance of the image of face f's iso-line (dir 0: u = c,
 * 1: v = c) from its first point, over the face's range of the other
 * parameter. */
hoc_status hoc_face_line_spread(const hoc_model *model, int f, int dir, double c, double *s) {
  const hoc_cad_face *face = &model->faces[f];
  int o = 1 - dir;
  double uv[2 * ALONG], xyz[3 * ALONG];
  for (int k = 0; k < ALONG; ++k) {
    uv[2 * k + dir] = c;
    uv[2 * k + o] = face->lo[o] + (face->hi[o] - face->lo[o]) * k / (ALONG - 1);
  }
  HOC_TRY(hoc_cad_face_eval(model, f, ALONG, uv, xyz, NULL, NULL));
  *s = 0;
  for (int k = 1; k < ALONG; ++k)
    *s = fmax(*s, hoc_dist3(xyz + 3 * k, xyz));
  return HOC_OK;
}

hoc_status hoc_face_pinches(const hoc_model *model, int f, double share, hoc_pinch *pinch, int max,
                           int *n) {
  HOC_CHECK(model && pinch && n && f >= 0 && f < model->n_faces && max > 0 && share > 0,
            HOC_ERR_ARGUMENT, "pinch search: bad argument");
  *n = 0;
  const hoc_cad_face *face = &model->faces[f];
  double tol = share * face_size(face);
  for (int dir = 0; dir < 2; ++dir) {
    double lo = face->lo[dir], hi = face->hi[dir], h = (hi - lo) / LINES, s[LINES + 1];
    if (!(hi > lo)) continue;
    for (int i = 0; i <= LINES; ++i)
      HOC_TRY(hoc_face_line_spread(model, f, dir, lo + i * h, &s[i]));
    for (int i = 1; i < LINES && *n < max; ++i) {
      /* a minimum, not a plateau (a cylinder's lines all spread alike) */
      if (!(s[i] <= s[i - 1] && s[i] <= s[i + 1] && (s[i] < s[i - 1] || s[i] < s[i + 1])))
        continue;
      /* the narrowest line between the neighbouring probes */
      const double g = 0.5 * (sqrt(5.0) - 1);
      double a = lo + (i - 1) * h, b = lo + (i + 1) * h;
      double x1 = b - g * (b - a), x2 = a + g * (b - a), f1, f2;
      HOC_TRY(hoc_face_line_spread(model, f, dir, x1, &f1));
      HOC_TRY(hoc_face_line_spread(model, f, dir, x2, &f2));
      for (int k = 0; k < REFINE; ++k) {
        if (f1 <= f2) {
          b = x2, x2 = x1, f2 = f1, x1 = b - g * (b - a);
          HOC_TRY(hoc_face_line_spread(model, f, dir, x1, &f1));
        } else {
          a = x1, x1 = x2, f1 = f2, x2 = a + g * (b - a);
          HOC_TRY(hoc_face_line_spread(model, f, dir, x2, &f2));
        }
      }
      double c = f1 <= f2 ? x1 : x2, sc = fmin(f1, f2);
      /* inside the face: a collapsed side is a pole (hoc_cad_face.pole) */
      if (sc < tol && c > lo + 1e-9 * (hi - lo) && c < hi - 1e-9 * (hi - lo)) {
        pinch[*n].dir = dir;
        pinch[*n].c = c;
        ++*n;
      }
    }
  }
  return HOC_OK;
}

int hoc_mesh_element_crosses_pinch(const hoc_mesh *mesh, size_t e, const hoc_pinch *pinch,
                                   int n) {
  const hoc_cad_face *face = &mesh->model->faces[mesh->elem_face[e]];
  const double *uv = mesh->elem_uv + 2 * (size_t)mesh->np * e;
  for (int k = 0; k < n; ++k) {
    int d = pinch[k].dir;
    double eps = 1e-9 * (face->hi[d] - face->lo[d]);
    /* an element across a seam has its parameters unwrapped past it */
    for (int w = -1; w <= 1; ++w) {
      if (w && !(face->period[d] > 0)) continue;
      double c = pinch[k].c + w * face->period[d];
      int below = 0, above = 0;
      for (int i = 0; i < mesh->np; ++i) {
        below |= uv[2 * i + d] < c - eps;
        above |= uv[2 * i + d] > c + eps;
      }
      if (below && above) return 1;
    }
  }
  return 0;
}

hoc_status hoc_pinch_table_init(hoc_pinch_table *t, const hoc_model *model, double share,
                                int max) {
  HOC_CHECK(t && model && share > 0 && max > 0, HOC_ERR_ARGUMENT, "pinch table: bad argument");
  size_t nf = (size_t)model->n_faces;
  t->share = share;
  t->spread = 0;
  t->max = max;
  t->n = hoc_calloc(nf + 1, sizeof *t->n);
  t->line = hoc_calloc(nf * (size_t)max + 1, sizeof *t->line);
  if (!t->n || !t->line) {
    hoc_pinch_table_free(t);
    return HOC_ERROR(HOC_ERR_MEMORY, "out of memory");
  }
  for (size_t f = 0; f < nf; ++f)
    t->n[f] = -1;
  return HOC_OK;
}

void hoc_pinch_table_free(hoc_pinch_table *t) {
  if (!t) return;
  free(t->n);
  free(t->line);
  t->n = NULL;
  t->line = NULL;
}

hoc_status hoc_mesh_element_across_pinch(const hoc_mesh *mesh, size_t e, hoc_pinch_table *t,
                                         int *across) {
  int f = mesh->elem_face[e];
  hoc_pinch *line = t->line + (size_t)f * (size_t)t->max;
  if (t->n[f] < 0) {
    double share = t->share, size = face_size(&mesh->model->faces[f]);
    if (t->spread > 0 && size > 0) share = fmin(share, t->spread / size);
    HOC_TRY(hoc_face_pinches(mesh->model, f, share, line, t->max, &t->n[f]));
  }
  *across = hoc_mesh_element_crosses_pinch(mesh, e, line, t->n[f]);
  return HOC_OK;
}

/* Cutting a linear mesh along its faces' pinches --------------------------
 *
 * gmsh meshes a face in its (u, v) and does not know that a line there is
 * one point: its triangles straddle the line, and each, raised to a higher
 * order, is curved through the point (its Jacobian vanishes there; where
 * the face's normal reverses across the line, as it does across a bow
 * tie's waist, it folds). The mesh needs the point as a node and no
 * triangle across the line. Cutting the triangles along the line and
 * collapsing the line to the point does it without new triangles inside
 * the face: a triangle with one corner on one side and two on the other
 * becomes the triangle of the two and the point (the rest of it has two
 * corners at the point), one with a corner on the line and one on each
 * side has nothing left. The line ends on the face's boundary curves,
 * which pass through the point: their lines across it are split there, and
 * the triangles of the faces beyond them with them. The point's node lies
 * on the first such curve; it is on the others to within the collapse
 * distance (assemble.c accepts it at their lines' ends), and its slots on
 * the face are poles (each element sees the face's normal on its own side
 * of the line). */

/* Bisection steps for the point where a curve crosses a pinch line. */
enum { CROSS_BISECTIONS = 60 };

typedef struct cutter {
  const hoc_mesh *m;
  size_t n_nodes, node_cap, n_tri, tri_cap, n_lines, line_cap;
  double *par;      /* [node_cap][2] */
  signed char *dim; /* [node_cap] */
  int *ent;         /* [node_cap] */
  double *fu;       /* [node_cap] the pinch's coordinate of each node on the current face */
  size_t *tri;      /* [tri_cap][3] */
  int *tri_face;    /* [tri_cap] */
  size_t *line;     /* [line_cap][2] */
  int *line_curve;  /* [line_cap] */
  double *line_t;   /* [line_cap][2] */
} cutter;

static void cutter_free(cutter *C) {
  free(C->par);
  free(C->dim);
  free(C->ent);
  free(C->fu);
  free(C->tri);
  free(C->tri_face);
  free(C->line);
  free(C->line_curve);
  free(C->line_t);
}

/* Room for `more` further triangles and lines. */
static hoc_status cutter_reserve(cutter *C, size_t more) {
  if (C->n_tri + more > C->tri_cap) {
    size_t cap = 2 * (C->n_tri + more);
    size_t *tri = hoc_realloc(C->tri, 3 * cap, sizeof *tri);
    if (tri) C->tri = tri;
    int *face = hoc_realloc(C->tri_face, cap, sizeof *face);
    if (face) C->tri_face = face;
    HOC_CHECK(tri && face, HOC_ERR_MEMORY, "out of memory");
    C->tri_cap = cap;
  }
  if (C->n_lines + more > C->line_cap) {
    size_t cap = 2 * (C->n_lines + more);
    size_t *line = hoc_realloc(C->line, 2 * cap, sizeof *line);
    if (line) C->line = line;
    int *curve = hoc_realloc(C->line_curve, cap, sizeof *curve);
    if (curve) C->line_curve = curve;
    double *t = hoc_realloc(C->line_t, 2 * cap, sizeof *t);
    if (t) C->line_t = t;
    HOC_CHECK(line && curve && t, HOC_ERR_MEMORY, "out of memory");
    C->line_cap = cap;
  }
  return HOC_OK;
}

static hoc_status cutter_init(cutter *C, const hoc_mesh *m, size_t extra_nodes) {
  memset(C, 0, sizeof *C);
  C->m = m;
  C->n_nodes = m->n_nodes;
  C->node_cap = m->n_nodes + extra_nodes;
  C->par = hoc_calloc(2 * C->node_cap, sizeof *C->par);
  C->dim = hoc_calloc(C->node_cap, sizeof *C->dim);
  C->ent = hoc_calloc(C->node_cap, sizeof *C->ent);
  C->fu = hoc_calloc(C->node_cap, sizeof *C->fu);
  HOC_CHECK(C->par && C->dim && C->ent && C->fu, HOC_ERR_MEMORY, "out of memory");
  memcpy(C->par, m->param, 2 * m->n_nodes * sizeof *C->par);
  memcpy(C->dim, m->dim, m->n_nodes * sizeof *C->dim);
  memcpy(C->ent, m->entity, m->n_nodes * sizeof *C->ent);
  HOC_TRY(cutter_reserve(C, m->n_elems + m->n_lines + 16));
  memcpy(C->tri, m->conn, 3 * m->n_elems * sizeof *C->tri);
  memcpy(C->tri_face, m->elem_face, m->n_elems * sizeof *C->tri_face);
  memcpy(C->line, m->line_conn, 2 * m->n_lines * sizeof *C->line);
  memcpy(C->line_curve, m->line_curve, m->n_lines * sizeof *C->line_curve);
  memcpy(C->line_t, m->line_t, 2 * m->n_lines * sizeof *C->line_t);
  C->n_tri = m->n_elems;
  C->n_lines = m->n_lines;
  return HOC_OK;
}

/* Which side of the line coordinate c node i is on: -1, +1, 0 on it, 2
 * unknown (not on the face, or its coordinate differs between elements). */
static int node_side(const cutter *C, size_t i, double c, double eps) {
  double u = C->fu[i];
  if (isnan(u)) return 2;
  return u < c - eps ? -1 : u > c + eps ? 1 : 0;
}

/* The parameter t of line l's curve where its pcurve on face f crosses
 * coordinate d = c, between the line's ends (end 0 on side s0). */
static hoc_status line_crossing(const cutter *C, size_t l, int f, int d, double c, int s0,
                                double *t) {
  const hoc_model *model = C->m->model;
  int k = C->line_curve[l];
  const hoc_cad_curve *cv = &model->curves[k];
  double a = C->line_t[2 * l], b = C->line_t[2 * l + 1];
  for (int it = 0; it < CROSS_BISECTIONS; ++it) {
    double mid = 0.5 * (a + b), w = mid, uv[2];
    if (cv->period > 0) w = cv->lo + fmod(fmod(w - cv->lo, cv->period) + cv->period, cv->period);
    HOC_TRY(hoc_cad_curve_to_face(model, k, f, 1, &w, uv));
    if ((uv[d] < c ? -1 : 1) == s0)
      a = mid;
    else
      b = mid;
  }
  *t = 0.5 * (a + b);
  if (cv->period > 0) *t = cv->lo + fmod(fmod(*t - cv->lo, cv->period) + cv->period, cv->period);
  return HOC_OK;
}

/* The coordinate along pinch direction d of every node of face f's
 * triangles, from the mesh's element parameters (NAN for the others). */
static void face_coordinates(cutter *C, int f, int d) {
  const hoc_mesh *m = C->m;
  double eps = 1e-9 * (m->model->faces[f].hi[d] - m->model->faces[f].lo[d]);
  for (size_t i = 0; i < C->n_nodes; ++i) C->fu[i] = NAN;
  for (size_t e = 0; e < m->n_elems; ++e) {
    if (m->elem_face[e] != f) continue;
    for (int k = 0; k < 3; ++k) {
      size_t i = m->conn[3 * e + (size_t)k];
      double u = m->elem_uv[6 * e + 2 * (size_t)k + (size_t)d];
      /* a node whose coordinate differs between its elements (a pole's
       * arbitrary one) has none */
      if (isnan(C->fu[i]))
        C->fu[i] = u;
      else if (fabs(C->fu[i] - u) > eps)
        C->fu[i] = INFINITY;
    }
  }
  for (size_t i = 0; i < C->n_nodes; ++i)
    if (isinf(C->fu[i])) C->fu[i] = NAN;
}

static hoc_status node_point(const cutter *C, size_t i, double x[3]) {
  if (i < C->m->n_nodes) {
    memcpy(x, C->m->xyz + 3 * i, 3 * sizeof *x);
    return HOC_OK;
  }
  return hoc_cad_curve_eval(C->m->model, C->ent[i], 1, C->par + 2 * i, x, NULL);
}

/* Does triangle j have the edge (a, b) in either direction? */
static int has_edge(const size_t *t, size_t a, size_t b) {
  for (int k = 0; k < 3; ++k) {
    size_t p = t[k], q = t[(k + 1) % 3];
    if ((p == a && q == b) || (p == b && q == a)) return 1;
  }
  return 0;
}

/* Cut face f's triangles along pinch (d, c): 1 in *done if it did. */
static hoc_status cut_one(cutter *C, int f, int d, double c, int *done) {
  const hoc_model *model = C->m->model;
  const hoc_cad_face *face = &model->faces[f];
  double eps = 1e-9 * (face->hi[d] - face->lo[d]), tol = hoc_mesh_collapse_distance(model);
  *done = 0;
  /* the triangles across, all of whose corners have a side */
  size_t n_across = 0;
  for (size_t j = 0; j < C->n_tri; ++j) {
    if (C->tri_face[j] != f) continue;
    int lo = 0, hi = 0, unknown = 0;
    for (int k = 0; k < 3; ++k) {
      int s = node_side(C, C->tri[3 * j + (size_t)k], c, eps);
      lo |= s == -1, hi |= s == 1, unknown |= s == 2;
    }
    if (lo && hi && unknown) return HOC_OK;
    n_across += lo && hi;
  }
  if (!n_across) return HOC_OK;
  /* the face's boundary lines across: the point's node goes on the first */
  size_t *across = NULL, n_lines_across = 0;
  double *t_cross = NULL;
  hoc_status status = HOC_OK;
  HOC_ALLOC(across, C->n_lines + 1);
  HOC_ALLOC_GOTO(t_cross, C->n_lines + 1, done);
  for (size_t l = 0; l < C->n_lines; ++l) {
    size_t a = C->line[2 * l], b = C->line[2 * l + 1];
    int sa = node_side(C, a, c, eps), sb = node_side(C, b, c, eps);
    if (!((sa == -1 && sb == 1) || (sa == 1 && sb == -1))) continue;
    int bounds = 0;
    for (size_t j = 0; j < C->n_tri && !bounds; ++j)
      bounds = C->tri_face[j] == f && has_edge(C->tri + 3 * j, a, b);
    if (!bounds) continue;
    HOC_TRY_GOTO(line_crossing(C, l, f, d, c, sa, &t_cross[n_lines_across]), done);
    across[n_lines_across++] = l;
  }
  if (!n_lines_across) goto done; /* a line closed inside the face: not cut */
  /* the point: every crossing and every node on the line within the
   * collapse distance of it, or no cut */
  double p[3], x[3];
  int k0 = C->line_curve[across[0]];
  HOC_TRY_GOTO(hoc_cad_curve_eval(model, k0, 1, &t_cross[0], p, NULL), done);
  for (size_t q = 1; q < n_lines_across; ++q) {
    HOC_TRY_GOTO(hoc_cad_curve_eval(model, C->line_curve[across[q]], 1, &t_cross[q], x, NULL),
                 done);
    if (!(hoc_dist3(x, p) <= tol)) goto done;
  }
  for (size_t i = 0; i < C->n_nodes; ++i) {
    if (node_side(C, i, c, eps) != 0) continue;
    HOC_TRY_GOTO(node_point(C, i, x), done);
    if (!(hoc_dist3(x, p) <= tol)) goto done;
  }
  if (C->n_nodes >= C->node_cap) {
    status = HOC_ERROR(HOC_ERR_INTERNAL, "pinch cut: no room for a node");
    goto done;
  }
  size_t P = C->n_nodes++;
  C->dim[P] = HOC_ON_CURVE;
  C->ent[P] = k0;
  C->par[2 * P] = t_cross[0];
  C->par[2 * P + 1] = 0;
  C->fu[P] = c;
  HOC_TRY_GOTO(cutter_reserve(C, 2 * n_lines_across + 2), done);
  /* the lines across split at the point, and the triangles of other faces
   * along them */
  for (size_t q = 0; q < n_lines_across; ++q) {
    size_t l = across[q], a = C->line[2 * l], b = C->line[2 * l + 1];
    size_t n = C->n_lines++;
    C->line[2 * n] = P;
    C->line[2 * n + 1] = b;
    C->line_curve[n] = C->line_curve[l];
    C->line_t[2 * n] = t_cross[q];
    C->line_t[2 * n + 1] = C->line_t[2 * l + 1];
    C->line[2 * l + 1] = P;
    C->line_t[2 * l + 1] = t_cross[q];
    size_t n_tri = C->n_tri;
    for (size_t j = 0; j < n_tri; ++j) {
      size_t *t = C->tri + 3 * j;
      if (C->tri_face[j] == f || !has_edge(t, a, b)) continue;
      HOC_TRY_GOTO(cutter_reserve(C, 1), done);
      t = C->tri + 3 * j;
      int k = 0;
      while (!((t[k] == a && t[(k + 1) % 3] == b) || (t[k] == b && t[(k + 1) % 3] == a))) ++k;
      /* (t[k], t[k+1], z) -> (t[k], P, z) and (P, t[k+1], z) */
      size_t u = C->n_tri++, *s = C->tri + 3 * u;
      s[0] = P;
      s[1] = t[(k + 1) % 3];
      s[2] = t[(k + 2) % 3];
      C->tri_face[u] = C->tri_face[j];
      t[(k + 1) % 3] = P;
    }
  }
  /* face f: the minority corner of a triangle across goes to the point; a
   * triangle with a corner on the line and the others across is dropped */
  for (size_t j = 0; j < C->n_tri; ++j) {
    if (C->tri_face[j] != f) continue;
    size_t *t = C->tri + 3 * j;
    int s[3], lo = 0, hi = 0, on = 0;
    for (int k = 0; k < 3; ++k) {
      s[k] = t[k] == P ? 0 : node_side(C, t[k], c, eps);
      lo += s[k] == -1, hi += s[k] == 1, on += s[k] == 0;
    }
    if (!lo || !hi) continue;
    if (on) {
      t[0] = t[1] = t[2] = P; /* dropped below */
      continue;
    }
    int minority = lo == 1 ? -1 : 1;
    for (int k = 0; k < 3; ++k)
      if (s[k] == minority) t[k] = P;
  }
  /* nodes on the line are the point, in every triangle and line */
  for (size_t j = 0; j < 3 * C->n_tri; ++j)
    if (C->tri[j] != P && node_side(C, C->tri[j], c, eps) == 0) C->tri[j] = P;
  for (size_t j = 0; j < 2 * C->n_lines; ++j)
    if (C->line[j] != P && node_side(C, C->line[j], c, eps) == 0) C->line[j] = P;
  /* a node beside the point, closer to it than HOC_CUT_NEAR of its
   * longest edge (a boundary node that gmsh put just beside the line's
   * end): the point too. Its triangles with the point would reach along
   * the line, whose image is the point, and fold there when curved. */
  size_t near_cap = 64, n_near = 0, near[64];
  for (size_t j = 0; j < C->n_tri; ++j) {
    const size_t *t = C->tri + 3 * j;
    if (C->tri_face[j] != f || (t[0] != P && t[1] != P && t[2] != P)) continue;
    for (int k = 0; k < 3; ++k) {
      size_t i = t[k];
      if (i == P || C->dim[i] == HOC_ON_VERTEX) continue;
      int known = 0;
      for (size_t q = 0; q < n_near; ++q) known |= near[q] == i;
      if (known) continue;
      double longest = 0, y[3];
      HOC_TRY_GOTO(node_point(C, i, x), done);
      for (size_t g = 0; g < C->n_tri; ++g) {
        const size_t *r = C->tri + 3 * g;
        for (int a = 0; a < 3; ++a) {
          if (r[a] != i) continue;
          for (int b = 1; b < 3; ++b) {
            HOC_TRY_GOTO(node_point(C, r[(a + b) % 3], y), done);
            longest = fmax(longest, hoc_dist3(x, y));
          }
        }
      }
      if (hoc_dist3(x, p) < HOC_CUT_NEAR * longest && n_near < near_cap) near[n_near++] = i;
    }
  }
  for (size_t q = 0; q < n_near; ++q) {
    for (size_t j = 0; j < 3 * C->n_tri; ++j)
      if (C->tri[j] == near[q]) C->tri[j] = P;
    for (size_t j = 0; j < 2 * C->n_lines; ++j)
      if (C->line[j] == near[q]) C->line[j] = P;
  }
  *done = 1;
done:
  free(across);
  free(t_cross);
  return status;
}

int hoc_face_may_pinch(const hoc_cad_face *face) {
  static const char *const analytic[] = {"Plane", "Cylinder", "Cone", "Sphere", "Torus"};
  if (face->plane) return 0;
  for (size_t k = 0; k < sizeof analytic / sizeof *analytic; ++k)
    if (!strcmp(face->type, analytic[k])) return 0;
  return 1;
}

/* The cut mesh as a source, assembled into *out. */
static hoc_status cutter_assemble(cutter *C, hoc_mesh **out) {
  const hoc_mesh *m = C->m;
  size_t *remap = NULL;
  hoc_status status = HOC_OK;
  HOC_ALLOC(remap, C->n_nodes + 1);
  size_t nt = 0, nl = 0, nn = 0;
  for (size_t j = 0; j < C->n_tri; ++j) {
    const size_t *t = C->tri + 3 * j;
    if (t[0] == t[1] || t[1] == t[2] || t[0] == t[2]) continue;
    memmove(C->tri + 3 * nt, t, 3 * sizeof *t);
    C->tri_face[nt++] = C->tri_face[j];
  }
  C->n_tri = nt;
  for (size_t l = 0; l < C->n_lines; ++l) {
    if (C->line[2 * l] == C->line[2 * l + 1]) continue;
    memmove(C->line + 2 * nl, C->line + 2 * l, 2 * sizeof *C->line);
    C->line_curve[nl++] = C->line_curve[l];
  }
  C->n_lines = nl;
  /* nodes no triangle uses any more (those on the lines, now the point) */
  for (size_t i = 0; i < C->n_nodes; ++i) remap[i] = SIZE_MAX;
  for (size_t j = 0; j < 3 * nt; ++j) remap[C->tri[j]] = 0;
  for (size_t i = 0; i < C->n_nodes; ++i) {
    if (remap[i] == SIZE_MAX) continue;
    remap[i] = nn;
    memmove(C->par + 2 * nn, C->par + 2 * i, 2 * sizeof *C->par);
    C->dim[nn] = C->dim[i];
    C->ent[nn++] = C->ent[i];
  }
  for (size_t j = 0; j < 3 * nt; ++j) C->tri[j] = remap[C->tri[j]];
  for (size_t l = 0; l < nl; ++l) {
    if (remap[C->line[2 * l]] == SIZE_MAX || remap[C->line[2 * l + 1]] == SIZE_MAX) {
      status = HOC_ERROR(HOC_ERR_INTERNAL, "pinch cut: a line of no triangle");
      goto done;
    }
    for (int k = 0; k < 2; ++k) C->line[2 * l + (size_t)k] = remap[C->line[2 * l + (size_t)k]];
  }
  hoc_mesh_source src = {0};
  src.order = 1;
  src.nodeset = m->nodeset;
  src.n_nodes = nn;
  src.param = C->par;
  src.dim = C->dim;
  src.entity = C->ent;
  src.n_elems = nt;
  src.conn = C->tri;
  src.elem_face = C->tri_face;
  src.n_lines = nl;
  src.line_conn = C->line;
  src.line_curve = C->line_curve;
  src.face_orient = m->face_orient;
  HOC_TRY_GOTO(hoc_mesh_assemble(m->model, &src, out), done);
  status = hoc_mesh_copy_record(m, *out);
  if (status != HOC_OK) hoc_mesh_destroy(out);
done:
  free(remap);
  return status;
}

hoc_status hoc_mesh_cut_pinches(const hoc_mesh *m, hoc_mesh **out, int *n_cut) {
  HOC_CHECK(m && out && n_cut, HOC_ERR_ARGUMENT, "pinch cut: bad argument");
  *out = NULL;
  *n_cut = 0;
  if (m->order != 1 || !m->n_elems) return HOC_OK;
  const hoc_model *model = m->model;
  int nf = model->n_faces, total = 0;
  unsigned char *used = NULL;
  int *count = NULL;
  hoc_pinch *line = NULL;
  cutter C = {0};
  hoc_status status = HOC_OK;
  HOC_ALLOC(used, (size_t)nf + 1);
  HOC_ALLOC_GOTO(count, (size_t)nf + 1, done);
  HOC_ALLOC_GOTO(line, (size_t)nf * HOC_CUT_PINCHES + 1, done);
  for (size_t e = 0; e < m->n_elems; ++e) used[m->elem_face[e]] = 1;
  double tol = hoc_mesh_collapse_distance(model);
  /* the search: about 3 000 evaluations per face, the faces in parallel */
  hoc_par_error err = {0};
#pragma omp parallel for schedule(dynamic, 1) if (nf > 1 && model->thread_safe)
  for (int f = 0; f < nf; ++f) {
    const hoc_cad_face *face = &model->faces[f];
    if (!used[f] || !hoc_face_may_pinch(face)) continue;
    double size = face_size(face);
    if (!(size > tol)) continue;
    hoc_par_error_catch(&err, hoc_face_pinches(model, f, tol / size,
                                               line + (size_t)f * HOC_CUT_PINCHES,
                                               HOC_CUT_PINCHES, &count[f]));
  }
  HOC_TRY_GOTO(hoc_par_error_raise(&err), done);
  for (int f = 0; f < nf; ++f) total += count[f];
  if (!total) goto done;
  HOC_TRY_GOTO(cutter_init(&C, m, (size_t)total), done);
  for (int f = 0; f < nf; ++f) {
    if (!count[f]) continue;
    const hoc_pinch *p = line + (size_t)f * HOC_CUT_PINCHES;
    /* the pinches along the first one's direction (the point of a line
     * across it has no coordinate along it) */
    int d = p[0].dir;
    if (model->faces[f].period[d] > 0) continue;
    face_coordinates(&C, f, d);
    for (int k = 0; k < count[f]; ++k) {
      if (p[k].dir != d) continue;
      int done_one = 0;
      HOC_TRY_GOTO(cut_one(&C, f, d, p[k].c, &done_one), done);
      *n_cut += done_one;
    }
  }
  if (*n_cut) HOC_TRY_GOTO(cutter_assemble(&C, out), done);
done:
  if (status != HOC_OK) *n_cut = 0;
  cutter_free(&C);
  free(used);
  free(count);
  free(line);
  return status;
}
