/* Brute-force sigma for the exact fold tests' tests.
 * SPDX-License-Identifier: GPL-2.0-or-later */
#ifndef HOC_TEST_SIGMA_H
#define HOC_TEST_SIGMA_H

#include "quality/quality.h"
#include "test_util.h"

#include <math.h>
#include <stddef.h>

/* Smallest sigma / |D phi|^2 over n points, from basis values N[n][np]
 * and reference gradients dN[n][np][2] there (sigma's sign is the same in
 * reference and ideal coordinates), nodes x[np][3], normals nrm[np][3]. */
static double sigma_min_points(size_t n, int np, const double *N, const double *dN, const double *x,
                               const double *nrm) {
  double mn = INFINITY;
  for (size_t q = 0; q < n; ++q) {
    const double *Nq = N + q * (size_t)np, *dq = dN + 2 * q * (size_t)np;
    double a1[3] = {0, 0, 0}, a2[3] = {0, 0, 0}, nn[3] = {0, 0, 0};
    for (int i = 0; i < np; ++i)
      for (int c = 0; c < 3; ++c) {
        a1[c] += dq[2 * i] * x[3 * i + c];
        a2[c] += dq[2 * i + 1] * x[3 * i + c];
        nn[c] += Nq[i] * nrm[3 * i + c];
      }
    double cr[3] = {a1[1] * a2[2] - a1[2] * a2[1], a1[2] * a2[0] - a1[0] * a2[2],
                    a1[0] * a2[1] - a1[1] * a2[0]};
    double f = a1[0] * a1[0] + a1[1] * a1[1] + a1[2] * a1[2] + a2[0] * a2[0] + a2[1] * a2[1] +
               a2[2] * a2[2];
    mn = fmin(mn, (cr[0] * nn[0] + cr[1] * nn[1] + cr[2] * nn[2]) / f);
  }
  return mn;
}

/* An exact fold test on an order-4 element: straight, not folded; seen
 * from below, folded everywhere; collapsed to a point, or with a node not
 * a number, folded (not a long search). */
static void check_fixed_cases(int (*folded)(const hoc_quality_tables *, const double *,
                                            const double *)) {
  const hoc_quality_tables *t;
  CHECK_OK(hoc_quality_tables_get(4, HOC_NODES_EQUISPACED, &t));
  double x[15 * 3], n[15 * 3];
  for (int i = 0; i < t->np; ++i) {
    x[3 * i] = t->rs[2 * i], x[3 * i + 1] = t->rs[2 * i + 1], x[3 * i + 2] = 0;
    n[3 * i] = 0, n[3 * i + 1] = 0, n[3 * i + 2] = 1;
  }
  CHECK(folded(t, x, n) == 0);
  for (int i = 0; i < t->np; ++i)
    n[3 * i + 2] = -1;
  CHECK(folded(t, x, n) == 1);
  for (int i = 0; i < 3 * t->np; ++i)
    x[i] = 0;
  CHECK(folded(t, x, n) == 1);
  x[4] = NAN;
  CHECK(folded(t, x, n) == 1);
}

#endif
