/* Basis and quadrature tables of the quality kernel, one per (order, node
 * set), built once and shared.
 * SPDX-License-Identifier: GPL-2.0-or-later */
#include "basis/basis.h"
#include "quality/quality.h"

#include <math.h>
#include <pthread.h>
#include <stdlib.h>

int hoc_quality_degree(int p) {
  /* see docs/quality.md and tests/test_quality_quadrature.c: eta^2 of a
   * curved element is not a polynomial; on real optimised meshes degree
   * 3p + 3 integrates it to within about 1e-3 of a rule of degree 6p + 16 */
  return 3 * p + 3;
}

static pthread_mutex_t cache_lock = PTHREAD_MUTEX_INITIALIZER;
static hoc_quality_tables *cache[HOC_MAX_ORDER + 1][3];

static void tables_free(hoc_quality_tables *t) {
  if (!t) return;
  free(t->w);
  free(t->N);
  free(t->G);
  free(t->Gn);
  free(t->rs);
  free(t->Nv);
  free(t->Gv);
  free(t->Bx);
  free(t->By);
  free(t->Bn);
  free(t->Bw);
  free(t->Ge);
  free(t->Ca);
  free(t->Cn);
  free(t->Wb);
  free(t->enode);
  free(t->Cb);
  free(t->Mb);
  free(t->Pb);
  hoc_lagrange_destroy(&t->basis);
  free(t);
}

void hoc_quality_to_ideal(size_t n, const double *dN, double *G) {
  const double inv_sqrt3 = 0.57735026918962576451;
  for (size_t k = 0; k < n; ++k) {
    double dr = dN[2 * k], ds = dN[2 * k + 1];
    G[2 * k] = dr;
    G[2 * k + 1] = (2 * ds - dr) * inv_sqrt3;
  }
}

