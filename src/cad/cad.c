/* Backend-independent part of the CAD interface: entity lookup, seams
 * (closed directions), poles, wrapped evaluation and local inversion.
 * SPDX-License-Identifier: GPL-2.0-or-later */
#include "cad/cad.h"
#include "core/geometry.h"

#include <float.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

hoc_status hoc_cad_create(int n_faces, int n_curves, int n_vertices, hoc_model **model) {
  HOC_CHECK(model, HOC_ERR_ARGUMENT, "model output is NULL");
  *model = NULL;
  HOC_CHECK(n_faces >= 0 && n_curves >= 0 && n_vertices >= 0, HOC_ERR_ARGUMENT,
            "negative entity count");
  hoc_model *m;
  HOC_ALLOC(m, 1);
  m->n_faces = n_faces;
  m->n_curves = n_curves;
  m->n_vertices = n_vertices;
  m->faces = hoc_calloc((size_t)n_faces, sizeof *m->faces);
  m->curves = hoc_calloc((size_t)n_curves, sizeof *m->curves);
  m->vertices = hoc_calloc((size_t)n_vertices, sizeof *m->vertices);
  if (!m->faces || !m->curves || !m->vertices) {
    hoc_model_destroy(&m);
    return HOC_ERROR(HOC_ERR_MEMORY, "out of memory for the CAD entities");
  }
  for (int i = 0; i < n_curves; ++i) m->curves[i].v0 = m->curves[i].v1 = -1;
  *model = m;
  return HOC_OK;
}

void hoc_model_destroy(hoc_model **model) {
  if (!model || !*model) return;
  hoc_model *m = *model;
  if (m->ops && m->ops->destroy) m->ops->destroy(m->ctx);
  for (int i = 0; i < m->n_faces; ++i) free(m->faces[i].curves);
  free(m->faces);
  free(m->curves);
  free(m->vertices);
  free(m->face_of_tag);
  free(m->curve_of_tag);
  free(m->vertex_of_tag);
  free(m->mesher_failed);
  free(m->mesher_limit);
  free(m);
  *model = NULL;
}

int hoc_model_num_faces(const hoc_model *model) { return model ? model->n_faces : 0; }
int hoc_model_num_curves(const hoc_model *model) { return model ? model->n_curves : 0; }
int hoc_model_num_vertices(const hoc_model *model) { return model ? model->n_vertices : 0; }

void hoc_model_bbox(const hoc_model *model, double bbox[6]) {
  for (int k = 0; k < 6; ++k) bbox[k] = model ? model->bbox[k] : 0.0;
}

/* tag -> index table for tags 0..max (tags are small positive integers in
 * every kernel we use; a negative tag is rejected). */
static hoc_status build_lookup(int n, const int *tags, size_t stride, int **lookup, int *max_tag) {
  int mx = 0;
  for (int i = 0; i < n; ++i) {
    int tag = *(const int *)((const char *)tags + stride * (size_t)i);
    HOC_CHECK(tag >= 0, HOC_ERR_CAD, "CAD entity with negative tag %d", tag);
    if (tag > mx) mx = tag;
  }
  int *tab;
  HOC_ALLOC(tab, (size_t)mx + 1);
  for (int t = 0; t <= mx; ++t) tab[t] = -1;
  for (int i = 0; i < n; ++i) tab[*(const int *)((const char *)tags + stride * (size_t)i)] = i;
  *lookup = tab;
  *max_tag = mx;
  return HOC_OK;
}

enum { PROBES = 9 };

/* The largest |phi_u| and |phi_v| of face f at PROBES^2 points inside it:
 * the scales against which a stalled derivative is zero
 * (hoc_cad_face_singular). */
