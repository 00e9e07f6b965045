/* Edge swaps of a linear mesh: two triangles of one face that share an
 * edge on no CAD curve become the two triangles on the quadrilateral's
 * other diagonal where that raises the smaller q of the pair, straight,
 * and does not lower it curved (raised to order 2). gmsh meshes each face
 * in its parameters; where the surface's metric differs much from the
 * parameters' (an angle in radians along a rim hundreds of units long, a
 * length across it), a triangle well shaped in (u, v) can be a sliver on
 * the surface while the swap beside it is not.
 * SPDX-License-Identifier: GPL-2.0-or-later */
#include "core/geometry.h"
#include "core/hash.h"
#include "mesh/mesh.h"
#include "quality/quality.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

typedef struct swapper {
  hoc_mesh *m;
  const hoc_quality_tables *t, *t2; /* orders 1 and 2 */
  const double *normal;             /* [n_slots][3] */
  double *q;                        /* [n_elems] current q */
  hoc_hash lines;                   /* the end nodes of each line on a CAD curve */
} swapper;

/* q of a straight triangle of mesh corners with slots sl[3]. */
static double triangle_q(const swapper *S, const size_t c[3], const size_t sl[3]) {
  double x[9], n[9], eta;
  for (int i = 0; i < 3; ++i) {
    memcpy(x + 3 * i, S->m->xyz + 3 * c[i], 3 * sizeof *x);
    memcpy(n + 3 * i, S->normal + 3 * sl[i], 3 * sizeof *n);
  }
  return hoc_element_quality(S->t, HOC_MEASURE_SHAPE, x, n, &eta, NULL);
}

/* q of the triangle of order 2 on face f with corners c[3] (slots sl[3],
 * unwrapped parameters uv[3][2]) and its edges' middles at the middles of
 * its sides in (u, v), the face's there: how it curves when raised, which
 * the straight q does not see (a new diagonal can span more of a bend). */
static hoc_status curved_q(const swapper *S, int f, const size_t c[3], const size_t sl[3],
                           const double *const uv[3], double *q) {
  const hoc_mesh *m = S->m;
  double x[18], n[18], mid[6], du[9], dv[9], eta;
  for (int i = 0; i < 3; ++i) {
    memcpy(x + 3 * i, m->xyz + 3 * c[i], 3 * sizeof *x);
    memcpy(n + 3 * i, S->normal + 3 * sl[i], 3 * sizeof *n);
    for (int d = 0; d < 2; ++d)
      mid[2 * i + d] = 0.5 * (uv[i][d] + uv[(i + 1) % 3][d]);
    hoc_cad_face_wrap(&m->model->faces[f], mid + 2 * i);
  }
  HOC_TRY(hoc_cad_face_eval(m->model, f, 3, mid, x + 9, du, dv));
  double sign = m->face_orient[f] < 0 ? -1.0 : 1.0;
  for (int i = 0; i < 3; ++i) {
    double *ni = n + 9 + 3 * i;
    hoc_cross3(du + 3 * i, dv + 3 * i, ni);
    double len = sqrt(hoc_dot3(ni, ni));
    for (int d = 0; d < 3; ++d)
      ni[d] *= len > 0 ? sign / len : 0.0;
  }
  *q = hoc_element_quality(S->t2, HOC_MEASURE_SHAPE, x, n, &eta, NULL);
  return HOC_OK;
}

/* Do the three nodes lie on one CAD curve (on it or at its ends)? Such a
 * triangle has two edges on the curve and its third a chord of it: raised,
 * its two edges along the curve meet at 180 degrees at the middle corner
 * (tangled at some orders), whatever its straight q says. */
