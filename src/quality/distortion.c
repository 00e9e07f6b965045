/* The element kernel: pointwise distortion (Table 1), element quality
 * (Definitions 1-2) and least-squares residuals with their derivatives.
 * One definition of eta serves the report and the optimiser.
 * SPDX-License-Identifier: GPL-2.0-or-later */
#include "basis/basis.h"
#include "quality/quality.h"

#include <math.h>
#include <string.h>

static inline void cross(const double *a, const double *b, double *c) {
  c[0] = a[1] * b[2] - a[2] * b[1];
  c[1] = a[2] * b[0] - a[0] * b[2];
  c[2] = a[0] * b[1] - a[1] * b[0];
}

static inline double dot(const double *a, const double *b) {
  return a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
}

double hoc_distortion_point(hoc_measure measure, const double a1[3], const double a2[3],
                            const double n[3], double delta, double *sigma, double *g1,
                            double *g2) {
  double c[3];
  cross(a1, a2, c);
  double cl = sqrt(dot(c, c));
  double gamma = dot(c, n) > 0 ? 1.0 : -1.0; /* orientation of T's basis from the CAD normal */
  double sig = gamma * cl;                   /* sigma = det T(D phi) */
  if (sigma) *sigma = sig;
  double g11 = dot(a1, a1), g22 = dot(a2, a2), g12 = dot(a1, a2), F = g11 + g22; /* F = |S|^2 */
  double s, ds; /* sigma_delta and its derivative in sigma */
  if (delta > 0) {
    double root = sqrt(sig * sig + 4 * delta * delta);
    s = sig >= 0 ? 0.5 * (sig + root) : 2 * delta * delta / (root - sig); /* no cancellation */
    ds = s / root;
  } else {
    if (!(sig > 0)) {
      if (g1) memset(g1, 0, 3 * sizeof *g1);
      if (g2) memset(g2, 0, 3 * sizeof *g2);
      return INFINITY;
    }
    s = sig;
    ds = 1;
  }
  double eta, deta_ds;
  double dA1[3], dA2[3]; /* d eta / d a at fixed sigma */
  if (measure == HOC_MEASURE_ODDY) {
    /* eta = (3/2) (|S^T S|^2 - |S|^4 / 3) / sigma^2 */
    double H = g11 * g11 + 2 * g12 * g12 + g22 * g22 - F * F / 3;
    double inv2 = 1 / (s * s);
    eta = 1.5 * H * inv2;
    deta_ds = -3 * H * inv2 / s;
    double c11 = 1.5 * inv2 * (4 * g11 - 4 * F / 3), c12 = 1.5 * inv2 * 4 * g12,
           c22 = 1.5 * inv2 * (4 * g22 - 4 * F / 3);
    for (int k = 0; k < 3; ++k) {
      dA1[k] = c11 * a1[k] + c12 * a2[k];
      dA2[k] = c12 * a1[k] + c22 * a2[k];
    }
  } else {
    /* eta = |S|^2 / (2 sigma) */
    eta = F / (2 * s);
    deta_ds = -F / (2 * s * s);
    for (int k = 0; k < 3; ++k) {
      dA1[k] = a1[k] / s;
      dA2[k] = a2[k] / s;
    }
  }
  if (g1 || g2) {
    /* d sigma / d a1 = a2 x c^, d sigma / d a2 = c^ x a1, c^ the unit normal of
     * the element turned by gamma (the reference normal where a1 x a2 = 0) */
    double chat[3];
    if (cl > 0) {
      for (int k = 0; k < 3; ++k) chat[k] = gamma * c[k] / cl;
    } else {
      double nl = sqrt(dot(n, n));
      for (int k = 0; k < 3; ++k) chat[k] = nl > 0 ? n[k] / nl : 0;
    }
    double ds1[3], ds2[3];
    cross(a2, chat, ds1);
    cross(chat, a1, ds2);
    double f = deta_ds * ds;
    for (int k = 0; k < 3; ++k) {
      if (g1) g1[k] = dA1[k] + f * ds1[k];
      if (g2) g2[k] = dA2[k] + f * ds2[k];
    }
  }
  return eta;
}

