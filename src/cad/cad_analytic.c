/* Analytic CAD models with exact evaluation, for tests: a plane square, a
 * sphere (seam + two poles), a cylinder (seam), a torus (two seams) and a
 * cone (seam + a pole at its apex, where the surface has no tangent plane)
 * and a square that folds along a line of its parameters.
 * Each has one face (tag 1) and the curves and vertices of its boundary.
 * SPDX-License-Identifier: GPL-2.0-or-later */
#include "cad/cad.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>

#define TWO_PI 6.283185307179586476925286766559

/* A curve of the boundary, as a straight segment in the face's parameters:
 * uv(t) = uv0 + (t - lo) * duv. */
typedef struct curve_def {
  double uv0[2], duv[2];
} curve_def;

typedef struct analytic {
  hoc_analytic_kind kind;
  double a, b;
  curve_def curves[4];
} analytic;

/* d of HOC_ANALYTIC_STALL and HOC_ANALYTIC_EAR: the scale of the ear at
 * their side u = 0. */
static double ear_width(const analytic *s) {
  return (s->kind == HOC_ANALYTIC_EAR ? 1e-3 : 1e-6) * s->a;
}

static void face_point(const analytic *s, double u, double v, double *x, double *du, double *dv) {
  double a = s->a, b = s->b, cu = cos(u), su = sin(u), cv = cos(v), sv = sin(v);
  double X[3], U[3], V[3];
  switch (s->kind) {
  case HOC_ANALYTIC_PLANE:
    X[0] = u, X[1] = v, X[2] = 0;
    U[0] = 1, U[1] = 0, U[2] = 0;
    V[0] = 0, V[1] = 1, V[2] = 0;
    break;
  case HOC_ANALYTIC_SPHERE:
    X[0] = a * cv * cu, X[1] = a * cv * su, X[2] = a * sv;
    U[0] = -a * cv * su, U[1] = a * cv * cu, U[2] = 0;
    V[0] = -a * sv * cu, V[1] = -a * sv * su, V[2] = a * cv;
    break;
  case HOC_ANALYTIC_CYLINDER:
    X[0] = a * cu, X[1] = a * su, X[2] = v;
    U[0] = -a * su, U[1] = a * cu, U[2] = 0;
    V[0] = 0, V[1] = 0, V[2] = 1;
    break;
  case HOC_ANALYTIC_CONE: {
    double k = a / b; /* radius over height */
    X[0] = k * v * cu, X[1] = k * v * su, X[2] = v;
    U[0] = -k * v * su, U[1] = k * v * cu, U[2] = 0;
    V[0] = k * cu, V[1] = k * su, V[2] = 1;
  } break;
  case HOC_ANALYTIC_KINK: {
    double slope = u > b ? 0.25 : 1.0; /* the right derivative at the knot */
    X[0] = u > b ? b + (u - b) * slope : u, X[1] = v, X[2] = 0;
    U[0] = slope, U[1] = 0, U[2] = 0;
    V[0] = 0, V[1] = 1, V[2] = 0;
  } break;
  case HOC_ANALYTIC_FOLD: {
    double w = v - b;
    X[0] = u, X[1] = w * w, X[2] = w * w * w;
    U[0] = 1, U[1] = 0, U[2] = 0;
    V[0] = 0, V[1] = 2 * w, V[2] = 3 * w * w;
  } break;
  case HOC_ANALYTIC_STALL:
  case HOC_ANALYTIC_EAR: {
    double d = ear_width(s), e = exp(-u / d);
    X[0] = u * u - d * d * (1 - e), X[1] = (b + u * u) * v, X[2] = 0;
    U[0] = 2 * u - d * e, U[1] = 2 * u * v, U[2] = 0;
    V[0] = 0, V[1] = b + u * u, V[2] = 0;
  } break;
  case HOC_ANALYTIC_TORUS:
  default: {
    double r = a + b * cv;
    X[0] = r * cu, X[1] = r * su, X[2] = b * sv;
    U[0] = -r * su, U[1] = r * cu, U[2] = 0;
    V[0] = -b * sv * cu, V[1] = -b * sv * su, V[2] = b * cv;
  } break;
  }
  for (int k = 0; k < 3; ++k) {
    if (x) x[k] = X[k];
    if (du) du[k] = U[k];
    if (dv) dv[k] = V[k];
  }
}