static hoc_status derivative_scales(hoc_model *m, hoc_cad_face *f) {
  double uv[2 * PROBES * PROBES], du[3 * PROBES * PROBES], dv[3 * PROBES * PROBES];
  for (int i = 0; i < PROBES; ++i)
    for (int j = 0; j < PROBES; ++j) {
      uv[2 * (i * PROBES + j)] = f->lo[0] + (i + 0.5) / PROBES * (f->hi[0] - f->lo[0]);
      uv[2 * (i * PROBES + j) + 1] = f->lo[1] + (j + 0.5) / PROBES * (f->hi[1] - f->lo[1]);
    }
  HOC_TRY(m->ops->face_eval(m->ctx, f, PROBES * PROBES, uv, NULL, du, dv));
  f->du_scale = f->dv_scale = 0;
  for (int k = 0; k < PROBES * PROBES; ++k) {
    f->du_scale = fmax(f->du_scale, sqrt(hoc_dot3(du + 3 * k, du + 3 * k)));
    f->dv_scale = fmax(f->dv_scale, sqrt(hoc_dot3(dv + 3 * k, dv + 3 * k)));
  }
  return HOC_OK;
}

/* Closed directions and poles of a face, measured: side u = lo is a pole if
 * phi(lo, v) is one point for all v; u is closed if phi(lo, v) = phi(hi, v). */
static hoc_status detect_face_topology(hoc_model *m, hoc_cad_face *f, double tol) {
  double uv[4 * PROBES * 2], xyz[4 * PROBES * 3];
  /* sides in order: u = lo, u = hi, v = lo, v = hi, each sampled at PROBES points */
  for (int side = 0; side < 4; ++side) {
    int fixed = side / 2;  /* 0: u fixed, 1: v fixed */
    int other = 1 - fixed;
    double val = (side % 2) ? f->hi[fixed] : f->lo[fixed];
    for (int k = 0; k < PROBES; ++k) {
      double s = (k + 0.5) / PROBES;
      double *p = uv + 2 * (side * PROBES + k);
      p[fixed] = val;
      p[other] = f->lo[other] + s * (f->hi[other] - f->lo[other]);
    }
  }
  HOC_TRY(m->ops->face_eval(m->ctx, f, 4 * PROBES, uv, xyz, NULL, NULL));
  HOC_TRY(derivative_scales(m, f));
  double spread[4];
  for (int side = 0; side < 4; ++side) {
    spread[side] = 0;
    for (int k = 1; k < PROBES; ++k)
      spread[side] = fmax(spread[side], hoc_dist3(xyz + 3 * (side * PROBES + k),
                                               xyz + 3 * (side * PROBES)));
    if (spread[side] < tol) f->pole[side] = 1;
  }
  for (int dir = 0; dir < 2; ++dir) {
    if (f->period[dir] > 0) continue;
    if (f->pole[2 * dir] && f->pole[2 * dir + 1]) continue; /* both sides points: not a seam */
    double gap = 0;
    for (int k = 0; k < PROBES; ++k)
      gap = fmax(gap, hoc_dist3(xyz + 3 * ((2 * dir) * PROBES + k),
                            xyz + 3 * ((2 * dir + 1) * PROBES + k)));
    if (gap < tol) f->period[dir] = f->hi[dir] - f->lo[dir];
  }
  return HOC_OK;
}

/* Whether face f, of the kernel's type "Plane", is phi = o + u a + v b to
 * rounding (at its corners and middle): then its frame is kept. */
