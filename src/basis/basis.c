/* Reference triangle: node sets (equispaced, warp & blend, Fekete), the
 * Lagrange basis through an orthonormal (Dubiner/PKDO) basis, and Gauss
 * quadrature.
 * SPDX-License-Identifier: GPL-2.0-or-later
 *
 * References for the formulas (implemented here from the mathematics):
 *  - orthonormal triangle basis and its gradient: Dubiner (1991); Hesthaven &
 *    Warburton, Nodal Discontinuous Galerkin Methods, Springer 2008, ch. 6;
 *  - warp & blend nodes: T. Warburton, An explicit construction of
 *    interpolation nodes on the simplex, J. Eng. Math. 56 (2006) 247-262,
 *    with the published optimal alpha for p <= 15;
 *  - Fekete points: maximal |det V|; their edge nodes are the 1D Fekete
 *    (Gauss-Lobatto-Legendre) points (Bos 1991).
 */
#include "basis/basis.h"

#include <float.h>
#include <math.h>
#include <pthread.h>
#include <stdlib.h>
#include <string.h>

#define PI 3.14159265358979323846

/* Lattice in gmsh order ------------------------------------------------- */

/* Order-p triangle with corner lattice offset (off, off): vertices, edges,
 * then its interior as an order p-3 triangle one step in. */
static void lattice_recursive(int p, int off, int *ij, int *k) {
  if (p < 0) return;
  if (p == 0) {
    ij[2 * *k] = off;
    ij[2 * *k + 1] = off;
    ++*k;
    return;
  }
  const int v[3][2] = {{0, 0}, {p, 0}, {0, p}};
  for (int i = 0; i < 3; ++i, ++*k) {
    ij[2 * *k] = off + v[i][0];
    ij[2 * *k + 1] = off + v[i][1];
  }
  for (int e = 0; e < 3; ++e) {
    const int *a = v[e], *b = v[(e + 1) % 3];
    for (int j = 1; j < p; ++j, ++*k) {
      ij[2 * *k] = off + a[0] + (b[0] - a[0]) * j / p;
      ij[2 * *k + 1] = off + a[1] + (b[1] - a[1]) * j / p;
    }
  }
  lattice_recursive(p - 3, off + 1, ij, k);
}

hoc_status hoc_tri_lattice(int p, int *ij) {
  HOC_CHECK(p >= 1 && p <= HOC_MAX_ORDER, HOC_ERR_ARGUMENT, "order %d out of range", p);
  HOC_CHECK(ij, HOC_ERR_ARGUMENT, "NULL output");
  int k = 0;
  lattice_recursive(p, 0, ij, &k);
  HOC_ASSERT(k == hoc_tri_num_nodes(p));
  return HOC_OK;
}

/* Jacobi polynomials ------------------------------------------------------ */

/* Orthonormal Jacobi polynomial P_n^{(a,b)}(x) on [-1,1] with weight
 * (1-x)^a (1+x)^b (as in Hesthaven & Warburton's JacobiP). */
static double jacobi(double x, double a, double b, int n) {
  double g0 = pow(2, a + b + 1) / (a + b + 1) * tgamma(a + 1) * tgamma(b + 1) / tgamma(a + b + 1);
  double p0 = 1 / sqrt(g0);
  if (n == 0) return p0;
  double g1 = (a + 1) * (b + 1) / (a + b + 3) * g0;
  double p1 = ((a + b + 2) * x / 2 + (a - b) / 2) / sqrt(g1);
  if (n == 1) return p1;
  double aold = 2 / (2 + a + b) * sqrt((a + 1) * (b + 1) / (a + b + 3));
  for (int i = 1; i < n; ++i) {
    double h1 = 2 * i + a + b;
    double anew = 2 / (h1 + 2) *
                  sqrt((i + 1) * (i + 1 + a + b) * (i + 1 + a) * (i + 1 + b) / (h1 + 1) / (h1 + 3));
    double bnew = -(a * a - b * b) / h1 / (h1 + 2);
    double p2 = 1 / anew * (-aold * p0 + (x - bnew) * p1);
    aold = anew;
    p0 = p1;
    p1 = p2;
  }
  return p1;
}

