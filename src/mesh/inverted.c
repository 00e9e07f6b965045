/* Why an order-1 element is tangled: inverted on the surface (across a
 * fold of the face, or not), or valid once the face's normal at a
 * singular corner is taken along the element.
 * SPDX-License-Identifier: GPL-2.0-or-later
 *
 * A straight triangle is valid when its normal t = (x1 - x0) x (x2 - x0)
 * points to the side of the face's normal at each corner (sigma, the
 * interpolated normal's component along t, is linear and smallest at a
 * corner). The measure takes each corner's normal from its slot: one
 * normal per node and face. Where phi_u x phi_v vanishes (a pole, a cone's
 * apex, a B-spline corner whose side collapses), the normal's limit
 * depends on the direction from which the point is approached, and the
 * slot's one normal, taken just inside the face towards its middle, is
 * not the limit along every element around the point. */
#include "core/geometry.h"
#include "mesh/mesh.h"

#include <math.h>

/* Fraction of the way from a singular corner to the element's centroid
 * (in the face's parameters) at which its normal is taken: close enough
 * to be the limit along the element, far enough from the singular point
 * for phi_u x phi_v to be well above rounding. */
#define ALONG_ELEMENT 1e-4

/* Corner k of a triangle with corners c[0..5] in face f's parameters,
 * moved toward its centroid (ALONG_ELEMENT of the way, then ten times
 * farther each time, to a fifth) while the face is singular there
 * (hoc_cad_face_singular): *p and the derivatives du, dv at it, the limit
 * along the element where phi_u x phi_v vanishes or is rounding. */
static hoc_status regular_toward_centroid(const hoc_mesh *m, int f, const double *c, int k,
                                          double *p, double *du, double *dv) {
  const hoc_cad_face *face = &m->model->faces[f];
  p[0] = c[2 * k];
  p[1] = c[2 * k + 1];
  HOC_TRY(hoc_cad_face_eval(m->model, f, 1, p, NULL, du, dv));
  for (double t = ALONG_ELEMENT; hoc_cad_face_singular(face, du, dv) && t < 0.2; t *= 10) {
    for (int d = 0; d < 2; ++d) {
      double centroid = (c[d] + c[2 + d] + c[4 + d]) / 3;
      p[d] = c[2 * k + d] + t * (centroid - c[2 * k + d]);
    }
    HOC_TRY(hoc_cad_face_eval(m->model, f, 1, p, NULL, du, dv));
  }
  return HOC_OK;
}

/* The face's normal (unnormalised, oriented as the mesh) at corner k of
 * order-1 element e, as the limit along the element where phi_u x phi_v
 * vanishes at the corner (the criterion of the slot normals). */
static hoc_status corner_normal(const hoc_mesh *m, size_t e, int k, double *n) {
  int f = m->elem_face[e];
  double p[2], du[3], dv[3];
  HOC_TRY(regular_toward_centroid(m, f, m->elem_uv + 6 * e, k, p, du, dv));
  hoc_cross3(du, dv, n);
  double sign = m->face_orient[f] < 0 ? -1.0 : 1.0;
  for (int d = 0; d < 3; ++d)
    n[d] *= sign;
  return HOC_OK;
}

/* Lattice points per side of an element's (u, v) triangle at which the
 * fold test samples the face's normal: neighbours 1/8 of the element
 * apart. A smooth face turns its normal by more than a right angle over
 * that distance only where it is at least eight times too curved for the
 * element, and a fold reverses it at once. */
#define FOLD_SAMPLES 8

