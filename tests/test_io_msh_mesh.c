/* hocad meshes of bundled models through every MSH format the writer knows
 * (4.1 and 2.2, ASCII and binary, with and without parametric coordinates)
 * and back with hoc_mesh_read_msh: the same elements (in the file's order:
 * grouped by face tag, stable), nodes bit for bit, the same classification
 * and curve lines, parameters bit for bit from parametric files and located
 * otherwise (each position within 1e-12 of the model's size of its located
 * CAD point), the same q; and writing what was read gives the same file
 * byte for byte. The default is MSH 4.1 ASCII without parameters. Models:
 * the screw (orders 2 to 10), periodic_u_cst (a periodic face with a pole)
 * and the bottle (a curve whose parametrisation slows down and doubles
 * back near its start, where Newton from the vertex finds a local minimum).
 * SPDX-License-Identifier: GPL-2.0-or-later */
#include "io/io.h"
#include "mesh/mesh.h"
#include "test_fixtures.h"
#include "test_util.h"

#include <stdint.h>
#include <stdio.h>
#include <string.h>

static const struct {
  hoc_msh_options o;
  const char *suffix;
} formats[] = {{{41, 0, 0}, "41"},          {{41, 0, 1}, "41_param"},   {{41, 1, 0}, "41bin"},
               {{41, 1, 1}, "41bin_param"}, {{22, 0, 0}, "22"},         {{22, 0, 1}, "22_param"},
               {{22, 1, 0}, "22bin"},       {{22, 1, 1}, "22bin_param"}};

static int same_bits(double a, double b) { return !memcmp(&a, &b, sizeof a); }

static int same_file(const char *a, const char *b) {
  size_t na, nb;
  char *x = fixture_slurp(a, &na), *y = fixture_slurp(b, &nb);
  int same = x && y && na == nb && !memcmp(x, y, na);
  free(x);
  free(y);
  return same;
}

/* The writer's element order: stable by face tag. order[k] = element of m. */
static void file_order(const hoc_mesh *m, size_t *order) {
  size_t k = 0;
  int last = INT32_MIN;
  for (;;) {
    int next = INT32_MAX, found = 0;
    for (size_t e = 0; e < m->n_elems; ++e) {
      int t = m->model->faces[m->elem_face[e]].tag;
      if (t > last && t <= next) next = t, found = 1;
    }
    if (!found) break;
    for (size_t e = 0; e < m->n_elems; ++e)
      if (m->model->faces[m->elem_face[e]].tag == next) order[k++] = e;
    last = next;
  }
}

/* Does r (read from a file) hold the mesh `ref`? Nodes match through the
 * elements; positions and classification must be identical, parameters
 * identical if `parametric`, and q within `q_tol` (0: bit for bit). */
