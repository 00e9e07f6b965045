/* One local repair as `hocad mesh` makes it from order 6 on: read a mesh
 * (e.g. the one `hocad mesh MODEL --order 10 --refinements 0 -o IN.msh`
 * writes: the first optimisation's result), split its tangled elements,
 * and optimise only the children and two rings around them
 * (hoc_optimize_options.free_elements), printing each sweep's tangled
 * count and the result. With `none`, nothing is split: the tangled
 * elements and two rings around them are optimised as they are.
 * usage: local_repair MODEL IN.msh [red-green|longest-edge|none [OUT.msh]]
 *        (OMP_NUM_THREADS threads)
 * SPDX-License-Identifier: GPL-2.0-or-later */
#include "hocad.h"

#include <stdio.h>
#include <stdlib.h>
#include <string.h>

static int progress(void *user, const hoc_optimize_iteration *it) {
  (void)user;
  printf("sweep %3d: f %.6g, min q %.4f, %zu tangled, %zu nodes moved (%.1f s)%s\n",
         it->iteration, it->objective, it->min_q, it->tangled, it->moved, it->seconds,
         it->attempt == 2 ? ", second attempt" : "");
  fflush(stdout);
  return 0;
}

static int fail(const char *what) {
  fprintf(stderr, "local_repair: %s: %s\n", what, hoc_last_error());
  return 1;
}

int main(int argc, char **argv) {
  if (argc < 3 || argc > 5) {
    fprintf(stderr, "usage: local_repair MODEL IN.msh [red-green|longest-edge|none [OUT.msh]]\n");
    return 2;
  }
  hoc_split_kind kind = HOC_SPLIT_RED_GREEN;
  int split = !(argc > 3 && !strcmp(argv[3], "none"));
  if (argc > 3 && !strcmp(argv[3], "longest-edge")) kind = HOC_SPLIT_LONGEST_EDGE;
  else if (argc > 3 && split && strcmp(argv[3], "red-green")) {
    fprintf(stderr, "local_repair: unknown split '%s'\n", argv[3]);
    return 2;
  }
  hoc_model *model = NULL;
  hoc_mesh *mesh = NULL, *fine = NULL;
  unsigned char *tangled = NULL, *pieces = NULL, *children = NULL;
  int code = 1;
  if (hoc_model_open(argv[1], &model) != HOC_OK) return fail(argv[1]);
  if (hoc_mesh_read_msh(model, argv[2], &mesh) != HOC_OK) {
    code = fail(argv[2]);
    goto done;
  }
  size_t ne = hoc_mesh_num_elements(mesh);
  tangled = calloc(ne ? ne : 1, 1);
  pieces = calloc(ne ? ne : 1, 1);
  if (!tangled || !pieces) {
    fprintf(stderr, "local_repair: out of memory\n");
    goto done;
  }
  hoc_quality_stats s;
  if (hoc_mesh_measure(mesh, HOC_MEASURE_SHAPE, NULL, tangled, &s) != HOC_OK) {
    code = fail("measure");
    goto done;
  }
  printf("input: %zu elements, %zu tangled\n", ne, s.tangled);
  if (!split) { /* the same elements: the tangled ones are the region's core */
    if (hoc_mesh_copy(mesh, &fine) != HOC_OK) {
      code = fail("copy");
      goto done;
    }
  } else if (hoc_mesh_split(mesh, tangled, kind, &fine, pieces) != HOC_OK) {
    code = fail("split");
    goto done;
  }
  size_t nf = hoc_mesh_num_elements(fine), j = 0;
  if (!(children = calloc(nf ? nf : 1, 1))) {
    fprintf(stderr, "local_repair: out of memory\n");
    goto done;
  }
  if (!split) memcpy(children, tangled, ne);
  for (size_t e = 0; split && e < ne; j += pieces[e++])
    for (size_t c = j; c < j + pieces[e] && c < nf; ++c) children[c] = pieces[e] > 1;
  if (hoc_mesh_measure(fine, HOC_MEASURE_SHAPE, NULL, NULL, &s) != HOC_OK) {
    code = fail("measure");
    goto done;
  }
  printf("split (%s): %zu elements, %zu tangled\n",
         !split ? "none" : kind == HOC_SPLIT_RED_GREEN ? "red-green" : "longest edge", nf,
         s.tangled);
  hoc_optimize_options o;
  hoc_optimize_options_default(&o);
  o.progress = progress;
  o.free_elements = children;
  o.free_rings = 2; /* as hocad's LOCAL_RINGS */
  hoc_optimize_result r;
  if (hoc_mesh_optimize(fine, &o, &r) != HOC_OK) {
    code = fail("optimize");
    goto done;
  }
  if (hoc_mesh_measure(fine, HOC_MEASURE_SHAPE, NULL, NULL, &s) != HOC_OK) {
    code = fail("measure");
    goto done;
  }
  printf("result: %zu tangled, min q %.4f, mean q %.4f; %d sweeps (fewest at %d), %zu by the "
         "polish, %.1f s\n",
         s.tangled, s.min, s.mean, r.iterations, r.best_iteration, r.diagnostics.polished, r.seconds);
  if (argc > 4 && hoc_mesh_write_msh(fine, argv[4]) != HOC_OK) {
    code = fail(argv[4]);
    goto done;
  }
  code = 0;
done:
  free(tangled);
  free(pieces);
  free(children);
  hoc_mesh_destroy(&fine);
  hoc_mesh_destroy(&mesh);
  hoc_model_destroy(&model);
  return code;
}