static hoc_status an_face_eval(void *ctx, const hoc_cad_face *f, size_t n, const double *uv,
                               double *xyz, double *du, double *dv) {
  (void)f;
  const analytic *s = ctx;
  for (size_t i = 0; i < n; ++i)
    face_point(s, uv[2 * i], uv[2 * i + 1], xyz ? xyz + 3 * i : NULL, du ? du + 3 * i : NULL,
               dv ? dv + 3 * i : NULL);
  return HOC_OK;
}

static hoc_status an_curve_eval(void *ctx, const hoc_cad_curve *c, size_t n, const double *t,
                                double *xyz, double *dt) {
  const analytic *s = ctx;
  const curve_def *d = &s->curves[c->tag - 1];
  for (size_t i = 0; i < n; ++i) {
    double tt = t[i] - c->lo, du[3], dv[3];
    face_point(s, d->uv0[0] + tt * d->duv[0], d->uv0[1] + tt * d->duv[1],
               xyz ? xyz + 3 * i : NULL, du, dv);
    if (dt)
      for (int k = 0; k < 3; ++k) dt[3 * i + k] = du[k] * d->duv[0] + dv[k] * d->duv[1];
  }
  return HOC_OK;
}

static hoc_status an_curve_to_face(void *ctx, const hoc_cad_curve *c, const hoc_cad_face *f,
                                   size_t n, const double *t, double *uv) {
  (void)f;
  const analytic *s = ctx;
  const curve_def *d = &s->curves[c->tag - 1];
  for (size_t i = 0; i < n; ++i) {
    uv[2 * i] = d->uv0[0] + (t[i] - c->lo) * d->duv[0];
    uv[2 * i + 1] = d->uv0[1] + (t[i] - c->lo) * d->duv[1];
  }
  return HOC_OK;
}

/* Closed-form inverse of the face map; angles in [0, 2pi). */
static void face_inverse(const analytic *s, const double *x, double *uv) {
  double u = atan2(x[1], x[0]);
  if (u < 0) u += TWO_PI;
  double rho = hypot(x[0], x[1]);
  switch (s->kind) {
  case HOC_ANALYTIC_PLANE:
    uv[0] = x[0];
    uv[1] = x[1];
    break;
  case HOC_ANALYTIC_KINK:
    uv[0] = x[0] > s->b ? s->b + 4 * (x[0] - s->b) : x[0];
    uv[1] = x[1];
    break;
  case HOC_ANALYTIC_FOLD:
    uv[0] = x[0];
    uv[1] = s->b + cbrt(x[2]);
    break;
  case HOC_ANALYTIC_STALL:
  case HOC_ANALYTIC_EAR: { /* (the branch past the ear: x = u^2 - d^2 there) */
    double d = ear_width(s);
    uv[0] = sqrt(fmax(x[0] + d * d, 0));
    uv[1] = x[1] / (s->b + uv[0] * uv[0]);
  } break;
  case HOC_ANALYTIC_SPHERE:
    uv[0] = rho > 0 ? u : 0;
    uv[1] = atan2(x[2], rho);
    break;
  case HOC_ANALYTIC_CYLINDER:
    uv[0] = u;
    uv[1] = x[2];
    break;
  case HOC_ANALYTIC_CONE:
    uv[0] = rho > 0 ? u : 0;
    uv[1] = x[2];
    break;
  case HOC_ANALYTIC_TORUS:
  default: {
    double v = atan2(x[2], rho - s->a);
    if (v < 0) v += TWO_PI;
    uv[0] = u;
    uv[1] = v;
  } break;
  }
}

