/* Quadrature on the reference triangle: exact on every monomial up to its
 * degree (closed form a! b! / (a+b+2)!), positive weights summing to 1/2,
 * points inside; Gauss-Legendre exact to degree 2n-1.
 * SPDX-License-Identifier: GPL-2.0-or-later */
#include "basis/basis.h"
#include "test_util.h"

static double factorial(int n) {
  double f = 1;
  for (int k = 2; k <= n; ++k) f *= k;
  return f;
}

int main(void) {
  for (int d = 0; d <= 40; ++d) {
    hoc_quadrature q;
    CHECK_OK(hoc_quadrature_triangle(d, &q));
    double wsum = 0;
    int inside = 1, positive = 1;
    for (int k = 0; k < q.n; ++k) {
      double r = q.rs[2 * k], s = q.rs[2 * k + 1];
      inside &= r > 0 && s > 0 && r + s < 1;
      positive &= q.w[k] > 0;
      wsum += q.w[k];
    }
    CHECK(inside);
    CHECK(positive);
    CHECK_NEAR(wsum, 0.5, 1e-15);
    double worst = 0;
    for (int a = 0; a <= d; ++a)
      for (int b = 0; a + b <= d; ++b) {
        double exact = factorial(a) * factorial(b) / factorial(a + b + 2), sum = 0;
        for (int k = 0; k < q.n; ++k) sum += q.w[k] * pow(q.rs[2 * k], a) * pow(q.rs[2 * k + 1], b);
        worst = fmax(worst, fabs(sum - exact) / exact);
      }
    CHECK(worst < 1e-12);
    if (!(worst < 1e-12)) fprintf(stderr, "  degree %d: relative error %.3g\n", d, worst);
    hoc_quadrature_free(&q);
  }
  hoc_quadrature bad;
  CHECK_STATUS(hoc_quadrature_triangle(-1, &bad), HOC_ERR_ARGUMENT);
  CHECK_STATUS(hoc_quadrature_triangle(61, &bad), HOC_ERR_ARGUMENT);
  for (int n = 1; n <= 30; ++n) {
    double x[30], w[30], worst = 0;
    CHECK_OK(hoc_gauss_legendre01(n, x, w));
    for (int a = 0; a <= 2 * n - 1; ++a) {
      double sum = 0;
      for (int k = 0; k < n; ++k) sum += w[k] * pow(x[k], a);
      worst = fmax(worst, fabs(sum - 1.0 / (a + 1)) * (a + 1));
    }
    CHECK(worst < 1e-13);
    int sorted = 1;
    for (int k = 1; k < n; ++k) sorted &= x[k] > x[k - 1];
    CHECK(sorted);
  }
  return test_report();
}
