/* Exact fold test of a whole curved triangle: the sign of
 * sigma = (x_r x x_s) . n over the reference triangle from the Bernstein
 * coefficients of that polynomial, with subdivision in four.
 * SPDX-License-Identifier: GPL-2.0-or-later
 *
 * x is a polynomial of degree p, so its derivatives x_r, x_s are of degree
 * p - 1 and the interpolated normal n of degree p: (x_r x x_s) . n is of
 * degree 3p - 2. Its sign is that of sigma = (a1 x a2) . n (a1, a2 are x_r,
 * x_s times W^-1, whose determinant is positive). In the Bernstein basis of
 * degree m on the triangle (barycentric l0 = 1 - r - s, l1 = r, l2 = s),
 *   d/dr sum_a b_a B_a^m = m sum_c (b_{c+e1} - b_{c+e0}) B_c^{m-1},
 *   B_a^i B_c^j = [C(a) C(c) / C(a + c)] B_{a+c}^{i+j}
 * with C(a) = |a|! / (a0! a1! a2!); the coefficients at the three corners
 * are the values there. All coefficients positive proves sigma > 0 on the
 * triangle; a corner value below -tol proves a fold; otherwise the triangle
 * is cut in four at its edges' midpoints (the children's coefficients of x
 * and n by blossoming) and each child decided the same way. */
#include "basis/basis.h"
#include "quality/quality.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

enum {
  MAXP = HOC_MAX_ORDER,
  NET_P = (MAXP + 1) * (MAXP + 2) / 2,     /* a net of degree p */
  NET_2 = (2 * MAXP - 1) * (2 * MAXP) / 2, /* degree 2p - 2 */
  NET_3 = (3 * MAXP - 1) * (3 * MAXP) / 2, /* degree 3p - 2 */
  MAX_LEVELS = 5                           /* children down to 1/32 of the edges */
};

/* Index of the coefficient (m - j - k, j, k) in a net of degree m. */
static inline int ix(int m, int j, int k) { return k * (m + 1) - k * (k - 1) / 2 + j; }

static double factorial(int n) {
  double f = 1;
  for (int i = 2; i <= n; ++i)
    f *= i;
  return f;
}

/* C(a) of every multi-index of degree m, in net order. */
static void multinomials(int m, double *c) {
  for (int k = 0; k <= m; ++k)
    for (int j = 0; j + k <= m; ++j)
      c[ix(m, j, k)] = factorial(m) / (factorial(m - j - k) * factorial(j) * factorial(k));
}

hoc_status hoc_quality_interior_tables(hoc_quality_tables *t) {
  int p = t->p, np = t->np;
  if (p < 2) return HOC_OK;
  size_t n = (size_t)np;
  int m1 = p - 1, m2 = 2 * p - 2, m3 = 3 * p - 2;
  size_t n1 = (size_t)ix(m1, 0, m1 + 1), n2 = (size_t)ix(m2, 0, m2 + 1),
         n3 = (size_t)ix(m3, 0, m3 + 1);
  HOC_ALLOC(t->Cb, n * n);
  HOC_ALLOC(t->Mb, n1 + n2 + n + n3);
  multinomials(m1, t->Mb);
  multinomials(m2, t->Mb + n1);
  multinomials(p, t->Mb + n1 + n2);
  multinomials(m3, t->Mb + n1 + n2 + n);
  const double *cm = t->Mb + n1 + n2;
  /* the weights of sigma_net's two products, in its loops' order and
   * computed as it would (the same rounding) */
  HOC_ALLOC(t->Pb, n1 * n1 + n2 * n);
  const double *c1 = t->Mb, *c2 = c1 + n1, *c3 = cm + n;
  double *w = t->Pb;
  for (int k1 = 0; k1 <= m1; ++k1)
    for (int j1 = 0; j1 + k1 <= m1; ++j1)
      for (int k2 = 0; k2 <= m1; ++k2)
        for (int j2 = 0; j2 + k2 <= m1; ++j2)
          *w++ = c1[ix(m1, j1, k1)] * c1[ix(m1, j2, k2)] / c2[ix(m2, j1 + j2, k1 + k2)];
  for (int k1 = 0; k1 <= m2; ++k1)
    for (int j1 = 0; j1 + k1 <= m2; ++j1)
      for (int k2 = 0; k2 <= p; ++k2)
        for (int j2 = 0; j2 + k2 <= p; ++j2)
          *w++ = c2[ix(m2, j1, k1)] * cm[ix(p, j2, k2)] / c3[ix(m3, j1 + j2, k1 + k2)];
  /* V[node][coefficient] = B_a^p(node); Cb = V^-1 (row a: coefficient a
   * as a sum over the nodes) */
  double *V = hoc_calloc(n * n, sizeof *V);
  if (!V) return HOC_ERROR(HOC_ERR_MEMORY, "out of memory");
  for (size_t r = 0; r < n; ++r) {
    double l1 = t->rs[2 * r], l2 = t->rs[2 * r + 1], l0 = 1 - l1 - l2;
    for (int k = 0; k <= p; ++k)
      for (int j = 0; j + k <= p; ++j)
        V[r * n + (size_t)ix(p, j, k)] =
            cm[ix(p, j, k)] * pow(l0, p - j - k) * pow(l1, j) * pow(l2, k);
  }
  hoc_status status = hoc_quality_invert(np, V, t->Cb);
  free(V);
  return status;
}