static int on_one_curve(const hoc_mesh *m, const size_t c[3]) {
  const hoc_model *model = m->model;
  int candidate = -1;
  for (int i = 0; i < 3; ++i) {
    if (m->dim[c[i]] == HOC_ON_FACE) return 0;
    if (m->dim[c[i]] == HOC_ON_CURVE) candidate = m->entity[c[i]];
  }
  for (int cv = candidate >= 0 ? candidate : 0;
       cv < (candidate >= 0 ? candidate + 1 : model->n_curves); ++cv) {
    int all = 1;
    for (int i = 0; i < 3 && all; ++i)
      all = hoc_node_on_curve(model, m->dim[c[i]], m->entity[c[i]], cv);
    if (all) return 1;
  }
  return 0;
}

/* Try the swap of element e's edge k with element f's edge kf (the same
 * edge, the other way): e = (a, b, c), f = (b, a, d) become (a, d, c) and
 * (d, b, c). *done: whether it was made. */
static hoc_status try_swap(swapper *S, hoc_hash *edges, size_t e, int k, size_t f, int kf,
                           int *done) {
  hoc_mesh *m = S->m;
  *done = 0;
  size_t *ce = m->conn + 3 * e, *cf = m->conn + 3 * f;
  size_t *se = m->elem_slot + 3 * e, *sf = m->elem_slot + 3 * f;
  size_t a = ce[k], b = ce[(k + 1) % 3], c = ce[(k + 2) % 3], d = cf[(kf + 2) % 3];
  size_t sa = se[k], sb = se[(k + 1) % 3], sc = se[(k + 2) % 3], sd = sf[(kf + 2) % 3];
  /* the shared corners seen from one slot each (not a pole's per-element
   * slots), and no edge c-d already */
  if (cf[kf] != b || cf[(kf + 1) % 3] != a || sf[kf] != sb || sf[(kf + 1) % 3] != sa) return HOC_OK;
  if (m->slot_pole[sa] || m->slot_pole[sb] || m->slot_pole[sc] || m->slot_pole[sd]) return HOC_OK;
  if (c == d || hoc_hash_get(edges, hoc_pair_key(c, d)) != SIZE_MAX) return HOC_OK;
  size_t t1[3] = {a, d, c}, t2[3] = {d, b, c};
  size_t s1[3] = {sa, sd, sc}, s2[3] = {sd, sb, sc};
  /* a triangle inverted on the CAD: its face is meshed again with gmsh's
   * other algorithms (pipeline/repair.c), whose mesh of the whole face
   * serves high orders better than a local swap; but a triangle with its
   * three corners on one curve, inverted there (gmsh makes them along
   * sides where the face's parametrisation stalls, flat in (u, v), and
   * across a concave curve), goes for any valid pair */
  double before = fmin(S->q[e], S->q[f]);
  int ear = !(before > 0) && (on_one_curve(m, ce) || on_one_curve(m, cf));
  if (!ear && !(before > 0)) return HOC_OK;
  double need = ear ? 0.0 : before * (1 + HOC_LINEAR_SWAP_GAIN);
  double q1 = triangle_q(S, t1, s1);
  if (!(q1 > need)) return HOC_OK;
  double q2 = triangle_q(S, t2, s2);
  if (!(q2 > need)) return HOC_OK;
  if (on_one_curve(m, t1) || on_one_curve(m, t2)) return HOC_OK;
  /* d's parameters as e unwraps them (across a seam f's may differ by a
   * period): shifted by a's offset between the two */
  double *ue = m->elem_uv + 6 * e, *uf = m->elem_uv + 6 * f;
  int k1 = (k + 1) % 3, k2 = (k + 2) % 3, kd = (kf + 2) % 3, ka = (kf + 1) % 3;
  double ua[2] = {ue[2 * k], ue[2 * k + 1]}, ub[2] = {ue[2 * k1], ue[2 * k1 + 1]};
  double uc[2] = {ue[2 * k2], ue[2 * k2 + 1]};
  double ud[2] = {uf[2 * kd] + ua[0] - uf[2 * ka], uf[2 * kd + 1] + ua[1] - uf[2 * ka + 1]};
  const double *u1[3] = {ua, ud, uc}, *u2[3] = {ud, ub, uc};
  /* curved, the new pair is no worse than the old */
  const double *u_e[3] = {ue, ue + 2, ue + 4}, *u_f[3] = {uf, uf + 2, uf + 4};
  double c_e, c_f, c_1, c_2;
  int face = m->elem_face[e];
  HOC_TRY(curved_q(S, face, t1, s1, u1, &c_1));
  HOC_TRY(curved_q(S, face, t2, s2, u2, &c_2));
  HOC_TRY(curved_q(S, face, ce, se, u_e, &c_e));
  HOC_TRY(curved_q(S, face, cf, sf, u_f, &c_f));
  if (!(fmin(c_1, c_2) >= fmin(c_e, c_f) || (ear && fmin(c_1, c_2) > 0))) return HOC_OK;
  for (int i = 0; i < 3; ++i) {
    ce[i] = t1[i];
    se[i] = s1[i];
    cf[i] = t2[i];
    sf[i] = s2[i];
    memcpy(ue + 2 * i, u1[i], 2 * sizeof *ue);
    memcpy(uf + 2 * i, u2[i], 2 * sizeof *uf);
  }
  S->q[e] = q1;
  S->q[f] = q2;
  HOC_TRY(hoc_hash_insert(edges, hoc_pair_key(c, d), 3 * e + 2, NULL, NULL));
  *done = 1;
  return HOC_OK;
}