static hoc_status an_vertex_to_face(void *ctx, const hoc_cad_vertex *v, const hoc_cad_face *f,
                                    double *uv) {
  (void)f;
  face_inverse(ctx, v->xyz, uv);
  return HOC_OK;
}

static hoc_status an_face_project(void *ctx, const hoc_cad_face *f, size_t n, const double *xyz,
                                  double *uv) {
  (void)f;
  for (size_t i = 0; i < n; ++i) face_inverse(ctx, xyz + 3 * i, uv + 2 * i);
  return HOC_OK;
}

static hoc_status an_curve_project(void *ctx, const hoc_cad_curve *c, size_t n,
                                   const double *xyz, double *t) {
  const analytic *s = ctx;
  const curve_def *d = &s->curves[c->tag - 1];
  for (size_t i = 0; i < n; ++i) {
    double uv[2];
    face_inverse(s, xyz + 3 * i, uv);
    /* the curve moves along one parameter: read t from it */
    int k = fabs(d->duv[0]) > fabs(d->duv[1]) ? 0 : 1;
    t[i] = c->lo + (uv[k] - d->uv0[k]) / d->duv[k];
    /* where the face is two-to-one (the ear of HOC_ANALYTIC_EAR) its
     * inverse takes one branch: Newton steps on the curve itself */
    for (int it = 0; it < 8; ++it) {
      double tt = t[i] - c->lo, y[3], du[3], dv[3], r = 0, g = 0;
      face_point(s, d->uv0[0] + tt * d->duv[0], d->uv0[1] + tt * d->duv[1], y, du, dv);
      for (int q = 0; q < 3; ++q) {
        double dt = du[q] * d->duv[0] + dv[q] * d->duv[1];
        r += (y[q] - xyz[3 * i + q]) * dt;
        g += dt * dt;
      }
      if (!(fabs(r) > 1e-14 * (s->a + s->b) * sqrt(g))) break;
      t[i] -= r / g;
    }
  }
  return HOC_OK;
}

static void an_destroy(void *ctx) { free(ctx); }

static const hoc_cad_ops analytic_ops = {
    an_face_eval,    an_curve_eval,    an_curve_to_face, an_vertex_to_face,
    an_face_project, an_curve_project, an_destroy,
};

static void set_curve(hoc_model *m, int i, double lo, double hi, int v0, int v1, analytic *s,
                      double u0, double v0p, double du, double dv) {
  hoc_cad_curve *c = &m->curves[i];
  c->tag = i + 1;
  c->lo = lo;
  c->hi = hi;
  c->v0 = v0;
  c->v1 = v1;
  curve_def *d = &s->curves[i];
  d->uv0[0] = u0;
  d->uv0[1] = v0p;
  d->duv[0] = du;
  d->duv[1] = dv;
}