/* The products' weights of the test (hoc_quality_tables.Pb). */
typedef struct weights {
  int p;
  const double *w1, *w3; /* d1 x d2 (degrees p - 1, p - 1); c . n (degrees 2p - 2, p) */
} weights;

/* The corner of the parent that barycentric point w is, or -1. */
static int corner_of(const double w[3]) {
  for (int c = 0; c < 3; ++c)
    if (w[c] == 1 && w[(c + 1) % 3] == 0 && w[(c + 2) % 3] == 0) return c;
  return -1;
}

/* One de Casteljau step of a net of 3-vectors of degree m at the point w
 * (barycentric): out, of degree m - 1; out may be in (each coefficient
 * reads only coefficients not yet overwritten). restrict_net never steps
 * at a corner of the parent: it picks there instead. */
static void step(int m, const double *in, const double w[3], double *out) {
  for (int k = 0; k < m; ++k)
    for (int j = 0; j + k < m; ++j) {
      const double *a0 = in + 3 * ix(m, j, k), *a1 = in + 3 * ix(m, j + 1, k),
                   *a2 = in + 3 * ix(m, j, k + 1);
      double *o = out + 3 * ix(m - 1, j, k);
      for (int d = 0; d < 3; ++d)
        o[d] = w[0] * a0[d] + w[1] * a1[d] + w[2] * a2[d];
    }
}

/* The net of degree m on the child triangle with corners W[0..2]
 * (barycentric in the parent): coefficient (a0, a1, a2) is the blossom
 * at W0 a0 times, W1 a1 times, W2 a2 times.
 * The blossom is symmetric, so its arguments may come in any order: the
 * outer loops step with two of the W (outer, then middle) and the inner
 * one reduces the rest with the third W to one coefficient, O(deg^3) for
 * each of the O(m^2) coefficients. Where a W is a corner of the parent
 * (three of the four children have one), a step with it only shifts the
 * net's indices, so it goes innermost and its reduction is a pick of one
 * coefficient: O(m^4) for the whole net instead of O(m^5). The other two
 * keep their order (W2 before W1 before W0), and a shift commutes exactly
 * with the steps, so every coefficient is the same number either way. */
static void restrict_net(int m, const double *in, const double W[3][3], double *out) {
  int inner = 0, corner = -1;
  for (int i = 2; i >= 0 && corner < 0; --i)
    if ((corner = corner_of(W[i])) >= 0) inner = i;
  /* the other two, in the order W2, W1, W0 */
  int outer = inner == 2 ? 1 : 2, middle = inner == 0 ? 1 : 0;
  double buf[4][NET_P * 3];
  const double *n2 = in;
  int b2 = 0;
  for (int k = 0; k <= m; ++k) {
    if (k) {
      step(m - k + 1, n2, W[outer], buf[b2]);
      n2 = buf[b2];
      b2 ^= 1;
    }
    const double *n1 = n2;
    int b1 = 2;
    for (int j = 0; j + k <= m; ++j) {
      if (j) {
        step(m - k - j + 1, n1, W[middle], buf[b1]);
        n1 = buf[b1];
        b1 ^= 1; /* 2 <-> 3 */
      }
      int deg = m - k - j, a[3];
      a[outer] = k;
      a[middle] = j;
      a[inner] = deg;
      double *o = out + 3 * ix(m, a[1], a[2]);
      if (corner >= 0) {
        /* deg steps at the corner: the coefficient deg times toward it
         * (stepping would add terms of weight 0: the same values, but
         * for a zero's sign, which no comparison of the test sees) */
        memcpy(o, n1 + 3 * ix(deg, corner == 1 ? deg : 0, corner == 2 ? deg : 0), 3 * sizeof *o);
        continue;
      }
      /* W[inner] down to one coefficient, in place (each step reads only
       * coefficients it has not yet overwritten) */
      double v[3 * (MAXP + 1) * (MAXP + 2) / 2];
      memcpy(v, n1, (size_t)(3 * ix(deg, 0, deg + 1)) * sizeof *v);
      for (int i = deg; i > 0; --i)
        step(i, v, W[inner], v);
      memcpy(o, v, 3 * sizeof *v);
    }
  }
}

