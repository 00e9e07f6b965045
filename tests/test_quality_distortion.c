/* The distortion measures against closed forms: the ideal element, linear
 * triangles, invariances, Definition 2 = Definition 1 on a plane, and the
 * analytic derivatives against finite differences.
 * SPDX-License-Identifier: GPL-2.0-or-later */
#include "basis/basis.h"
#include "quality/quality.h"
#include "test_util.h"

#include <stdio.h>
#include <string.h>

static const double SQRT3 = 1.7320508075688772935;

static unsigned long long rng_state = 88172645463325252ULL;
static double rnd(void) { /* xorshift64 in [0, 1) */
  rng_state ^= rng_state << 13;
  rng_state ^= rng_state >> 7;
  rng_state ^= rng_state << 17;
  return (double)(rng_state >> 11) / 9007199254740992.0;
}

/* Node positions of the element x = A * (ideal coordinates) + b in 3D, with
 * ideal coordinates W rs. A: 3x2 row-major. */
static void affine_element(const hoc_quality_tables *t, const double *A, const double *b, double *x) {
  for (int i = 0; i < t->np; ++i) {
    double r = t->rs[2 * i], s = t->rs[2 * i + 1];
    double X = r + 0.5 * s, Y = 0.5 * SQRT3 * s; /* W rs */
    for (int k = 0; k < 3; ++k) x[3 * i + k] = A[2 * k] * X + A[2 * k + 1] * Y + (b ? b[k] : 0);
  }
}

static void constant_normals(int np, const double *n, double *out) {
  for (int i = 0; i < np; ++i) memcpy(out + 3 * i, n, 3 * sizeof *n);
}

static void random_rotation(double R[9]) {
  /* Gram-Schmidt on random vectors */
  double a[3] = {rnd() - 0.5, rnd() - 0.5, rnd() - 0.5}, b[3] = {rnd() - 0.5, rnd() - 0.5, rnd() - 0.5};
  double la = sqrt(a[0] * a[0] + a[1] * a[1] + a[2] * a[2]);
  for (int k = 0; k < 3; ++k) a[k] /= la;
  double d = a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
  for (int k = 0; k < 3; ++k) b[k] -= d * a[k];
  double lb = sqrt(b[0] * b[0] + b[1] * b[1] + b[2] * b[2]);
  for (int k = 0; k < 3; ++k) b[k] /= lb;
  double c[3] = {a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]};
  for (int k = 0; k < 3; ++k) R[3 * k] = a[k], R[3 * k + 1] = b[k], R[3 * k + 2] = c[k];
}

static void apply(const double R[9], double s, const double *in, double *out) {
  double y[3];
  for (int k = 0; k < 3; ++k) y[k] = s * (R[3 * k] * in[0] + R[3 * k + 1] * in[1] + R[3 * k + 2] * in[2]);
  memcpy(out, y, sizeof y);
}

/* The ideal element has eta = 1 for every order, node set and measure. */
static void test_ideal(void) {
  const double A[6] = {1, 0, 0, 1, 0, 0}, n[3] = {0, 0, 1};
  for (int set = 0; set < 3; ++set)
    for (int p = 1; p <= HOC_MAX_ORDER; ++p) {
      const hoc_quality_tables *t;
      CHECK_OK(hoc_quality_tables_get(p, (hoc_nodeset)set, &t));
      double *x = calloc(3 * (size_t)t->np, sizeof *x), *nn = calloc(3 * (size_t)t->np, sizeof *nn);
      affine_element(t, A, NULL, x);
      constant_normals(t->np, n, nn);
      for (int m = 0; m < 2; ++m) {
        double eta, smin;
        double q = hoc_element_quality(t, (hoc_measure)m, x, nn, &eta, &smin);
        CHECK_NEAR(q, 1.0, 1e-11 * p * p);
        CHECK_NEAR(eta, 1.0, 1e-11 * p * p);
      }
      free(x);
      free(nn);
    }
}

/* Linear triangles: shape q = 4 sqrt(3) area / sum of squared edges; the right
 * isosceles triangle has shape q = sqrt(3)/2 and Oddy eta = 7/3. */
