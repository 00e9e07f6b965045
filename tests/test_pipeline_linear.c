/* Inverted linear triangles (the pipeline's hoc_repair_linear) and faces
 * that fold (hoc_mesh_element_folds).
 *
 * t106_blade_face.brep: gmsh 4.8's default (Frontal-Delaunay) mesh of this
 * B-spline blade face at edges up to 46 has straight triangles inverted on
 * the CAD, on a face that does not fold; hoc_mesh_model meshes the face
 * again with MeshAdapt and its linear stage has none. hocad's edge swaps
 * (mesh/swap.c) leave pairs with an inverted triangle to that repair: a
 * swap that untangles them locally leaves order 10 of the whole T106
 * tangled on this face and costs two remeshings (434 s, 22 093 elements,
 * against 30 s and 790).
 *
 * surf114_face1.brep: a spline patch whose normal reverses along a curve
 * near each end of u (phi_v changes sign there): every mesh of it whose
 * edges do not follow those folds has elements across them, which
 * hoc_mesh_model names and, when they stay tangled, splits instead of
 * meshing the face again finer.
 * SPDX-License-Identifier: GPL-2.0-or-later */
#include "hocad.h"
#include "mesh/mesh.h"
#include "pipeline/pipeline.h"
#include "test_util.h"

#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#define DATA HOC_SOURCE_DIR "/tests/data/"

/* The edge bound at which gmsh inverts triangles of the blade face (the
 * whole T106 model's default: its bounding-box diagonal / 20). */
#define BLADE_SIZE 46.0

typedef struct seen {
  int repair_inverted, meshed_again, fold_note, fold_split, remeshed, kept_split;
} seen;

static int on_event(void *user, const hoc_event *ev) {
  seen *s = user;
  if (!ev->message) return 0;
  if (ev->kind == HOC_EVENT_REPAIR && strstr(ev->message, "inverted on the CAD"))
    s->repair_inverted++;
  if (ev->kind == HOC_EVENT_NOTE && strstr(ev->message, "meshed again: face 1 with MeshAdapt"))
    s->meshed_again++;
  if (ev->kind == HOC_EVENT_NOTE && strstr(ev->message, "cross a fold of their face"))
    s->fold_note++;
  if (ev->kind == HOC_EVENT_REPAIR && strstr(ev->message, "on faces that fold")) s->fold_split++;
  if (ev->kind == HOC_EVENT_NOTE && strstr(ev->message, "kept the mesh of refinement"))
    s->kept_split++;
  if (ev->kind == HOC_EVENT_REPAIR && strstr(ev->message, "with edges half as long")) s->remeshed++;
  return 0;
}

/* Elements of each hoc_inverted_kind in an order-1 mesh. */
static void count_kinds(const hoc_mesh *mesh, size_t count[4]) {
  size_t ne = hoc_mesh_num_elements(mesh);
  unsigned char *tangled = calloc(ne, 1), *kind = calloc(ne, 1);
  for (int k = 0; k < 4; ++k)
    count[k] = 0;
  CHECK(tangled && kind);
  if (tangled && kind) {
    CHECK_OK(hoc_mesh_measure(mesh, HOC_MEASURE_SHAPE, NULL, tangled, NULL));
    CHECK_OK(hoc_mesh_inverted_kinds(mesh, tangled, kind));
    for (size_t e = 0; e < ne; ++e)
      count[kind[e]]++;
  }
  free(tangled);
  free(kind);
}

static size_t count_folds(const hoc_mesh *mesh) {
  size_t n = 0;
  for (size_t e = 0; e < hoc_mesh_num_elements(mesh); ++e) {
    int folds = -1;
    CHECK_OK(hoc_mesh_element_folds(mesh, e, &folds));
    n += folds == 1;
  }
  return n;
}