static hoc_status detect_plane(hoc_model *m, hoc_cad_face *f) {
  if (strcmp(f->type, "Plane") != 0) return HOC_OK;
  double uv[6] = {f->lo[0], f->lo[1], f->hi[0], f->hi[1], 0.5 * (f->lo[0] + f->hi[0]),
                  0.5 * (f->lo[1] + f->hi[1])};
  double x[9], du[9], dv[9];
  HOC_TRY(m->ops->face_eval(m->ctx, f, 3, uv, x, du, dv));
  double o[3], tol = 1e-12 * m->diagonal;
  for (int d = 0; d < 3; ++d) o[d] = x[d] - uv[0] * du[d] - uv[1] * dv[d];
  for (int k = 1; k < 3; ++k)
    for (int d = 0; d < 3; ++d) {
      double p = o[d] + uv[2 * k] * du[d] + uv[2 * k + 1] * dv[d];
      if (!(fabs(p - x[3 * k + d]) <= tol + 1e-14 * fabs(x[3 * k + d])) ||
          !(fabs(du[3 * k + d] - du[d]) <= 1e-12 * (fabs(du[d]) + 1)) ||
          !(fabs(dv[3 * k + d] - dv[d]) <= 1e-12 * (fabs(dv[d]) + 1)))
        return HOC_OK;
    }
  double aa = hoc_dot3(du, du), ab = hoc_dot3(du, dv), bb = hoc_dot3(dv, dv), det = aa * bb - ab * ab;
  if (!(det > 1e-12 * aa * bb)) return HOC_OK;
  memcpy(f->plane_o, o, sizeof o);
  memcpy(f->plane_a, du, 3 * sizeof *du);
  memcpy(f->plane_b, dv, 3 * sizeof *dv);
  f->plane_g[0] = bb / det;
  f->plane_g[1] = -ab / det;
  f->plane_g[2] = aa / det;
  f->plane = 1;
  return HOC_OK;
}

hoc_status hoc_cad_finish(hoc_model *m) {
  HOC_TRY(build_lookup(m->n_faces, &m->faces[0].tag, sizeof(hoc_cad_face), &m->face_of_tag,
                       &m->max_face_tag));
  HOC_TRY(build_lookup(m->n_curves, m->n_curves ? &m->curves[0].tag : NULL,
                       sizeof(hoc_cad_curve), &m->curve_of_tag, &m->max_curve_tag));
  HOC_TRY(build_lookup(m->n_vertices, m->n_vertices ? &m->vertices[0].tag : NULL,
                       sizeof(hoc_cad_vertex), &m->vertex_of_tag, &m->max_vertex_tag));
  double diag2 = 0;
  for (int k = 0; k < 3; ++k) diag2 += (m->bbox[k + 3] - m->bbox[k]) * (m->bbox[k + 3] - m->bbox[k]);
  m->diagonal = sqrt(diag2);
  HOC_CHECK(m->diagonal > 0 && isfinite(m->diagonal), HOC_ERR_CAD,
            "the model has an empty or invalid bounding box");
  double tol = 1e-7 * m->diagonal;
  for (int i = 0; i < m->n_faces; ++i) {
    hoc_cad_face *f = &m->faces[i];
    HOC_CHECK(isfinite(f->lo[0]) && isfinite(f->hi[0]) && isfinite(f->lo[1]) &&
                  isfinite(f->hi[1]) && f->hi[0] >= f->lo[0] && f->hi[1] >= f->lo[1],
              HOC_ERR_CAD, "face %d has invalid parametric bounds", f->tag);
    HOC_TRY(detect_face_topology(m, f, tol));
    HOC_TRY(detect_plane(m, f));
  }
  for (int i = 0; i < m->n_curves; ++i) {
    hoc_cad_curve *c = &m->curves[i];
    HOC_CHECK(isfinite(c->lo) && isfinite(c->hi) && c->hi >= c->lo, HOC_ERR_CAD,
              "curve %d has invalid parametric bounds", c->tag);
    double t[3] = {c->lo, 0.5 * (c->lo + c->hi), c->hi}, x[9];
    HOC_TRY(m->ops->curve_eval(m->ctx, c, 3, t, x, NULL));
    if (hoc_dist3(x, x + 3) < tol && hoc_dist3(x, x + 6) < tol) {
      c->degenerate = 1;
    } else if (hoc_dist3(x, x + 6) < tol && c->period == 0) {
      c->period = c->hi - c->lo;
    }
  }
  return HOC_OK;
}

/* Tolerance ---------------------------------------------------------------- */

enum { GAP_SAMPLES = 33 };

static hoc_status curve_to_face(const hoc_model *m, int curve, int face, size_t n,
                                const double *t, double *uv, int kernel);

