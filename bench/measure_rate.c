/* Measuring speed: order-p elements per second and per core, for the
 * element kernel alone (positions and normals given) and for the whole
 * hoc_mesh_measure (with the CAD normals), on a raised mesh of a model.
 * usage: measure_rate MODEL [ORDER [SIZE_FACTOR]]
 * SPDX-License-Identifier: GPL-2.0-or-later */
#include "mesh/mesh.h"
#include "quality/quality.h"

#include <omp.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

static double now(void) {
  struct timespec t;
  clock_gettime(CLOCK_MONOTONIC, &t);
  return (double)t.tv_sec + 1e-9 * (double)t.tv_nsec;
}

int main(int argc, char **argv) {
  if (argc < 2) {
    fprintf(stderr, "usage: %s MODEL [ORDER [SIZE_FACTOR]]\n", argv[0]);
    return 1;
  }
  int p = argc > 2 ? atoi(argv[2]) : 3;
  double factor = argc > 3 ? atof(argv[3]) : 0;
  hoc_model *model;
  if (hoc_model_open(argv[1], &model) != HOC_OK) {
    fprintf(stderr, "%s\n", hoc_last_error());
    return 1;
  }
  hoc_linear_options o;
  hoc_linear_options_default(&o);
  o.order = p;
  if (factor > 0) o.size_max = model->diagonal / factor;
  hoc_mesh *lin, *m;
  if (hoc_mesh_generate_linear(model, &o, &lin) != HOC_OK ||
      hoc_mesh_elevate(lin, p, HOC_NODES_EQUISPACED, &m) != HOC_OK) {
    fprintf(stderr, "%s\n", hoc_last_error());
    return 1;
  }
  const hoc_quality_tables *t;
  hoc_quality_tables_get(p, HOC_NODES_EQUISPACED, &t);
  size_t ne = m->n_elems, np = (size_t)m->np;
  /* element data gathered once: the kernel's own speed */
  double *normal = malloc(3 * m->n_slots * sizeof *normal), *q = malloc(ne * sizeof *q);
  double *x = malloc(3 * ne * np * sizeof *x), *n = malloc(3 * ne * np * sizeof *n);
  hoc_mesh_slot_normals(m, normal);
  for (size_t e = 0; e < ne; ++e)
    for (size_t i = 0; i < np; ++i) {
      memcpy(x + 3 * (e * np + i), m->xyz + 3 * m->conn[e * np + i], 3 * sizeof *x);
      memcpy(n + 3 * (e * np + i), normal + 3 * m->elem_slot[e * np + i], 3 * sizeof *n);
    }
  int threads = omp_get_max_threads();
  double best = 1e300;
  for (int rep = 0; rep < 5; ++rep) {
    double t0 = now();
#pragma omp parallel for schedule(static)
    for (size_t e = 0; e < ne; ++e) {
      double eta;
      q[e] = hoc_element_quality(t, HOC_MEASURE_SHAPE, x + 3 * e * np, n + 3 * e * np, &eta, NULL);
    }
    double dt = now() - t0;
    if (dt < best) best = dt;
  }
  double bestm = 1e300;
  for (int rep = 0; rep < 3; ++rep) {
    double t0 = now();
    hoc_mesh_measure(m, HOC_MEASURE_SHAPE, q, NULL, NULL);
    double dt = now() - t0;
    if (dt < bestm) bestm = dt;
  }
  printf("%s order %d: %zu elements, %d quadrature + %d node + %d lattice points, %d thread(s)\n",
         argv[1], p, ne, t->nq, t->np, t->nv, threads);
  printf("  kernel only:        %8.3f s  %10.0f elements/s  %10.0f elements/s/core\n", best,
         (double)ne / best, (double)ne / best / threads);
  printf("  with CAD normals:   %8.3f s  %10.0f elements/s  %10.0f elements/s/core\n", bestm,
         (double)ne / bestm, (double)ne / bestm / threads);
  free(normal);
  free(q);
  free(x);
  free(n);
  hoc_mesh_destroy(&m);
  hoc_mesh_destroy(&lin);
  hoc_model_destroy(&model);
  return 0;
}
