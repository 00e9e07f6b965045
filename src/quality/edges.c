/* Exact fold test along the edges of a curved triangle: the sign of
 * sigma = (a1 x a2) . n on an edge from Bernstein coefficients.
 * SPDX-License-Identifier: GPL-2.0-or-later */
#include "basis/basis.h"
#include "quality/quality.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

enum { MAX_D = 3 * HOC_MAX_ORDER - 2, MAX_DEPTH = 14 };

static double binomial(int n, int k) {
  double c = 1;
  for (int i = 1; i <= k; ++i)
    c = c * (n - k + i) / i;
  return c;
}

static double bernstein(int m, int i, double s) {
  return binomial(m, i) * pow(s, i) * pow(1 - s, m - i);
}

hoc_status hoc_quality_invert(int n, const double *V, double *inv) {
  size_t w = 2 * (size_t)n;
  double *a = hoc_calloc((size_t)n * w, sizeof *a);
  if (!a) return HOC_ERROR(HOC_ERR_MEMORY, "out of memory");
  for (int r = 0; r < n; ++r) {
    memcpy(a + (size_t)r * w, V + (size_t)r * (size_t)n, (size_t)n * sizeof *a);
    a[(size_t)r * w + (size_t)(n + r)] = 1;
  }
  for (int c = 0; c < n; ++c) {
    int piv = c;
    for (int r = c + 1; r < n; ++r)
      if (fabs(a[(size_t)r * w + (size_t)c]) > fabs(a[(size_t)piv * w + (size_t)c])) piv = r;
    if (!(fabs(a[(size_t)piv * w + (size_t)c]) > 0)) {
      free(a);
      return HOC_ERROR(HOC_ERR_INTERNAL, "singular %d x %d Bernstein matrix", n, n);
    }
    double *rc = a + (size_t)c * w, *rp = a + (size_t)piv * w;
    for (size_t k = 0; k < w; ++k) {
      double tmp = rc[k];
      rc[k] = rp[k];
      rp[k] = tmp;
    }
    double d = rc[c];
    for (size_t k = 0; k < w; ++k)
      rc[k] /= d;
    for (int r = 0; r < n; ++r) {
      double *rr = a + (size_t)r * w, f = rr[c];
      if (r != c && f != 0)
        for (size_t k = 0; k < w; ++k)
          rr[k] -= f * rc[k];
    }
  }
  for (int r = 0; r < n; ++r)
    memcpy(inv + (size_t)r * (size_t)n, a + (size_t)r * w + n, (size_t)n * sizeof *inv);
  free(a);
  return HOC_OK;
}

/* inv = V^{-1} for V[r][c] = B_c^m(s_r), r, c = 0..m. */
static hoc_status bernstein_inverse(int m, const double *s, double *inv) {
  int n = m + 1;
  double *V = hoc_calloc((size_t)(n * n), sizeof *V);
  if (!V) return HOC_ERROR(HOC_ERR_MEMORY, "out of memory");
  for (int r = 0; r < n; ++r)
    for (int c = 0; c < n; ++c)
      V[r * n + c] = bernstein(m, c, s[r]);
  hoc_status status = hoc_quality_invert(n, V, inv);
  free(V);
  return status;
}

void hoc_quality_edge_point(int k, double s, double *rs) {
  const double r[3][2] = {{s, 0}, {1 - s, s}, {0, 1 - s}};
  rs[0] = r[k][0];
  rs[1] = r[k][1];
}

/* The columns a1, a2 of D phi from gradients g[np][2] at one point. */
static void columns(const double *g, const double *x, int np, double *a1, double *a2) {
  for (int q = 0; q < 3; ++q)
    a1[q] = a2[q] = 0;
  for (int i = 0; i < np; ++i)
    for (int q = 0; q < 3; ++q) {
      a1[q] += g[2 * i] * x[3 * i + q];
      a2[q] += g[2 * i + 1] * x[3 * i + q];
    }
}

