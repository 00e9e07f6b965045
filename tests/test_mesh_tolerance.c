/* Tolerances from the model: a square whose edge x = 1 bulges 0.03 off the
 * plane of its face (tests/data/square_bumped_edge.brep, edge tolerance
 * 0.03, 2% of the model's size): the model's measured tolerance is that
 * bulge, hocad's own mesh of it is accepted with every node on its entity
 * (the gap recorded), and a mesh read from a file is refused only when a
 * node lies farther from the model than the documented multiple of the
 * tolerance, with the figures in the message.
 * SPDX-License-Identifier: GPL-2.0-or-later */
#include "mesh/mesh.h"
#include "test_util.h"

#include <string.h>

#define DATA HOC_SOURCE_DIR "/tests/data/"

static const double BULGE = 0.03;

/* The text of a file, NUL-terminated (NULL on failure). */
static char *slurp(const char *path) {
  FILE *f = fopen(path, "rb");
  if (!f) return NULL;
  fseek(f, 0, SEEK_END);
  long n = ftell(f);
  rewind(f);
  char *s = malloc((size_t)n + 1);
  if (s && fread(s, 1, (size_t)n, f) != (size_t)n) {
    free(s);
    s = NULL;
  }
  if (s) s[n] = '\0';
  fclose(f);
  return s;
}

/* Copy of the MSH file `in` to `out` with the z coordinate of one node
 * raised by dz: the first node of the first block on an entity of
 * dimension `dim` whose first node has z = 0 and, unless y0 is NaN,
 * y = y0 (for dim 1: a straight edge in the face's plane). Returns that
 * node's tag, 0 if none. */
static long move_node(const char *in, const char *out, int dim, double y0, double dz) {
  char *text = slurp(in);
  if (!text) return 0;
  FILE *f = fopen(out, "w");
  if (!f) {
    free(text);
    return 0;
  }
  long moved = 0;
  int in_nodes = 0, header = 0;
  long left_tags = 0, left_coords = 0, block_n = 0;
  int block_dim = -1, candidate = 0;
  for (char *line = strtok(text, "\n"); line; line = strtok(NULL, "\n")) {
    if (!strcmp(line, "$Nodes")) {
      in_nodes = header = 1;
      fprintf(f, "%s\n", line);
      continue;
    }
    if (!strcmp(line, "$EndNodes")) in_nodes = 0;
    if (!in_nodes) {
      fprintf(f, "%s\n", line);
      continue;
    }
    if (header) { /* numEntityBlocks numNodes minTag maxTag */
      header = 0;
    } else if (!left_tags && !left_coords) { /* entityDim entityTag parametric numNodes */
      int d, tag, par;
      long n;
      if (sscanf(line, "%d %d %d %ld", &d, &tag, &par, &n) == 4) {
        block_dim = d;
        left_tags = left_coords = block_n = n;
      }
    } else if (left_tags) {
      if (left_tags == block_n) candidate = (int)strtol(line, NULL, 10);
      --left_tags;
    } else {
      double x, y, z;
      int consumed = 0, first = left_coords == block_n;
      if (first && !moved && block_dim == dim &&
          sscanf(line, "%lf %lf %lf%n", &x, &y, &z, &consumed) == 3 && (isnan(y0) || fabs(y - y0) < 1e-12) &&
          fabs(z) < 1e-12) {
        fprintf(f, "%.17g %.17g %.17g%s\n", x, y, z + dz, line + consumed);
        moved = candidate;
        --left_coords;
        continue;
      }
      --left_coords;
    }
    fprintf(f, "%s\n", line);
  }
  fclose(f);
  free(text);
  return moved;
}

/* The measured tolerance is the bulge (a sample falls on its top). */
static void test_model_tolerance(hoc_model *model) {
  double t = 0;
  CHECK_OK(hoc_model_tolerance(model, &t));
  printf("tolerance %.6g (diagonal %.6g), curve %d face %d\n", t, model->diagonal,
         model->tolerance_curve, model->tolerance_face);
  CHECK_NEAR(t, BULGE, 1e-9);
  CHECK(model->tolerance_face == 1);
  double limit = 0;
  CHECK_OK(hoc_mesh_given_limit(model, &limit));
  CHECK_NEAR(limit, 4 * BULGE, 1e-9);
}