/* One pass over the edges: each element swapped at most once. */
static hoc_status swap_pass(swapper *S, size_t *mate, unsigned char *touched, size_t *n_swapped) {
  hoc_mesh *m = S->m;
  size_t ne = m->n_elems;
  hoc_hash edges = {0};
  hoc_status status = hoc_hash_init(&edges, 3 * ne);
  /* mate[3 e + k]: the other side of element e's edge k, SIZE_MAX if none
   * or on a curve, SIZE_MAX - 1 if more than two elements share it */
  for (size_t i = 0; i < 3 * ne; ++i)
    mate[i] = SIZE_MAX;
  for (size_t i = 0; i < 3 * ne && status == HOC_OK; ++i) {
    size_t e = i / 3, k = i % 3;
    size_t a = m->conn[3 * e + k], b = m->conn[3 * e + (k + 1) % 3];
    uint64_t key = hoc_pair_key(a, b);
    if (hoc_hash_get(&S->lines, key) != SIZE_MAX) continue;
    int found = 0;
    size_t first;
    status = hoc_hash_insert(&edges, key, i, &found, &first);
    if (!found) continue;
    if (mate[first] == SIZE_MAX && m->elem_face[first / 3] == m->elem_face[e]) {
      mate[first] = i;
      mate[i] = first;
    } else {
      if (mate[first] < SIZE_MAX - 1) mate[mate[first]] = SIZE_MAX - 1;
      mate[first] = mate[i] = SIZE_MAX - 1;
    }
  }
  memset(touched, 0, ne);
  for (size_t i = 0; i < 3 * ne && status == HOC_OK; ++i) {
    size_t j = mate[i];
    if (j >= SIZE_MAX - 1 || j < i || touched[i / 3] || touched[j / 3]) continue;
    int done = 0;
    status = try_swap(S, &edges, i / 3, (int)(i % 3), j / 3, (int)(j % 3), &done);
    if (done) {
      touched[i / 3] = touched[j / 3] = 1;
      ++*n_swapped;
    }
  }
  hoc_hash_free(&edges);
  return status;
}

/* The smallest of q[n]. */
static double smallest(const double *q, size_t n) {
  double mn = INFINITY;
  for (size_t e = 0; e < n; ++e)
    mn = fmin(mn, q[e]);
  return mn;
}