static double jacobi_deriv(double x, double a, double b, int n) {
  if (n == 0) return 0;
  return sqrt(n * (n + a + b + 1)) * jacobi(x, a + 1, b + 1, n - 1);
}

/* Gauss-Lobatto-Legendre points on [-1,1]: the ends and the roots of P'_p. */
static void gll_points(int p, double *x) {
  x[0] = -1;
  x[p] = 1;
  for (int k = 1; k < p; ++k) {
    /* Chebyshev-Gauss-Lobatto guess, Newton on P'_p (= c P^{(1,1)}_{p-1}) */
    double z = -cos(PI * k / p);
    for (int it = 0; it < 100; ++it) {
      double f = jacobi(z, 1, 1, p - 1), df = jacobi_deriv(z, 1, 1, p - 1);
      double dz = f / df;
      z -= dz;
      if (fabs(dz) < 1e-16) break;
    }
    x[k] = z;
  }
  /* exact symmetry */
  for (int k = 0; k <= p / 2; ++k) {
    double m = 0.5 * (x[p - k] - x[k]);
    x[k] = -m;
    x[p - k] = m;
  }
}

hoc_status hoc_edge_nodes(int p, hoc_nodeset set, double *s) {
  HOC_CHECK(p >= 1 && p <= HOC_MAX_ORDER, HOC_ERR_ARGUMENT, "order %d out of range", p);
  HOC_CHECK(s, HOC_ERR_ARGUMENT, "NULL output");
  if (set == HOC_NODES_EQUISPACED) {
    for (int k = 0; k <= p; ++k) s[k] = (double)k / p;
    return HOC_OK;
  }
  HOC_CHECK(set == HOC_NODES_FEKETE || set == HOC_NODES_WARP_BLEND, HOC_ERR_ARGUMENT,
            "unknown node set %d", (int)set);
  double x[HOC_MAX_ORDER + 1];
  gll_points(p, x);
  for (int k = 0; k <= p; ++k) s[k] = 0.5 * (x[k] + 1);
  s[0] = 0;
  s[p] = 1;
  return HOC_OK;
}

/* Gauss quadrature --------------------------------------------------------- */

hoc_status hoc_gauss_legendre01(int n, double *x, double *w) {
  HOC_CHECK(n >= 1 && n <= 200, HOC_ERR_ARGUMENT, "Gauss-Legendre size %d out of range", n);
  for (int i = 0; i < (n + 1) / 2; ++i) {
    double z = cos(PI * (i + 0.75) / (n + 0.5)), dp = 1;
    for (int it = 0; it < 100; ++it) {
      double p0 = 1, p1 = z;
      for (int k = 2; k <= n; ++k) {
        double p2 = ((2 * k - 1) * z * p1 - (k - 1) * p0) / k;
        p0 = p1;
        p1 = p2;
      }
      if (n == 1) p0 = 1, p1 = z;
      dp = n * (z * p1 - p0) / (z * z - 1);
      double dz = p1 / dp;
      z -= dz;
      if (fabs(dz) < 1e-16) break;
    }
    if (n == 1) dp = 1, z = 0;
    double wi = n == 1 ? 2 : 2 / ((1 - z * z) * dp * dp);
    /* map [-1,1] -> [0,1]; symmetric pair */
    x[i] = 0.5 * (1 - z);
    x[n - 1 - i] = 0.5 * (1 + z);
    w[i] = w[n - 1 - i] = 0.5 * wi;
  }
  if (n % 2) x[n / 2] = 0.5; /* increasing order: z = cos(...) decreases with i */
  return HOC_OK;
}

/* Collapsed (Duffy) product rule: r = a (1 - b), s = b on the unit square
 * with Jacobian (1 - b). A polynomial of degree d in (r,s) becomes one of
 * degree d in a and d + 1 in b, so Gauss-Legendre with ceil((d+1)/2) points
 * in a and ceil((d+2)/2) in b is exact. */
