/* The CAD interface: what the mesh, the measure and the optimiser may ask of
 * a CAD model. Backends: gmsh (cad_gmsh.c) and exact analytic surfaces for
 * tests (cad_analytic.c).
 * SPDX-License-Identifier: GPL-2.0-or-later
 *
 * Entities are addressed by index (0..n-1); `tag` is the kernel's own number,
 * used only in files and messages.
 *
 * Parameters: a face is phi(u, v), a curve is c(t). On a face closed in a
 * direction (a periodic seam), `period` is its period and callers may pass
 * unwrapped parameters outside [min, max]: hoc_cad_face_eval wraps them back
 * before asking the backend, so backends only see parameters in range.
 */
#ifndef HOC_CAD_H
#define HOC_CAD_H

#include "core/error.h"

typedef struct hoc_cad_face {
  int tag;
  double lo[2], hi[2];   /* parametric bounds (u, v) */
  double period[2];      /* period of u and v where the face closes on itself, else 0 */
  unsigned char pole[4]; /* degenerate side: u = lo[0], u = hi[0], v = lo[1], v = hi[1] */
  char type[40];         /* kernel's surface type ("Plane", "BSpline surface", ...) */
  char name[64];         /* kernel's entity name, may be empty */
  double bbox[6];
  int *curves, n_curves; /* boundary curve tags, signed by orientation (for files) */
  unsigned char concurrent; /* backend evaluates this face from several threads at once */
  /* a plane: phi(u, v) = plane_o + u plane_a + v plane_b (hoc_cad_finish
   * checks it), plane_g the inverse of the Gram matrix of a and b (g00,
   * g01, g11); a curve's parameters on it are those of its points' feet */
  unsigned char plane;
  double plane_o[3], plane_a[3], plane_b[3], plane_g[3];
  /* largest |phi_u| and |phi_v| at interior sample points (hoc_cad_finish):
   * a derivative below HOC_CAD_STALL x these is zero to the model's precision */
  double du_scale, dv_scale;
} hoc_cad_face;

/* Relative size below which a face derivative is taken as zero: a side
 * where phi_u (or phi_v) stalls (B-spline control rows that coincide to the
 * file's digits) has phi_u x phi_v tiny but of rounding direction there. */
#define HOC_CAD_STALL 1e-5

/** Whether phi_u x phi_v at a point with derivatives du, dv of face f is
 *  rounding: it vanishes next to |du|, |dv|, or one of them is zero to the
 *  face's scale. */
int hoc_cad_face_singular(const hoc_cad_face *f, const double du[3], const double dv[3]);

typedef struct hoc_cad_curve {
  int tag;
  double lo, hi;         /* parameter bounds */
  double period;         /* hi - lo if the curve is closed, else 0 */
  int v0, v1;            /* start and end vertex index, -1 if none */
  int degenerate;        /* collapses to a point (pole) */
  double bbox[6];
  unsigned char concurrent; /* backend evaluates this curve from several threads at once */
} hoc_cad_curve;

typedef struct hoc_cad_vertex {
  int tag;
  double xyz[3];
} hoc_cad_vertex;

typedef struct hoc_cad_ops {
  /** Position and first derivatives of face f at n points uv[n][2] (in range).
   *  xyz[n][3], du[n][3], dv[n][3]; any output may be NULL. */
  hoc_status (*face_eval)(void *ctx, const hoc_cad_face *f, size_t n, const double *uv,
                          double *xyz, double *du, double *dv);
  /** Position and derivative of curve c at n parameters t[n]: xyz[n][3], dt[n][3]. */
  hoc_status (*curve_eval)(void *ctx, const hoc_cad_curve *c, size_t n, const double *t,
                           double *xyz, double *dt);
  /** Parameters uv[n][2] on face f of the points c(t[k]) of a boundary curve. */
  hoc_status (*curve_to_face)(void *ctx, const hoc_cad_curve *c, const hoc_cad_face *f,
                              size_t n, const double *t, double *uv);
  /** Parameters uv[2] on face f of a vertex of its boundary. */
  hoc_status (*vertex_to_face)(void *ctx, const hoc_cad_vertex *v, const hoc_cad_face *f,
                               double *uv);
  /** Slow inverse without initial guess: parameters uv[n][2] of the points of
   *  face f closest to xyz[n][3]. */
  hoc_status (*face_project)(void *ctx, const hoc_cad_face *f, size_t n, const double *xyz,
                             double *uv);
  /** Slow inverse on a curve: t[n] of the points closest to xyz[n][3]. */
  hoc_status (*curve_project)(void *ctx, const hoc_cad_curve *c, size_t n, const double *xyz,
                              double *t);
  void (*destroy)(void *ctx);
} hoc_cad_ops;