/* Coefficients P[ix(3p-2, ., .)] of (x_r x x_s) . n from the nets of x and
 * n (degree p); returns the largest magnitude of a term (NaN if one is
 * not finite: the caller treats NaN and infinity alike).
 * The products' output index ix(m, j1 + j2, k1 + k2) runs on with j2, so
 * their inner loops are over j2 on arrays of one component each (vector
 * code); every coefficient still sums its terms in the same order. */
static double sigma_net(const weights *wt, const double *bx, const double *bn, double *P) {
  int p = wt->p, m1 = p - 1, m2 = 2 * p - 2, m3 = 3 * p - 2;
  double d1[3][NET_P], d2[3][NET_P], c[3][NET_2], g[3][NET_P];
  for (int k = 0; k <= m1; ++k)
    for (int j = 0; j + k <= m1; ++j) {
      const double *b0 = bx + 3 * ix(p, j, k), *b1 = bx + 3 * ix(p, j + 1, k),
                   *b2 = bx + 3 * ix(p, j, k + 1);
      for (int d = 0; d < 3; ++d) {
        d1[d][ix(m1, j, k)] = p * (b1[d] - b0[d]);
        d2[d][ix(m1, j, k)] = p * (b2[d] - b0[d]);
      }
    }
  for (int a = 0; a < ix(p, 0, p + 1); ++a)
    for (int d = 0; d < 3; ++d) g[d][a] = bn[3 * a + d];
  memset(c, 0, sizeof c);
  const double *w1 = wt->w1, *w3 = wt->w3;
  for (int k1 = 0; k1 <= m1; ++k1)
    for (int j1 = 0; j1 + k1 <= m1; ++j1) {
      int a = ix(m1, j1, k1);
      double f0 = d1[0][a], f1 = d1[1][a], f2 = d1[2][a];
      for (int k2 = 0; k2 <= m1; ++k2) {
        int len = m1 - k2 + 1, b = ix(m1, 0, k2), o = ix(m2, j1, k1 + k2);
        const double *g0 = d2[0] + b, *g1 = d2[1] + b, *g2 = d2[2] + b;
        double *c0 = c[0] + o, *c1 = c[1] + o, *c2 = c[2] + o;
        for (int j2 = 0; j2 < len; ++j2) {
          double w = w1[j2];
          c0[j2] += w * (f1 * g2[j2] - f2 * g1[j2]);
          c1[j2] += w * (f2 * g0[j2] - f0 * g2[j2]);
          c2[j2] += w * (f0 * g1[j2] - f1 * g0[j2]);
        }
        w1 += len;
      }
    }
  memset(P, 0, (size_t)ix(m3, 0, m3 + 1) * sizeof *P);
  /* per position j2 (no reduction in the loop, which would keep it
   * scalar): the largest |term|, and 0 or NaN where a term is not finite */
  double lmax[MAXP + 1] = {0}, lz[MAXP + 1] = {0};
  for (int k1 = 0; k1 <= m2; ++k1)
    for (int j1 = 0; j1 + k1 <= m2; ++j1) {
      int a = ix(m2, j1, k1);
      double f0 = c[0][a], f1 = c[1][a], f2 = c[2][a];
      for (int k2 = 0; k2 <= p; ++k2) {
        int len = p - k2 + 1, b = ix(p, 0, k2);
        const double *g0 = g[0] + b, *g1 = g[1] + b, *g2 = g[2] + b;
        double *Po = P + ix(m3, j1, k1 + k2);
        for (int j2 = 0; j2 < len; ++j2) {
          double v = w3[j2] * (f0 * g0[j2] + f1 * g1[j2] + f2 * g2[j2]);
          Po[j2] += v;
          double av = fabs(v);
          lmax[j2] = av > lmax[j2] ? av : lmax[j2];
          lz[j2] += v * 0;
        }
        w3 += len;
      }
    }
  double scale = 0;
  for (int j = 0; j <= p; ++j) {
    if (lz[j] != lz[j]) return NAN;
    if (lmax[j] > scale) scale = lmax[j];
  }
  return scale;
}