/* Measuring: every point of the element (quadrature, nodes, lattice) in
 * vectors of 2 doubles (SSE2, any x86-64) or 4 (AVX2, picked at run time),
 * with GCC/clang vector extensions. The same operations in the same order
 * at both widths, so the same results. At each point the same arithmetic
 * as hoc_distortion_point with delta = 0 (sigma = gamma |a1 x a2|, gamma =
 * +1 where (a1 x a2) . n > 0, else -1); the weighted sum of eta^2 is
 * accumulated per lane (point k in lane k mod HOC_QB) and the lanes added
 * last, an order other than the points' own: q may differ from a
 * point-by-point sum in its last bits. */
typedef double v2d __attribute__((vector_size(2 * sizeof(double))));
typedef long long v2l __attribute__((vector_size(2 * sizeof(long long))));
typedef double v2d_u __attribute__((vector_size(2 * sizeof(double)), aligned(8), may_alias));
typedef double v4d __attribute__((vector_size(4 * sizeof(double))));
typedef long long v4l __attribute__((vector_size(4 * sizeof(long long))));
typedef double v4d_u __attribute__((vector_size(4 * sizeof(double)), aligned(8), may_alias));

/* (macros: functions taking or returning vectors would depend on the ABI) */
#define KW 2
#define KV v2d
#define KL v2l
#define KNAME quality_points_2
#define KFRAMES frames_2
#define KATTR
#define KLOAD(p) (*(const v2d_u *)(const void *)(p))
#define KSPLAT(x) ((v2d){(x), (x)})
#define KMASK01(m) ((v2d)((v2l)KSPLAT(1.0) & (m))) /* 1.0 where the mask is set */
#include "quality/kernel_body.h"
#undef KW
#undef KV
#undef KL
#undef KNAME
#undef KFRAMES
#undef KATTR
#undef KLOAD
#undef KSPLAT
#undef KMASK01

#if (defined(__GNUC__) || defined(__clang__)) && defined(__x86_64__) && !defined(HOC_NO_AVX2)
#define HOC_HAVE_AVX2_KERNEL 1
#define KW 4
#define KV v4d
#define KL v4l
#define KNAME quality_points_4
#define KFRAMES frames_4
#define KATTR __attribute__((target("avx2")))
#define KLOAD(p) (*(const v4d_u *)(const void *)(p))
#define KSPLAT(x) ((v4d){(x), (x), (x), (x)})
#define KMASK01(m) ((v4d)((v4l)KSPLAT(1.0) & (m)))
#include "quality/kernel_body.h"
#endif

static int forced_width; /* 0: the widest available */

static int avx2_available(void) {
#ifdef HOC_HAVE_AVX2_KERNEL
  return __builtin_cpu_supports("avx2");
#else
  return 0;
#endif
}

int hoc_quality_set_width(int width) {
  forced_width = width == 2 || (width == 4 && avx2_available()) ? width : 0;
  return forced_width ? forced_width : avx2_available() ? 4 : 2;
}

/* Frames (a1, a2, n) at the points of blocks b0..b1-1 (see KFRAMES). */
static void frames(const hoc_quality_tables *t, int b0, int b1, const double *x, const double *n,
                   double *out) {
#ifdef HOC_HAVE_AVX2_KERNEL
  if (forced_width != 2 && __builtin_cpu_supports("avx2"))
    frames_4(t, b0, b1, x, n, out);
  else
#endif
    frames_2(t, b0, b1, x, n, out);
}

/* Walks the points first..last-1 of the blocked layout (quadrature points,
 * then nodes, then the lattice) with their frames, computed FRAME_BLOCKS
 * blocks at a time in vector code. */
enum { FRAME_BLOCKS = 16, FRAME_POINTS = FRAME_BLOCKS * HOC_QB };

typedef struct point_walk {
  const hoc_quality_tables *t;
  const double *x, *n;
  int k, last, b0, b1;
  double fr[9 * FRAME_POINTS];
} point_walk;

static void walk_begin(point_walk *w, const hoc_quality_tables *t, const double *x, const double *n,
                       int first, int last) {
  w->t = t;
  w->x = x;
  w->n = n;
  w->k = first;
  w->last = last;
  w->b0 = w->b1 = 0;
}

