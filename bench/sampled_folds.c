/* Folds between the samples after the optimiser's first phase: mesh MODEL
 * as `hocad mesh` does, raise to order P, optimise, and keep the state of
 * the last sweep whose samples said untangled before a sweep that did not
 * (the exact phase's first sweep counts by the exact tests: the run is
 * stopped there). That state is measured as `hocad quality` measures:
 * elements tangled at the samples, and folded between them by the exact
 * edge test and by the exact whole-triangle test.
 * usage: sampled_folds MODEL [ORDER [OUT.msh]]   (OMP_NUM_THREADS threads)
 * SPDX-License-Identifier: GPL-2.0-or-later */
#include "mesh/mesh.h"
#include "quality/quality.h"

#include <stdio.h>
#include <stdlib.h>
#include <string.h>

typedef struct watch {
  hoc_mesh *mesh;   /* being optimised */
  hoc_mesh *kept;   /* copy at the last sweep the samples said untangled */
  int kept_sweep;   /* its sweep */
  double kept_time; /* and seconds */
  int failed;
} watch;

static int progress(void *user, const hoc_optimize_iteration *it) {
  watch *w = user;
  if (it->tangled == 0) {
    hoc_mesh_destroy(&w->kept);
    if (hoc_mesh_copy(w->mesh, &w->kept) != HOC_OK) {
      w->failed = 1;
      return 1;
    }
    w->kept_sweep = it->iteration;
    w->kept_time = it->seconds;
    return 0;
  }
  /* a tangled sweep after an untangled one: the exact phase has begun */
  return w->kept != NULL;
}

int main(int argc, char **argv) {
  if (argc < 2) {
    fprintf(stderr, "usage: %s MODEL [ORDER [OUT.msh]]\n", argv[0]);
    return 1;
  }
  int p = argc > 2 ? atoi(argv[2]) : 10;
  hoc_model *model = NULL;
  hoc_mesh *lin = NULL, *m = NULL;
  hoc_linear_options lo;
  hoc_linear_options_default(&lo);
  lo.order = p;
  if (hoc_model_open(argv[1], &model) != HOC_OK ||
      hoc_mesh_generate_linear(model, &lo, &lin) != HOC_OK ||
      hoc_mesh_elevate(lin, p, HOC_NODES_EQUISPACED, &m) != HOC_OK) {
    fprintf(stderr, "%s\n", hoc_last_error());
    hoc_mesh_destroy(&lin);
    hoc_model_destroy(&model);
    return 1;
  }
  watch w = {m, NULL, 0, 0, 0};
  hoc_optimize_options oo;
  hoc_optimize_options_default(&oo);
  oo.progress = progress;
  oo.progress_user = &w;
  hoc_optimize_result res;
  hoc_status st = hoc_mesh_optimize(m, &oo, &res);
  int code = 0;
  if (w.failed || (st != HOC_OK && st != HOC_ERR_INTERRUPTED)) {
    fprintf(stderr, "%s\n", hoc_last_error());
    code = 1;
  } else if (!w.kept) {
    printf("%s p=%d: the samples never said untangled\n", argv[1], p);
  } else {
    const hoc_quality_tables *t;
    double *normal = hoc_calloc(3 * w.kept->n_slots + 3, sizeof *normal);
    double *x = hoc_calloc(6 * (size_t)w.kept->np, sizeof *x);
    if (!normal || !x) {
      fprintf(stderr, "out of memory\n");
      code = 1;
    } else if (hoc_quality_tables_get(p, w.kept->nodeset, &t) != HOC_OK ||
               hoc_mesh_slot_normals(w.kept, normal) != HOC_OK) {
      fprintf(stderr, "%s\n", hoc_last_error());
      code = 1;
    }
    size_t sampled = 0, edges = 0, inside = 0, folded = 0, np = (size_t)w.kept->np;
    for (size_t e = 0; !code && e < w.kept->n_elems; ++e) {
      double *n = x + 3 * np;
      for (size_t i = 0; i < np; ++i) {
        memcpy(x + 3 * i, w.kept->xyz + 3 * w.kept->conn[e * np + i], 3 * sizeof *x);
        memcpy(n + 3 * i, normal + 3 * w.kept->elem_slot[e * np + i], 3 * sizeof *n);
      }
      int s = hoc_element_tangled(t, x, n, 0), ed = hoc_element_edges_folded(t, x, n),
          in = hoc_element_interior_folded(t, x, n);
      sampled += s;
      edges += !s && ed;
      inside += !s && in;
      folded += s || ed || in;
    }
    if (!code)
      printf("%s p=%d: samples untangled after sweep %d (%.1f s); %zu elements: %zu tangled "
             "at the samples, %zu folded between them (%zu on an edge, %zu inside)\n",
             argv[1], p, w.kept_sweep, w.kept_time, w.kept->n_elems, sampled, folded - sampled,
             edges, inside);
    if (!code && argc > 3 && hoc_mesh_write_msh(w.kept, argv[3]) != HOC_OK) {
      fprintf(stderr, "%s\n", hoc_last_error());
      code = 1;
    }
    free(normal);
    free(x);
  }
  hoc_mesh_destroy(&w.kept);
  hoc_mesh_destroy(&m);
  hoc_mesh_destroy(&lin);
  hoc_model_destroy(&model);
  return code;
}