static double triple(const double *a1, const double *a2, const double *n) {
  return (a1[1] * a2[2] - a1[2] * a2[1]) * n[0] + (a1[2] * a2[0] - a1[0] * a2[2]) * n[1] +
         (a1[0] * a2[1] - a1[1] * a2[0]) * n[2];
}

hoc_status hoc_quality_edge_tables(hoc_quality_tables *t, const hoc_lagrange *basis) {
  int p = t->p, np = t->np;
  if (p < 2) return HOC_OK;
  size_t np2 = (size_t)np * 2;
  double *pts = NULL, *dN = NULL, *s = NULL, *sa = NULL;
  hoc_status status = HOC_OK;
  HOC_ALLOC_GOTO(t->Ge, 3 * (size_t)p * np2, done);
  HOC_ALLOC_GOTO(t->Ca, (size_t)p * (size_t)p, done);
  HOC_ALLOC_GOTO(t->Cn, (size_t)(p + 1) * (size_t)(p + 1), done);
  HOC_ALLOC_GOTO(t->Wb, (size_t)p * (size_t)p * (size_t)(p + 1), done);
  HOC_ALLOC_GOTO(t->enode, 3 * (size_t)(p + 1), done);
  HOC_ALLOC_GOTO(pts, 2 * (size_t)p, done);
  HOC_ALLOC_GOTO(dN, (size_t)p * np2, done);
  HOC_ALLOC_GOTO(s, (size_t)p + 1, done);
  HOC_ALLOC_GOTO(sa, (size_t)p, done);
  HOC_TRY_GOTO(hoc_edge_nodes(p, t->set, s), done);
  for (int j = 0; j < p; ++j)
    sa[j] = (j + 0.5) / p;
  for (int k = 0; k < 3; ++k) {
    for (int j = 0; j < p; ++j)
      hoc_quality_edge_point(k, sa[j], pts + 2 * j);
    HOC_TRY_GOTO(hoc_lagrange_eval(basis, p, pts, NULL, dN), done);
    const double inv_sqrt3 = 0.57735026918962576451; /* to ideal space, as tables.c */
    double *G = t->Ge + (size_t)k * (size_t)p * np2;
    for (size_t i = 0; i < (size_t)p * (size_t)np; ++i) {
      double dr = dN[2 * i], ds = dN[2 * i + 1];
      G[2 * i] = dr;
      G[2 * i + 1] = (2 * ds - dr) * inv_sqrt3;
    }
    int *en = t->enode + k * (p + 1);
    en[0] = k;
    en[p] = (k + 1) % 3;
    for (int j = 0; j < p - 1; ++j)
      en[1 + j] = 3 + k * (p - 1) + j;
  }
  HOC_TRY_GOTO(bernstein_inverse(p - 1, sa, t->Ca), done);
  HOC_TRY_GOTO(bernstein_inverse(p, s, t->Cn), done);
  for (int i = 0; i < p; ++i)
    for (int j = 0; j < p; ++j)
      for (int k = 0; k <= p; ++k)
        t->Wb[((size_t)i * p + (size_t)j) * (size_t)(p + 1) + (size_t)k] =
            binomial(p - 1, i) * binomial(p - 1, j) * binomial(p, k) /
            binomial(3 * p - 2, i + j + k);
done:
  free(pts);
  free(dN);
  free(s);
  free(sa);
  return status;
}