/* Largest distance between curve c and face f along the curve. Samples
 * cluster at the curve's ends, where a curve and its face part most (the
 * intersection curves of wing_fuselage.step peak within 0.4% of their
 * ends), and avoid the evenly spaced knots where a fitted curve on the
 * face meets the curve exactly. A kernel failure (no curve on that face)
 * leaves the pair out. */
static double curve_face_gap(const hoc_model *m, int c, int f) {
  const hoc_cad_curve *cv = &m->curves[c];
  double t[GAP_SAMPLES], x[3 * GAP_SAMPLES], uv[2 * GAP_SAMPLES], y[3 * GAP_SAMPLES];
  for (int i = 0; i < GAP_SAMPLES; ++i) {
    double s = 0.5 * (1 - cos(3.14159265358979323846 * i / (GAP_SAMPLES - 1)));
    t[i] = cv->lo + s * (cv->hi - cv->lo);
  }
  double gap = 0;
  if (hoc_cad_curve_eval(m, c, GAP_SAMPLES, t, x, NULL) != HOC_OK ||
      curve_to_face(m, c, f, GAP_SAMPLES, t, uv, 1) != HOC_OK ||
      hoc_cad_face_eval(m, f, GAP_SAMPLES, uv, y, NULL, NULL) != HOC_OK) {
    hoc_error_clear();
    return 0;
  }
  for (int i = 0; i < GAP_SAMPLES; ++i) {
    double d = hoc_dist3(x + 3 * i, y + 3 * i);
    if (d > gap) gap = d; /* NaN ignored */
  }
  return gap;
}

hoc_status hoc_cad_tolerance(hoc_model *m, double *tolerance) {
  HOC_CHECK(m && tolerance, HOC_ERR_ARGUMENT, "NULL argument");
  if (m->tolerance_known) {
    *tolerance = m->tolerance;
    return HOC_OK;
  }
  double tol = 0;
  int at_curve = -1, at_face = -1;
  for (int f = 0; f < m->n_faces; ++f) {
    const hoc_cad_face *face = &m->faces[f];
    for (int k = 0; k < face->n_curves; ++k) {
      int c = hoc_cad_curve_index(m, abs(face->curves[k]));
      if (c < 0) continue;
      double g = curve_face_gap(m, c, f);
      if (g > tol) tol = g, at_curve = m->curves[c].tag, at_face = face->tag;
      /* the curve's vertices on this face */
      const hoc_cad_curve *cv = &m->curves[c];
      int ends[2] = {cv->v0, cv->v1};
      for (int e = 0; e < 2; ++e) {
        if (ends[e] < 0) continue;
        double uv[2], y[3];
        if (hoc_cad_vertex_to_face(m, ends[e], f, uv) != HOC_OK ||
            hoc_cad_face_eval(m, f, 1, uv, y, NULL, NULL) != HOC_OK) {
          hoc_error_clear();
          continue;
        }
        double d = hoc_dist3(y, m->vertices[ends[e]].xyz);
        if (d > tol) tol = d, at_curve = -1, at_face = face->tag;
      }
    }
  }
  for (int c = 0; c < m->n_curves; ++c) {
    const hoc_cad_curve *cv = &m->curves[c];
    double t[2] = {cv->lo, cv->hi}, x[6];
    if (hoc_cad_curve_eval(m, c, 2, t, x, NULL) != HOC_OK) {
      hoc_error_clear();
      continue;
    }
    if (cv->v0 >= 0 && hoc_dist3(x, m->vertices[cv->v0].xyz) > tol)
      tol = hoc_dist3(x, m->vertices[cv->v0].xyz), at_curve = cv->tag, at_face = -1;
    if (cv->v1 >= 0 && hoc_dist3(x + 3, m->vertices[cv->v1].xyz) > tol)
      tol = hoc_dist3(x + 3, m->vertices[cv->v1].xyz), at_curve = cv->tag, at_face = -1;
  }
  m->tolerance = tol;
  m->tolerance_curve = at_curve;
  m->tolerance_face = at_face;
  m->tolerance_known = 1;
  *tolerance = tol;
  return HOC_OK;
}