static hoc_status build(int p, hoc_nodeset set, int degree, hoc_quality_tables **out) {
  hoc_quality_tables *t;
  HOC_ALLOC(t, 1);
  hoc_status status = HOC_OK;
  hoc_quadrature quad = {0};
  hoc_lagrange *basis = NULL;
  double *dN = NULL;
  t->p = p;
  t->set = set;
  t->np = hoc_tri_num_nodes(p);
  t->degree = degree;
  size_t np = (size_t)t->np;
  HOC_ALLOC_GOTO(t->rs, 2 * np, fail);
  HOC_TRY_GOTO(hoc_tri_nodes(p, set, t->rs), fail);
  HOC_TRY_GOTO(hoc_quadrature_triangle(t->degree, &quad), fail);
  t->nq = quad.n;
  size_t nq = (size_t)quad.n;
  HOC_ALLOC_GOTO(t->w, nq, fail);
  HOC_ALLOC_GOTO(t->N, nq * np, fail);
  HOC_ALLOC_GOTO(t->G, 2 * nq * np, fail);
  HOC_ALLOC_GOTO(t->Gn, 2 * np * np, fail);
  HOC_ALLOC_GOTO(dN, 2 * (nq > np ? nq : np) * np, fail);
  double wsum = 0;
  for (size_t q = 0; q < nq; ++q) wsum += quad.w[q];
  for (size_t q = 0; q < nq; ++q) t->w[q] = quad.w[q] / wsum;
  HOC_TRY_GOTO(hoc_lagrange_create(p, t->rs, &basis), fail);
  HOC_TRY_GOTO(hoc_lagrange_eval(basis, quad.n, quad.rs, t->N, dN), fail);
  hoc_quality_to_ideal(nq * np, dN, t->G);
  HOC_TRY_GOTO(hoc_lagrange_eval(basis, t->np, t->rs, NULL, dN), fail);
  hoc_quality_to_ideal(np * np, dN, t->Gn);
  HOC_TRY_GOTO(hoc_quality_edge_tables(t, basis), fail);
  HOC_TRY_GOTO(hoc_quality_interior_tables(t), fail);
  {
    /* validation points: the lattice (i, j) / 2p (the tangle test's),
     * copies of its last point up to the end of a block of HOC_QB points,
     * then on each edge the points k / 8p between the lattice's (residuals
     * that see an edge pinched between the lattice's points; the exact
     * edge test decides such folds) */
    int m = 2 * p;
    t->nlat = (m + 1) * (m + 2) / 2;
    t->nvpad = (HOC_QB - (t->nq + t->np + t->nlat) % HOC_QB) % HOC_QB;
    t->nv = t->nlat + t->nvpad + 3 * m * (HOC_EDGE_REFINE - 1);
    size_t nv = (size_t)t->nv;
    double *pts = hoc_calloc(2 * nv, sizeof *pts), *dv = hoc_calloc(2 * nv * np, sizeof *dv);
    t->Nv = hoc_calloc(nv * np, sizeof *t->Nv);
    t->Gv = hoc_calloc(2 * nv * np, sizeof *t->Gv);
    if (!pts || !dv || !t->Nv || !t->Gv) {
      free(pts);
      free(dv);
      status = HOC_ERROR(HOC_ERR_MEMORY, "out of memory");
      goto fail;
    }
    size_t k = 0;
    for (int i = 0; i <= m; ++i)
      for (int j = 0; i + j <= m; ++j, ++k) pts[2 * k] = (double)i / m, pts[2 * k + 1] = (double)j / m;
    for (int i = 0; i < t->nvpad; ++i, ++k)
      pts[2 * k] = 1, pts[2 * k + 1] = 0;
    for (int e = 0; e < 3; ++e)
      for (int i = 0; i < m * HOC_EDGE_REFINE; ++i)
        if (i % HOC_EDGE_REFINE)
          hoc_quality_edge_point(e, (double)i / (m * HOC_EDGE_REFINE), pts + 2 * k++);
    status = hoc_lagrange_eval(basis, t->nv, pts, t->Nv, dv);
    if (status == HOC_OK) hoc_quality_to_ideal(nv * np, dv, t->Gv);
    free(pts);
    free(dv);
    if (status != HOC_OK) goto fail;
  }
  {
    /* the blocked copy: quadrature points, nodes, lattice */
    int total = t->nq + t->np + t->nv;
    t->n_blocks = (total + HOC_QB - 1) / HOC_QB;
    t->n_check_blocks = (t->nq + t->np + t->nlat + t->nvpad) / HOC_QB;
    size_t nb = (size_t)t->n_blocks;
    HOC_ALLOC_GOTO(t->Bx, nb * np * HOC_QB, fail);
    HOC_ALLOC_GOTO(t->By, nb * np * HOC_QB, fail);
    HOC_ALLOC_GOTO(t->Bn, nb * np * HOC_QB, fail);
    HOC_ALLOC_GOTO(t->Bw, nb * HOC_QB, fail);
    for (int k = 0; k < t->n_blocks * HOC_QB; ++k) {
      int j = k < total ? k : total - 1;
      size_t b = (size_t)k / HOC_QB, l = (size_t)k % HOC_QB;
      for (size_t i = 0; i < np; ++i) {
        const double *g;
        double nv;
        if (j < t->nq) {
          g = t->G + 2 * ((size_t)j * np + i);
          nv = t->N[(size_t)j * np + i];
        } else if (j < t->nq + t->np) {
          g = t->Gn + 2 * ((size_t)(j - t->nq) * np + i);
          nv = (size_t)(j - t->nq) == i ? 1.0 : 0.0;
        } else {
          g = t->Gv + 2 * ((size_t)(j - t->nq - t->np) * np + i);
          nv = t->Nv[(size_t)(j - t->nq - t->np) * np + i];
        }
        t->Bx[(b * np + i) * HOC_QB + l] = g[0];
        t->By[(b * np + i) * HOC_QB + l] = g[1];
        t->Bn[(b * np + i) * HOC_QB + l] = nv;
      }
      t->Bw[k] = k < t->nq ? t->w[k] : 0.0;
    }
  }
  t->basis = basis; /* kept for hoc_element_point_residual */
  hoc_quadrature_free(&quad);
  free(dN);
  *out = t;
  return HOC_OK;
fail:
  hoc_lagrange_destroy(&basis);
  hoc_quadrature_free(&quad);
  free(dN);
  tables_free(t);
  return status;
}

hoc_status hoc_quality_tables_get(int p, hoc_nodeset set, const hoc_quality_tables **tables) {
  HOC_CHECK(p >= 1 && p <= HOC_MAX_ORDER, HOC_ERR_ARGUMENT, "order %d out of range 1..%d", p,
            HOC_MAX_ORDER);
  HOC_CHECK(set == HOC_NODES_EQUISPACED || set == HOC_NODES_FEKETE || set == HOC_NODES_WARP_BLEND,
            HOC_ERR_ARGUMENT, "unknown node set %d", (int)set);
  pthread_mutex_lock(&cache_lock);
  hoc_status status = HOC_OK;
  if (!cache[p][set]) status = build(p, set, hoc_quality_degree(p), &cache[p][set]);
  *tables = cache[p][set];
  pthread_mutex_unlock(&cache_lock);
  return status;
}

hoc_status hoc_quality_tables_create(int p, hoc_nodeset set, int degree,
                                     hoc_quality_tables **tables) {
  HOC_CHECK(tables, HOC_ERR_ARGUMENT, "NULL output");
  *tables = NULL;
  HOC_CHECK(p >= 1 && p <= HOC_MAX_ORDER, HOC_ERR_ARGUMENT, "order %d out of range", p);
  HOC_CHECK(degree >= 0 && degree <= 60, HOC_ERR_ARGUMENT, "quadrature degree %d out of range",
            degree);
  return build(p, set, degree, tables);
}

void hoc_quality_tables_destroy(hoc_quality_tables **tables) {
  if (!tables || !*tables) return;
  tables_free(*tables);
  *tables = NULL;
}