/* The next point's index (-1 at the end) and its a1, a2, normal. */
static int walk_next(point_walk *w, double *a1, double *a2, double *nq) {
  if (w->k >= w->last) return -1;
  if (w->k >= w->b1 * HOC_QB || w->k < w->b0 * HOC_QB) {
    w->b0 = w->k / HOC_QB;
    int end = (w->last + HOC_QB - 1) / HOC_QB; /* no frames past the last point asked */
    w->b1 = w->b0 + FRAME_BLOCKS < end ? w->b0 + FRAME_BLOCKS : end;
    frames(w->t, w->b0, w->b1, w->x, w->n, w->fr);
  }
  size_t st = (size_t)(w->b1 - w->b0) * HOC_QB, j = (size_t)(w->k - w->b0 * HOC_QB);
  for (int c = 0; c < 3; ++c) {
    a1[c] = w->fr[(size_t)c * st + j];
    a2[c] = w->fr[(size_t)(3 + c) * st + j];
    nq[c] = w->fr[(size_t)(6 + c) * st + j];
  }
  return w->k++;
}

double hoc_element_min_sigma_area(const hoc_quality_tables *t, const double *x, const double *n) {
  const int np = t->np;
  double mn = INFINITY;
  for (int b = 0; b < t->n_check_blocks; ++b)
    for (int l = 0; l < HOC_QB; ++l) {
      size_t off = (size_t)b * (size_t)np * HOC_QB + (size_t)l;
      double a1[3] = {0, 0, 0}, a2[3] = {0, 0, 0}, nq[3] = {0, 0, 0};
      for (int i = 0; i < np; ++i) {
        double gx = t->Bx[off + (size_t)i * HOC_QB], gy = t->By[off + (size_t)i * HOC_QB],
               gn = t->Bn[off + (size_t)i * HOC_QB];
        for (int c = 0; c < 3; ++c) {
          a1[c] += gx * x[3 * i + c];
          a2[c] += gy * x[3 * i + c];
          nq[c] += gn * n[3 * i + c];
        }
      }
      double c0 = a1[1] * a2[2] - a1[2] * a2[1], c1 = a1[2] * a2[0] - a1[0] * a2[2],
             c2 = a1[0] * a2[1] - a1[1] * a2[0];
      double sig = sqrt(c0 * c0 + c1 * c1 + c2 * c2);
      if (!(c0 * nq[0] + c1 * nq[1] + c2 * nq[2] > 0)) sig = -sig;
      if (!(sig >= mn)) mn = sig;
    }
  /* the corners' straight triangle, in the same units (a right angle at
   * corner 0 in the reference triangle, whose ideal map is fixed) */
  double e1[3], e2[3];
  for (int c = 0; c < 3; ++c) {
    e1[c] = x[3 + c] - x[c];
    e2[c] = x[6 + c] - x[c];
  }
  double d0 = e1[1] * e2[2] - e1[2] * e2[1], d1 = e1[2] * e2[0] - e1[0] * e2[2],
         d2 = e1[0] * e2[1] - e1[1] * e2[0];
  double area = sqrt(d0 * d0 + d1 * d1 + d2 * d2);
  return area > 0 ? mn / area : mn;
}

double hoc_element_quality(const hoc_quality_tables *t, hoc_measure measure, const double *x,
                           const double *n, double *eta_out, double *min_sigma) {
  return hoc_element_quality_test(t, measure, x, n, 1, eta_out, min_sigma);
}

double hoc_element_quality_test(const hoc_quality_tables *t, hoc_measure measure, const double *x,
                                const double *n, int exact, double *eta_out, double *min_sigma) {
  double sum[HOC_QB], smin[HOC_QB], bad[HOC_QB];
  int oddy = measure == HOC_MEASURE_ODDY;
#ifdef HOC_HAVE_AVX2_KERNEL
  if (forced_width != 2 && __builtin_cpu_supports("avx2"))
    quality_points_4(t, oddy, x, n, sum, smin, bad);
  else
#endif
    quality_points_2(t, oddy, x, n, sum, smin, bad);
  double total = 0, mn = INFINITY;
  int tangled = 0;
  for (int l = 0; l < HOC_QB; ++l) {
    total += sum[l];
    tangled |= bad[l] != 0;
    if (!(smin[l] >= mn)) mn = smin[l];
  }
  /* a fold between the samples (exact tests; most elements pass their
   * first check, all Bernstein coefficients positive) */
  if (!tangled && exact) tangled = hoc_element_folded(t, x, n);
  double eta = tangled ? INFINITY : sqrt(total);
  if (eta_out) *eta_out = eta;
  if (min_sigma) *min_sigma = mn;
  return tangled || !isfinite(eta) ? 0.0 : 1.0 / eta;
}