hoc_status hoc_model_tolerance(hoc_model *model, double *tolerance) {
  return hoc_cad_tolerance(model, tolerance);
}

int hoc_cad_face_index(const hoc_model *m, int tag) {
  return (tag >= 0 && tag <= m->max_face_tag && m->face_of_tag) ? m->face_of_tag[tag] : -1;
}
int hoc_cad_curve_index(const hoc_model *m, int tag) {
  return (tag >= 0 && tag <= m->max_curve_tag && m->curve_of_tag) ? m->curve_of_tag[tag] : -1;
}
int hoc_cad_vertex_index(const hoc_model *m, int tag) {
  return (tag >= 0 && tag <= m->max_vertex_tag && m->vertex_of_tag) ? m->vertex_of_tag[tag]
                                                                      : -1;
}

static double wrap1(double x, double lo, double period) {
  if (!(period > 0)) return x;
  double k = floor((x - lo) / period);
  double y = x - k * period;
  if (y >= lo + period) y -= period; /* rounding */
  if (y < lo) y = lo;
  return y;
}

void hoc_cad_face_wrap(const hoc_cad_face *f, double uv[2]) {
  for (int d = 0; d < 2; ++d) uv[d] = wrap1(uv[d], f->lo[d], f->period[d]);
}

void hoc_cad_face_unwrap_near(const hoc_cad_face *f, const double ref[2], double uv[2]) {
  for (int d = 0; d < 2; ++d) {
    double P = f->period[d];
    if (P > 0) uv[d] -= P * floor((uv[d] - ref[d]) / P + 0.5);
  }
}

enum { STACK_POINTS = 64 };

hoc_status hoc_cad_face_eval(const hoc_model *m, int face, size_t n, const double *uv,
                             double *xyz, double *du, double *dv) {
  HOC_CHECK(face >= 0 && face < m->n_faces, HOC_ERR_ARGUMENT, "face index %d out of range", face);
  const hoc_cad_face *f = &m->faces[face];
  if (!n) return HOC_OK;
  if (!(f->period[0] > 0) && !(f->period[1] > 0))
    return m->ops->face_eval(m->ctx, f, n, uv, xyz, du, dv);
  double stack[2 * STACK_POINTS];
  double *w = n <= STACK_POINTS ? stack : hoc_calloc(2 * n, sizeof *w);
  HOC_CHECK(w, HOC_ERR_MEMORY, "out of memory for %zu parameter pairs", n);
  for (size_t i = 0; i < n; ++i) {
    w[2 * i] = uv[2 * i];
    w[2 * i + 1] = uv[2 * i + 1];
    hoc_cad_face_wrap(f, w + 2 * i);
  }
  hoc_status st = m->ops->face_eval(m->ctx, f, n, w, xyz, du, dv);
  if (w != stack) free(w);
  return st;
}

hoc_status hoc_cad_curve_eval(const hoc_model *m, int curve, size_t n, const double *t,
                              double *xyz, double *dt) {
  HOC_CHECK(curve >= 0 && curve < m->n_curves, HOC_ERR_ARGUMENT, "curve index %d out of range",
            curve);
  const hoc_cad_curve *c = &m->curves[curve];
  if (!n) return HOC_OK;
  if (!(c->period > 0)) return m->ops->curve_eval(m->ctx, c, n, t, xyz, dt);
  double stack[STACK_POINTS];
  double *w = n <= STACK_POINTS ? stack : hoc_calloc(n, sizeof *w);
  HOC_CHECK(w, HOC_ERR_MEMORY, "out of memory for %zu curve parameters", n);
  for (size_t i = 0; i < n; ++i) w[i] = wrap1(t[i], c->lo, c->period);
  hoc_status st = m->ops->curve_eval(m->ctx, c, n, w, xyz, dt);
  if (w != stack) free(w);
  return st;
}

/* hoc_cad_curve_to_face; kernel: the kernel's curve on the face even on a
 * plane. */