static void test_linear_closed_forms(void) {
  const hoc_quality_tables *t;
  CHECK_OK(hoc_quality_tables_get(1, HOC_NODES_EQUISPACED, &t));
  double n[9] = {0, 0, 1, 0, 0, 1, 0, 0, 1};
  double x[9] = {0, 0, 0, 1, 0, 0, 0, 1, 0}, eta;
  CHECK_NEAR(hoc_element_quality(t, HOC_MEASURE_SHAPE, x, n, &eta, NULL), SQRT3 / 2, 1e-14);
  CHECK_NEAR(hoc_element_quality(t, HOC_MEASURE_ODDY, x, n, &eta, NULL), 3.0 / 7.0, 1e-14);
  for (int trial = 0; trial < 200; ++trial) {
    double y[9];
    for (int k = 0; k < 9; ++k) y[k] = k % 3 == 2 ? 0 : rnd();
    double e1[2] = {y[3] - y[0], y[4] - y[1]}, e2[2] = {y[6] - y[0], y[7] - y[1]},
           e3[2] = {y[6] - y[3], y[7] - y[4]};
    double area = 0.5 * (e1[0] * e2[1] - e1[1] * e2[0]);
    double l2 = e1[0] * e1[0] + e1[1] * e1[1] + e2[0] * e2[0] + e2[1] * e2[1] + e3[0] * e3[0] +
                e3[1] * e3[1];
    double q = hoc_element_quality(t, HOC_MEASURE_SHAPE, y, n, &eta, NULL);
    if (area > 1e-3) {
      CHECK_NEAR(q, 4 * SQRT3 * area / l2, 1e-12);
    } else if (area < -1e-3) {
      CHECK(q == 0.0); /* inverted: tangled */
      CHECK(isinf(eta));
    }
    /* Oddy for a linear triangle: (3/2)(|S^T S|^2 - |S|^4/3)/sigma^2 >= 1 */
    double qo = hoc_element_quality(t, HOC_MEASURE_ODDY, y, n, &eta, NULL);
    if (area > 1e-3) CHECK(qo > 0 && qo <= 1 + 1e-14);
  }
  /* the same triangle seen from below is inverted */
  double down[9] = {0, 0, -1, 0, 0, -1, 0, 0, -1};
  CHECK(hoc_element_quality(t, HOC_MEASURE_SHAPE, x, down, &eta, NULL) == 0.0);
  /* a degenerate (zero-area) triangle is tangled */
  double flat[9] = {0, 0, 0, 1, 0, 0, 2, 0, 0};
  CHECK(hoc_element_quality(t, HOC_MEASURE_SHAPE, flat, n, &eta, NULL) == 0.0);
}

/* Curved element: the ideal element with interior/edge nodes moved. */
static void curved_element(const hoc_quality_tables *t, double amp, double *x) {
  const double A[6] = {1, 0, 0, 1, 0, 0};
  affine_element(t, A, NULL, x);
  for (int i = 3; i < t->np; ++i)
    for (int k = 0; k < 3; ++k) x[3 * i + k] += amp * (rnd() - 0.5);
}

/* A random curved element of order p (curved_element), normals tilted at
 * random from +z, and if `fold`, its corners 1 and 2 swapped: tangled. */
static void random_element(const hoc_quality_tables *t, int p, int fold, double *x, double *n) {
  curved_element(t, 0.3 / p, x);
  for (int i = 0; i < t->np; ++i) {
    double nz[3] = {0.05 * (rnd() - 0.5), 0.05 * (rnd() - 0.5), 1};
    memcpy(n + 3 * i, nz, sizeof nz);
  }
  if (fold) {
    double tmp[3];
    memcpy(tmp, x + 3, sizeof tmp);
    memcpy(x + 3, x + 6, sizeof tmp);
    memcpy(x + 6, tmp, sizeof tmp);
  }
}

/* eta is invariant under rotation, scaling and translation (with the normals
 * rotated too). */