/* distortion_lanes' values per point: a1 x a2, its squared length and
 * length, sqrt(sigma^2 + 4 delta^2), and gamma (+1 or -1) */
typedef struct lanes {
  double c[3][FRAME_POINTS], cc[FRAME_POINTS], cl[FRAME_POINTS], root[FRAME_POINTS];
  double gam[FRAME_POINTS];
} lanes;

/* The loop over the points, for one choice of regularised, Oddy and
 * gradients (constants where it is inlined, so no branch in the loop). */
static inline __attribute__((always_inline)) void lanes_body(int reg, int oddy, int grads,
                                                             double delta, int m, const double *fr,
                                                             size_t st, const lanes *L,
                                                             double *eta, double *rel,
                                                             double (*g)[FRAME_POINTS]) {
  const double *a10 = fr, *a11 = fr + st, *a12 = fr + 2 * st, *a20 = fr + 3 * st,
               *a21 = fr + 4 * st, *a22 = fr + 5 * st;
  for (int j = 0; j < m; ++j) {
    double A1[3] = {a10[j], a11[j], a12[j]}, A2[3] = {a20[j], a21[j], a22[j]};
    double sig = L->gam[j] * L->cl[j], root = L->root[j];
    double g11 = dot(A1, A1), g22 = dot(A2, A2), g12 = dot(A1, A2), F = g11 + g22;
    double s, ds, bad;
    if (reg) {
      double sp = 0.5 * (sig + root), sn = 2 * delta * delta / (root - sig);
      s = sig >= 0 ? sp : sn;
      ds = s / root;
      bad = 0;
    } else {
      bad = sig > 0 ? 0 : 1;
      s = sig;
      ds = 1;
    }
    rel[j] = sig / F;
    double e, deta_ds, d11 = 0, d12 = 0, d22 = 0;
    if (oddy) {
      double H = g11 * g11 + 2 * g12 * g12 + g22 * g22 - F * F / 3;
      double inv2 = 1 / (s * s);
      e = 1.5 * H * inv2;
      deta_ds = -3 * H * inv2 / s;
      d11 = 1.5 * inv2 * (4 * g11 - 4 * F / 3);
      d12 = 1.5 * inv2 * 4 * g12;
      d22 = 1.5 * inv2 * (4 * g22 - 4 * F / 3);
    } else {
      e = F / (2 * s);
      deta_ds = -F / (2 * s * s);
    }
    eta[j] = bad != 0 ? INFINITY : e;
    if (!grads) continue;
    double chat[3];
    for (int k = 0; k < 3; ++k) chat[k] = L->gam[j] * L->c[k][j] / L->cl[j];
    double ds1[3], ds2[3];
    cross(A2, chat, ds1);
    cross(chat, A1, ds2);
    double f = deta_ds * ds;
    for (int k = 0; k < 3; ++k) {
      double dA1 = oddy ? d11 * A1[k] + d12 * A2[k] : A1[k] / s;
      double dA2 = oddy ? d12 * A1[k] + d22 * A2[k] : A2[k] / s;
      g[k][j] = bad != 0 ? 0 : dA1 + f * ds1[k];
      g[3 + k][j] = bad != 0 ? 0 : dA2 + f * ds2[k];
    }
  }
}

/* hoc_distortion_point at the m points of a block of frames (fr, stride
 * st; see KFRAMES), in loops over the points that gcc turns into vector
 * code (the square roots apart): eta, sigma / |D phi|^2 and, if g, the
 * gradients g[0..2][j] = d eta / d a1, g[3..5][j] = d eta / d a2. The
 * same operations in the same order as hoc_distortion_point at every
 * point, so the same results. */