hoc_status hoc_mesh_swap_edges(hoc_mesh *m, size_t *n_swapped, double *min_q) {
  HOC_CHECK(m && n_swapped, HOC_ERR_ARGUMENT, "NULL argument");
  HOC_CHECK(m->order == 1, HOC_ERR_ARGUMENT, "edge swaps need a linear mesh, not order %d",
            m->order);
  *n_swapped = 0;
  size_t ne = m->n_elems;
  swapper S = {m, NULL, NULL, NULL, NULL, {0}};
  HOC_TRY(hoc_quality_tables_get(1, m->nodeset, &S.t));
  HOC_TRY(hoc_quality_tables_get(2, HOC_NODES_EQUISPACED, &S.t2));
  double *normal = NULL;
  size_t *mate = NULL, *conn0 = NULL, *slot0 = NULL;
  double *uv0 = NULL;
  unsigned char *touched = NULL;
  hoc_status status = HOC_OK;
  HOC_ALLOC_GOTO(normal, 3 * m->n_slots + 3, done);
  HOC_ALLOC_GOTO(S.q, ne + 1, done);
  HOC_ALLOC_GOTO(mate, 3 * ne + 1, done);
  HOC_ALLOC_GOTO(touched, ne + 1, done);
  HOC_ALLOC_GOTO(conn0, 3 * ne + 1, done);
  HOC_ALLOC_GOTO(slot0, 3 * ne + 1, done);
  HOC_ALLOC_GOTO(uv0, 6 * ne + 1, done);
  HOC_TRY_GOTO(hoc_hash_init(&S.lines, m->n_lines), done);
  for (size_t l = 0; l < m->n_lines; ++l)
    HOC_TRY_GOTO(hoc_hash_insert(&S.lines,
                                 hoc_pair_key(m->line_conn[2 * l], m->line_conn[2 * l + 1]), l,
                                 NULL, NULL),
                 done);
  memcpy(conn0, m->conn, 3 * ne * sizeof *conn0);
  memcpy(slot0, m->elem_slot, 3 * ne * sizeof *slot0);
  memcpy(uv0, m->elem_uv, 6 * ne * sizeof *uv0);
  HOC_TRY_GOTO(hoc_mesh_slot_normals(m, normal), done);
  S.normal = normal;
  HOC_TRY_GOTO(hoc_mesh_measure(m, HOC_MEASURE_SHAPE, S.q, NULL, NULL), done);
  size_t tangled0 = 0;
  for (size_t e = 0; e < ne; ++e)
    tangled0 += S.q[e] == 0.0;
  if (min_q) min_q[0] = min_q[1] = smallest(S.q, ne);
  for (int pass = 0; pass < HOC_LINEAR_SWAP_PASSES; ++pass) {
    size_t before = *n_swapped;
    HOC_TRY_GOTO(swap_pass(&S, mate, touched, n_swapped), done);
    if (*n_swapped == before) break;
  }
  if (*n_swapped) {
    /* measured as the mesh measures (each element's own normals): no
     * more tangled than before, else the mesh as it was */
    HOC_TRY_GOTO(hoc_mesh_measure(m, HOC_MEASURE_SHAPE, S.q, NULL, NULL), done);
    size_t tangled = 0;
    for (size_t e = 0; e < ne; ++e)
      tangled += S.q[e] == 0.0;
    if (tangled > tangled0) {
      memcpy(m->conn, conn0, 3 * ne * sizeof *conn0);
      memcpy(m->elem_slot, slot0, 3 * ne * sizeof *slot0);
      memcpy(m->elem_uv, uv0, 6 * ne * sizeof *uv0);
      *n_swapped = 0;
    } else if (min_q) {
      min_q[1] = smallest(S.q, ne);
    }
  }
done:
  hoc_hash_free(&S.lines);
  free(normal);
  free(S.q);
  free(mate);
  free(touched);
  free(conn0);
  free(slot0);
  free(uv0);
  return status;
}