static void test_invariance(void) {
  for (int p = 1; p <= 6; ++p) {
    const hoc_quality_tables *t;
    CHECK_OK(hoc_quality_tables_get(p, HOC_NODES_EQUISPACED, &t));
    size_t np = (size_t)t->np;
    double *x = calloc(3 * np, sizeof *x), *y = calloc(3 * np, sizeof *y),
           *n = calloc(3 * np, sizeof *n), *m = calloc(3 * np, sizeof *m);
    for (int trial = 0; trial < 10; ++trial) {
      curved_element(t, 0.15 / p, x);
      for (size_t i = 0; i < np; ++i) x[3 * i + 2] *= 0.3; /* a little out of plane */
      double up[3] = {0.1, -0.2, 1};
      constant_normals(t->np, up, n);
      double R[9], s = 0.001 + 100 * rnd(), b[3] = {rnd(), rnd(), rnd()};
      random_rotation(R);
      for (size_t i = 0; i < np; ++i) {
        apply(R, s, x + 3 * i, y + 3 * i);
        for (int k = 0; k < 3; ++k) y[3 * i + k] += b[k];
        apply(R, 1, n + 3 * i, m + 3 * i);
      }
      for (int meas = 0; meas < 2; ++meas) {
        double e1, e2;
        double q1 = hoc_element_quality(t, (hoc_measure)meas, x, n, &e1, NULL);
        double q2 = hoc_element_quality(t, (hoc_measure)meas, y, m, &e2, NULL);
        CHECK_NEAR(q1, q2, 1e-12);
      }
    }
    free(x);
    free(y);
    free(n);
    free(m);
  }
}

/* Definition 2 with the normal e_z equals Definition 1 computed in 2D. */
static void test_planar_definition1(void) {
  for (int p = 1; p <= 8; ++p) {
    const hoc_quality_tables *t;
    CHECK_OK(hoc_quality_tables_get(p, HOC_NODES_FEKETE, &t));
    size_t np = (size_t)t->np;
    double *x = calloc(3 * np, sizeof *x), *n = calloc(3 * np, sizeof *n);
    double ez[3] = {0, 0, 1};
    constant_normals(t->np, ez, n);
    for (int trial = 0; trial < 5; ++trial) {
      curved_element(t, 0.1 / p, x);
      for (size_t i = 0; i < np; ++i) x[3 * i + 2] = 0;
      for (int meas = 0; meas < 2; ++meas) {
        /* Definition 1 in 2D: S = sum x_i (x) grad N_i, square */
        double sum = 0;
        int tangled = 0;
        for (int q = 0; q < t->nq; ++q) {
          double S[4] = {0, 0, 0, 0};
          for (size_t i = 0; i < np; ++i)
            for (int r = 0; r < 2; ++r)
              for (int c = 0; c < 2; ++c) S[2 * r + c] += x[3 * i + r] * t->G[2 * ((size_t)q * np + i) + c];
          double sig = S[0] * S[3] - S[1] * S[2];
          double F = S[0] * S[0] + S[1] * S[1] + S[2] * S[2] + S[3] * S[3];
          double eta;
          if (meas == 0) {
            eta = F / (2 * sig);
          } else {
            double g11 = S[0] * S[0] + S[2] * S[2], g22 = S[1] * S[1] + S[3] * S[3],
                   g12 = S[0] * S[1] + S[2] * S[3];
            eta = 1.5 * (g11 * g11 + 2 * g12 * g12 + g22 * g22 - F * F / 3) / (sig * sig);
          }
          if (sig <= 0) tangled = 1;
          sum += t->w[q] * eta * eta;
        }
        for (size_t j = 0; j < np; ++j) { /* Definition 2 also asks det > 0 at the nodes */
          double S[4] = {0, 0, 0, 0};
          for (size_t i = 0; i < np; ++i)
            for (int r = 0; r < 2; ++r)
              for (int c = 0; c < 2; ++c) S[2 * r + c] += x[3 * i + r] * t->Gn[2 * (j * np + i) + c];
          if (S[0] * S[3] - S[1] * S[2] <= 0) tangled = 1;
        }
        double eta2, q2 = hoc_element_quality(t, (hoc_measure)meas, x, n, &eta2, NULL);
        if (!tangled) CHECK_NEAR(q2, 1 / sqrt(sum), 1e-12);
        else CHECK(q2 == 0.0);
      }
    }
    free(x);
    free(n);
  }
}