static void distortion_lanes(hoc_measure measure, double delta, int m, const double *fr,
                             size_t st, lanes *L, double *eta, double *rel,
                             double (*g)[FRAME_POINTS]) {
  const double *a10 = fr, *a11 = fr + st, *a12 = fr + 2 * st, *a20 = fr + 3 * st,
               *a21 = fr + 4 * st, *a22 = fr + 5 * st, *n0 = fr + 6 * st, *n1 = fr + 7 * st,
               *n2 = fr + 8 * st;
  for (int j = 0; j < m; ++j) {
    double c0 = a11[j] * a22[j] - a12[j] * a21[j], c1 = a12[j] * a20[j] - a10[j] * a22[j],
           c2 = a10[j] * a21[j] - a11[j] * a20[j];
    L->c[0][j] = c0;
    L->c[1][j] = c1;
    L->c[2][j] = c2;
    L->cc[j] = c0 * c0 + c1 * c1 + c2 * c2;
    L->gam[j] = c0 * n0[j] + c1 * n1[j] + c2 * n2[j] > 0 ? 1.0 : -1.0;
  }
  for (int j = 0; j < m; ++j) L->cl[j] = sqrt(L->cc[j]);
  int reg = delta > 0, oddy = measure == HOC_MEASURE_ODDY;
  if (reg) {
    for (int j = 0; j < m; ++j) {
      double sig = L->gam[j] * L->cl[j];
      L->root[j] = sig * sig + 4 * delta * delta;
    }
    for (int j = 0; j < m; ++j) L->root[j] = sqrt(L->root[j]);
  }
#define LANES_CASE(R, O, G) lanes_body(R, O, G, delta, m, fr, st, L, eta, rel, g)
  if (g) {
    if (reg)
      oddy ? LANES_CASE(1, 1, 1) : LANES_CASE(1, 0, 1);
    else
      oddy ? LANES_CASE(0, 1, 1) : LANES_CASE(0, 0, 1);
  } else {
    if (reg)
      oddy ? LANES_CASE(1, 1, 0) : LANES_CASE(1, 0, 0);
    else
      oddy ? LANES_CASE(0, 1, 0) : LANES_CASE(0, 0, 0);
  }
#undef LANES_CASE
  if (!g) return;
  /* where a1 x a2 = 0 (rare, or not a number): hoc_distortion_point
   * itself, which takes the reference normal there */
  for (int j = 0; j < m; ++j) {
    if (L->cl[j] > 0) continue;
    double A1[3] = {a10[j], a11[j], a12[j]}, A2[3] = {a20[j], a21[j], a22[j]};
    double N[3] = {n0[j], n1[j], n2[j]}, g1[3], g2[3], sig;
    hoc_distortion_point(measure, A1, A2, N, delta, &sig, g1, g2);
    for (int k = 0; k < 3; ++k) {
      g[k][j] = g1[k];
      g[3 + k][j] = g2[k];
    }
  }
}

/* Residuals (and J) of the quadrature points q0 .. q0 + m - 1 from their
 * frames fr (stride st): the common part of hoc_element_residuals and
 * hoc_element_residuals_frames. need_list[n_need]: the nodes whose
 * columns of J are written. Returns the smallest sigma / |D phi|^2. */
static double residual_chunk(const hoc_quality_tables *t, hoc_measure measure, double delta,
                             int q0, int m, const double *fr, size_t st, const int *need_list,
                             int n_need, double *r, double *J, lanes *L) {
  int np = t->np;
  double smin = INFINITY;
  double eta[FRAME_POINTS], rel[FRAME_POINTS], g[6][FRAME_POINTS];
  distortion_lanes(measure, delta, m, fr, st, L, eta, rel, J ? g : NULL);
  for (int j = 0; j < m; ++j) {
    int q = q0 + j;
    if (!(rel[j] >= smin)) smin = rel[j];
    double sw = sqrt(t->w[q]);
    r[q] = sw * (eta[j] - 1);
    if (!J) continue;
    const double *G = t->G + 2 * (size_t)q * np;
    double g1[3] = {g[0][j], g[1][j], g[2][j]}, g2[3] = {g[3][j], g[4][j], g[5][j]};
    double *Jq = J + 3 * (size_t)q * np;
    for (int a = 0; a < n_need; ++a) {
      int i = need_list[a];
      double gx = G[2 * i], gy = G[2 * i + 1];
      for (int k = 0; k < 3; ++k) Jq[3 * i + k] = sw * (g1[k] * gx + g2[k] * gy);
    }
  }
  return smin;
}

/* The nodes whose columns of J are wanted (need NULL: all). */
static int need_to_list(int np, const unsigned char *need, int *list) {
  int n = 0;
  for (int i = 0; i < np; ++i)
    if (!need || need[i]) list[n++] = i;
  return n;
}

enum { NP_LIST = (HOC_MAX_ORDER + 1) * (HOC_MAX_ORDER + 2) / 2 };