static void test_blade(void) {
  hoc_model *model = NULL;
  CHECK_OK(hoc_model_open(DATA "t106_blade_face.brep", &model));
  if (!model) return;
  /* gmsh's own mesh: inverted triangles, none across a fold */
  hoc_linear_options lo;
  hoc_linear_options_default(&lo);
  lo.size_max = BLADE_SIZE;
  lo.order = 2;
  hoc_mesh *lin = NULL;
  CHECK_OK(hoc_mesh_generate_linear(model, &lo, &lin));
  size_t count[4];
  if (lin) {
    count_kinds(lin, count);
    printf("blade, gmsh's default algorithm: %zu elements, %zu inverted on the CAD, %zu across "
           "a fold\n",
           hoc_mesh_num_elements(lin), count[HOC_INVERTED_ON_CAD], count[HOC_INVERTED_ACROSS_FOLD]);
    CHECK(count[HOC_INVERTED_ON_CAD] > 0); /* the swaps leave them */
    CHECK(count[HOC_INVERTED_ACROSS_FOLD] == 0);
    CHECK(count_folds(lin) == 0);
  }
  hoc_mesh_destroy(&lin);
  /* an algorithm out of gmsh's range is refused */
  int bad = 99;
  CHECK_STATUS(hoc_mesh_generate_linear_with(model, &lo, &bad, &lin), HOC_ERR_ARGUMENT);
  CHECK(lin == NULL);

  /* the pipeline meshes the face again: no inverted triangle is left */
  seen s = {0};
  hoc_mesh_options o;
  hoc_mesh_options_default(&o);
  o.order = 2;
  o.optimize = 0;
  o.size = BLADE_SIZE;
  o.event = on_event;
  o.event_user = &s;
  hoc_mesh *mesh = NULL;
  hoc_report *r = NULL;
  CHECK_OK(hoc_mesh_model(model, &o, &mesh, &r));
  if (r) {
    const hoc_stage *linear = hoc_report_stage(r, 0);
    CHECK(linear && !strcmp(linear->name, "linear"));
    if (linear) {
      printf("blade, hoc_mesh_model: linear stage %zu elements, %zu tangled, min q %.4f\n",
             linear->stats.elements, linear->stats.tangled, linear->stats.min);
      CHECK(linear->stats.tangled == 0 && linear->stats.min > 0);
    }
  }
  CHECK(s.repair_inverted == 1 && s.meshed_again == 1 && s.fold_note == 0);
  hoc_report_destroy(&r);
  hoc_mesh_destroy(&mesh);
  hoc_model_destroy(&model);
}

static void test_folded_face(void) {
  hoc_model *model = NULL;
  CHECK_OK(hoc_model_open(DATA "surf114_face1.brep", &model));
  if (!model) return;
  hoc_linear_options lo;
  hoc_linear_options_default(&lo);
  lo.order = 2;
  hoc_mesh *lin = NULL;
  CHECK_OK(hoc_mesh_generate_linear(model, &lo, &lin));
  size_t count[4], folds = 0;
  if (lin) {
    count_kinds(lin, count);
    folds = count_folds(lin);
    printf("folded face: %zu elements, %zu across a fold (%zu inverted there), %zu inverted "
           "elsewhere\n",
           hoc_mesh_num_elements(lin), folds, count[HOC_INVERTED_ACROSS_FOLD],
           count[HOC_INVERTED_ON_CAD]);
    CHECK(count[HOC_INVERTED_ACROSS_FOLD] > 0 && folds >= count[HOC_INVERTED_ACROSS_FOLD]);
  }
  hoc_mesh_destroy(&lin);

  seen s = {0};
  hoc_mesh_options o;
  hoc_mesh_options_default(&o);
  o.order = 2;
  o.max_iterations = 10;
  o.refinements = 1;
  o.event = on_event;
  o.event_user = &s;
  hoc_mesh *mesh = NULL;
  hoc_report *r = NULL;
  CHECK_OK(hoc_mesh_model(model, &o, &mesh, &r));
  printf("folded face, hoc_mesh_model at order 2: %zu tangled, %d refinements, %d remeshings\n",
         r ? hoc_report_tangled(r) : 0, r ? hoc_report_refinements(r) : -1,
         r ? hoc_report_remeshings(r) : -1);
  CHECK(s.fold_note == 1);
  /* tangled elements on the folded face are split, never meshed again */
  if (r && hoc_report_tangled(r)) CHECK(s.fold_split == 1);
  CHECK(s.remeshed == 0 && r && hoc_report_remeshings(r) == 0);
  hoc_report_destroy(&r);
  hoc_mesh_destroy(&mesh);
  hoc_model_destroy(&model);
}