/* Analytic derivatives of the residuals against central differences. */
static void test_gradients(void) {
  for (int p = 1; p <= 5; ++p) {
    const hoc_quality_tables *t;
    CHECK_OK(hoc_quality_tables_get(p, HOC_NODES_EQUISPACED, &t));
    size_t np = (size_t)t->np, nq = (size_t)t->nq;
    double *x = calloc(3 * np, sizeof *x), *n = calloc(3 * np, sizeof *n);
    double *r = calloc(nq, sizeof *r), *rp = calloc(nq, sizeof *rp), *rm = calloc(nq, sizeof *rm);
    double *J = calloc(nq * np * 3, sizeof *J);
    for (int trial = 0; trial < 6; ++trial) {
      random_element(t, p, trial >= 3, x, n); /* folded: tangled, regularised */
      for (int meas = 0; meas < 2; ++meas) {
        double delta = trial >= 3 ? 0.05 : (trial == 2 ? 1e-3 : 0.0);
        double smin = hoc_element_residuals(t, (hoc_measure)meas, x, n, delta, NULL, r, J);
        if (delta == 0 && !(smin > 0)) continue;
        double err = 0, scale = 0;
        for (size_t i = 0; i < np; ++i)
          for (int k = 0; k < 3; ++k) {
            double h = 1e-6, save = x[3 * i + k];
            x[3 * i + k] = save + h;
            hoc_element_residuals(t, (hoc_measure)meas, x, n, delta, NULL, rp, NULL);
            x[3 * i + k] = save - h;
            hoc_element_residuals(t, (hoc_measure)meas, x, n, delta, NULL, rm, NULL);
            x[3 * i + k] = save;
            for (size_t q = 0; q < nq; ++q) {
              double fd = (rp[q] - rm[q]) / (2 * h), an = J[(q * np + i) * 3 + k];
              err = fmax(err, fabs(fd - an));
              scale = fmax(scale, fabs(an));
            }
          }
        CHECK(err <= 1e-6 * (1 + scale));
        if (!(err <= 1e-6 * (1 + scale)))
          fprintf(stderr, "  p=%d measure=%d delta=%g: gradient error %g (scale %g)\n", p, meas,
                  delta, err, scale);
        /* with a mask: the same residuals and wanted columns, bit for bit,
         * and the other columns not written */
        unsigned char *need = calloc(np, 1);
        double *Jm = calloc(nq * np * 3, sizeof *Jm);
        for (size_t i = 0; i < np; ++i) need[i] = (unsigned char)(i % 3 == (size_t)trial % 3);
        for (size_t k = 0; k < nq * np * 3; ++k) Jm[k] = -7.5;
        hoc_element_residuals(t, (hoc_measure)meas, x, n, delta, need, rp, Jm);
        int same = 1;
        for (size_t q = 0; q < nq; ++q) {
          same &= memcmp(&rp[q], &r[q], sizeof *r) == 0;
          for (size_t i = 0; i < np; ++i)
            for (int k = 0; k < 3; ++k) {
              size_t at = (q * np + i) * 3 + (size_t)k;
              same &= need[i] ? memcmp(&Jm[at], &J[at], sizeof *J) == 0 : Jm[at] == -7.5;
            }
        }
        CHECK(same);
        free(need);
        free(Jm);
      }
    }
    free(x);
    free(n);
    free(r);
    free(rp);
    free(rm);
    free(J);
  }
}

/* hoc_element_point_residual (a fold point's residual, basis evaluated at
 * the point): at the quadrature points it gives hoc_element_residuals'
 * residuals with their weights; its derivatives against central
 * differences at random points, valid and folded elements, regularised;
 * with a mask the wanted columns alone. */