/** A CAD model: the public hoc_model. */
struct hoc_model {
  const hoc_cad_ops *ops;
  void *ctx;
  /* Every operation may be called from several threads at once: the backend
   * lets evaluations of `concurrent` entities run in parallel and serialises
   * the rest internally. Both backends are; the flag is for future ones. */
  int thread_safe;
  int is_gmsh;     /* the global gmsh model belongs to this object */
  int n_faces, n_curves, n_vertices;
  hoc_cad_face *faces;
  hoc_cad_curve *curves;
  hoc_cad_vertex *vertices;
  /* tag -> index, -1 where no entity has the tag */
  int *face_of_tag, *curve_of_tag, *vertex_of_tag;
  int max_face_tag, max_curve_tag, max_vertex_tag;
  double bbox[6];
  double diagonal; /* bounding-box diagonal: the model's length scale */
  /* The model's own tolerance, measured on demand (hoc_cad_tolerance): how
   * far its curves lie from the faces they bound, and its vertices from
   * their curves and faces. */
  int tolerance_known;
  double tolerance;
  int tolerance_curve, tolerance_face; /* tags where it was found (-1: none or a vertex) */
  /* Faces gmsh's mesher failed on alone in an earlier linear meshing of
   * this model (mesh/linear_gmsh.c), left out of the later ones: NULL, or
   * per face 0, the signal that ended its probe, or HOC_MESHER_TIMED_OUT
   * (it did not finish within mesher_limit[f] seconds). */
  unsigned char *mesher_failed;
  double *mesher_limit;
  /* hoc_now() past which gmsh's mesher is stopped (0: none), set by a
   * caller whose meshing has a time budget (a remeshing among repairs): a
   * meshing it stops fails, no face probed or remembered as failed. */
  double mesher_deadline;
};

/** hoc_model.mesher_failed of a face gmsh's mesher did not finish in time. */
enum { HOC_MESHER_TIMED_OUT = 254 };

/** Allocate an empty model with room for the entities; the backend fills
 *  them and then calls hoc_cad_finish. */
hoc_status hoc_cad_create(int n_faces, int n_curves, int n_vertices, hoc_model **model);

/** Build the tag lookups, the bounding box and detect closed directions and
 *  poles of each face numerically (if not set by the backend). */
hoc_status hoc_cad_finish(hoc_model *model);

/** Index of the entity with a tag, or -1. */
int hoc_cad_face_index(const hoc_model *model, int tag);
int hoc_cad_curve_index(const hoc_model *model, int tag);
int hoc_cad_vertex_index(const hoc_model *model, int tag);

/** Face evaluation with unwrapped parameters (wrapped into range first).
 *  Thread-safe when model->thread_safe; otherwise call from one thread. */
hoc_status hoc_cad_face_eval(const hoc_model *model, int face, size_t n, const double *uv,
                             double *xyz, double *du, double *dv);
/** Curve evaluation; t outside [lo, hi] is wrapped on closed curves. */
hoc_status hoc_cad_curve_eval(const hoc_model *model, int curve, size_t n, const double *t,
                              double *xyz, double *dt);
/** The parameters on face `face` of curve `curve`'s points at t[n] (uv[n][2]):
 *  the kernel's curve on that face, or on a plane the feet of the points
 *  (closed form; the kernel projects the curve onto the plane anew at each
 *  call where the model stores no curve on it). */
hoc_status hoc_cad_curve_to_face(const hoc_model *model, int curve, int face, size_t n,
                                 const double *t, double *uv);
hoc_status hoc_cad_vertex_to_face(const hoc_model *model, int vertex, int face, double *uv);

/** The model's tolerance: the largest distance measured between a curve
 *  and a face it bounds, c(t) against phi_f(pcurve_f(t)) (the kernel's
 *  curve on that face, also on a plane), at 33 Chebyshev points of
 *  each curve (closer together at its ends), and between each vertex and
 *  the ends of its curves and its place on the faces around it. STEP and
 *  IGES models agree only to such a tolerance (OpenCASCADE keeps one per
 *  edge and vertex; gmsh's API does not expose it). Samples bound the gap
 *  from below: on the 26 models of the corpus the largest gap of a dense
 *  measure (8193 points per curve) is at most 2.5 times this one
 *  (docs/kernel.md). Measured on the first call (at most 0.05 s on the
 *  largest models of the corpus), then kept: call it from one thread. */
hoc_status hoc_cad_tolerance(hoc_model *model, double *tolerance);

