/* Body of the measuring kernel for one vector width, included by
 * distortion.c once per width (a template in C): KW lanes of type KV (mask
 * type KL), function KNAME with attributes KATTR. It adds, for every point
 * of the element, w eta^2 to sum[], the smallest sigma / |D phi|^2 to
 * smin[] and 1 to bad[] where sigma <= 0 (or NaN), lane by lane (HOC_QB
 * lanes; blocks of HOC_QB points are taken KW at a time).
 * SPDX-License-Identifier: GPL-2.0-or-later */
/* Declares a10..a22 (the columns of D phi) and n0..n2 (the interpolated
 * normal) at KW points from the tables' columns bx, by, bn (node i at
 * i HOC_QB) and the element's x, n. */
#ifndef KFRAME_SUMS
#define KFRAME_SUMS(bx, by, bn)                                                                    \
  KV a10 = KSPLAT(0), a11 = a10, a12 = a10, a20 = a10, a21 = a10, a22 = a10;                       \
  KV n0 = a10, n1 = a10, n2 = a10;                                                                 \
  for (int i = 0; i < np; ++i) {                                                                   \
    KV gx = KLOAD((bx) + i * HOC_QB), gy = KLOAD((by) + i * HOC_QB),                               \
       gn = KLOAD((bn) + i * HOC_QB);                                                              \
    KV x0 = KSPLAT(x[3 * i]), x1 = KSPLAT(x[3 * i + 1]), x2 = KSPLAT(x[3 * i + 2]);                \
    a10 += gx * x0;                                                                                \
    a11 += gx * x1;                                                                                \
    a12 += gx * x2;                                                                                \
    a20 += gy * x0;                                                                                \
    a21 += gy * x1;                                                                                \
    a22 += gy * x2;                                                                                \
    n0 += gn * KSPLAT(n[3 * i]);                                                                   \
    n1 += gn * KSPLAT(n[3 * i + 1]);                                                               \
    n2 += gn * KSPLAT(n[3 * i + 2]);                                                               \
  }
#endif

KATTR static void KNAME(const hoc_quality_tables *t, int oddy, const double *x, const double *n,
                        double *sum_out, double *smin_out, double *bad_out) {
  const int np = t->np;
  for (int h = 0; h < HOC_QB; h += KW) {
    KV sum = KSPLAT(0), smin = KSPLAT(INFINITY), bad = KSPLAT(0);
    for (int b = 0; b < t->n_check_blocks; ++b) {
      size_t off = (size_t)b * (size_t)np * HOC_QB + (size_t)h;
      const double *bx = t->Bx + off, *by = t->By + off, *bn = t->Bn + off;
      KFRAME_SUMS(bx, by, bn);
      KV c0 = a11 * a22 - a12 * a21, c1 = a12 * a20 - a10 * a22, c2 = a10 * a21 - a11 * a20;
      KV cc = c0 * c0 + c1 * c1 + c2 * c2;
      double l2[KW], cl[KW];
      memcpy(l2, &cc, sizeof l2);
      for (int l = 0; l < KW; ++l)
        cl[l] = sqrt(l2[l]);
      KV pos = KMASK01(c0 * n0 + c1 * n1 + c2 * n2 > KSPLAT(0));
      KV sig = KLOAD(cl) * (2 * pos - 1);
      KV g11 = a10 * a10 + a11 * a11 + a12 * a12, g22 = a20 * a20 + a21 * a21 + a22 * a22;
      KV F = g11 + g22, rel = sig / F;
      bad += 1 - KMASK01(rel > KSPLAT(0));
      KL lower = rel < smin;
      smin = (KV)(((KL)rel & lower) | ((KL)smin & ~lower));
      KV e;
      if (oddy) {
        KV g12 = a10 * a20 + a11 * a21 + a12 * a22;
        e = KSPLAT(1.5) * (g11 * g11 + 2 * g12 * g12 + g22 * g22 - F * F / 3) * (1 / (sig * sig));
      } else {
        e = F / (2 * sig);
      }
      /* only where the weight is not 0: elsewhere eta may be infinite */
      KV w = KLOAD(t->Bw + (size_t)b * HOC_QB + (size_t)h);
      sum += (KV)((KL)(w * e * e) & (w != KSPLAT(0)));
    }
    memcpy(sum_out + h, &sum, sizeof sum);
    memcpy(smin_out + h, &smin, sizeof smin);
    memcpy(bad_out + h, &bad, sizeof bad);
  }
}

/* The columns of D phi and the interpolated normal at the points of blocks
 * b0..b1-1: out[c][k] for c = a1 (0..2), a2 (3..5), n (6..8) and k the point
 * counted from block b0, with stride = (b1 - b0) HOC_QB. */
KATTR static void KFRAMES(const hoc_quality_tables *t, int b0, int b1, const double *x,
                          const double *n, double *out) {
  const int np = t->np;
  const size_t stride = (size_t)(b1 - b0) * HOC_QB;
  for (int b = b0; b < b1; ++b)
    for (int h = 0; h < HOC_QB; h += KW) {
      size_t off = (size_t)b * (size_t)np * HOC_QB + (size_t)h;
      const double *bx = t->Bx + off, *by = t->By + off, *bn = t->Bn + off;
      KFRAME_SUMS(bx, by, bn);
      size_t k = (size_t)(b - b0) * HOC_QB + (size_t)h;
      memcpy(out + 0 * stride + k, &a10, sizeof a10);
      memcpy(out + 1 * stride + k, &a11, sizeof a11);
      memcpy(out + 2 * stride + k, &a12, sizeof a12);
      memcpy(out + 3 * stride + k, &a20, sizeof a20);
      memcpy(out + 4 * stride + k, &a21, sizeof a21);
      memcpy(out + 5 * stride + k, &a22, sizeof a22);
      memcpy(out + 6 * stride + k, &n0, sizeof n0);
      memcpy(out + 7 * stride + k, &n1, sizeof n1);
      memcpy(out + 8 * stride + k, &n2, sizeof n2);
    }
}