static int same_as_written(const hoc_mesh *ref, const hoc_mesh *r, int parametric,
                           const double *q_ref, double q_tol, const char *path) {
  int np = ref->np, ok = 1;
  if (r->order != ref->order || r->n_elems != ref->n_elems || r->n_nodes != ref->n_nodes ||
      r->n_lines != ref->n_lines || r->nodeset != HOC_NODES_EQUISPACED) {
    fprintf(stderr,
            "%s: order %d, %zu elements, %zu nodes, %zu lines (%d, %zu, %zu, %zu written)\n", path,
            r->order, r->n_elems, r->n_nodes, r->n_lines, ref->order, ref->n_elems, ref->n_nodes,
            ref->n_lines);
    return 0;
  }
  size_t *order = malloc(ref->n_elems * sizeof *order);
  size_t *map = malloc(ref->n_nodes * sizeof *map), *rev = malloc(ref->n_nodes * sizeof *rev);
  double *q = malloc(ref->n_elems * sizeof *q);
  if (!order || !map || !rev || !q) {
    free(order), free(map), free(rev), free(q);
    return 0;
  }
  file_order(ref, order);
  for (size_t i = 0; i < ref->n_nodes; ++i)
    map[i] = rev[i] = SIZE_MAX;
  for (size_t k = 0; k < ref->n_elems && ok; ++k) {
    size_t e = order[k];
    ok &= r->elem_face[k] == ref->elem_face[e];
    for (int j = 0; j < np && ok; ++j) {
      size_t a = ref->conn[e * (size_t)np + (size_t)j], b = r->conn[k * (size_t)np + (size_t)j];
      if (map[a] == SIZE_MAX && rev[b] == SIZE_MAX) map[a] = b, rev[b] = a;
      ok &= map[a] == b && rev[b] == a;
    }
  }
  if (!ok) fprintf(stderr, "%s: other elements\n", path);
  int nodes_ok = ok, class_ok = ok, param_ok = ok;
  for (size_t a = 0; a < ref->n_nodes && ok; ++a) {
    size_t b = map[a];
    if (b == SIZE_MAX) {
      ok = nodes_ok = 0;
      break;
    }
    for (int c = 0; c < 3; ++c)
      nodes_ok &= same_bits(r->xyz[3 * b + (size_t)c], ref->xyz[3 * a + (size_t)c]);
    class_ok &= r->dim[b] == ref->dim[a] && r->entity[b] == ref->entity[a];
    if (parametric)
      for (int c = 0; c < ref->dim[a]; ++c)
        param_ok &= same_bits(r->param[2 * b + (size_t)c], ref->param[2 * a + (size_t)c]);
  }
  if (!nodes_ok) fprintf(stderr, "%s: other node positions\n", path);
  if (!class_ok) fprintf(stderr, "%s: other classification\n", path);
  if (!param_ok) fprintf(stderr, "%s: other parameters\n", path);
  ok &= nodes_ok && class_ok && param_ok;
  /* curve lines: the same set, in the file's order (by curve tag, stable) */
  for (size_t l = 0; l < ref->n_lines && ok; ++l) {
    int found = 0;
    for (size_t s = 0; s < r->n_lines && !found; ++s) {
      int same = r->line_curve[s] == ref->line_curve[l];
      for (int j = 0; j <= ref->order && same; ++j)
        same = r->line_conn[s * (size_t)(ref->order + 1) + (size_t)j] ==
               map[ref->line_conn[l * (size_t)(ref->order + 1) + (size_t)j]];
      found = same;
    }
    if (!found) fprintf(stderr, "%s: line %zu missing\n", path, l);
    ok &= found;
  }
  /* q, element by element */
  double worst = 0;
  if (ok && hoc_mesh_measure(r, HOC_MEASURE_SHAPE, q, NULL, NULL) == HOC_OK) {
    for (size_t k = 0; k < ref->n_elems; ++k) {
      double a = q_ref[order[k]], b = q[k];
      if (q_tol == 0 ? !same_bits(a, b) : !(fabs(a - b) <= q_tol)) ok = 0;
      if (fabs(a - b) > worst) worst = fabs(a - b);
    }
    if (!ok) fprintf(stderr, "%s: q differs by up to %.3g\n", path, worst);
  } else {
    ok = 0;
  }
  free(order), free(map), free(rev), free(q);
  return ok;
}

static void test_model(const char *name, const int *orders, int n_orders) {
  char path[1024];
  snprintf(path, sizeof path, "%s/%s", HOC_MODELS_DIR, name);
  hoc_model *model = NULL;
  CHECK_OK(hoc_model_open(path, &model));
  if (!model) return;
  hoc_mesh *lin = NULL;
  CHECK_OK(hoc_mesh_generate_linear(model, NULL, &lin));
  for (int k = 0; k < n_orders && lin; ++k) {
    int p = orders[k];
    hoc_mesh *fekete = NULL, *m = NULL;
    CHECK_OK(hoc_mesh_elevate(lin, p, HOC_NODES_FEKETE, &fekete));
    if (!fekete) continue;
    /* the files hold the equispaced nodes of the same elements */
    CHECK_OK(hoc_mesh_convert(fekete, HOC_NODES_EQUISPACED, &m));
    double *q = m ? malloc(m->n_elems * sizeof *q) : NULL;
    if (!m || !q || hoc_mesh_measure(m, HOC_MEASURE_SHAPE, q, NULL, NULL) != HOC_OK) {
      CHECK(0);
      free(q), hoc_mesh_destroy(&m), hoc_mesh_destroy(&fekete);
      continue;
    }
    /* the writer converts a Fekete mesh to the same file */
    char a[256], b[256];
    snprintf(a, sizeof a, "%.64s_p%d_fekete.msh", name, p);
    snprintf(b, sizeof b, "%.64s_p%d_41.msh", name, p);
    CHECK_OK(hoc_mesh_write_msh(fekete, a));
    CHECK_OK(hoc_mesh_write_msh_with(m, b, NULL));
    CHECK(same_file(a, b));
    remove(a), remove(b); /* megabytes each: none is kept */
    size_t located = 0;
    for (size_t f = 0; f < sizeof formats / sizeof *formats; ++f) {
      const hoc_msh_options *o = &formats[f].o;
      snprintf(a, sizeof a, "%.64s_p%d_%s.msh", name, p, formats[f].suffix);
      CHECK_OK(hoc_mesh_write_msh_with(m, a, o));
      hoc_mesh *r = NULL;
      CHECK_OK(hoc_mesh_read_msh(model, a, &r));
      if (!r) continue;
      /* parameters from the file: the same q bit for bit; located: the
       * same positions, normals from parameters found by Newton to the
       * position (1e-12 of q is far above that rounding, far below any
       * difference in the elements) */
      CHECK(same_as_written(m, r, o->parametric, q, o->parametric ? 0 : 1e-12, a));
      double dist = 1;
      CHECK_OK(hoc_mesh_max_cad_distance(r, &dist));
      if (!(dist <= 1e-12 * model->diagonal))
        fprintf(stderr, "%s: %.3g from the CAD (diag %.3g)\n", a, dist, model->diagonal);
      CHECK(dist <= 1e-12 * model->diagonal);
      if (!o->parametric) located += r->n_nodes;
      /* what was read writes the same file again */
      snprintf(b, sizeof b, "%.64s_p%d_%s_again.msh", name, p, formats[f].suffix);
      CHECK_OK(hoc_mesh_write_msh_with(r, b, o));
      CHECK(same_file(a, b));
      remove(a), remove(b);
      hoc_mesh_destroy(&r);
    }
    printf("%s order %d: %zu elements, %zu nodes, %zu lines, every format read back "
           "(%zu nodes located)\n",
           name, p, m->n_elems, m->n_nodes, m->n_lines, located);
    free(q);
    hoc_mesh_destroy(&m);
    hoc_mesh_destroy(&fekete);
  }
  hoc_mesh_destroy(&lin);
  hoc_model_destroy(&model);
}

