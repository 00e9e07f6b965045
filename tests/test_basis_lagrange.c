/* Lagrange bases on every node set and order: Kronecker property, partition
 * of unity, exact reproduction of polynomials of the order (values and
 * derivatives), derivatives against finite differences; non-unisolvent node
 * sets rejected.
 * SPDX-License-Identifier: GPL-2.0-or-later */
#include "basis/basis.h"
#include "test_util.h"

#include <string.h>

static unsigned long long seed = 0x9E3779B97F4A7C15ULL;
static double rnd(void) {
  seed ^= seed << 13;
  seed ^= seed >> 7;
  seed ^= seed << 17;
  return (double)(seed >> 11) / 9007199254740992.0;
}

int main(void) {
  for (int set = 0; set < 3; ++set)
    for (int p = 1; p <= HOC_MAX_ORDER; ++p) {
      int np = hoc_tri_num_nodes(p);
      double *rs = calloc(2 * (size_t)np, sizeof *rs);
      CHECK_OK(hoc_tri_nodes(p, (hoc_nodeset)set, rs));
      hoc_lagrange *b;
      CHECK_OK(hoc_lagrange_create(p, rs, &b));
      if (!b) continue;
      CHECK(hoc_lagrange_num_nodes(b) == np);
      /* Kronecker at the nodes */
      double *N = calloc((size_t)np * np, sizeof *N), *dN = calloc(2 * (size_t)np * np, sizeof *dN);
      CHECK_OK(hoc_lagrange_eval(b, np, rs, N, dN));
      double kron = 0;
      for (int k = 0; k < np; ++k)
        for (int i = 0; i < np; ++i) kron = fmax(kron, fabs(N[(size_t)k * np + i] - (i == k)));
      CHECK(kron < 1e-9);
      /* random points: unity, polynomial reproduction, FD derivatives */
      enum { M = 20 };
      double pts[2 * M];
      for (int k = 0; k < M; ++k) {
        double r = rnd(), s = rnd();
        if (r + s > 1) r = 1 - r, s = 1 - s;
        pts[2 * k] = r;
        pts[2 * k + 1] = s;
      }
      double *Np = calloc((size_t)M * np, sizeof *Np), *dNp = calloc(2 * (size_t)M * np, sizeof *dNp);
      CHECK_OK(hoc_lagrange_eval(b, M, pts, Np, dNp));
      double unity = 0, dunity = 0, poly = 0, dpoly = 0, fd = 0, dscale = 0;
      for (int k = 0; k < M; ++k) {
        double su = 0, sr = 0, ss = 0;
        for (int i = 0; i < np; ++i) {
          su += Np[(size_t)k * np + i];
          sr += dNp[2 * ((size_t)k * np + i)];
          ss += dNp[2 * ((size_t)k * np + i) + 1];
          dscale = fmax(dscale, fabs(dNp[2 * ((size_t)k * np + i)]));
        }
        unity = fmax(unity, fabs(su - 1));
        dunity = fmax(dunity, fmax(fabs(sr), fabs(ss)));
        /* f = r^a s^c with a + c = p (the hardest monomials) and a lower one */
        for (int a = 0; a <= p; a += (p > 4 ? 2 : 1)) {
          int c = p - a;
          double r = pts[2 * k], s = pts[2 * k + 1], v = 0, vr = 0, vs = 0;
          for (int i = 0; i < np; ++i) {
            double fi = pow(rs[2 * i], a) * pow(rs[2 * i + 1], c);
            v += fi * Np[(size_t)k * np + i];
            vr += fi * dNp[2 * ((size_t)k * np + i)];
            vs += fi * dNp[2 * ((size_t)k * np + i) + 1];
          }
          double ex = pow(r, a) * pow(s, c);
          double exr = a ? a * pow(r, a - 1) * pow(s, c) : 0, exs = c ? c * pow(r, a) * pow(s, c - 1) : 0;
          poly = fmax(poly, fabs(v - ex));
          dpoly = fmax(dpoly, fmax(fabs(vr - exr), fabs(vs - exs)));
        }
        /* central differences of the basis */
        double h = 1e-6, q2[4] = {pts[2 * k] + h, pts[2 * k + 1], pts[2 * k] - h, pts[2 * k + 1]};
        double Nq[2 * 136];
        CHECK_OK(hoc_lagrange_eval(b, 2, q2, Nq, NULL));
        for (int i = 0; i < np; ++i)
          fd = fmax(fd, fabs((Nq[i] - Nq[np + i]) / (2 * h) - dNp[2 * ((size_t)k * np + i)]));
      }
      /* tolerances grow with the conditioning of high orders */
      double tol = 1e-12 * pow(4.0, p / 2.0) * (set == 0 ? pow(3.0, p / 2.0) : 1);
      CHECK(unity < tol);
      CHECK(poly < tol);
      CHECK(dunity < 100 * tol);
      CHECK(dpoly < 100 * tol);
      CHECK(fd < 1e-6 * (1 + dscale));
      if (!(unity < tol) || !(poly < tol) || !(dpoly < 100 * tol) || !(dunity < 100 * tol))
        fprintf(stderr, "  set %d p=%d: unity %.2g d %.2g poly %.2g dpoly %.2g (tol %.2g)\n", set, p,
                unity, dunity, poly, dpoly, tol);
      free(N);
      free(dN);
      free(Np);
      free(dNp);
      hoc_lagrange_destroy(&b);
      CHECK(b == NULL);
      free(rs);
    }
  /* non-unisolvent nodes: all on a line, or a node repeated */
  double line[2 * 6], dup[2 * 6];
  for (int k = 0; k < 6; ++k) line[2 * k] = 0.1 * k, line[2 * k + 1] = 0.1 * k;
  CHECK_OK(hoc_tri_nodes(2, HOC_NODES_EQUISPACED, dup));
  dup[2 * 5] = dup[2 * 4], dup[2 * 5 + 1] = dup[2 * 4 + 1];
  hoc_lagrange *b = (hoc_lagrange *)1;
  CHECK_STATUS(hoc_lagrange_create(2, line, &b), HOC_ERR_ARGUMENT);
  CHECK(b == NULL);
  CHECK_STATUS(hoc_lagrange_create(2, dup, &b), HOC_ERR_ARGUMENT);
  CHECK_STATUS(hoc_lagrange_create(0, dup, &b), HOC_ERR_ARGUMENT);
  /* 1D Lagrange: Kronecker, unity, derivative sums to zero, reproduces x^p */
  for (int p = 1; p <= 15; ++p) {
    double s[16], L[16], dL[16];
    CHECK_OK(hoc_edge_nodes(p, HOC_NODES_FEKETE, s));
    hoc_lagrange_1d(p, s, s[p / 2], L, dL);
    double k0 = 0;
    for (int k = 0; k <= p; ++k) k0 = fmax(k0, fabs(L[k] - (k == p / 2)));
    CHECK(k0 < 1e-13);
    hoc_lagrange_1d(p, s, 0.3141, L, dL);
    double u = 0, du = 0, v = 0, dv = 0;
    for (int k = 0; k <= p; ++k) {
      u += L[k];
      du += dL[k];
      v += L[k] * pow(s[k], p);
      dv += dL[k] * pow(s[k], p);
    }
    CHECK_NEAR(u, 1, 1e-12);
    CHECK_NEAR(du, 0, 1e-9);
    CHECK_NEAR(v, pow(0.3141, p), 1e-12);
    CHECK_NEAR(dv, p * pow(0.3141, p - 1), 1e-9);
  }
  return test_report();
}