static hoc_status curve_to_face(const hoc_model *m, int curve, int face, size_t n,
                                const double *t, double *uv, int kernel) {
  HOC_CHECK(curve >= 0 && curve < m->n_curves && face >= 0 && face < m->n_faces,
            HOC_ERR_ARGUMENT, "entity index out of range");
  const hoc_cad_curve *c = &m->curves[curve];
  const hoc_cad_face *f = &m->faces[face];
  if (!n) return HOC_OK;
  double stack[STACK_POINTS];
  double *w = n <= STACK_POINTS ? stack : hoc_calloc(n, sizeof *w);
  HOC_CHECK(w, HOC_ERR_MEMORY, "out of memory for %zu curve parameters", n);
  for (size_t i = 0; i < n; ++i) w[i] = wrap1(t[i], c->lo, c->period);
  hoc_status st;
  if (f->plane && !kernel) {
    /* the feet of the curve's points: the Gram system of the frame (one
     * point a call in the optimiser: no allocation then) */
    double xs[3 * STACK_POINTS];
    double *x = n <= STACK_POINTS ? xs : hoc_calloc(3 * n, sizeof *x);
    st = x ? m->ops->curve_eval(m->ctx, c, n, w, x, NULL)
           : HOC_ERROR(HOC_ERR_MEMORY, "out of memory for %zu curve points", n);
    for (size_t i = 0; i < n && st == HOC_OK; ++i) {
      double r[3];
      for (int d = 0; d < 3; ++d) r[d] = x[3 * i + d] - f->plane_o[d];
      double ra = hoc_dot3(r, f->plane_a), rb = hoc_dot3(r, f->plane_b);
      uv[2 * i] = f->plane_g[0] * ra + f->plane_g[1] * rb;
      uv[2 * i + 1] = f->plane_g[1] * ra + f->plane_g[2] * rb;
    }
    if (x != xs) free(x);
  } else {
    st = m->ops->curve_to_face(m->ctx, c, f, n, w, uv);
  }
  if (w != stack) free(w);
  return st;
}

hoc_status hoc_cad_curve_to_face(const hoc_model *m, int curve, int face, size_t n,
                                 const double *t, double *uv) {
  return curve_to_face(m, curve, face, n, t, uv, 0);
}

hoc_status hoc_cad_vertex_to_face(const hoc_model *m, int vertex, int face, double *uv) {
  HOC_CHECK(vertex >= 0 && vertex < m->n_vertices && face >= 0 && face < m->n_faces,
            HOC_ERR_ARGUMENT, "entity index out of range");
  return m->ops->vertex_to_face(m->ctx, &m->vertices[vertex], &m->faces[face], uv);
}

/* Keep a parameter inside the bounds of a non-closed direction (B-splines
 * must not be extrapolated), with a margin for rounding. */
static double clamp_param(double x, double lo, double hi, double period) {
  if (period > 0) return x;
  double margin = 1e-12 * (hi - lo);
  if (x < lo - margin) return lo;
  if (x > hi + margin) return hi;
  return x;
}