hoc_status hoc_mesh_element_folds(const hoc_mesh *mesh, size_t e, int *folds) {
  HOC_CHECK(mesh && folds && e < mesh->n_elems, HOC_ERR_ARGUMENT, "fold test: bad argument");
  enum { N = FOLD_SAMPLES, POINTS = (N + 1) * (N + 2) / 2 };
  int f = mesh->elem_face[e];
  const double *c = mesh->elem_uv + 2 * (size_t)mesh->np * e; /* corners first */
  double uv[2 * POINTS], du[3 * POINTS], dv[3 * POINTS], n[3 * POINTS];
  int regular[POINTS], at[N + 1][N + 1];
  int k = 0;
  for (int i = 0; i <= N; ++i)
    for (int j = 0; i + j <= N; ++j, ++k) {
      double a = (double)i / N, b = (double)j / N;
      for (int d = 0; d < 2; ++d)
        uv[2 * k + d] = (1 - a - b) * c[d] + a * c[2 + d] + b * c[4 + d];
      at[i][j] = k;
    }
  /* a corner where phi_u x phi_v vanishes: the limit along the element
   * (a fold next to a collapsed side lies between it and the next sample) */
  const hoc_cad_face *face = &mesh->model->faces[f];
  for (int corner = 0; corner < 3; ++corner) {
    double dd[6];
    HOC_TRY(regular_toward_centroid(mesh, f, c, corner,
                                    uv + 2 * at[corner == 1 ? N : 0][corner == 2 ? N : 0], dd,
                                    dd + 3));
  }
  HOC_TRY(hoc_cad_face_eval(mesh->model, f, POINTS, uv, NULL, du, dv));
  for (k = 0; k < POINTS; ++k) {
    hoc_cross3(du + 3 * k, dv + 3 * k, n + 3 * k);
    /* where phi_u x phi_v vanishes (a pole, a collapsed or stalled side)
     * its sign is rounding: no sample */
    regular[k] = !hoc_cad_face_singular(face, du + 3 * k, dv + 3 * k);
  }
  *folds = 0;
  for (int i = 0; i <= N && !*folds; ++i)
    for (int j = 0; i + j <= N && !*folds; ++j) {
      /* the lattice's three edge directions from (i, j) */
      int p = at[i][j], q[3] = {i + j < N ? at[i + 1][j] : -1, i + j < N ? at[i][j + 1] : -1,
                                j > 0 ? at[i + 1][j - 1] : -1};
      for (int m = 0; m < 3 && !*folds; ++m)
        *folds = q[m] >= 0 && regular[p] && regular[q[m]] && hoc_dot3(n + 3 * p, n + 3 * q[m]) < 0;
    }
  return HOC_OK;
}

hoc_status hoc_mesh_inverted_kinds(const hoc_mesh *mesh, const unsigned char *tangled,
                                   unsigned char *kind) {
  HOC_CHECK(mesh && tangled && kind, HOC_ERR_ARGUMENT, "NULL argument");
  HOC_CHECK(mesh->order == 1, HOC_ERR_ARGUMENT,
            "inverted triangles are told apart on order-1 meshes, not order %d", mesh->order);
  for (size_t e = 0; e < mesh->n_elems; ++e) {
    kind[e] = HOC_INVERTED_NONE;
    if (!tangled[e]) continue;
    const size_t *cn = mesh->conn + 3 * e;
    const double *x0 = mesh->xyz + 3 * cn[0], *x1 = mesh->xyz + 3 * cn[1],
                 *x2 = mesh->xyz + 3 * cn[2];
    double a[3], b[3], t[3];
    for (int d = 0; d < 3; ++d) {
      a[d] = x1[d] - x0[d];
      b[d] = x2[d] - x0[d];
    }
    hoc_cross3(a, b, t);
    int valid = 1;
    for (int k = 0; k < 3 && valid; ++k) {
      double n[3];
      HOC_TRY(corner_normal(mesh, e, k, n));
      valid = hoc_dot3(t, n) > 0;
    }
    int folds = 0;
    if (!valid) HOC_TRY(hoc_mesh_element_folds(mesh, e, &folds));
    kind[e] = valid   ? HOC_INVERTED_AT_SINGULAR
              : folds ? HOC_INVERTED_ACROSS_FOLD
                      : HOC_INVERTED_ON_CAD;
  }
  return HOC_OK;
}