static void test_point_residual(void) {
  for (int p = 1; p <= 10; p += 3) {
    const hoc_quality_tables *t;
    CHECK_OK(hoc_quality_tables_get(p, HOC_NODES_EQUISPACED, &t));
    hoc_quadrature quad = {0};
    CHECK_OK(hoc_quadrature_triangle(t->degree, &quad));
    size_t np = (size_t)t->np, nq = (size_t)t->nq;
    double *x = calloc(3 * np, sizeof *x), *n = calloc(3 * np, sizeof *n);
    double *r = calloc(nq, sizeof *r), *J = calloc(np * 3, sizeof *J);
    double *Jm = calloc(np * 3, sizeof *Jm);
    unsigned char *need = calloc(np, 1);
    for (int trial = 0; trial < 4; ++trial) {
      random_element(t, p, trial >= 2, x, n);
      double delta = trial % 2 ? 1e-3 : (trial >= 2 ? 0.05 : 0.0);
      hoc_element_residuals(t, HOC_MEASURE_SHAPE, x, n, delta, NULL, r, NULL);
      double worst = 0;
      for (size_t q = 0; q < nq; ++q) {
        double rq;
        hoc_element_point_residual(t, HOC_MEASURE_SHAPE, x, n, delta, quad.rs + 2 * q, t->w[q],
                                   NULL, &rq, NULL);
        worst = fmax(worst, fabs(rq - r[q]) / (1 + fabs(r[q])));
      }
      CHECK(worst < 1e-10);
      if (!(worst < 1e-10)) fprintf(stderr, "  p=%d: point residual differs by %g\n", p, worst);
      for (int k = 0; k < 3; ++k) {
        double rs[2] = {rnd(), rnd()};
        if (rs[0] + rs[1] > 1) rs[0] = 1 - rs[0], rs[1] = 1 - rs[1];
        for (int meas = 0; meas < 2; ++meas) {
          double r0, rp, rm, err = 0, scale = 0;
          double rel = hoc_element_point_residual(t, (hoc_measure)meas, x, n, delta, rs, 0.3, NULL,
                                                  &r0, J);
          if (delta == 0 && !(rel > 0)) continue;
          for (size_t i = 0; i < np; ++i)
            for (int d = 0; d < 3; ++d) {
              double h = 1e-6, save = x[3 * i + d];
              x[3 * i + d] = save + h;
              hoc_element_point_residual(t, (hoc_measure)meas, x, n, delta, rs, 0.3, NULL, &rp,
                                         NULL);
              x[3 * i + d] = save - h;
              hoc_element_point_residual(t, (hoc_measure)meas, x, n, delta, rs, 0.3, NULL, &rm,
                                         NULL);
              x[3 * i + d] = save;
              double fd = (rp - rm) / (2 * h), an = J[3 * i + (size_t)d];
              err = fmax(err, fabs(fd - an));
              scale = fmax(scale, fabs(an));
            }
          CHECK(err <= 1e-6 * (1 + scale));
          if (!(err <= 1e-6 * (1 + scale)))
            fprintf(stderr, "  p=%d measure=%d delta=%g: point gradient error %g (scale %g)\n", p,
                    meas, delta, err, scale);
          for (size_t i = 0; i < np; ++i) need[i] = (unsigned char)(i % 2 == (size_t)k % 2);
          for (size_t i = 0; i < 3 * np; ++i) Jm[i] = -7.5;
          double rk;
          hoc_element_point_residual(t, (hoc_measure)meas, x, n, delta, rs, 0.3, need, &rk, Jm);
          int same = memcmp(&rk, &r0, sizeof rk) == 0;
          for (size_t i = 0; i < 3 * np; ++i)
            same &= need[i / 3] ? memcmp(&Jm[i], &J[i], sizeof *J) == 0 : Jm[i] == -7.5;
          CHECK(same);
        }
      }
    }
    hoc_quadrature_free(&quad);
    free(x);
    free(n);
    free(r);
    free(J);
    free(Jm);
    free(need);
  }
}

/* The regularised determinant: sigma_delta -> sigma as delta -> 0 (sigma > 0),
 * and eta stays finite and positive for tangled points when delta > 0. */
static void test_regularisation(void) {
  double a1[3] = {1, 0, 0}, a2[3] = {0.5, 0.8, 0}, n[3] = {0, 0, 1}, sig;
  double e0 = hoc_distortion_point(HOC_MEASURE_SHAPE, a1, a2, n, 0, &sig, NULL, NULL);
  double e1 = hoc_distortion_point(HOC_MEASURE_SHAPE, a1, a2, n, 1e-9, &sig, NULL, NULL);
  CHECK_NEAR(e0, e1, 1e-12);
  CHECK_NEAR(sig, 0.8, 1e-15);
  double b2[3] = {0.5, -0.8, 0};
  CHECK(isinf(hoc_distortion_point(HOC_MEASURE_SHAPE, a1, b2, n, 0, &sig, NULL, NULL)));
  CHECK_NEAR(sig, -0.8, 1e-15);
  double er = hoc_distortion_point(HOC_MEASURE_ODDY, a1, b2, n, 1e-3, &sig, NULL, NULL);
  CHECK(isfinite(er) && er > 1);
  /* an element standing on its edge, perpendicular to the surface: sigma =
   * gamma |a1 x a2| with gamma = -1 (tangled) */
  double c2[3] = {0, 0, 1};
  double n2[3] = {0, 1e-3, 1};
  hoc_distortion_point(HOC_MEASURE_SHAPE, a1, c2, n2, 0, &sig, NULL, NULL);
  CHECK_NEAR(sig, -1.0, 1e-15);
}

