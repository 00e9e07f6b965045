/* Files for tests/test_io_readers.py: a hocad mesh of a model, raised to
 * each order given, written through the library in every MSH format and as
 * VTU, with a reference dump of the same mesh straight from the library's
 * arrays, which the Python readers' findings are compared with.
 *
 * usage: io_readers_data MODEL OUTDIR ORDER...
 * For each order P (1..10) it writes in OUTDIR:
 *   pP_41.msh (hoc_mesh_write_msh: the default, MSH 4.1 ASCII), pP_41bin.msh,
 *   pP_22.msh, pP_22bin.msh, pP_41_param.msh, pP_22_param.msh, pP.vtu
 *   (hoc_mesh_write_vtu with the q below), and pP.ref:
 *     hocad-reference 1
 *     order P
 *     nodes N
 *     x y z dim entity_tag u v          (N lines; u v: t 0 on a curve, 0 0 on a vertex)
 *     elements E
 *     face_tag q n_0 ... n_{np-1}       (E lines; 0-based nodes, gmsh order)
 *     lines L
 *     curve_tag n_0 ... n_P             (L lines)
 *   numbers as printf "%.17g" writes them. The mesh is the equispaced one
 *   the files hold (elevated with Fekete nodes, converted), q its shape
 *   measure.
 * SPDX-License-Identifier: GPL-2.0-or-later */
#include "mesh/mesh.h"

#include <stdio.h>
#include <stdlib.h>
#include <string.h>

static int fail(const char *what) {
  fprintf(stderr, "io_readers_data: %s: %s\n", what, hoc_last_error());
  return 1;
}

static int entity_tag(const hoc_mesh *m, size_t i) {
  const hoc_model *model = m->model;
  int e = m->entity[i];
  return m->dim[i] == HOC_ON_FACE    ? model->faces[e].tag
         : m->dim[i] == HOC_ON_CURVE ? model->curves[e].tag
                                     : model->vertices[e].tag;
}

static int write_reference(const hoc_mesh *m, const double *q, const char *path) {
  FILE *f = fopen(path, "w");
  if (!f) return 0;
  int np = m->np, p = m->order;
  fprintf(f, "hocad-reference 1\norder %d\nnodes %zu\n", p, m->n_nodes);
  for (size_t i = 0; i < m->n_nodes; ++i) {
    const double *x = m->xyz + 3 * i, *u = m->param + 2 * i;
    fprintf(f, "%.17g %.17g %.17g %d %d %.17g %.17g\n", x[0], x[1], x[2], m->dim[i],
            entity_tag(m, i), u[0], u[1]);
  }
  fprintf(f, "elements %zu\n", m->n_elems);
  for (size_t e = 0; e < m->n_elems; ++e) {
    fprintf(f, "%d %.17g", m->model->faces[m->elem_face[e]].tag, q[e]);
    for (int k = 0; k < np; ++k)
      fprintf(f, " %zu", m->conn[e * (size_t)np + (size_t)k]);
    fputc('\n', f);
  }
  fprintf(f, "lines %zu\n", m->n_lines);
  for (size_t l = 0; l < m->n_lines; ++l) {
    fprintf(f, "%d", m->model->curves[m->line_curve[l]].tag);
    for (int k = 0; k <= p; ++k)
      fprintf(f, " %zu", m->line_conn[l * (size_t)(p + 1) + (size_t)k]);
    fputc('\n', f);
  }
  return fclose(f) == 0;
}

int main(int argc, char **argv) {
  if (argc < 4) {
    fprintf(stderr, "usage: io_readers_data MODEL OUTDIR ORDER...\n");
    return 2;
  }
  static const struct {
    hoc_msh_options o;
    const char *suffix;
  } formats[] = {{{41, 1, 0}, "41bin"},    {{22, 0, 0}, "22"},       {{22, 1, 0}, "22bin"},
                 {{41, 0, 1}, "41_param"}, {{22, 0, 1}, "22_param"}};
  hoc_model *model = NULL;
  if (hoc_model_open(argv[1], &model) != HOC_OK) return fail(argv[1]);
  hoc_mesh *lin = NULL;
  int code = 0;
  if (hoc_mesh_generate_linear(model, NULL, &lin) != HOC_OK) code = fail("linear mesh");
  for (int a = 3; a < argc && !code; ++a) {
    int p = atoi(argv[a]);
    hoc_mesh *fekete = NULL, *m = NULL;
    double *q = NULL;
    char path[4096];
    if (p < 1 || p > 10) {
      fprintf(stderr, "io_readers_data: order '%s' out of 1..10\n", argv[a]);
      code = 2;
    } else if (hoc_mesh_elevate(lin, p, HOC_NODES_FEKETE, &fekete) != HOC_OK ||
               hoc_mesh_convert(fekete, HOC_NODES_EQUISPACED, &m) != HOC_OK) {
      code = fail("elevation");
    } else if (!(q = malloc(m->n_elems * sizeof *q)) ||
               hoc_mesh_measure(m, HOC_MEASURE_SHAPE, q, NULL, NULL) != HOC_OK) {
      code = fail("measure");
    }
    if (!code) {
      snprintf(path, sizeof path, "%s/p%d.ref", argv[2], p);
      if (!write_reference(m, q, path)) {
        fprintf(stderr, "io_readers_data: cannot write '%s'\n", path);
        code = 1;
      }
    }
    if (!code) {
      snprintf(path, sizeof path, "%s/p%d_41.msh", argv[2], p);
      if (hoc_mesh_write_msh(m, path) != HOC_OK) code = fail(path);
    }
    for (size_t f = 0; f < sizeof formats / sizeof *formats && !code; ++f) {
      snprintf(path, sizeof path, "%s/p%d_%s.msh", argv[2], p, formats[f].suffix);
      if (hoc_mesh_write_msh_with(m, path, &formats[f].o) != HOC_OK) code = fail(path);
    }
    if (!code) {
      snprintf(path, sizeof path, "%s/p%d.vtu", argv[2], p);
      if (hoc_mesh_write_vtu(m, q, path) != HOC_OK) code = fail(path);
    }
    free(q);
    hoc_mesh_destroy(&m);
    hoc_mesh_destroy(&fekete);
  }
  hoc_mesh_destroy(&lin);
  hoc_model_destroy(&model);
  return code;
}