hoc_status hoc_cad_face_invert(const hoc_model *m, int face, const double xyz[3], double uv[2],
                               double *dist) {
  const hoc_cad_face *f = &m->faces[face];
  double x[3], du[3], dv[3];
  HOC_TRY(hoc_cad_face_eval(m, face, 1, uv, x, du, dv));
  double d = hoc_dist3(x, xyz);
  double stop = 1e-15 * m->diagonal;
  double mu = 0;
  for (int it = 0; it < 60 && d > stop; ++it) {
    double r[3] = {xyz[0] - x[0], xyz[1] - x[1], xyz[2] - x[2]};
    double a = du[0] * du[0] + du[1] * du[1] + du[2] * du[2];
    double b = du[0] * dv[0] + du[1] * dv[1] + du[2] * dv[2];
    double c = dv[0] * dv[0] + dv[1] * dv[1] + dv[2] * dv[2];
    double g0 = du[0] * r[0] + du[1] * r[1] + du[2] * r[2];
    double g1 = dv[0] * r[0] + dv[1] * r[1] + dv[2] * r[2];
    double scale = fmax(a + c, DBL_MIN);
    int accepted = 0;
    for (int tries = 0; tries < 30 && !accepted; ++tries) {
      double aa = a + mu * scale, cc = c + mu * scale;
      double det = aa * cc - b * b;
      if (!(fabs(det) > 1e-300)) {
        mu = mu ? 10 * mu : 1e-8;
        continue;
      }
      double s0 = (cc * g0 - b * g1) / det, s1 = (aa * g1 - b * g0) / det;
      /* a step of more than half a period in a closed direction goes nowhere
       * new, and a huge one loses the parameter's precision when wrapped */
      if (f->period[0] > 0 && fabs(s0) > 0.5 * f->period[0]) s0 = copysign(0.5 * f->period[0], s0);
      if (f->period[1] > 0 && fabs(s1) > 0.5 * f->period[1]) s1 = copysign(0.5 * f->period[1], s1);
      double trial[2] = {clamp_param(uv[0] + s0, f->lo[0], f->hi[0], f->period[0]),
                         clamp_param(uv[1] + s1, f->lo[1], f->hi[1], f->period[1])};
      double xt[3], dut[3], dvt[3];
      HOC_TRY(hoc_cad_face_eval(m, face, 1, trial, xt, dut, dvt));
      double dt = hoc_dist3(xt, xyz);
      if (dt < d) {
        uv[0] = trial[0];
        uv[1] = trial[1];
        memcpy(x, xt, sizeof x);
        memcpy(du, dut, sizeof du);
        memcpy(dv, dvt, sizeof dv);
        double gain = d - dt;
        d = dt;
        accepted = 1;
        mu *= 0.1;
        if (mu < 1e-12) mu = 0;
        if (gain < 1e-3 * d && d < 1e-9 * m->diagonal) it = 1000; /* stagnated near zero */
      } else {
        mu = mu ? 10 * mu : 1e-6;
      }
    }
    if (!accepted) break;
  }
  *dist = d;
  return HOC_OK;
}

enum { FOOT_STEPS = 20, FOOT_HALVINGS = 8 };

/* Position x[3] and derivatives J[n][3] of a face (n = 2) or curve (n = 1). */
static hoc_status foot_eval(const hoc_model *m, int n, int entity, const double *par, double *x,
                            double (*J)[3]) {
  if (n == 2) return hoc_cad_face_eval(m, entity, 1, par, x, J[0], J[1]);
  return hoc_cad_curve_eval(m, entity, 1, par, x, J[0]);
}

/* hoc_cad_face_foot and hoc_cad_curve_foot: n parameters par[n] with
 * bounds lo, hi and periods. */