/* The measuring kernel gives bit for bit the same q, eta and smallest
 * sigma at both vector widths, on curved, folded and flat elements. */
static void test_widths_agree(void) {
  if (hoc_quality_set_width(4) != 4) {
    printf("no AVX2 here: the 4-wide kernel is not compared\n");
    hoc_quality_set_width(0);
    return;
  }
  for (int p = 1; p <= HOC_MAX_ORDER; ++p) {
    const hoc_quality_tables *t;
    CHECK_OK(hoc_quality_tables_get(p, HOC_NODES_EQUISPACED, &t));
    size_t np = (size_t)t->np;
    double *x = calloc(3 * np, sizeof *x), *n = calloc(3 * np, sizeof *n);
    int same = 1, folded = 0;
    for (int trial = 0; trial < 20; ++trial) {
      curved_element(t, 0.4 / p, x);
      for (size_t i = 0; i < np; ++i) {
        double nz[3] = {0.1 * (rnd() - 0.5), 0.1 * (rnd() - 0.5), trial % 7 == 3 ? -1 : 1};
        memcpy(n + 3 * i, nz, sizeof nz);
      }
      if (trial % 5 == 4 && np > 3)
        memcpy(x + 3 * (np - 1), x, 3 * sizeof *x); /* a node on a vertex */
      for (int meas = 0; meas < 2; ++meas) {
        double e[2], s[2], q[2];
        for (int w = 0; w < 2; ++w) {
          hoc_quality_set_width(w ? 4 : 2);
          q[w] = hoc_element_quality(t, (hoc_measure)meas, x, n, &e[w], &s[w]);
        }
        folded += q[0] == 0;
        same &= memcmp(q, q + 1, sizeof *q) == 0 && memcmp(e, e + 1, sizeof *e) == 0 &&
                memcmp(s, s + 1, sizeof *s) == 0;
      }
    }
    CHECK(same);
    CHECK(folded > 0); /* both kinds of element were seen */
    free(x);
    free(n);
  }
  hoc_quality_set_width(0);
}

/* hoc_element_min_sigma_area: sigma over the corners' area is 2/sqrt(3)
 * on any straight element (the ideal map's determinant is sqrt(3)/2 of
 * the reference one), its negative with the normals reversed; and unlike
 * sigma / |D phi|^2 it deepens as a fold's node is pulled farther out. */
static void test_min_sigma_area(void) {
  for (int p = 1; p <= 6; ++p) {
    const hoc_quality_tables *t;
    CHECK_OK(hoc_quality_tables_get(p, HOC_NODES_EQUISPACED, &t));
    size_t np = (size_t)t->np;
    double *x = calloc(3 * np, sizeof *x), *n = calloc(3 * np, sizeof *n);
    for (int trial = 0; trial < 5; ++trial) {
      double A[6], b[3] = {rnd(), rnd(), rnd()};
      for (int k = 0; k < 6; ++k)
        A[k] = rnd() - 0.5;
      affine_element(t, A, b, x);
      double c[3] = {A[2] * A[5] - A[4] * A[3], A[4] * A[1] - A[0] * A[5],
                     A[0] * A[3] - A[2] * A[1]};
      double lc = sqrt(c[0] * c[0] + c[1] * c[1] + c[2] * c[2]);
      for (int k = 0; k < 3; ++k)
        c[k] /= lc;
      constant_normals(t->np, c, n);
      CHECK_NEAR(hoc_element_min_sigma_area(t, x, n), 2 / SQRT3, 1e-12);
      for (int k = 0; k < 3; ++k)
        c[k] = -c[k];
      constant_normals(t->np, c, n);
      CHECK_NEAR(hoc_element_min_sigma_area(t, x, n), -2 / SQRT3, 1e-12);
    }
    free(x);
    free(n);
  }
  const hoc_quality_tables *t;
  CHECK_OK(hoc_quality_tables_get(3, HOC_NODES_EQUISPACED, &t));
  double x[30], n[30], up[3] = {0, 0, 1}, sig[2], rel[2];
  const double A[6] = {1, 0, 0, 1, 0, 0};
  constant_normals(t->np, up, n);
  for (int k = 0; k < 2; ++k) {
    affine_element(t, A, NULL, x);
    x[3 * 9 + 1] -= k ? 10 : 1; /* the interior node below edge 0 */
    double eta;
    CHECK(hoc_element_quality(t, HOC_MEASURE_SHAPE, x, n, &eta, &rel[k]) == 0.0);
    sig[k] = hoc_element_min_sigma_area(t, x, n);
  }
  CHECK(sig[1] < sig[0] && sig[0] < 0);
  CHECK(rel[0] < rel[1] && rel[1] < 0);
}

