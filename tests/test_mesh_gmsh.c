/* Real CAD through gmsh: import, linear mesh with classification, order
 * elevation with every node on the CAD, and gmsh's own order-3 mesh of
 * gmsh_t20_component8.step measured as gmsh measures it (12 elements with a
 * negative Jacobian).
 * SPDX-License-Identifier: GPL-2.0-or-later */
#include "mesh/mesh.h"
#include "quality/quality.h"
#include "test_util.h"

#include <gmshc.h>
#include <string.h>

static void test_model(const char *name, double min_linear_q) {
  char path[1024];
  snprintf(path, sizeof path, "%s/%s", HOC_MODELS_DIR, name);
  hoc_model *model;
  CHECK_OK(hoc_model_open(path, &model));
  if (!model) return;
  hoc_mesh *lin;
  CHECK_OK(hoc_mesh_generate_linear(model, NULL, &lin));
  if (!lin) {
    hoc_model_destroy(&model);
    return;
  }
  CHECK(lin->n_elems > 0);
  CHECK(lin->n_failed_faces == 0);
  double dist;
  CHECK_OK(hoc_mesh_max_cad_distance(lin, &dist));
  CHECK(dist <= 1e-10 * model->diagonal);
  hoc_quality_stats st;
  CHECK_OK(hoc_mesh_measure(lin, HOC_MEASURE_SHAPE, NULL, NULL, &st));
  CHECK(st.tangled == 0);
  CHECK(st.min >= min_linear_q);
  printf("%s: linear %zu elements, q min %.3f mean %.3f\n", name, st.elements, st.min, st.mean);
  int orders[] = {2, 3, 5, 10};
  for (size_t k = 0; k < sizeof orders / sizeof *orders; ++k) {
    hoc_mesh *m;
    CHECK_OK(hoc_mesh_elevate(lin, orders[k], HOC_NODES_EQUISPACED, &m));
    if (!m) continue;
    CHECK_OK(hoc_mesh_max_cad_distance(m, &dist));
    CHECK(dist <= 1e-10 * model->diagonal);
    CHECK_OK(hoc_mesh_measure(m, HOC_MEASURE_SHAPE, NULL, NULL, &st));
    CHECK(isfinite(st.min) && isfinite(st.mean) && isfinite(st.std));
    printf("%s: order %d, q min %.3f mean %.3f, %zu tangled\n", name, orders[k], st.min, st.mean,
           st.tangled);
    hoc_mesh_destroy(&m);
  }
  hoc_mesh_destroy(&lin);
  hoc_model_destroy(&model);
}

/* gmsh's own order 3 at gmsh's default size, read back and measured. */
static void test_gmsh_order3_t20(void) {
  char path[1024];
  snprintf(path, sizeof path, "%s/gmsh_t20_component8.step", HOC_MODELS_DIR);
  hoc_model *model;
  CHECK_OK(hoc_model_open(path, &model));
  if (!model) return;
  int ierr = 0;
  /* gmsh's defaults, as the gmsh program uses them */
  gmshOptionSetNumber("Mesh.MeshSizeMax", 1e22, &ierr);
  gmshOptionSetNumber("Mesh.MeshSizeMin", 0, &ierr);
  gmshOptionSetNumber("Mesh.MeshSizeFromCurvature", 0, &ierr);
  gmshModelMeshGenerate(2, &ierr);
  CHECK(ierr == 0);
  gmshModelMeshSetOrder(3, &ierr);
  CHECK(ierr == 0);
  gmshWrite("t20_gmsh_order3.msh", &ierr);
  CHECK(ierr == 0);
  hoc_mesh *m;
  CHECK_OK(hoc_mesh_read_msh(model, "t20_gmsh_order3.msh", &m));
  if (m) {
    CHECK(m->order == 3);
    hoc_quality_stats st;
    CHECK_OK(hoc_mesh_measure(m, HOC_MEASURE_SHAPE, NULL, NULL, &st));
    printf("gmsh order 3 on t20: %zu elements, q min %.3f mean %.3f, %zu tangled\n", st.elements,
           st.min, st.mean, st.tangled);
    CHECK(st.tangled == 12);
    double dist;
    CHECK_OK(hoc_mesh_max_cad_distance(m, &dist));
    CHECK(dist <= 1e-10 * model->diagonal);
    hoc_mesh_destroy(&m);
  }
  hoc_model_destroy(&model);
}

/* Bad input: one clear error, nothing open afterwards. */
static void test_bad_input(void) {
  hoc_model *model = (hoc_model *)1;
  CHECK_STATUS(hoc_model_open("does-not-exist.step", &model), HOC_ERR_IO);
  CHECK(model == NULL);
  FILE *f = fopen("empty.step", "w");
  if (f) fclose(f);
  CHECK_STATUS(hoc_model_open("empty.step", &model), HOC_ERR_FORMAT);
  f = fopen("garbage.step", "w");
  if (f) {
    fputs("this is not a STEP file\n", f);
    fclose(f);
  }
  CHECK_STATUS(hoc_model_open("garbage.step", &model), HOC_ERR_FORMAT);
  f = fopen("notcad.txt", "w");
  if (f) {
    fputs("hello\n", f);
    fclose(f);
  }
  CHECK_STATUS(hoc_model_open("notcad.txt", &model), HOC_ERR_FORMAT);
  CHECK(strstr(hoc_last_error(), "not a CAD file") != NULL);
  /* a valid STEP file with no geometry */
  f = fopen("nogeom.step", "w");
  if (f) {
    fputs("ISO-10303-21;\nHEADER;\nFILE_DESCRIPTION((''),'2;1');\nFILE_NAME('','',(''),(''),'','','');\n"
          "FILE_SCHEMA(('CONFIG_CONTROL_DESIGN'));\nENDSEC;\nDATA;\nENDSEC;\nEND-ISO-10303-21;\n",
          f);
    fclose(f);
  }
  hoc_status st = hoc_model_open("nogeom.step", &model);
  CHECK(st == HOC_ERR_CAD || st == HOC_ERR_FORMAT);
  CHECK(model == NULL);
  /* after all that, a good model still opens */
  char path[1024];
  snprintf(path, sizeof path, "%s/screw.step", HOC_MODELS_DIR);
  CHECK_OK(hoc_model_open(path, &model));
  hoc_model *second = NULL;
  CHECK_STATUS(hoc_model_open(path, &second), HOC_ERR_ARGUMENT);
  hoc_mesh *m = NULL;
  hoc_linear_options o;
  hoc_linear_options_default(&o);
  o.size_max = -1;
  CHECK_STATUS(hoc_mesh_generate_linear(model, &o, &m), HOC_ERR_ARGUMENT);
  o.size_max = NAN;
  CHECK_STATUS(hoc_mesh_generate_linear(model, &o, &m), HOC_ERR_ARGUMENT);
  hoc_mesh_destroy(&m);
  hoc_model_destroy(&model);
}

int main(void) {
  test_bad_input();
  test_model("gmsh_t20_component8.step", 0.15);
  test_model("screw.step", 0.2);
  test_model("periodic_u_cst.step", 0.2);
  test_gmsh_order3_t20();
  return test_report();
}
