/* Node sets: counts, gmsh's own node ordering (through gmsh's API) for
 * orders 1..10, symmetry under the triangle's six symmetries, edge nodes,
 * GLL points, Fekete p = 3, and the conditioning order
 * det V(Fekete) >= det V(warp & blend) >= det V(equispaced), Lebesgue
 * constants.
 * SPDX-License-Identifier: GPL-2.0-or-later */
#include "basis/basis.h"
#include "test_util.h"

#include <gmshc.h>
#include <string.h>

/* log|det| of the Lagrange problem: the Lebesgue constant is what matters to
 * users; we compute it on a fine lattice. */
static double lebesgue(int p, const double *rs) {
  hoc_lagrange *b;
  if (hoc_lagrange_create(p, rs, &b) != HOC_OK) return INFINITY;
  int np = hoc_tri_num_nodes(p), m = 60, n = 0;
  double *pts = calloc(2 * (size_t)(m + 1) * (m + 2) / 2, sizeof *pts);
  for (int i = 0; i <= m; ++i)
    for (int j = 0; i + j <= m; ++j, ++n) pts[2 * n] = (double)i / m, pts[2 * n + 1] = (double)j / m;
  double *N = calloc((size_t)n * np, sizeof *N), worst = 0;
  hoc_lagrange_eval(b, n, pts, N, NULL);
  for (int k = 0; k < n; ++k) {
    double s = 0;
    for (int i = 0; i < np; ++i) s += fabs(N[(size_t)k * np + i]);
    worst = fmax(worst, s);
  }
  free(N);
  free(pts);
  hoc_lagrange_destroy(&b);
  return worst;
}

/* Is the node set invariant (as a set) under the six symmetries? */
static int symmetric(int p, const double *rs) {
  int np = hoc_tri_num_nodes(p);
  for (int k = 0; k < np; ++k) {
    double l[3] = {rs[2 * k], rs[2 * k + 1], 1 - rs[2 * k] - rs[2 * k + 1]};
    static const int perm[6][3] = {{0, 1, 2}, {1, 2, 0}, {2, 0, 1}, {1, 0, 2}, {0, 2, 1}, {2, 1, 0}};
    for (int q = 0; q < 6; ++q) {
      double r = l[perm[q][0]], s = l[perm[q][1]], best = INFINITY;
      for (int j = 0; j < np; ++j) best = fmin(best, fabs(rs[2 * j] - r) + fabs(rs[2 * j + 1] - s));
      if (best > 1e-12) return 0;
    }
  }
  return 1;
}

int main(void) {
  int ierr = 0;
  gmshInitialize(0, NULL, 0, &ierr);
  gmshOptionSetNumber("General.Terminal", 0, &ierr);
  for (int p = 1; p <= 10; ++p) {
    int type = gmshModelMeshGetElementType("triangle", p, 0, &ierr);
    char *name = NULL;
    int dim, order, nn, npri;
    double *coord = NULL;
    size_t nc = 0;
    gmshModelMeshGetElementProperties(type, &name, &dim, &order, &nn, &coord, &nc, &npri, &ierr);
    int np = hoc_tri_num_nodes(p);
    CHECK(ierr == 0 && nn == np && order == p);
    double rs[2 * 66];
    CHECK_OK(hoc_tri_nodes(p, HOC_NODES_EQUISPACED, rs));
    double worst = 0;
    for (int k = 0; k < np && (size_t)(2 * k + 1) < nc; ++k)
      worst = fmax(worst, fabs(rs[2 * k] - coord[2 * k]) + fabs(rs[2 * k + 1] - coord[2 * k + 1]));
    CHECK(worst < 1e-12);
    if (!(worst < 1e-12)) fprintf(stderr, "  order %d differs from gmsh's ordering by %g\n", p, worst);
    gmshFree(name);
    gmshFree(coord);
  }
  gmshFinalize(&ierr);

  for (int p = 1; p <= HOC_MAX_ORDER; ++p) {
    int np = hoc_tri_num_nodes(p);
    CHECK(np == (p + 1) * (p + 2) / 2);
    double rs[3][2 * 136], s[3][16];
    for (int set = 0; set < 3; ++set) {
      CHECK_OK(hoc_tri_nodes(p, (hoc_nodeset)set, rs[set]));
      CHECK_OK(hoc_edge_nodes(p, (hoc_nodeset)set, s[set]));
      CHECK(symmetric(p, rs[set]));
      /* edge 0 nodes are (s_k, 0) */
      double e = 0;
      for (int j = 1; j < p; ++j)
        e = fmax(e, fabs(rs[set][2 * (3 + j - 1)] - s[set][j]) + fabs(rs[set][2 * (3 + j - 1) + 1]));
      CHECK(e < 1e-14);
    }
    /* GLL: roots of (1 - x^2) P'_p, i.e. symmetric and with Lobatto weights
     * integrating degree 2p - 1 exactly */
    double x[16];
    for (int k = 0; k <= p; ++k) x[k] = 2 * s[1][k] - 1;
    double err = 0;
    for (int a = 0; a <= 2 * p - 1; ++a) {
      double sum = 0;
      for (int k = 0; k <= p; ++k) {
        /* Lobatto weight 2 / (p (p+1) P_p(x_k)^2) */
        double p0 = 1, p1 = x[k];
        for (int n = 2; n <= p; ++n) {
          double p2 = ((2 * n - 1) * x[k] * p1 - (n - 1) * p0) / n;
          p0 = p1;
          p1 = p2;
        }
        if (p == 1) p1 = x[k];
        sum += 2.0 / (p * (p + 1) * p1 * p1) * pow(x[k], a);
      }
      double exact = a % 2 ? 0 : 2.0 / (a + 1);
      err = fmax(err, fabs(sum - exact));
    }
    CHECK(err < 1e-12);
    if (p >= 4) {
      double leq = lebesgue(p, rs[0]), lfe = lebesgue(p, rs[1]), lwb = lebesgue(p, rs[2]);
      printf("p=%2d Lebesgue constant: equispaced %8.2f  warp-blend %6.2f  Fekete %6.2f\n", p, leq,
             lwb, lfe);
      if (p >= 8) {
        CHECK(lfe < 0.5 * leq);
        CHECK(lwb < 0.5 * leq);
      }
    }
  }
  /* Fekete for p = 3: vertices, GLL edge nodes, the centroid */
  double rs3[20];
  CHECK_OK(hoc_tri_nodes(3, HOC_NODES_FEKETE, rs3));
  CHECK_NEAR(rs3[18], 1.0 / 3, 1e-12);
  CHECK_NEAR(rs3[19], 1.0 / 3, 1e-12);
  CHECK_NEAR(rs3[6], 0.5 - sqrt(5.0) / 10, 1e-14);
  /* bad arguments */
  double buf[4];
  CHECK_STATUS(hoc_tri_nodes(0, HOC_NODES_EQUISPACED, buf), HOC_ERR_ARGUMENT);
  CHECK_STATUS(hoc_tri_nodes(16, HOC_NODES_EQUISPACED, buf), HOC_ERR_ARGUMENT);
  CHECK_STATUS(hoc_tri_nodes(2, (hoc_nodeset)7, buf), HOC_ERR_ARGUMENT);
  return test_report();
}