hoc_status hoc_quadrature_triangle(int degree, hoc_quadrature *q) {
  HOC_CHECK(q, HOC_ERR_ARGUMENT, "NULL output");
  memset(q, 0, sizeof *q);
  HOC_CHECK(degree >= 0 && degree <= 60, HOC_ERR_ARGUMENT, "quadrature degree %d out of range",
            degree);
  int na = (degree + 2) / 2, nb = (degree + 3) / 2;
  double xa[64], wa[64], xb[64], wb[64];
  HOC_TRY(hoc_gauss_legendre01(na, xa, wa));
  HOC_TRY(hoc_gauss_legendre01(nb, xb, wb));
  q->degree = degree;
  q->n = na * nb;
  q->rs = hoc_calloc(2 * (size_t)q->n, sizeof *q->rs);
  q->w = hoc_calloc((size_t)q->n, sizeof *q->w);
  if (!q->rs || !q->w) {
    hoc_quadrature_free(q);
    return HOC_ERROR(HOC_ERR_MEMORY, "out of memory");
  }
  int k = 0;
  for (int j = 0; j < nb; ++j)
    for (int i = 0; i < na; ++i, ++k) {
      q->rs[2 * k] = xa[i] * (1 - xb[j]);
      q->rs[2 * k + 1] = xb[j];
      q->w[k] = wa[i] * wb[j] * (1 - xb[j]);
    }
  return HOC_OK;
}

void hoc_quadrature_free(hoc_quadrature *q) {
  if (!q) return;
  free(q->rs);
  free(q->w);
  q->rs = q->w = NULL;
  q->n = 0;
}

/* Orthonormal basis on the triangle --------------------------------------- */

/* Value and gradient (in our (r,s) on the unit triangle) of the
 * orthonormal mode (i, j) at a point. */
static void pkdo_mode(int i, int j, double r, double s, double *v, double *dr, double *ds) {
  /* biunit coordinates and the collapsed square */
  double R = 2 * r - 1, S = 2 * s - 1;
  double a = S < 1 - 1e-14 ? 2 * (1 + R) / (1 - S) - 1 : -1, b = S;
  double fa = jacobi(a, 0, 0, i), gb = jacobi(b, 2 * i + 1, 0, j);
  double c = pow(0.5 * (1 - b), i);
  double norm = 2 * sqrt(2.0); /* a scale per mode: the Lagrange basis does not depend on it */
  if (v) *v = norm * fa * gb * c;
  if (dr || ds) {
    double dfa = jacobi_deriv(a, 0, 0, i), dgb = jacobi_deriv(b, 2 * i + 1, 0, j);
    double cm1 = i > 0 ? pow(0.5 * (1 - b), i - 1) : 1;
    double dR = dfa * gb * (i > 0 ? cm1 : 1);
    double dS = dfa * gb * 0.5 * (1 + a) * (i > 0 ? cm1 : 1);
    double tmp = dgb * c;
    if (i > 0) tmp -= 0.5 * i * gb * cm1;
    dS += fa * tmp;
    /* derivatives of fa(a) gb(b) c(b) in the biunit (R, S); d/dr = 2 d/dR */
    if (dr) *dr = 2 * norm * dR;
    if (ds) *ds = 2 * norm * dS;
  }
}

/* All modes at one point: psi[np], and optionally gradients. */
static void pkdo_all(int p, double r, double s, double *psi, double *dpr, double *dps) {
  int k = 0;
  for (int i = 0; i <= p; ++i)
    for (int j = 0; i + j <= p; ++j, ++k)
      pkdo_mode(i, j, r, s, psi ? psi + k : NULL, dpr ? dpr + k : NULL, dps ? dps + k : NULL);
}

/* LU factorisation with partial pivoting of A[n][n] (in place); piv[n].
 * Returns the smallest |pivot| relative to the largest entry. */