double hoc_element_residuals(const hoc_quality_tables *t, hoc_measure measure, const double *x,
                             const double *n, double delta, const unsigned char *need, double *r,
                             double *J) {
  int nq = t->nq, list[NP_LIST];
  int n_need = J ? need_to_list(t->np, need, list) : 0;
  double smin = INFINITY, fr[9 * FRAME_POINTS];
  lanes L;
  int end = (nq + HOC_QB - 1) / HOC_QB;
  for (int b0 = 0; b0 < end; b0 += FRAME_BLOCKS) {
    int b1 = b0 + FRAME_BLOCKS < end ? b0 + FRAME_BLOCKS : end;
    frames(t, b0, b1, x, n, fr);
    int q0 = b0 * HOC_QB, m = (b1 * HOC_QB < nq ? b1 * HOC_QB : nq) - q0;
    double s = residual_chunk(t, measure, delta, q0, m, fr, (size_t)(b1 - b0) * HOC_QB, list,
                              n_need, r, J, &L);
    if (!(s >= smin)) smin = s;
  }
  return smin;
}

int hoc_element_frame_points(const hoc_quality_tables *t) { return t->n_check_blocks * HOC_QB; }

void hoc_element_frames(const hoc_quality_tables *t, const double *x, const double *n,
                        double *fr) {
  frames(t, 0, t->n_check_blocks, x, n, fr);
}

void hoc_element_frames_move(const hoc_quality_tables *t, const double *fr, int node,
                             const double dx[3], const double dn[3], double *out) {
  int np = t->np, nb = t->n_check_blocks;
  size_t st = (size_t)nb * HOC_QB;
  for (int b = 0; b < nb; ++b) {
    size_t off = ((size_t)b * (size_t)np + (size_t)node) * HOC_QB;
    const double *gx = t->Bx + off, *gy = t->By + off, *gn = t->Bn + off;
    size_t k0 = (size_t)b * HOC_QB;
    for (int c = 0; c < 3; ++c) {
      const double *f1 = fr + c * st + k0, *f2 = fr + (3 + c) * st + k0, *f3 = fr + (6 + c) * st + k0;
      double *o1 = out + c * st + k0, *o2 = out + (3 + c) * st + k0, *o3 = out + (6 + c) * st + k0;
      double x = dx[c], nn = dn[c];
      for (int l = 0; l < HOC_QB; ++l) {
        o1[l] = f1[l] + gx[l] * x;
        o2[l] = f2[l] + gy[l] * x;
        o3[l] = f3[l] + gn[l] * nn;
      }
    }
  }
}

double hoc_element_residuals_frames(const hoc_quality_tables *t, hoc_measure measure,
                                    const double *fr, double delta, const unsigned char *need,
                                    double *r, double *J) {
  int nq = t->nq, list[NP_LIST];
  int n_need = J ? need_to_list(t->np, need, list) : 0;
  size_t st = (size_t)t->n_check_blocks * HOC_QB;
  double smin = INFINITY;
  lanes L;
  for (int q0 = 0; q0 < nq; q0 += FRAME_POINTS) {
    int m = nq - q0 < FRAME_POINTS ? nq - q0 : FRAME_POINTS;
    double s = residual_chunk(t, measure, delta, q0, m, fr + q0, st, list, n_need, r, J, &L);
    if (!(s >= smin)) smin = s;
  }
  return smin;
}

int hoc_element_frames_tangled(const hoc_quality_tables *t, const double *fr, int first,
                               int last) {
  size_t st = (size_t)t->n_check_blocks * HOC_QB;
  const double *a10 = fr, *a11 = fr + st, *a12 = fr + 2 * st, *a20 = fr + 3 * st,
               *a21 = fr + 4 * st, *a22 = fr + 5 * st, *n0 = fr + 6 * st, *n1 = fr + 7 * st,
               *n2 = fr + 8 * st;
  int bad = 0;
  for (int k = first; k < last; ++k) {
    double c0 = a11[k] * a22[k] - a12[k] * a21[k], c1 = a12[k] * a20[k] - a10[k] * a22[k],
           c2 = a10[k] * a21[k] - a11[k] * a20[k];
    bad |= !(c0 * n0[k] + c1 * n1[k] + c2 * n2[k] > 0) | !(c0 * c0 + c1 * c1 + c2 * c2 > 0);
  }
  return bad;
}

int hoc_element_node_points(const hoc_quality_tables *t, int dense) {
  return t->np + t->nlat + (dense ? t->nv - t->nlat - t->nvpad : 0);
}