/* hoc_repair_tangled_unrefinable tells faces that fold: a grid on a square
 * folded along v = 0.37 (phi = (u, w^2, w^3), w = v - 0.37) has elements
 * across the fold, tangled, all on the folded face; a plain square has
 * none. */
static void test_tangled_on_folds(void) {
  hoc_run run = {0};
  hoc_mesh_options_default(&run.o);
  const hoc_analytic_kind kinds[2] = {HOC_ANALYTIC_FOLD, HOC_ANALYTIC_PLANE};
  for (int k = 0; k < 2; ++k) {
    hoc_model *model = NULL;
    CHECK_OK(hoc_cad_create_analytic(kinds[k], 1, 0.37, &model));
    hoc_mesh *lin = NULL;
    if (model) CHECK_OK(hoc_mesh_grid_linear(model, 5, 5, &lin));
    if (!lin) {
      hoc_model_destroy(&model);
      continue;
    }
    size_t ne = hoc_mesh_num_elements(lin), n_tangled = 0, folds = count_folds(lin);
    unsigned char *tangled = calloc(ne, 1);
    CHECK(tangled != NULL);
    if (tangled) CHECK_OK(hoc_mesh_measure(lin, run.o.measure, NULL, tangled, NULL));
    for (size_t e = 0; tangled && e < ne; ++e)
      n_tangled += tangled[e] != 0;
    int why = -1;
    CHECK_OK(hoc_repair_tangled_unrefinable(&run, lin, &why));
    printf("%s: %zu elements, %zu tangled, %zu across a fold, unrefinable %d\n",
           k == 0 ? "folded square" : "plain square", ne, n_tangled, folds, why);
    if (k == 0)
      /* each tangled element is across the fold itself: no split either */
      CHECK(n_tangled > 0 && folds >= n_tangled &&
            why == (HOC_UNREFINABLE_FOLDS | HOC_UNREFINABLE_EACH));
    else
      CHECK(n_tangled == 0 && folds == 0 && why == 0);
    free(tangled);
    hoc_mesh_destroy(&lin);
    hoc_model_destroy(&model);
  }
}

/* A face whose normal turns over within the model's tolerance of its
 * side: the bottle's face 4 (occt_bottle.brep, the thread's end) turns its
 * normal by 140 degrees within 0.025 of its side u = pi, the model's
 * tolerance 0.013. The side's nodes take the face's normal past the turn
 * (docs/quality.md), so no linear element is tangled there and the mesh at
 * order 2 untangles without a split, a fold rule or a remeshing. Without
 * the rule 4 linear elements are tangled across the turn and order 2 needs
 * a split chain on the face. (gmsh's mesh, not graded: the graded mesh's
 * thin faces elsewhere take a split chain at order 2.) */
static void test_bottle_turned_side(void) {
  hoc_model *model = NULL;
  CHECK_OK(hoc_model_open(HOC_MODELS_DIR "/occt_bottle.brep", &model));
  if (!model) return;
  seen s = {0};
  hoc_mesh_options o;
  hoc_mesh_options_default(&o);
  o.order = 2;
  o.grading = 0;
  o.event = on_event;
  o.event_user = &s;
  hoc_report *r = NULL;
  CHECK_OK(hoc_mesh_model(model, &o, NULL, &r));
  const hoc_stage *lin = r ? hoc_report_stage(r, 0) : NULL;
  printf("bottle at order 2: %zu linear tangled, %zu tangled, %d refinement(s), %d split "
         "chain(s) on folded faces, %d remeshing(s)\n",
         lin ? lin->stats.tangled : 99, r ? hoc_report_tangled(r) : 99,
         r ? hoc_report_refinements(r) : -1, s.fold_split, s.remeshed);
  CHECK(lin && lin->stats.tangled == 0);
  CHECK(r && hoc_report_tangled(r) == 0 && hoc_report_refinements(r) == 0);
  CHECK(s.fold_split == 0 && s.remeshed == 0);
  hoc_report_destroy(&r);
  hoc_model_destroy(&model);
}