static double lu_factor(int n, double *A, int *piv) {
  double amax = 0, pmin = INFINITY;
  for (int i = 0; i < n * n; ++i) amax = fmax(amax, fabs(A[i]));
  for (int c = 0; c < n; ++c) {
    int r = c;
    for (int i = c + 1; i < n; ++i)
      if (fabs(A[i * n + c]) > fabs(A[r * n + c])) r = i;
    piv[c] = r;
    if (r != c)
      for (int j = 0; j < n; ++j) {
        double t = A[c * n + j];
        A[c * n + j] = A[r * n + j];
        A[r * n + j] = t;
      }
    double d = A[c * n + c];
    pmin = fmin(pmin, fabs(d));
    if (d == 0) return 0;
    for (int i = c + 1; i < n; ++i) {
      double f = A[i * n + c] / d;
      A[i * n + c] = f;
      for (int j = c + 1; j < n; ++j) A[i * n + j] -= f * A[c * n + j];
    }
  }
  return amax > 0 ? pmin / amax : 0;
}

/* Solve A x = b with the factors (b overwritten by x). */
static void lu_solve(int n, const double *LU, const int *piv, double *b) {
  for (int c = 0; c < n; ++c) {
    double t = b[c];
    b[c] = b[piv[c]];
    b[piv[c]] = t;
  }
  for (int i = 0; i < n; ++i)
    for (int j = 0; j < i; ++j) b[i] -= LU[i * n + j] * b[j];
  for (int i = n - 1; i >= 0; --i) {
    for (int j = i + 1; j < n; ++j) b[i] -= LU[i * n + j] * b[j];
    b[i] /= LU[i * n + i];
  }
}

/* Lagrange basis ----------------------------------------------------------- */

struct hoc_lagrange {
  int p, np;
  double *coef; /* [np][np]: N_i = sum_m coef[m][i] psi_m (the inverse Vandermonde) */
};

hoc_status hoc_lagrange_create(int p, const double *nodes, hoc_lagrange **basis) {
  HOC_CHECK(basis, HOC_ERR_ARGUMENT, "NULL output");
  *basis = NULL;
  HOC_CHECK(p >= 1 && p <= HOC_MAX_ORDER, HOC_ERR_ARGUMENT, "order %d out of range", p);
  HOC_CHECK(nodes, HOC_ERR_ARGUMENT, "no nodes given");
  int np = hoc_tri_num_nodes(p);
  double *V = hoc_calloc((size_t)np * (size_t)np, sizeof *V);
  int *piv = hoc_calloc((size_t)np, sizeof *piv);
  hoc_lagrange *b = hoc_calloc(1, sizeof *b);
  double *coef = hoc_calloc((size_t)np * (size_t)np, sizeof *coef);
  hoc_status status = HOC_OK;
  if (!V || !piv || !b || !coef) {
    status = HOC_ERROR(HOC_ERR_MEMORY, "out of memory");
    goto fail;
  }
  /* V[k][m] = psi_m(node k) */
  for (int k = 0; k < np; ++k) {
    HOC_CHECK(isfinite(nodes[2 * k]) && isfinite(nodes[2 * k + 1]), HOC_ERR_ARGUMENT,
              "non-finite node coordinate");
    pkdo_all(p, nodes[2 * k], nodes[2 * k + 1], V + (size_t)k * np, NULL, NULL);
  }
  if (!(lu_factor(np, V, piv) > 1e-13)) {
    status = HOC_ERROR(HOC_ERR_ARGUMENT, "the %d nodes are not unisolvent for order %d", np, p);
    goto fail;
  }
  /* coef = V^{-1}: column i solves V c = e_i; N_i(x) = sum_m c_m psi_m(x)
   * with N_i(node k) = sum_m V[k][m] c_m = delta_ki */
  double *col = hoc_calloc((size_t)np, sizeof *col);
  if (!col) {
    status = HOC_ERROR(HOC_ERR_MEMORY, "out of memory");
    goto fail;
  }
  for (int i = 0; i < np; ++i) {
    memset(col, 0, (size_t)np * sizeof *col);
    col[i] = 1;
    lu_solve(np, V, piv, col);
    for (int m = 0; m < np; ++m) coef[(size_t)m * np + i] = col[m];
  }
  free(col);
  b->p = p;
  b->np = np;
  b->coef = coef;
  free(V);
  free(piv);
  *basis = b;
  return HOC_OK;
fail:
  free(V);
  free(piv);
  free(b);
  free(coef);
  return status;
}

