/* How far each model's curves lie off their faces: the measured tolerance
 * (hoc_model_tolerance), its share of the bounding-box diagonal, where it
 * was found and what measuring it cost; with --dense N, the same measure
 * at N evenly spaced points per curve as well, to see how far the 33
 * samples fall short.
 * usage: cad_tolerance [--dense N] MODEL...
 * SPDX-License-Identifier: GPL-2.0-or-later */
#include "cad/cad.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

static double now(void) {
  struct timespec t;
  clock_gettime(CLOCK_MONOTONIC, &t);
  return (double)t.tv_sec + 1e-9 * (double)t.tv_nsec;
}

/* Largest c(t) - phi_f(pcurve_f(t)) over n evenly spaced t of each pair. */
static double dense_gap(const hoc_model *m, int n) {
  double *t = calloc((size_t)n, sizeof *t), *x = calloc(3 * (size_t)n, sizeof *x),
         *uv = calloc(2 * (size_t)n, sizeof *uv), *y = calloc(3 * (size_t)n, sizeof *y);
  double gap = 0;
  for (int f = 0; f < m->n_faces && t && x && uv && y; ++f)
    for (int k = 0; k < m->faces[f].n_curves; ++k) {
      int c = hoc_cad_curve_index(m, abs(m->faces[f].curves[k]));
      if (c < 0) continue;
      const hoc_cad_curve *cv = &m->curves[c];
      for (int i = 0; i < n; ++i) t[i] = cv->lo + (cv->hi - cv->lo) * i / (n - 1.0);
      if (hoc_cad_curve_eval(m, c, (size_t)n, t, x, NULL) ||
          hoc_cad_curve_to_face(m, c, f, (size_t)n, t, uv) ||
          hoc_cad_face_eval(m, f, (size_t)n, uv, y, NULL, NULL))
        continue;
      for (int i = 0; i < n; ++i) {
        double d = sqrt((x[3 * i] - y[3 * i]) * (x[3 * i] - y[3 * i]) +
                        (x[3 * i + 1] - y[3 * i + 1]) * (x[3 * i + 1] - y[3 * i + 1]) +
                        (x[3 * i + 2] - y[3 * i + 2]) * (x[3 * i + 2] - y[3 * i + 2]));
        if (d > gap) gap = d;
      }
    }
  free(t);
  free(x);
  free(uv);
  free(y);
  return gap;
}

int main(int argc, char **argv) {
  int dense = 0, first = 1;
  if (argc > 2 && !strcmp(argv[1], "--dense")) {
    dense = atoi(argv[2]);
    first = 3;
  }
  if (first >= argc || (first == 3 && dense < 2)) {
    fprintf(stderr, "usage: %s [--dense N] MODEL...\n", argv[0]);
    return 1;
  }
  printf("%-32s %6s %10s %10s %9s %7s %6s %7s %7s%s\n", "model", "faces", "diagonal",
         "tolerance", "/diagonal", "curve", "face", "open s", "tol s", dense ? "  dense/33" : "");
  for (int a = first; a < argc; ++a) {
    const char *name = strrchr(argv[a], '/') ? strrchr(argv[a], '/') + 1 : argv[a];
    hoc_model *m = NULL;
    double t0 = now();
    if (hoc_model_open(argv[a], &m) != HOC_OK) {
      printf("%-32s %s\n", name, hoc_last_error());
      continue;
    }
    double t_open = now() - t0, tol = 0;
    t0 = now();
    if (hoc_model_tolerance(m, &tol) != HOC_OK) {
      printf("%-32s %s\n", name, hoc_last_error());
      hoc_model_destroy(&m);
      continue;
    }
    double t_tol = now() - t0;
    printf("%-32s %6d %10.4g %10.3g %9.2e %7d %6d %7.2f %7.3f", name, m->n_faces, m->diagonal, tol,
           tol / m->diagonal, m->tolerance_curve, m->tolerance_face, t_open, t_tol);
    if (dense) printf("  %8.2f", tol > 0 ? dense_gap(m, dense) / tol : 0.0);
    printf("\n");
    hoc_model_destroy(&m);
  }
  return 0;
}