static hoc_status foot(const hoc_model *m, int n, int entity, const double *lo, const double *hi,
                       const double *period, const double xyz[3], double tol, double *par) {
  double x[3], J[2][3] = {{0}};
  HOC_TRY(foot_eval(m, n, entity, par, x, J));
  double d = hoc_dist3(x, xyz), stop = fmax(tol, 1e-14 * m->diagonal);
  for (int it = 0; it < FOOT_STEPS; ++it) {
    double r[3] = {xyz[0] - x[0], xyz[1] - x[1], xyz[2] - x[2]}, s[2] = {0, 0};
    double a = hoc_dot3(J[0], J[0]), g0 = hoc_dot3(J[0], r);
    if (n == 2) {
      double b = hoc_dot3(J[0], J[1]), c = hoc_dot3(J[1], J[1]), g1 = hoc_dot3(J[1], r);
      double det = a * c - b * b;
      if (!(det > 1e-24 * (a * c))) break; /* singular here (a pole): stay */
      s[0] = (c * g0 - b * g1) / det;
      s[1] = (a * g1 - b * g0) / det;
    } else {
      if (!(a > 0)) break;
      s[0] = g0 / a;
    }
    for (int k = 0; k < n; ++k)
      if (period[k] > 0 && fabs(s[k]) > 0.5 * period[k]) s[k] = copysign(0.5 * period[k], s[k]);
    double len = 0; /* the step's length on the tangent plane */
    for (int d3 = 0; d3 < 3; ++d3) {
      double l = J[0][d3] * s[0] + (n == 2 ? J[1][d3] * s[1] : 0);
      len += l * l;
    }
    len = sqrt(len);
    int accepted = 0;
    for (int h = 0; h < FOOT_HALVINGS && !accepted; ++h) {
      double trial[2] = {0, 0}, xt[3], Jt[2][3] = {{0}};
      for (int k = 0; k < n; ++k) trial[k] = clamp_param(par[k] + s[k], lo[k], hi[k], period[k]);
      HOC_TRY(foot_eval(m, n, entity, trial, xt, Jt));
      double dt = hoc_dist3(xt, xyz);
      if (dt <= d * (1 + 4 * DBL_EPSILON)) { /* closer, or as close within rounding */
        memcpy(par, trial, (size_t)n * sizeof *par);
        memcpy(x, xt, sizeof x);
        memcpy(J, Jt, sizeof J);
        d = dt;
        accepted = 1;
      } else {
        s[0] *= 0.5, s[1] *= 0.5, len *= 0.5;
      }
    }
    if (!accepted || len < stop) break;
  }
  return HOC_OK;
}

hoc_status hoc_cad_face_foot(const hoc_model *m, int face, const double xyz[3], double tol,
                             double uv[2]) {
  const hoc_cad_face *f = &m->faces[face];
  return foot(m, 2, face, f->lo, f->hi, f->period, xyz, tol, uv);
}

hoc_status hoc_cad_curve_foot(const hoc_model *m, int curve, const double xyz[3], double tol,
                              double *t) {
  const hoc_cad_curve *c = &m->curves[curve];
  return foot(m, 1, curve, &c->lo, &c->hi, &c->period, xyz, tol, t);
}

hoc_status hoc_cad_curve_invert(const hoc_model *m, int curve, const double xyz[3], double *t,
                                double *dist) {
  const hoc_cad_curve *c = &m->curves[curve];
  double x[3], dx[3];
  HOC_TRY(hoc_cad_curve_eval(m, curve, 1, t, x, dx));
  double d = hoc_dist3(x, xyz);
  double stop = 1e-15 * m->diagonal;
  for (int it = 0; it < 60 && d > stop; ++it) {
    double a = dx[0] * dx[0] + dx[1] * dx[1] + dx[2] * dx[2];
    double g = dx[0] * (xyz[0] - x[0]) + dx[1] * (xyz[1] - x[1]) + dx[2] * (xyz[2] - x[2]);
    if (!(a > 1e-300)) break;
    double step = g / a;
    int accepted = 0;
    for (int tries = 0; tries < 30 && !accepted; ++tries, step *= 0.5) {
      double tt = clamp_param(*t + step, c->lo, c->hi, c->period), xt[3], dxt[3];
      HOC_TRY(hoc_cad_curve_eval(m, curve, 1, &tt, xt, dxt));
      double dt = hoc_dist3(xt, xyz);
      if (dt < d) {
        *t = tt;
        memcpy(x, xt, sizeof x);
        memcpy(dx, dxt, sizeof dx);
        d = dt;
        accepted = 1;
      }
    }
    if (!accepted) break;
  }
  *dist = d;
  return HOC_OK;
}

int hoc_cad_face_singular(const hoc_cad_face *f, const double du[3], const double dv[3]) {
  double n[3];
  hoc_cross3(du, dv, n);
  double a = hoc_dot3(du, du), b = hoc_dot3(dv, dv);
  if (!(sqrt(hoc_dot3(n, n)) > 1e-10 * (a + b))) return 1;
  return sqrt(a) < HOC_CAD_STALL * f->du_scale || sqrt(b) < HOC_CAD_STALL * f->dv_scale;
}