void hoc_lagrange_destroy(hoc_lagrange **basis) {
  if (!basis || !*basis) return;
  free((*basis)->coef);
  free(*basis);
  *basis = NULL;
}

int hoc_lagrange_num_nodes(const hoc_lagrange *basis) { return basis ? basis->np : 0; }

hoc_status hoc_lagrange_eval(const hoc_lagrange *basis, int n, const double *rs, double *N,
                             double *dN) {
  HOC_CHECK(basis && (rs || n == 0) && n >= 0, HOC_ERR_ARGUMENT, "invalid arguments");
  int np = basis->np;
  double *psi = hoc_calloc(3 * (size_t)np, sizeof *psi);
  HOC_CHECK(psi, HOC_ERR_MEMORY, "out of memory");
  double *pr = psi + np, *ps = psi + 2 * np;
  for (int k = 0; k < n; ++k) {
    pkdo_all(basis->p, rs[2 * k], rs[2 * k + 1], psi, dN ? pr : NULL, dN ? ps : NULL);
    for (int i = 0; i < np; ++i) {
      double v = 0, dr = 0, ds = 0;
      for (int m = 0; m < np; ++m) {
        double c = basis->coef[(size_t)m * np + i];
        v += c * psi[m];
        if (dN) {
          dr += c * pr[m];
          ds += c * ps[m];
        }
      }
      if (N) N[(size_t)k * np + i] = v;
      if (dN) {
        dN[2 * ((size_t)k * np + i)] = dr;
        dN[2 * ((size_t)k * np + i) + 1] = ds;
      }
    }
  }
  free(psi);
  return HOC_OK;
}

void hoc_lagrange_1d(int p, const double *s, double x, double *L, double *dL) {
  for (int k = 0; k <= p; ++k) {
    double v = 1;
    for (int m = 0; m <= p; ++m)
      if (m != k) v *= (x - s[m]) / (s[k] - s[m]);
    L[k] = v;
    if (dL) {
      double d = 0;
      for (int j = 0; j <= p; ++j) {
        if (j == k) continue;
        double t = 1 / (s[k] - s[j]);
        for (int m = 0; m <= p; ++m)
          if (m != k && m != j) t *= (x - s[m]) / (s[k] - s[m]);
        d += t;
      }
      dL[k] = d;
    }
  }
}

/* Node sets ---------------------------------------------------------------- */

/* Warburton's 1D warp: the displacement that takes equispaced points of
 * [-1,1] to GLL points, interpolated at x, divided by the edge blend
 * 1 - x^2 (kept finite at the ends). */
static double warp_factor(int p, const double *gll, double x) {
  double w = 0;
  for (int k = 0; k <= p; ++k) {
    double xk = -1 + 2.0 * k / p, l = 1;
    for (int m = 0; m <= p; ++m) {
      double xm = -1 + 2.0 * m / p;
      if (m != k) l *= (x - xm) / (xk - xm);
    }
    w += l * (gll[k] - xk);
  }
  if (fabs(x) < 1 - 1e-10) w /= 1 - x * x;
  else w = 0;
  return w;
}