int hoc_bernstein_negative(const double *c, int d, double tol, int depth, double a, double b,
                           double *where) {
  if (c[0] < -tol || c[d] < -tol) {
    *where = c[0] < -tol ? a : b; /* end coefficients are the values there */
    return 1;
  }
  int positive = 1;
  for (int l = 0; l <= d && positive; ++l)
    positive = c[l] > 0;
  if (positive || depth == 0) return 0;
  double w[MAX_D + 1], left[MAX_D + 1], right[MAX_D + 1];
  memcpy(w, c, (size_t)(d + 1) * sizeof *w);
  left[0] = w[0];
  right[d] = w[d];
  for (int r = 1; r <= d; ++r) {
    for (int i = 0; i <= d - r; ++i)
      w[i] = 0.5 * (w[i] + w[i + 1]);
    left[r] = w[0];
    right[d - r] = w[d - r];
  }
  double mid = 0.5 * (a + b);
  return hoc_bernstein_negative(left, d, tol, depth - 1, a, mid, where) ||
         hoc_bernstein_negative(right, d, tol, depth - 1, mid, b, where);
}

int hoc_element_edges_folded(const hoc_quality_tables *t, const double *x, const double *n) {
  double rs[2];
  return hoc_element_edges_fold_point(t, x, n, rs);
}

int hoc_element_edges_fold_point(const hoc_quality_tables *t, const double *x, const double *n,
                                 double rs[2]) {
  int p = t->p, np = t->np, d = 3 * p - 2;
  if (p < 2 || !t->Ge) return 0;
  double A1[HOC_MAX_ORDER][3], A2[HOC_MAX_ORDER][3], B1[HOC_MAX_ORDER][3], B2[HOC_MAX_ORDER][3];
  double Bn[HOC_MAX_ORDER + 1][3], c[MAX_D + 1];
  for (int k = 0; k < 3; ++k) {
    const double *G = t->Ge + (size_t)k * (size_t)p * (size_t)np * 2;
    for (int j = 0; j < p; ++j)
      columns(G + (size_t)j * (size_t)np * 2, x, np, A1[j], A2[j]);
    for (int i = 0; i < p; ++i)
      for (int q = 0; q < 3; ++q) {
        double s1 = 0, s2 = 0;
        for (int j = 0; j < p; ++j) {
          s1 += t->Ca[i * p + j] * A1[j][q];
          s2 += t->Ca[i * p + j] * A2[j][q];
        }
        B1[i][q] = s1;
        B2[i][q] = s2;
      }
    const int *en = t->enode + k * (p + 1);
    for (int i = 0; i <= p; ++i)
      for (int q = 0; q < 3; ++q) {
        double sn = 0;
        for (int j = 0; j <= p; ++j)
          sn += t->Cn[i * (p + 1) + j] * n[3 * en[j] + q];
        Bn[i][q] = sn;
      }
    for (int l = 0; l <= d; ++l)
      c[l] = 0;
    double scale = 0;
    for (int i = 0; i < p; ++i)
      for (int j = 0; j < p; ++j) {
        const double *W = t->Wb + ((size_t)i * p + (size_t)j) * (size_t)(p + 1);
        for (int m = 0; m <= p; ++m) {
          double v = W[m] * triple(B1[i], B2[j], Bn[m]);
          c[i + j + m] += v;
          scale = fmax(scale, fabs(v));
        }
      }
    /* the corners directly (node gradients), not extrapolated from the
     * samples: they are where sigma comes closest to 0 at a cusp */
    for (int end = 0; end < 2; ++end) {
      int node = en[end ? p : 0];
      double a1[3], a2[3];
      columns(t->Gn + (size_t)node * (size_t)np * 2, x, np, a1, a2);
      c[end ? d : 0] = triple(a1, a2, n + 3 * node);
    }
    /* sigma identically 0 or not a number: folded (degenerate), without
     * subdividing to the end */
    int degenerate = !(scale > 0) || !isfinite(scale);
    for (int l = 0; l <= d && !degenerate; ++l)
      degenerate = !isfinite(c[l]);
    double where = 0.5;
    if (degenerate || hoc_bernstein_negative(c, d, 1e-10 * scale, MAX_DEPTH, 0, 1, &where)) {
      hoc_quality_edge_point(k, where, rs);
      return 1;
    }
  }
  return 0;
}