static void test_options(void) {
  char path[1024];
  snprintf(path, sizeof path, "%s/%s", HOC_MODELS_DIR, "screw.step");
  hoc_model *model = NULL;
  CHECK_OK(hoc_model_open(path, &model));
  if (!model) return;
  hoc_mesh *lin = NULL, *m = NULL;
  CHECK_OK(hoc_mesh_generate_linear(model, NULL, &lin));
  if (lin) CHECK_OK(hoc_mesh_elevate(lin, 2, HOC_NODES_EQUISPACED, &m));
  if (m) {
    hoc_msh_options o;
    memset(&o, 0x5a, sizeof o);
    hoc_msh_options_default(&o);
    CHECK(o.version == 41 && o.binary == 0 && o.parametric == 0);
    hoc_msh_options_default(NULL); /* no-op */
    /* defaults: 4.1 ASCII, no parametric node block */
    CHECK_OK(hoc_mesh_write_msh(m, "options_default.msh"));
    size_t n;
    char *text = fixture_slurp("options_default.msh", &n);
    CHECK(text && n > 20 && !strncmp(text, "$MeshFormat\n4.1 0 8\n", 20));
    free(text);
    hoc_msh_raw raw;
    CHECK_OK(hoc_msh_read("options_default.msh", &raw));
    int plain = raw.n_nodes == m->n_nodes;
    for (size_t i = 0; i < raw.n_nodes; ++i)
      plain &= !raw.has_param[i];
    CHECK(plain);
    hoc_msh_raw_free(&raw);
    CHECK_OK(hoc_mesh_write_msh_with(m, "options_explicit.msh", &o));
    CHECK(same_file("options_default.msh", "options_explicit.msh"));
    const hoc_msh_options bad[] = {{0, 0, 0}, {21, 0, 0}, {41, 2, 0}, {22, 0, 7}};
    for (size_t k = 0; k < sizeof bad / sizeof *bad; ++k)
      CHECK_STATUS(hoc_mesh_write_msh_with(m, "options_bad.msh", &bad[k]), HOC_ERR_ARGUMENT);
    FILE *f = fopen("options_bad.msh", "r");
    CHECK(f == NULL);
    if (f) fclose(f);
    CHECK_STATUS(hoc_mesh_write_msh_with(NULL, "options_bad.msh", NULL), HOC_ERR_ARGUMENT);
    CHECK_STATUS(hoc_mesh_write_msh_with(m, "", NULL), HOC_ERR_ARGUMENT);
  }
  hoc_mesh_destroy(&m);
  hoc_mesh_destroy(&lin);
  hoc_model_destroy(&model);
}

int main(void) {
  test_options();
  const int screw[] = {2, 3, 5, 10}, periodic[] = {2, 5}, bottle[] = {2};
  test_model("screw.step", screw, 4);
  test_model("periodic_u_cst.step", periodic, 2); /* a periodic face and its seam */
  test_model("occt_bottle.brep", bottle, 1);
  return test_report();
}