/* Warp & blend nodes in our ordering: r, s of each lattice point moved. */
static void warp_blend_nodes(int p, const int *ij, double *rs) {
  static const double alpha_opt[15] = {0.0000, 0.0000, 1.4152, 0.1001, 0.2751,
                                       0.9808, 1.0999, 1.2832, 1.3648, 1.4773,
                                       1.4959, 1.5743, 1.5770, 1.6223, 1.6258};
  double alpha = p <= 15 ? alpha_opt[p - 1] : 5.0 / 3.0;
  double gll[HOC_MAX_ORDER + 1];
  gll_points(p, gll);
  int np = hoc_tri_num_nodes(p);
  /* equilateral triangle A(-1,-1/sqrt3) = v0, B(1,-1/sqrt3) = v1, C(0,2/sqrt3) = v2 */
  const double sq3 = sqrt(3.0);
  for (int k = 0; k < np; ++k) {
    double LB = (double)ij[2 * k] / p, LC = (double)ij[2 * k + 1] / p, LA = 1 - LB - LC;
    /* Warburton's L1, L2, L3 are the barycentrics of C, A, B */
    double L1 = LC, L2 = LA, L3 = LB;
    double x = -L2 + L3, y = (-L2 - L3 + 2 * L1) / sq3;
    double b1 = 4 * L2 * L3, b2 = 4 * L1 * L3, b3 = 4 * L1 * L2;
    double w1 = b1 * warp_factor(p, gll, L3 - L2) * (1 + (alpha * L1) * (alpha * L1));
    double w2 = b2 * warp_factor(p, gll, L1 - L3) * (1 + (alpha * L2) * (alpha * L2));
    double w3 = b3 * warp_factor(p, gll, L2 - L1) * (1 + (alpha * L3) * (alpha * L3));
    x += w1 + cos(2 * PI / 3) * w2 + cos(4 * PI / 3) * w3;
    y += sin(2 * PI / 3) * w2 + sin(4 * PI / 3) * w3;
    /* back to barycentrics: C has y = 2/sqrt3, A and B y = -1/sqrt3 */
    double lc = (y + 1 / sq3) * sq3 / 3;
    double lb = 0.5 * (x + 1 - lc);
    rs[2 * k] = lb;
    rs[2 * k + 1] = lc;
  }
}

/* Index of the node at lattice point (i, j) in gmsh order. */
static int lattice_index(int p, const int *ij, int i, int j) {
  int np = hoc_tri_num_nodes(p);
  for (int k = 0; k < np; ++k)
    if (ij[2 * k] == i && ij[2 * k + 1] == j) return k;
  return -1;
}

/* log|det V| of the nodes and its gradient with respect to the interior
 * nodes' coordinates (grad[np][2], zero elsewhere). */
static double log_det(int p, const double *rs, double *grad, double *V, double *Vd, int *piv,
                      double *col) {
  int np = hoc_tri_num_nodes(p);
  double *dr = Vd, *ds = Vd + (size_t)np * np;
  for (int k = 0; k < np; ++k)
    pkdo_all(p, rs[2 * k], rs[2 * k + 1], V + (size_t)k * np, dr + (size_t)k * np,
             ds + (size_t)k * np);
  double rel = lu_factor(np, V, piv);
  if (!(rel > 0)) return -INFINITY;
  double ld = 0;
  for (int k = 0; k < np; ++k) ld += log(fabs(V[(size_t)k * np + k]));
  if (grad) {
    /* d log det / d x_k = sum_m (V^{-1})_{mk} d psi_m(x_k) / dx: column k of
     * V^{-1} is the solution of V c = e_k */
    for (int k = 0; k < np; ++k) {
      memset(col, 0, (size_t)np * sizeof *col);
      col[k] = 1;
      lu_solve(np, V, piv, col);
      double gr = 0, gs = 0;
      for (int m = 0; m < np; ++m) {
        gr += col[m] * dr[(size_t)k * np + m];
        gs += col[m] * ds[(size_t)k * np + m];
      }
      grad[2 * k] = gr;
      grad[2 * k + 1] = gs;
    }
  }
  return ld;
}

/* Fekete points: maximise log|det V| over the interior nodes (vertices and
 * GLL edge nodes fixed), from warp & blend, by gradient ascent with an
 * adaptive step, then symmetrised over the triangle's six symmetries. */
