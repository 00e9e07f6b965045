/* The exact fold test of an element's edges (hoc_element_edges_folded)
 * against brute force: random curved elements on a paraboloid, from
 * nearly straight to folded, sigma sampled at 4097 points of each edge. Where the brute force finds
 * sigma clearly negative the test must say folded, where clearly positive not folded; and some of
 * those folds lie between the points of the sampled tangle test (the lattice of order 2p), which is
 * why the exact test exists. SPDX-License-Identifier: GPL-2.0-or-later */
#include "basis/basis.h"
#include "quality/quality.h"
#include "test_sigma.h"
#include "test_util.h"

#include <string.h>

static unsigned long long rng_state = 88172645463325252ULL;
static double urand(void) {
  rng_state ^= rng_state << 13;
  rng_state ^= rng_state >> 7;
  rng_state ^= rng_state << 17;
  return (double)(rng_state >> 11) * (1.0 / 9007199254740992.0);
}

/* the surface z = c (x^2 + y^2) and its unit normal */
static const double curv = 0.3;
static void surface(double x, double y, double *X, double *n) {
  X[0] = x, X[1] = y, X[2] = curv * (x * x + y * y);
  double gx = -2 * curv * x, gy = -2 * curv * y, l = sqrt(gx * gx + gy * gy + 1);
  n[0] = gx / l, n[1] = gy / l, n[2] = 1 / l;
}

/* Basis values and reference gradients at the points j / m of the three
 * edges (sigma's sign is the same in reference and ideal coordinates). */
typedef struct edge_points {
  int m, np;
  double *N, *dN; /* [3 (m + 1)][np], [3 (m + 1)][np][2] */
} edge_points;

static int edge_points_make(const hoc_lagrange *b, int np, int m, edge_points *e) {
  size_t n = 3 * (size_t)(m + 1);
  e->m = m, e->np = np;
  e->N = malloc(n * (size_t)np * sizeof *e->N);
  e->dN = malloc(2 * n * (size_t)np * sizeof *e->dN);
  double *rs = malloc(2 * n * sizeof *rs);
  if (!e->N || !e->dN || !rs) {
    free(rs);
    return 0;
  }
  for (int k = 0; k < 3; ++k)
    for (int j = 0; j <= m; ++j) {
      double s = (double)j / m, r[3][2] = {{s, 0}, {1 - s, s}, {0, 1 - s}};
      size_t q = (size_t)k * (size_t)(m + 1) + (size_t)j;
      rs[2 * q] = r[k][0], rs[2 * q + 1] = r[k][1];
    }
  int ok = hoc_lagrange_eval(b, (int)n, rs, e->N, e->dN) == HOC_OK;
  free(rs);
  return ok;
}

/* smallest sigma / |D phi|^2 over the edge points */
static double edges_min(const edge_points *e, const double *x, const double *n) {
  return sigma_min_points(3 * (size_t)(e->m + 1), e->np, e->N, e->dN, x, n);
}

static void check_order(int p, hoc_nodeset set, double amplitude, int trials, int *hidden_total,
                        int *sampled_miss) {
  const hoc_quality_tables *t;
  CHECK_OK(hoc_quality_tables_get(p, set, &t));
  int np = t->np;
  hoc_lagrange *b = NULL;
  CHECK_OK(hoc_lagrange_create(p, t->rs, &b));
  double *x = malloc(3 * sizeof(double) * (size_t)np), *n = malloc(3 * sizeof(double) * (size_t)np);
  edge_points dense = {0}, lattice = {0};
  int made = b && edge_points_make(b, np, 4096, &dense) && edge_points_make(b, np, 2 * p, &lattice);
  CHECK(made);
  int folded = 0, valid = 0, hidden = 0, ambiguous = 0;
  for (int trial = 0; made && trial < trials; ++trial) {
    double d = amplitude / p * urand(); /* from nearly straight to folded */
    for (int i = 0; i < np; ++i) {
      double r = t->rs[2 * i], s = t->rs[2 * i + 1];
      double di = i < 3 ? 0 : d; /* corners fixed */
      double u = r + 0.5 * s + di * (2 * urand() - 1);
      double v = 0.8660254037844386 * s + di * (2 * urand() - 1);
      surface(u - 0.3, v - 0.2, x + 3 * i, n + 3 * i);
    }
    int exact = hoc_element_edges_folded(t, x, n);
    double mn = edges_min(&dense, x, n);
    if (mn < -1e-6) {
      CHECK(exact == 1);
      /* measuring counts it tangled, whatever the samples say */
      double eta;
      CHECK(hoc_element_quality(t, HOC_MEASURE_SHAPE, x, n, &eta, NULL) == 0.0);
      CHECK(hoc_element_tangled(t, x, n, 1) == 1);
      CHECK(hoc_element_nodes_tangled(t, x, n, 1) == 1);
      ++folded;
      if (edges_min(&lattice, x, n) > 0) ++hidden; /* between the lattice's points */
      if (!hoc_element_tangled(t, x, n, 0)) {
        /* only the exact test sees it: the samples alone say valid */
        CHECK(hoc_element_quality_test(t, HOC_MEASURE_SHAPE, x, n, 0, &eta, NULL) > 0);
        ++*sampled_miss;
      }
    } else if (mn > 1e-6) {
      CHECK(exact == 0);
      ++valid;
    } else {
      ++ambiguous;
    }
  }
  printf("p=%d, node set %d: %d folded (%d between the lattice's edge points), %d valid, %d "
         "within 1e-6 of 0\n",
         p, (int)set, folded, hidden, valid, ambiguous);
  CHECK(folded > 0 && valid > 0);
  *hidden_total += hidden;
  hoc_lagrange_destroy(&b);
  free(x);
  free(n);
  free(dense.N);
  free(dense.dN);
  free(lattice.N);
  free(lattice.dN);
}

int main(void) {
  int hidden = 0, sampled_miss = 0;
  check_order(2, HOC_NODES_EQUISPACED, 0.5, 300, &hidden, &sampled_miss);
  check_order(3, HOC_NODES_EQUISPACED, 0.5, 600, &hidden, &sampled_miss);
  check_order(4, HOC_NODES_EQUISPACED, 0.45, 300, &hidden, &sampled_miss);
  check_order(6, HOC_NODES_EQUISPACED, 0.25, 100, &hidden, &sampled_miss);
  check_order(10, HOC_NODES_EQUISPACED, 0.12, 40, &hidden, &sampled_miss);
  /* the other node sets' edge positions (their value-to-Bernstein maps) */
  check_order(4, HOC_NODES_FEKETE, 0.45, 100, &hidden, &sampled_miss);
  check_order(6, HOC_NODES_WARP_BLEND, 0.25, 60, &hidden, &sampled_miss);
  CHECK(hidden > 0);
  printf("%d folds that only the exact test finds (the sampled tangle test passes them)\n",
         sampled_miss);
  CHECK(sampled_miss > 0);
  check_fixed_cases(hoc_element_edges_folded);
  return test_report();
}