/* Order 1 with triangles inverted on the CAD (which gmsh's algorithms can
 * all leave, e.g. on t106_turbine_blade.step's face 2 at order 1): the
 * linear mesh is untangled by the optimiser at p = 1; without
 * optimisation, or with a valid linear mesh, the result is the linear
 * mesh. The case: a 5 x 5 grid on a square, one interior node pushed
 * across the opposite side of one of its triangles. */
static void test_order1_untangled(void) {
  hoc_model *model = NULL;
  hoc_mesh *lin = NULL;
  CHECK_OK(hoc_cad_create_analytic(HOC_ANALYTIC_PLANE, 1, 1, &model));
  if (model) CHECK_OK(hoc_mesh_grid_linear(model, 5, 5, &lin));
  if (!lin) {
    hoc_model_destroy(&model);
    return;
  }
  size_t e = 0;
  int k = -1;
  for (; e < lin->n_elems && k < 0; ++e)
    for (int j = 0; j < 3 && k < 0; ++j)
      if (lin->dim[lin->conn[3 * e + j]] == HOC_ON_FACE) k = j;
  --e;
  CHECK(k >= 0);
  if (k >= 0) {
    size_t i = lin->conn[3 * e + k];
    const double *u = lin->elem_uv + 6 * e;
    int a = (k + 1) % 3, b = (k + 2) % 3;
    double d[2];
    for (int c = 0; c < 2; ++c)
      d[c] = 1.6 * (0.5 * (u[2 * a + c] + u[2 * b + c]) - u[2 * k + c]);
    for (int c = 0; c < 2; ++c)
      lin->param[2 * i + c] += d[c];
    for (size_t f = 0; f < 3 * lin->n_elems; ++f)
      if (lin->conn[f] == i)
        for (int c = 0; c < 2; ++c)
          lin->elem_uv[2 * f + c] += d[c];
    for (size_t sl = 0; sl < lin->n_slots; ++sl)
      if (lin->slot_node[sl] == i)
        for (int c = 0; c < 2; ++c)
          lin->slot_uv[2 * sl + c] = lin->param[2 * i + c];
    hoc_mesh_update_xyz(lin);
  }
  for (int optimize = 0; optimize < 2; ++optimize) {
    hoc_mesh_options o;
    hoc_mesh_options_default(&o);
    o.order = 1;
    o.linear = lin;
    o.optimize = optimize;
    hoc_report *r = NULL;
    CHECK_OK(hoc_mesh_model(model, &o, NULL, &r));
    if (!r) continue;
    size_t n = hoc_report_num_stages(r);
    const hoc_stage *first = hoc_report_stage(r, 0), *last = hoc_report_stage(r, n - 1);
    printf("order 1, %s: linear %zu tangled, result %zu (%zu stage(s))\n",
           optimize ? "optimised" : "not optimised", first->stats.tangled, hoc_report_tangled(r),
           n);
    CHECK(first->stats.tangled > 0);
    if (optimize)
      CHECK(n == 2 && !strcmp(last->name, "optimized") && hoc_report_tangled(r) == 0 &&
            last->stats.order == 1);
    else
      CHECK(n == 1 && hoc_report_tangled(r) == first->stats.tangled);
    hoc_report_destroy(&r);
  }
  hoc_mesh_destroy(&lin);
  hoc_model_destroy(&model);
}

int main(void) {
  test_order1_untangled();
  test_tangled_on_folds();
  test_bottle_turned_side();
  test_blade();
  test_folded_face();
  return test_report();
}