static hoc_status fekete_nodes(int p, const int *ij, double *rs) {
  int np = hoc_tri_num_nodes(p);
  warp_blend_nodes(p, ij, rs);
  if (p < 3) return HOC_OK;
  double *V = hoc_calloc((size_t)np * np, sizeof *V), *Vd = hoc_calloc(2 * (size_t)np * np, sizeof *Vd);
  double *g = hoc_calloc(2 * (size_t)np, sizeof *g), *trial = hoc_calloc(2 * (size_t)np, sizeof *trial);
  double *col = hoc_calloc((size_t)np, sizeof *col), *gt = hoc_calloc(2 * (size_t)np, sizeof *gt);
  double *sym = hoc_calloc(2 * (size_t)np, sizeof *sym);
  int *piv = hoc_calloc((size_t)np, sizeof *piv);
  hoc_status status = HOC_OK;
  if (!V || !Vd || !g || !trial || !col || !gt || !sym || !piv) {
    status = HOC_ERROR(HOC_ERR_MEMORY, "out of memory");
    goto done;
  }
  int first_interior = 3 * p, nv = 2 * (np - first_interior);
  /* BFGS on the interior coordinates (maximising f = log|det V|), with an
   * inverse-Hessian approximation B[nv][nv] and a backtracking line search */
  double *B = hoc_calloc((size_t)nv * nv, sizeof *B), *dir = hoc_calloc((size_t)nv, sizeof *dir);
  double *sv = hoc_calloc((size_t)nv, sizeof *sv), *yv = hoc_calloc((size_t)nv, sizeof *yv);
  double *By = hoc_calloc((size_t)nv, sizeof *By);
  if (!B || !dir || !sv || !yv || !By) {
    free(B);
    free(dir);
    free(sv);
    free(yv);
    free(By);
    status = HOC_ERROR(HOC_ERR_MEMORY, "out of memory");
    goto done;
  }
  for (int i = 0; i < nv; ++i) B[(size_t)i * nv + i] = 1e-3;
  double f = log_det(p, rs, g, V, Vd, piv, col);
  const double *gi = g + 2 * first_interior;
  for (int it = 0; it < 2000; ++it) {
    double gn = 0;
    for (int i = 0; i < nv; ++i) gn = fmax(gn, fabs(gi[i]));
    if (gn < 1e-12) break;
    /* ascent direction dir = B g */
    double slope = 0;
    for (int i = 0; i < nv; ++i) {
      double d = 0;
      for (int j = 0; j < nv; ++j) d += B[(size_t)i * nv + j] * gi[j];
      dir[i] = d;
      slope += d * gi[i];
    }
    if (!(slope > 0)) { /* lost positive definiteness: restart */
      memset(B, 0, (size_t)nv * nv * sizeof *B);
      for (int i = 0; i < nv; ++i) B[(size_t)i * nv + i] = 1e-3, dir[i] = 1e-3 * gi[i];
      slope = 0;
      for (int i = 0; i < nv; ++i) slope += dir[i] * gi[i];
    }
    double t = 1, ft = -INFINITY;
    for (int ls = 0; ls < 40; ++ls, t *= 0.5) {
      memcpy(trial, rs, 2 * (size_t)np * sizeof *trial);
      for (int i = 0; i < nv; ++i) trial[2 * first_interior + i] += t * dir[i];
      ft = log_det(p, trial, gt, V, Vd, piv, col);
      if (ft >= f + 1e-4 * t * slope) break;
    }
    if (!(ft > f)) break;
    const double *gti = gt + 2 * first_interior;
    double sy = 0;
    for (int i = 0; i < nv; ++i) {
      sv[i] = t * dir[i];
      yv[i] = -(gti[i] - gi[i]); /* of -f, whose Hessian is positive near the maximum */
      sy += sv[i] * yv[i];
    }
    double gain = ft - f;
    memcpy(rs, trial, 2 * (size_t)np * sizeof *rs);
    memcpy(g, gt, 2 * (size_t)np * sizeof *g);
    f = ft;
    if (sy > 1e-300) {
      /* B <- (I - rho s y^T) B (I - rho y s^T) + rho s s^T */
      double rho = 1 / sy, yBy = 0;
      for (int i = 0; i < nv; ++i) {
        double d = 0;
        for (int j = 0; j < nv; ++j) d += B[(size_t)i * nv + j] * yv[j];
        By[i] = d;
        yBy += yv[i] * d;
      }
      for (int i = 0; i < nv; ++i)
        for (int j = 0; j < nv; ++j)
          B[(size_t)i * nv + j] += -rho * (By[i] * sv[j] + sv[i] * By[j]) +
                                   (rho * rho * yBy + rho) * sv[i] * sv[j];
    }
    if (gain < 1e-15 * fabs(f)) break;
  }
  free(B);
  free(dir);
  free(sv);
  free(yv);
  free(By);
  /* symmetrise: average each node over the images of the six vertex
   * permutations (lattice (i, j, l = p - i - j) permuted) */
  memset(sym, 0, 2 * (size_t)np * sizeof *sym);
  for (int k = 0; k < np; ++k) {
    int b[3] = {ij[2 * k], ij[2 * k + 1], p - ij[2 * k] - ij[2 * k + 1]};
    double lam[3] = {rs[2 * k], rs[2 * k + 1], 1 - rs[2 * k] - rs[2 * k + 1]};
    static const int perm[6][3] = {{0, 1, 2}, {1, 2, 0}, {2, 0, 1}, {1, 0, 2}, {0, 2, 1}, {2, 1, 0}};
    for (int q = 0; q < 6; ++q) {
      /* the permutation sends barycentric slot c to slot perm[q][c] */
      int bi[3];
      double li[3];
      for (int c = 0; c < 3; ++c) {
        bi[perm[q][c]] = b[c];
        li[perm[q][c]] = lam[c];
      }
      int k2 = lattice_index(p, ij, bi[0], bi[1]);
      if (k2 < 0) continue;
      sym[2 * k2] += li[0] / 6;
      sym[2 * k2 + 1] += li[1] / 6;
    }
  }
  for (int k = first_interior; k < np; ++k) {
    rs[2 * k] = sym[2 * k];
    rs[2 * k + 1] = sym[2 * k + 1];
  }
done:
  free(V);
  free(Vd);
  free(g);
  free(trial);
  free(col);
  free(gt);
  free(sym);
  free(piv);
  return status;
}