/* hocad's own mesh: accepted, every node on its entity, the curve nodes
 * of the bulging edge off the face by up to the bulge (recorded). */
static hoc_mesh *test_own_mesh(hoc_model *model) {
  hoc_linear_options o;
  hoc_linear_options_default(&o);
  hoc_mesh *lin = NULL;
  CHECK_OK(hoc_mesh_generate_linear(model, &o, &lin));
  if (!lin) return NULL;
  double dist = 1;
  CHECK_OK(hoc_mesh_max_cad_distance(lin, &dist));
  CHECK(dist <= 1e-12 * model->diagonal);
  double zmax = 0;
  for (size_t i = 0; i < lin->n_nodes; ++i)
    if (lin->dim[i] == HOC_ON_CURVE) zmax = fmax(zmax, lin->xyz[3 * i + 2]);
  printf("own mesh: %zu triangles, curve nodes up to z = %.4g, face gap %.4g\n", lin->n_elems,
         zmax, lin->face_gap);
  CHECK(zmax > 0.9 * BULGE && zmax <= BULGE * (1 + 1e-12));
  CHECK(hoc_mesh_face_gap(lin) > 0.9 * BULGE && hoc_mesh_face_gap(lin) <= BULGE * (1 + 1e-9));
  hoc_mesh *ho = NULL;
  CHECK_OK(hoc_mesh_elevate(lin, 2, HOC_NODES_EQUISPACED, &ho));
  if (ho) {
    CHECK_OK(hoc_mesh_max_cad_distance(ho, &dist));
    CHECK(dist <= 1e-12 * model->diagonal);
  }
  hoc_mesh_destroy(&lin);
  return ho;
}

/* A node of a mesh read from a file moved off the model by `dz`: accepted
 * within 4 times the tolerance, refused beyond with the figures. */
static void check_moved(hoc_model *model, int dim, double dz, int accepted) {
  long tag = move_node("bumped_p2.msh", "bumped_moved.msh", dim, dim == 1 ? 0.0 : NAN, dz);
  CHECK(tag > 0);
  hoc_mesh *m = NULL;
  hoc_status st = hoc_mesh_read_msh(model, "bumped_moved.msh", &m);
  printf("node %ld (dim %d) moved by %.3g: %s%s\n", tag, dim, dz, hoc_status_string(st),
         st ? ": " : "");
  if (st) printf("  %s\n", hoc_last_error());
  if (accepted) {
    CHECK(st == HOC_OK);
    if (m) CHECK_NEAR(m->off_cad, dz, 1e-9);
  } else {
    CHECK(st == HOC_ERR_MISMATCH);
    char node[32];
    snprintf(node, sizeof node, "node %ld ", tag);
    CHECK(strstr(hoc_last_error(), node) != NULL);
    CHECK(strstr(hoc_last_error(), "the model's own tolerance is 0.03)") != NULL);
    CHECK(strstr(hoc_last_error(), "more than the 0.12 allowed") != NULL);
  }
  hoc_mesh_destroy(&m);
  remove("bumped_moved.msh");
}

int main(void) {
  hoc_model *model = NULL;
  CHECK_OK(hoc_model_open(DATA "square_bumped_edge.brep", &model));
  if (!model) goto end;
  test_model_tolerance(model);
  hoc_mesh *ho = test_own_mesh(model);
  if (ho) {
    /* written and read back as a file: accepted */
    CHECK_OK(hoc_mesh_write_msh(ho, "bumped_p2.msh"));
    hoc_mesh *back = NULL;
    CHECK_OK(hoc_mesh_read_msh(model, "bumped_p2.msh", &back));
    if (back) CHECK(back->n_elems == ho->n_elems && back->off_cad <= 1e-12);
    hoc_mesh_destroy(&back);
    /* a node of the straight edge y = 0, and a corner inside the face */
    check_moved(model, 1, 0.9 * BULGE, 1);
    check_moved(model, 1, 3 * BULGE, 1);
    check_moved(model, 1, 5 * BULGE, 0);
    check_moved(model, 2, 3 * BULGE, 1);
    check_moved(model, 2, 5 * BULGE, 0);
    remove("bumped_p2.msh");
  }
  hoc_mesh_destroy(&ho);
  hoc_model_destroy(&model);
end:
  printf("%d passed, %d failed\n", test_passed_, test_failed_);
  return test_failed_ != 0;
}