/** Invert the face parametrisation near a guess: uv (in: guess, out: result)
 *  minimises |phi(uv) - xyz| by damped Gauss-Newton steps, staying on the
 *  same unwrapped copy as the guess. Sets *dist to the final distance.
 *  Never fails on convergence; the caller judges dist. */
hoc_status hoc_cad_face_invert(const hoc_model *model, int face, const double xyz[3],
                               double uv[2], double *dist);
/** Same on a curve: t in/out. */
hoc_status hoc_cad_curve_invert(const hoc_model *model, int curve, const double xyz[3],
                                double *t, double *dist);

/** Foot of the perpendicular from a point off the face, near a guess: uv
 *  (in: guess, out: result) by Gauss-Newton steps (each halved up to 8
 *  times until it brings phi(uv) closer to xyz), until a step moves the
 *  point by less than tol (at least 1e-14 of the model's diagonal), at
 *  most 20 steps.
 *  Stays on the guess's unwrapped copy and within the face's bounds.
 *  Unlike hoc_cad_face_invert it expects xyz off the surface and stops
 *  once the residual is normal to it: a handful of evaluations. */
hoc_status hoc_cad_face_foot(const hoc_model *model, int face, const double xyz[3], double tol,
                             double uv[2]);
/** Same on a curve: t in/out. */
hoc_status hoc_cad_curve_foot(const hoc_model *model, int curve, const double xyz[3], double tol,
                              double *t);

/** Wrap a face parameter pair into range along its closed directions. */
void hoc_cad_face_wrap(const hoc_cad_face *f, double uv[2]);

/** Shift uv by whole periods of f so that it is nearest to ref. */
void hoc_cad_face_unwrap_near(const hoc_cad_face *f, const double ref[2], double uv[2]);

/* Backends ---------------------------------------------------------------- */

/** Open a CAD file through gmsh (one such model at a time). */
hoc_status hoc_cad_open_gmsh(const char *path, hoc_model **model);

/** Linear triangulation of the current gmsh model: see mesh/linear_gmsh.c. */

/** Analytic surfaces with exact evaluation (tests): one face each. */
typedef enum hoc_analytic_kind {
  HOC_ANALYTIC_PLANE,    /* phi(u,v) = (u, v, 0) on [0,1]^2 scaled by a */
  HOC_ANALYTIC_SPHERE,   /* radius a: phi = a (cos v cos u, cos v sin u, sin v), u in [0,2pi], v in [-pi/2,pi/2] */
  HOC_ANALYTIC_CYLINDER, /* radius a, height b: phi = (a cos u, a sin u, v), u in [0,2pi], v in [0,b] */
  HOC_ANALYTIC_TORUS,    /* radii a > b: phi = ((a + b cos v) cos u, (a + b cos v) sin u, b sin v) */
  HOC_ANALYTIC_CONE,     /* base radius a, height b, apex at the origin: phi = (k v cos u,
                            k v sin u, v) with k = a / b, u in [0,2pi], v in [0,b]; its apex is a
                            pole where the normal depends on the direction of approach */
  HOC_ANALYTIC_FOLD,     /* a square [0,a]^2 that folds along v = b (0 < b < a): phi = (u,
                            w^2, w^3), w = v - b; phi_u x phi_v = (0, -3w^2, 2w) vanishes on
                            the fold and reverses across it (a cuspidal edge) */
  HOC_ANALYTIC_KINK,     /* the square [0,a]^2 of a plane whose u runs four times slower past
                            u = b (0 < b < a), as at a B-spline knot where the derivative
                            jumps: phi = (g(u), v, 0), g(u) = u below b, b + (u - b) / 4 above;
                            flat, its parametrisation only C0 */
  HOC_ANALYTIC_STALL,    /* the square [0,a]^2 of a plane whose side u = 0 (b long) stalls, as
                            B-spline control rows that coincide to a file's digits:
                            phi = (u^2 - d^2 (1 - exp(-u / d)), (b + u^2) v, 0), d = 1e-6 a:
                            |phi_u| is d there, and phi_u x phi_v, far from 0 next to
                            |phi_u|^2 + |phi_v|^2, points down in an ear a few d wide (no
                            element of a mesh resolves it) and up everywhere else */
  HOC_ANALYTIC_EAR       /* the same map with d = 1e-3 a: the side u = 0 is regular (|phi_u| =
                            d), and the face folds at u = 0.3517 d (phi_u = 0), 0.1728 d^2 from
                            the side; the normal points down in that ear, up past it */
} hoc_analytic_kind;

/** One analytic face (tag 1) with its seam/pole curves and vertices, thread-safe. */
hoc_status hoc_cad_create_analytic(hoc_analytic_kind kind, double a, double b,
                                   hoc_model **model);

#endif