/* 1 if a fold is found on the triangle of nets bx, bn (levels more cuts
 * allowed), 0 if proven positive or nothing found. */
static int folded_net(const weights *wt, const double *bx, const double *bn, int levels,
                      const double corner[3][2], double rs[2]) {
  int m3 = 3 * wt->p - 2, nc = ix(m3, 0, m3 + 1);
  double P[NET_3];
  double scale = sigma_net(wt, bx, bn, P);
  if (!(scale > 0) || !isfinite(scale)) { /* degenerate or not a number */
    for (int d = 0; d < 2; ++d)
      rs[d] = (corner[0][d] + corner[1][d] + corner[2][d]) / 3;
    return 1;
  }
  double tol = 1e-10 * scale;
  /* corner coefficients are the values at the corners */
  const int at[3] = {ix(m3, 0, 0), ix(m3, m3, 0), ix(m3, 0, m3)};
  for (int c = 0; c < 3; ++c)
    if (P[at[c]] < -tol) {
      rs[0] = corner[c][0];
      rs[1] = corner[c][1];
      return 1;
    }
  int positive = 1;
  for (int i = 0; i < nc && positive; ++i)
    positive = P[i] > 0;
  if (positive || levels == 0) return 0;
  /* the four children: the corners' triangles and the middle one (its
   * corners ordered so that it turns the same way) */
  static const double kids[4][3][3] = {
      {{1, 0, 0}, {0.5, 0.5, 0}, {0.5, 0, 0.5}},
      {{0.5, 0.5, 0}, {0, 1, 0}, {0, 0.5, 0.5}},
      {{0.5, 0, 0.5}, {0, 0.5, 0.5}, {0, 0, 1}},
      {{0, 0.5, 0.5}, {0.5, 0, 0.5}, {0.5, 0.5, 0}},
  };
  double cx[NET_P * 3], cn[NET_P * 3];
  for (int q = 0; q < 4; ++q) {
    restrict_net(wt->p, bx, kids[q], cx);
    restrict_net(wt->p, bn, kids[q], cn);
    double kc[3][2];
    for (int c = 0; c < 3; ++c)
      for (int d = 0; d < 2; ++d)
        kc[c][d] = kids[q][c][0] * corner[0][d] + kids[q][c][1] * corner[1][d] +
                   kids[q][c][2] * corner[2][d];
    if (folded_net(wt, cx, cn, levels - 1, (const double(*)[2])kc, rs)) return 1;
  }
  return 0;
}

int hoc_element_interior_folded(const hoc_quality_tables *t, const double *x, const double *n) {
  double rs[2];
  return hoc_element_interior_fold_point(t, x, n, rs);
}

int hoc_element_interior_fold_point(const hoc_quality_tables *t, const double *x, const double *n,
                                    double rs[2]) {
  int p = t->p, np = t->np;
  if (p < 2 || !t->Cb) return 0;
  int m1 = p - 1, n1 = ix(m1, 0, m1 + 1);
  weights wt = {p, t->Pb, t->Pb + (size_t)n1 * (size_t)n1};
  double bx[NET_P * 3], bn[NET_P * 3];
  for (int a = 0; a < np; ++a) {
    const double *row = t->Cb + (size_t)a * (size_t)np;
    double sx[3] = {0, 0, 0}, sn[3] = {0, 0, 0};
    for (int i = 0; i < np; ++i)
      for (int d = 0; d < 3; ++d) {
        sx[d] += row[i] * x[3 * i + d];
        sn[d] += row[i] * n[3 * i + d];
      }
    memcpy(bx + 3 * a, sx, sizeof sx);
    memcpy(bn + 3 * a, sn, sizeof sn);
  }
  static const double whole[3][2] = {{0, 0}, {1, 0}, {0, 1}};
  return folded_net(&wt, bx, bn, MAX_LEVELS, whole, rs);
}

int hoc_element_folded(const hoc_quality_tables *t, const double *x, const double *n) {
  return hoc_element_edges_folded(t, x, n) || hoc_element_interior_folded(t, x, n);
}

int hoc_element_fold_point(const hoc_quality_tables *t, const double *x, const double *n,
                           double rs[2]) {
  return hoc_element_edges_fold_point(t, x, n, rs) || hoc_element_interior_fold_point(t, x, n, rs);
}