static pthread_mutex_t fekete_lock = PTHREAD_MUTEX_INITIALIZER;
static double *fekete_cache[HOC_MAX_ORDER + 1];

hoc_status hoc_tri_nodes(int p, hoc_nodeset set, double *rs) {
  HOC_CHECK(p >= 1 && p <= HOC_MAX_ORDER, HOC_ERR_ARGUMENT, "order %d out of range", p);
  HOC_CHECK(rs, HOC_ERR_ARGUMENT, "NULL output");
  int np = hoc_tri_num_nodes(p);
  int ij[2 * ((HOC_MAX_ORDER + 1) * (HOC_MAX_ORDER + 2) / 2)];
  HOC_TRY(hoc_tri_lattice(p, ij));
  switch (set) {
  case HOC_NODES_EQUISPACED:
    for (int k = 0; k < 2 * np; ++k) rs[k] = (double)ij[k] / p;
    return HOC_OK;
  case HOC_NODES_WARP_BLEND:
    warp_blend_nodes(p, ij, rs);
    break;
  case HOC_NODES_FEKETE: {
    pthread_mutex_lock(&fekete_lock);
    hoc_status st = HOC_OK;
    if (!fekete_cache[p]) {
      double *c = hoc_calloc(2 * (size_t)np, sizeof *c);
      if (!c) st = HOC_ERROR(HOC_ERR_MEMORY, "out of memory");
      else st = fekete_nodes(p, ij, c);
      if (st == HOC_OK) fekete_cache[p] = c;
      else free(c);
    }
    if (st == HOC_OK) memcpy(rs, fekete_cache[p], 2 * (size_t)np * sizeof *rs);
    pthread_mutex_unlock(&fekete_lock);
    HOC_TRY(st);
    break;
  }
  default: return HOC_ERROR(HOC_ERR_ARGUMENT, "unknown node set %d", (int)set);
  }
  /* vertices and edge nodes exactly where hoc_edge_nodes puts them */
  double s[HOC_MAX_ORDER + 1];
  HOC_TRY(hoc_edge_nodes(p, set, s));
  rs[0] = rs[1] = rs[3] = rs[4] = 0;
  rs[2] = 1;
  rs[5] = 1;
  for (int e = 0; e < 3; ++e)
    for (int j = 1; j < p; ++j) {
      int k = 3 + e * (p - 1) + (j - 1);
      double t = s[j];
      if (e == 0) rs[2 * k] = t, rs[2 * k + 1] = 0;
      else if (e == 1) rs[2 * k] = 1 - t, rs[2 * k + 1] = t;
      else rs[2 * k] = 0, rs[2 * k + 1] = 1 - t;
    }
  return HOC_OK;
}