/* hoc_element_residuals (points in vector lanes) gives what
 * hoc_distortion_point gives point by point, bit for bit: shape and Oddy,
 * regularised or not, valid and folded elements, a point where a1 x a2 = 0 */
static void test_residuals_pointwise(void) {
  for (int p = 1; p <= 10; p += 3) {
    const hoc_quality_tables *t;
    CHECK_OK(hoc_quality_tables_get(p, HOC_NODES_EQUISPACED, &t));
    size_t np = (size_t)t->np, nq = (size_t)t->nq;
    double *x = calloc(3 * np, sizeof *x), *n = calloc(3 * np, sizeof *n);
    double *r = calloc(nq, sizeof *r), *J = calloc(nq * np * 3, sizeof *J);
    for (int trial = 0; trial < 5; ++trial) {
      random_element(t, p, trial >= 2, x, n);
      if (trial == 4) /* degenerate: a1 x a2 = 0 everywhere */
        for (size_t i = 0; i < np; ++i) x[3 * i + 1] = x[3 * i + 2] = 0;
      for (int meas = 0; meas < 2; ++meas)
        for (int reg = 0; reg < 2; ++reg) {
          double delta = reg ? 0.05 : 0;
          double smin = hoc_element_residuals(t, (hoc_measure)meas, x, n, delta, NULL, r, J);
          int same = 1;
          double mn = INFINITY;
          for (size_t q = 0; q < nq; ++q) {
            double a1[3] = {0, 0, 0}, a2[3] = {0, 0, 0}, nq3[3] = {0, 0, 0};
            const double *G = t->G + 2 * q * np;
            for (size_t i = 0; i < np; ++i)
              for (int k = 0; k < 3; ++k) {
                a1[k] += G[2 * i] * x[3 * i + k];
                a2[k] += G[2 * i + 1] * x[3 * i + k];
                nq3[k] += t->N[q * np + i] * n[3 * i + k];
              }
            double sig, g1[3], g2[3];
            double e = hoc_distortion_point((hoc_measure)meas, a1, a2, nq3, delta, &sig, g1, g2);
            double rel = sig / (a1[0] * a1[0] + a1[1] * a1[1] + a1[2] * a1[2] +
                                (a2[0] * a2[0] + a2[1] * a2[1] + a2[2] * a2[2]));
            if (!(rel >= mn)) mn = rel;
            double sw = sqrt(t->w[q]), rq = sw * (e - 1);
            same &= memcmp(&rq, &r[q], sizeof rq) == 0;
            for (size_t i = 0; i < np; ++i)
              for (int k = 0; k < 3; ++k) {
                double j = sw * (g1[k] * G[2 * i] + g2[k] * G[2 * i + 1]);
                same &= memcmp(&j, &J[(q * np + i) * 3 + (size_t)k], sizeof j) == 0;
              }
          }
          CHECK(same);
          CHECK(memcmp(&mn, &smin, sizeof mn) == 0);
          if (!same) fprintf(stderr, "  p=%d trial=%d measure=%d delta=%g differs\n", p, trial, meas, delta);
        }
    }
    free(x);
    free(n);
    free(r);
    free(J);
  }
}

int main(void) {
  /* every closed-form test at each vector width of the measuring kernel */
  for (int w = 2; w <= 4; w += 2) {
    if (hoc_quality_set_width(w) != w) continue;
    test_ideal();
    test_linear_closed_forms();
    test_invariance();
    test_planar_definition1();
  }
  hoc_quality_set_width(0);
  test_widths_agree();
  test_gradients();
  test_residuals_pointwise();
  test_point_residual();
  test_regularisation();
  test_min_sigma_area();
  return test_report();
}
