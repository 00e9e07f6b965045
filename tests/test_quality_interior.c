/* The exact fold test of a whole element (hoc_element_interior_folded)
 * against brute force: random curved elements on a paraboloid, corners
 * fixed and every other node moved, from nearly straight to folded, sigma
 * sampled on the lattice of order 96 (4 753 points). Where the samples find
 * sigma clearly negative the test must say folded, where they find it
 * clearly positive not folded; some of the folds lie inside the element,
 * where the edge test cannot see them.
 * SPDX-License-Identifier: GPL-2.0-or-later */
#include "basis/basis.h"
#include "quality/quality.h"
#include "test_sigma.h"
#include "test_util.h"

#include <string.h>

static unsigned long long rng_state = 0x9E3779B97F4A7C15ULL;
static double urand(void) {
  rng_state ^= rng_state << 13;
  rng_state ^= rng_state >> 7;
  rng_state ^= rng_state << 17;
  return (double)(rng_state >> 11) * (1.0 / 9007199254740992.0);
}

/* the surface z = c (x^2 + y^2) and its unit normal */
static void surface(double x, double y, double *X, double *n) {
  const double c = 0.3;
  X[0] = x, X[1] = y, X[2] = c * (x * x + y * y);
  double gx = -2 * c * x, gy = -2 * c * y, l = sqrt(gx * gx + gy * gy + 1);
  n[0] = gx / l, n[1] = gy / l, n[2] = 1 / l;
}

enum { M = 96, NPTS = (M + 1) * (M + 2) / 2 };

static void check_order(int p, hoc_nodeset set, double amplitude, int trials, int *inside) {
  const hoc_quality_tables *t;
  CHECK_OK(hoc_quality_tables_get(p, set, &t));
  int np = t->np;
  hoc_lagrange *b = NULL;
  CHECK_OK(hoc_lagrange_create(p, t->rs, &b));
  double *x = malloc(3 * (size_t)np * sizeof *x), *n = malloc(3 * (size_t)np * sizeof *n);
  double *pts = malloc(2 * NPTS * sizeof *pts), *N = malloc(NPTS * (size_t)np * sizeof *N);
  double *dN = malloc(2 * NPTS * (size_t)np * sizeof *dN);
  int made = b && x && n && pts && N && dN;
  CHECK(made);
  size_t k = 0;
  for (int i = 0; made && i <= M; ++i)
    for (int j = 0; i + j <= M; ++j, ++k)
      pts[2 * k] = (double)i / M, pts[2 * k + 1] = (double)j / M;
  if (made) CHECK_OK(hoc_lagrange_eval(b, NPTS, pts, N, dN));
  int folded = 0, valid = 0, ambiguous = 0, only_inside = 0;
  for (int trial = 0; made && trial < trials; ++trial) {
    /* every other element: straight edges (its nodes on the edges stay),
     * twice the amplitude inside, where only the whole-triangle test sees */
    int inner = trial % 2 && p >= 3;
    double d = (inner ? 2 : 1) * amplitude / p * urand();
    for (int i = 0; i < np; ++i) {
      double r = t->rs[2 * i], s = t->rs[2 * i + 1], di = i < (inner ? 3 * p : 3) ? 0 : d;
      double u = r + 0.5 * s + di * (2 * urand() - 1);
      double v = 0.8660254037844386 * s + di * (2 * urand() - 1);
      surface(u - 0.3, v - 0.2, x + 3 * i, n + 3 * i);
    }
    int exact = hoc_element_interior_folded(t, x, n);
    double mn = sigma_min_points(NPTS, np, N, dN, x, n);
    if (mn < -1e-6) {
      /* the edges' own test goes deeper along them (a fold narrower than
       * the whole-triangle test's 1/32 next to an edge is theirs) */
      CHECK(exact == 1 || hoc_element_edges_folded(t, x, n));
      CHECK(hoc_element_folded(t, x, n) == 1);
      /* and says where: a point of the element where sigma < 0 */
      double rs[2] = {-1, -1}, r;
      CHECK(hoc_element_fold_point(t, x, n, rs) == 1);
      CHECK(rs[0] >= 0 && rs[1] >= 0 && rs[0] + rs[1] <= 1 + 1e-15);
      double rel =
          hoc_element_point_residual(t, HOC_MEASURE_SHAPE, x, n, 0.0, rs, 1.0, NULL, &r, NULL);
      CHECK(rel < 0);
      if (exact) {
        CHECK(hoc_element_interior_fold_point(t, x, n, rs) == 1);
        CHECK(hoc_element_point_residual(t, HOC_MEASURE_SHAPE, x, n, 0.0, rs, 1.0, NULL, &r,
                                         NULL) < 0);
      }
      ++folded;
      if (!hoc_element_edges_folded(t, x, n)) {
        ++only_inside;
        /* measuring counts it tangled */
        double eta;
        CHECK(hoc_element_quality(t, HOC_MEASURE_SHAPE, x, n, &eta, NULL) == 0.0);
      }
    } else if (mn > 1e-3) {
      CHECK(exact == 0);
      double rs[2];
      CHECK(hoc_element_fold_point(t, x, n, rs) == 0);
      ++valid;
    } else {
      ++ambiguous;
    }
  }
  printf("p=%d, node set %d: %d folded (%d inside only), %d valid, %d within [-1e-6, 1e-3]\n", p,
         (int)set, folded, only_inside, valid, ambiguous);
  CHECK(folded > 0 && valid > 0);
  *inside += only_inside;
  hoc_lagrange_destroy(&b);
  free(x);
  free(n);
  free(pts);
  free(N);
  free(dN);
}

int main(void) {
  int inside = 0;
  check_order(2, HOC_NODES_EQUISPACED, 0.5, 300, &inside);
  check_order(3, HOC_NODES_EQUISPACED, 0.5, 300, &inside);
  check_order(5, HOC_NODES_EQUISPACED, 0.3, 150, &inside);
  check_order(10, HOC_NODES_EQUISPACED, 0.12, 40, &inside);
  check_order(4, HOC_NODES_FEKETE, 0.45, 100, &inside);
  check_order(6, HOC_NODES_WARP_BLEND, 0.25, 60, &inside);
  CHECK(inside > 0);
  check_fixed_cases(hoc_element_interior_folded);
  check_fixed_cases(hoc_element_folded);
  return test_report();
}