double hoc_element_node_residuals(const hoc_quality_tables *t, hoc_measure measure, const double *x,
                                  const double *n, double delta, int dense,
                                  const unsigned char *need, double *r, double *J) {
  int np = t->np, lat_end = np + t->nlat, pad_end = lat_end + t->nvpad;
  double smin = INFINITY, sw = sqrt(1.0 / hoc_element_node_points(t, dense)), a1[3], a2[3], nj[3];
  point_walk w;
  walk_begin(&w, t, x, n, t->nq, t->nq + np + (dense ? t->nv : t->nlat));
  for (int k, c = 0; (k = walk_next(&w, a1, a2, nj)) >= 0;) {
    int j = k - t->nq;
    if (j >= lat_end && j < pad_end) continue; /* the padding's copies */
    double sig, g1[3], g2[3];
    const double *G = j < np ? t->Gn + 2 * (size_t)j * np : t->Gv + 2 * (size_t)(j - np) * np;
    double e = hoc_distortion_point(measure, a1, a2, nj, delta, &sig, J ? g1 : NULL,
                                    J ? g2 : NULL);
    double rel = sig / (dot(a1, a1) + dot(a2, a2));
    if (!(rel >= smin)) smin = rel;
    r[c] = sw * (e - 1);
    if (J) {
      double *Jj = J + 3 * (size_t)c * np;
      for (int i = 0; i < np; ++i) {
        if (need && !need[i]) continue;
        for (int d = 0; d < 3; ++d)
          Jj[3 * i + d] = sw * (g1[d] * G[2 * i] + g2[d] * G[2 * i + 1]);
      }
    }
    ++c;
  }
  return smin;
}

double hoc_element_point_residual(const hoc_quality_tables *t, hoc_measure measure,
                                  const double *x, const double *n, double delta,
                                  const double rs[2], double w, const unsigned char *need,
                                  double *r, double *J) {
  enum { NP_MAX = (HOC_MAX_ORDER + 1) * (HOC_MAX_ORDER + 2) / 2 };
  int np = t->np;
  double N[NP_MAX], dN[2 * NP_MAX], G[2 * NP_MAX];
  *r = 0;
  if (!t->basis || np > NP_MAX || hoc_lagrange_eval(t->basis, 1, rs, N, dN) != HOC_OK) {
    hoc_error_clear();
    return NAN;
  }
  hoc_quality_to_ideal((size_t)np, dN, G);
  double a1[3] = {0, 0, 0}, a2[3] = {0, 0, 0}, nq[3] = {0, 0, 0};
  for (int i = 0; i < np; ++i)
    for (int d = 0; d < 3; ++d) {
      a1[d] += G[2 * i] * x[3 * i + d];
      a2[d] += G[2 * i + 1] * x[3 * i + d];
      nq[d] += N[i] * n[3 * i + d];
    }
  double sig, g1[3], g2[3], sw = sqrt(w);
  double e = hoc_distortion_point(measure, a1, a2, nq, delta, &sig, J ? g1 : NULL, J ? g2 : NULL);
  *r = sw * (e - 1);
  if (J)
    for (int i = 0; i < np; ++i) {
      if (need && !need[i]) continue;
      for (int d = 0; d < 3; ++d) J[3 * i + d] = sw * (g1[d] * G[2 * i] + g2[d] * G[2 * i + 1]);
    }
  return sig / (dot(a1, a1) + dot(a2, a2));
}

/* 1 if sigma <= 0 at one of the points first..last-1. */
static int points_tangled(const hoc_quality_tables *t, const double *x, const double *n, int first,
                          int last) {
  double a1[3], a2[3], nq[3], c[3];
  point_walk w;
  walk_begin(&w, t, x, n, first, last);
  while (walk_next(&w, a1, a2, nq) >= 0) {
    cross(a1, a2, c);
    if (!(dot(c, nq) > 0) || !(dot(c, c) > 0)) return 1;
  }
  return 0;
}

int hoc_element_tangled(const hoc_quality_tables *t, const double *x, const double *n, int exact) {
  return points_tangled(t, x, n, 0, t->n_check_blocks * HOC_QB) ||
         (exact && hoc_element_folded(t, x, n));
}

int hoc_element_nodes_tangled(const hoc_quality_tables *t, const double *x, const double *n,
                              int exact) {
  return points_tangled(t, x, n, t->nq, t->n_check_blocks * HOC_QB) ||
         (exact && hoc_element_folded(t, x, n));
}
