/* Interior nodes that follow the edges on CAD curves
 * (hoc_mesh_blend_interior, and the raise of hocad mesh that keeps it per
 * element where it helps).
 *
 * Raised straight in (u, v), an element along a curved CAD curve has its
 * edge nodes on the curve and its interior nodes on the straight map: where
 * the curve bends by more than the element is wide, the interior nodes lie
 * beyond the edge and the element folds. gear_f360.step's linear mesh
 * raised to order 5 so has over a hundred folded elements along the arcs
 * of its teeth. Blending each curved edge's displacement into the element
 * leaves a handful; the nodes on edges and the elements without a curved
 * edge stay as they were. hoc_mesh_model's raise keeps the blending.
 * SPDX-License-Identifier: GPL-2.0-or-later */
#include "hocad.h"
#include "mesh/mesh.h"
#include "test_util.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

static size_t count_tangled(const hoc_mesh *m) {
  size_t ne = hoc_mesh_num_elements(m), n = 0;
  unsigned char *t = calloc(ne + 1, 1);
  CHECK_OK(hoc_mesh_measure(m, HOC_MEASURE_SHAPE, NULL, t, NULL));
  for (size_t e = 0; e < ne; ++e)
    n += t[e];
  free(t);
  return n;
}

/* 1 if element e has an edge node on a CAD curve. */
static int on_curve(const hoc_mesh *m, size_t e) {
  for (int k = 3; k < 3 * m->order; ++k)
    if (m->dim[m->conn[e * (size_t)m->np + (size_t)k]] == HOC_ON_CURVE) return 1;
  return 0;
}

static void test_blend(const hoc_mesh *lin, int p) {
  hoc_mesh *a = NULL, *b = NULL;
  CHECK_OK(hoc_mesh_elevate(lin, p, HOC_NODES_EQUISPACED, &a));
  if (a) CHECK_OK(hoc_mesh_copy(a, &b));
  if (!b) {
    hoc_mesh_destroy(&a);
    return;
  }
  size_t ne = b->n_elems, np = (size_t)b->np, n_curved = 0, moved = 0, kept = 1, same = 1;
  unsigned char *all = malloc(ne + 1), *interior = calloc(b->n_nodes + 1, 1);
  memset(all, 1, ne + 1);
  for (size_t e = 0; e < ne; ++e)
    for (size_t k = 3 * (size_t)p; k < np; ++k)
      interior[b->conn[e * np + k]] = 1;
  CHECK_OK(hoc_mesh_blend_interior(lin, b, all));
  for (size_t i = 0; i < b->n_nodes; ++i)
    if (!interior[i])
      kept &= !memcmp(a->xyz + 3 * i, b->xyz + 3 * i, 3 * sizeof *a->xyz) &&
              !memcmp(a->param + 2 * i, b->param + 2 * i, 2 * sizeof *a->param);
  double size = 0; /* the model's extent: a scale for the nodes' moves */
  for (size_t i = 0; i < a->n_nodes; ++i)
    for (int d = 0; d < 3; ++d)
      size = fmax(size, fabs(a->xyz[3 * i + d]));
  for (size_t e = 0; e < ne; ++e) {
    int curved = on_curve(b, e);
    n_curved += curved;
    for (size_t k = 3 * (size_t)p; k < np; ++k) {
      size_t i = b->conn[e * np + k];
      double d = 0;
      for (int c = 0; c < 3; ++c)
        d = fmax(d, fabs(a->xyz[3 * i + c] - b->xyz[3 * i + c]));
      if (curved) moved += d > 1e-9 * size;
      else same &= d <= 1e-12 * size;
    }
  }
  size_t ta = count_tangled(a), tb = count_tangled(b);
  printf("order %d: %zu of %zu elements along curves, %zu interior nodes moved; tangled %zu "
         "straight, %zu blended\n",
         p, n_curved, ne, moved, ta, tb);
  CHECK(kept);     /* corners and edge nodes stay */
  CHECK(same);     /* elements without a curved edge stay on their map */
  CHECK(moved > 0);
  CHECK(ta > 50 && 10 * tb < ta);
  free(all);
  free(interior);
  hoc_mesh_destroy(&a);
  hoc_mesh_destroy(&b);
}

/* hoc_mesh_model's raise: far fewer folds than the straight raise. */
static void test_pipeline(hoc_model *model, const hoc_mesh *lin) {
  hoc_mesh_options o;
  hoc_mesh_options_default(&o);
  o.order = 5;
  o.optimize = 0;
  o.linear = lin;
  hoc_mesh *mesh = NULL, *straight = NULL;
  hoc_report *r = NULL;
  CHECK_OK(hoc_mesh_model(model, &o, &mesh, &r));
  CHECK_OK(hoc_mesh_elevate(lin, 5, HOC_NODES_EQUISPACED, &straight));
  if (r && straight) {
    size_t raised = hoc_report_stage(r, 1)->stats.tangled, ts = count_tangled(straight);
    printf("hoc_mesh_model's raise to order 5: %zu tangled (straight: %zu)\n", raised, ts);
    CHECK(4 * raised < ts);
  }
  hoc_report_destroy(&r);
  hoc_mesh_destroy(&mesh);
  hoc_mesh_destroy(&straight);
}

static void test_errors(const hoc_mesh *lin) {
  hoc_mesh *a = NULL;
  unsigned char flag[1] = {1};
  CHECK_STATUS(hoc_mesh_blend_interior(NULL, NULL, flag), HOC_ERR_ARGUMENT);
  CHECK_OK(hoc_mesh_elevate(lin, 2, HOC_NODES_EQUISPACED, &a));
  if (a) CHECK_STATUS(hoc_mesh_blend_interior(lin, a, NULL), HOC_ERR_ARGUMENT);
  hoc_mesh_destroy(&a);
}

int main(void) {
  hoc_model *model = NULL;
  CHECK_OK(hoc_model_open(HOC_MODELS_DIR "/gear_f360.step", &model));
  hoc_mesh *lin = NULL;
  hoc_linear_options lo;
  hoc_linear_options_default(&lo);
  lo.order = 5;
  if (model) CHECK_OK(hoc_mesh_generate_linear(model, &lo, &lin));
  if (lin) {
    test_blend(lin, 5);
    test_pipeline(model, lin);
    test_errors(lin);
  }
  hoc_mesh_destroy(&lin);
  hoc_model_destroy(&model);
  return test_report();
}