hoc_status hoc_cad_create_analytic(hoc_analytic_kind kind, double a, double b,
                                   hoc_model **model) {
  HOC_CHECK(model, HOC_ERR_ARGUMENT, "model output is NULL");
  *model = NULL;
  HOC_CHECK(isfinite(a) && a > 0, HOC_ERR_ARGUMENT, "analytic surface size must be > 0");
  HOC_CHECK(kind == HOC_ANALYTIC_PLANE || kind == HOC_ANALYTIC_SPHERE ||
                (isfinite(b) && b > 0 && (kind != HOC_ANALYTIC_TORUS || b < a) &&
                 ((kind != HOC_ANALYTIC_FOLD && kind != HOC_ANALYTIC_KINK) || b < a)),
            HOC_ERR_ARGUMENT, "invalid second size of the analytic surface");
  const double pi = 0.5 * TWO_PI;
  int nc = 0, nv = 0;
  switch (kind) {
  case HOC_ANALYTIC_PLANE: nc = 4, nv = 4; break;
  case HOC_ANALYTIC_FOLD: nc = 4, nv = 4; break;
  case HOC_ANALYTIC_KINK: nc = 4, nv = 4; break;
  case HOC_ANALYTIC_STALL: nc = 4, nv = 4; break;
  case HOC_ANALYTIC_EAR: nc = 4, nv = 4; break;
  case HOC_ANALYTIC_SPHERE: nc = 3, nv = 2; break;
  case HOC_ANALYTIC_CYLINDER: nc = 3, nv = 2; break;
  case HOC_ANALYTIC_CONE: nc = 3, nv = 2; break;
  case HOC_ANALYTIC_TORUS: nc = 2, nv = 1; break;
  default: return HOC_ERROR(HOC_ERR_ARGUMENT, "unknown analytic surface %d", (int)kind);
  }
  hoc_model *m;
  HOC_TRY(hoc_cad_create(1, nc, nv, &m));
  analytic *s = hoc_calloc(1, sizeof *s);
  if (!s) {
    hoc_model_destroy(&m);
    return HOC_ERROR(HOC_ERR_MEMORY, "out of memory");
  }
  s->kind = kind;
  s->a = a;
  s->b = b;
  m->ops = &analytic_ops;
  m->ctx = s;
  m->thread_safe = 1;
  hoc_cad_face *f = &m->faces[0];
  f->tag = 1;
  for (int i = 0; i < nv; ++i) m->vertices[i].tag = i + 1;
  switch (kind) {
  case HOC_ANALYTIC_PLANE:
  case HOC_ANALYTIC_FOLD:
  case HOC_ANALYTIC_KINK:
  case HOC_ANALYTIC_STALL:
  case HOC_ANALYTIC_EAR:
    snprintf(f->type, sizeof f->type, "%s",
             kind == HOC_ANALYTIC_PLANE   ? "Plane"
             : kind == HOC_ANALYTIC_FOLD  ? "Folded square"
             : kind == HOC_ANALYTIC_STALL ? "Plane with a stalled side"
             : kind == HOC_ANALYTIC_EAR   ? "Plane with a folded side"
                                          : "Plane with a knot");
    f->lo[0] = f->lo[1] = 0;
    f->hi[0] = f->hi[1] = a;
    set_curve(m, 0, 0, a, 0, 1, s, 0, 0, 1, 0);  /* v = 0 */
    set_curve(m, 1, 0, a, 1, 2, s, a, 0, 0, 1);  /* u = a */
    set_curve(m, 2, 0, a, 3, 2, s, 0, a, 1, 0);  /* v = a */
    set_curve(m, 3, 0, a, 0, 3, s, 0, 0, 0, 1);  /* u = 0 */
    face_point(s, 0, 0, m->vertices[0].xyz, NULL, NULL);
    face_point(s, a, 0, m->vertices[1].xyz, NULL, NULL);
    face_point(s, a, a, m->vertices[2].xyz, NULL, NULL);
    face_point(s, 0, a, m->vertices[3].xyz, NULL, NULL);
    m->bbox[3] = m->bbox[4] = a;
    if (kind == HOC_ANALYTIC_KINK) m->bbox[3] = b + 0.25 * (a - b);
    if (kind == HOC_ANALYTIC_STALL || kind == HOC_ANALYTIC_EAR) { /* x ~ u^2, y = (b + u^2) v */
      m->bbox[0] = -(kind == HOC_ANALYTIC_EAR ? 2e-7 : 1e-12) * a * a, m->bbox[3] = a * a;
      m->bbox[4] = (b + a * a) * a;
    }
    if (kind == HOC_ANALYTIC_FOLD) { /* x = u, y = w^2, z = w^3 with w in [-b, a - b] */
      m->bbox[4] = fmax(b * b, (a - b) * (a - b));
      m->bbox[2] = -b * b * b, m->bbox[5] = (a - b) * (a - b) * (a - b);
    }
    break;
  case HOC_ANALYTIC_SPHERE:
    snprintf(f->type, sizeof f->type, "Sphere");
    f->lo[0] = 0, f->hi[0] = TWO_PI, f->lo[1] = -0.5 * pi, f->hi[1] = 0.5 * pi;
    set_curve(m, 0, -0.5 * pi, 0.5 * pi, 0, 1, s, 0, -0.5 * pi, 0, 1); /* seam u = 0 */
    set_curve(m, 1, 0, TWO_PI, 0, 0, s, 0, -0.5 * pi, 1, 0);           /* south pole */
    set_curve(m, 2, 0, TWO_PI, 1, 1, s, 0, 0.5 * pi, 1, 0);            /* north pole */
    face_point(s, 0, -0.5 * pi, m->vertices[0].xyz, NULL, NULL);
    face_point(s, 0, 0.5 * pi, m->vertices[1].xyz, NULL, NULL);
    for (int k = 0; k < 3; ++k) m->bbox[k] = -a, m->bbox[k + 3] = a;
    break;
  case HOC_ANALYTIC_CYLINDER:
    snprintf(f->type, sizeof f->type, "Cylinder");
    f->lo[0] = 0, f->hi[0] = TWO_PI, f->lo[1] = 0, f->hi[1] = b;
    set_curve(m, 0, 0, b, 0, 1, s, 0, 0, 0, 1);      /* seam u = 0 */
    set_curve(m, 1, 0, TWO_PI, 0, 0, s, 0, 0, 1, 0); /* bottom circle */
    set_curve(m, 2, 0, TWO_PI, 1, 1, s, 0, b, 1, 0); /* top circle */
    face_point(s, 0, 0, m->vertices[0].xyz, NULL, NULL);
    face_point(s, 0, b, m->vertices[1].xyz, NULL, NULL);
    m->bbox[0] = m->bbox[1] = -a, m->bbox[3] = m->bbox[4] = a, m->bbox[2] = 0, m->bbox[5] = b;
    break;
  case HOC_ANALYTIC_CONE:
    snprintf(f->type, sizeof f->type, "Cone");
    f->lo[0] = 0, f->hi[0] = TWO_PI, f->lo[1] = 0, f->hi[1] = b;
    set_curve(m, 0, 0, b, 0, 1, s, 0, 0, 0, 1);      /* seam u = 0, apex to base */
    set_curve(m, 1, 0, TWO_PI, 0, 0, s, 0, 0, 1, 0); /* apex (degenerate) */
    set_curve(m, 2, 0, TWO_PI, 1, 1, s, 0, b, 1, 0); /* base circle */
    face_point(s, 0, 0, m->vertices[0].xyz, NULL, NULL);
    face_point(s, 0, b, m->vertices[1].xyz, NULL, NULL);
    m->bbox[0] = m->bbox[1] = -a, m->bbox[3] = m->bbox[4] = a, m->bbox[2] = 0, m->bbox[5] = b;
    break;
  case HOC_ANALYTIC_TORUS:
  default:
    snprintf(f->type, sizeof f->type, "Torus");
    f->lo[0] = f->lo[1] = 0;
    f->hi[0] = f->hi[1] = TWO_PI;
    set_curve(m, 0, 0, TWO_PI, 0, 0, s, 0, 0, 0, 1); /* seam u = 0 (a meridian) */
    set_curve(m, 1, 0, TWO_PI, 0, 0, s, 0, 0, 1, 0); /* seam v = 0 (outer equator) */
    face_point(s, 0, 0, m->vertices[0].xyz, NULL, NULL);
    m->bbox[0] = m->bbox[1] = -(a + b), m->bbox[3] = m->bbox[4] = a + b;
    m->bbox[2] = -b, m->bbox[5] = b;
    break;
  }
  for (int k = 0; k < 6; ++k) f->bbox[k] = m->bbox[k];
  hoc_status st = hoc_cad_finish(m);
  if (st != HOC_OK) hoc_model_destroy(&m);
  *model = m;
  return st;
}
