/* What reading a .msh costs, with and without parametric coordinates:
 * hoc_msh_read (the file's text or bytes to arrays) and hoc_mesh_read_msh
 * (that, then every node without parameters located on its CAD entity, and
 * the mesh assembled), best of --repeat runs, per node; and how far the
 * located nodes are from the positions the file gives. With --write, the
 * mesh read is written again in the format given (to make the same mesh
 * without parameters, or as MSH 2.2).
 *
 * usage: read_msh MODEL FILE.msh [--repeat N] [--write OUT.msh [--version 41|22]
 *                 [--binary] [--parametric]]
 * SPDX-License-Identifier: GPL-2.0-or-later */
#include "io/io.h"
#include "mesh/mesh.h"

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
  if (argc < 3) {
    fprintf(stderr, "usage: read_msh MODEL FILE.msh [--repeat N] [--write OUT.msh "
                    "[--version 41|22] [--binary] [--parametric]]\n");
    return 1;
  }
  int repeat = 3;
  const char *out = NULL;
  hoc_msh_options o;
  hoc_msh_options_default(&o);
  for (int a = 3; a < argc; ++a) {
    if (!strcmp(argv[a], "--repeat") && a + 1 < argc)
      repeat = atoi(argv[++a]);
    else if (!strcmp(argv[a], "--write") && a + 1 < argc)
      out = argv[++a];
    else if (!strcmp(argv[a], "--version") && a + 1 < argc)
      o.version = atoi(argv[++a]);
    else if (!strcmp(argv[a], "--binary"))
      o.binary = 1;
    else if (!strcmp(argv[a], "--parametric"))
      o.parametric = 1;
    else {
      fprintf(stderr, "read_msh: unknown argument '%s'\n", argv[a]);
      return 1;
    }
  }
  if (repeat < 1) repeat = 1;
  hoc_model *model = NULL;
  if (hoc_model_open(argv[1], &model) != HOC_OK) {
    fprintf(stderr, "read_msh: %s\n", hoc_last_error());
    return 2;
  }
  double parse = 1e300, whole = 1e300;
  size_t nodes = 0, elements = 0, with_param = 0;
  hoc_mesh *mesh = NULL;
  int code = 0;
  for (int r = 0; r < repeat && !code; ++r) {
    hoc_msh_raw raw;
    double t0 = now();
    if (hoc_msh_read(argv[2], &raw) != HOC_OK) {
      code = 2;
      break;
    }
    double t1 = now();
    with_param = 0;
    for (size_t i = 0; i < raw.n_nodes; ++i)
      with_param += raw.has_param[i];
    hoc_msh_raw_free(&raw);
    hoc_mesh_destroy(&mesh);
    double t2 = now();
    if (hoc_mesh_read_msh(model, argv[2], &mesh) != HOC_OK) {
      code = 2;
      break;
    }
    double t3 = now();
    if (t1 - t0 < parse) parse = t1 - t0;
    if (t3 - t2 < whole) whole = t3 - t2;
    nodes = hoc_mesh_num_nodes(mesh);
    elements = hoc_mesh_num_elements(mesh);
  }
  if (code) {
    fprintf(stderr, "read_msh: %s\n", hoc_last_error());
  } else {
    double off = 0;
    hoc_mesh_max_cad_distance(mesh, &off);
    printf("%s: order %d, %zu elements, %zu nodes (%zu with parameters in the file)\n", argv[2],
           hoc_mesh_order(mesh), elements, nodes, with_param);
    printf("  parse %.3f s (%.3f us/node), read and locate %.3f s (%.3f us/node), best of %d\n",
           parse, 1e6 * parse / (double)nodes, whole, 1e6 * whole / (double)nodes, repeat);
    printf("  largest distance of a node's position from its located CAD point: %.3g "
           "(model diagonal %.3g)\n",
           off, model->diagonal);
    if (out && hoc_mesh_write_msh_with(mesh, out, &o) != HOC_OK) {
      fprintf(stderr, "read_msh: %s\n", hoc_last_error());
      code = 3;
    }
  }
  hoc_mesh_destroy(&mesh);
  hoc_model_destroy(&model);
  return code;
}
